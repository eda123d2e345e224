"""The quickstart's patrol, with its actions written in Python: one worker process answers
every action of the run (JSON Lines on stdin/stdout, see docs/actions.md)."""

import os
import sys

# The helper is the gspn package's worker module (python/gspn/worker.py, standard library
# only): from the checkout here, or from `pip install ./python`.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))

from gspn.worker import action, run  # noqa: E402


@action("patrol")
def patrol(ctx):
    print("robot %d patrols %s" % (ctx.agent, ctx.place))
    return ctx.outputs[0]  # T_A_done or T_B_done


@action("choose")
def choose(ctx):
    # Charge when the charger is free and the other robot is out on patrol; else let the
    # plan's policy decide.
    if ctx.marking["Charger"] > 0 and ctx.marking["Patrol_B"] > 0:
        return "t_charge"
    return None


run()
