"""Place functions in the shape of the 2020 thesis's standalone example
(`gspn_framework_package/example_functions/functions.py`): each takes the token's id,
prints, works a little (sleeps), and returns the transition to fire, or nothing to let the
policy decide."""

import time


def work_place_1(token_id):
    print("token %d works in place 1" % token_id)
    time.sleep(0.05)
    return "t1"


def work_place_2(token_id):
    print("token %d works in place 2" % token_id)
    time.sleep(0.05)
    return "t2"


def work_place_3(token_id):
    print("token %d is done, in place 3" % token_id)
    time.sleep(0.05)
    # Nothing returned: the policy decides (p3 has no output: the token stays).
