"""Runs the 2020 thesis framework's place functions as gspn worker actions.

The thesis's standalone executor mapped each place to a Python function
(`place_to_function_mapping`: {'p1': 'functions.work_place_1', ...}) and called
`work_place_1(token_id)`: it prints, sleeps, and returns a transition name ('t1') to fire,
or None to let the policy decide. `plan-runner import-thesis` writes a plan whose places
send their action, the function's `module.function` name, to this worker:

    python3 thesis_functions.py PROJECT_PATH

imports `module` from PROJECT_PATH (the input's `project_path`) and calls
`function(agent_id)`, each call on its own thread (the functions sleep), its prints recorded
as the agent's output. Needs the gspn Python package's worker helper (`gspn.worker`,
standard library only): `pip install ./python` from a gspn checkout, or PYTHONPATH set to
its python/ directory.
"""

import importlib
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

try:
    from gspn.worker import fallback, run
except ImportError as e:
    sys.exit(
        "thesis_functions.py needs the gspn Python package (gspn.worker): "
        "pip install ./python from a gspn checkout, or set PYTHONPATH to its python/ "
        "directory (%s)" % e
    )

PROJECT = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else HERE
sys.path.insert(0, PROJECT)


@fallback
def thesis_function(name):
    module, _, function = name.rpartition(".")
    if not module:
        raise ValueError("expected module.function, as in place_to_function_mapping")
    f = getattr(importlib.import_module(module), function)
    return lambda ctx: f(ctx.agent)


run()
