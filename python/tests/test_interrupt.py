"""Ctrl-C during gspn.run and a long gspn.analyze returns control to Python within 1 s
(a real child process, a real SIGINT)."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest

from conftest import REPO

CHILD = r"""
import sys, time
import gspn
what = sys.argv[1]
if what == "analyze":
    # 8 rings of 3 places with 4 tokens each: 15**8 markings, far more than a second's work.
    places, transitions, arcs = {}, {}, []
    for r in range(8):
        for i in range(3):
            places[f"p{r}_{i}"] = 4 if i == 0 else 0
            transitions[f"t{r}_{i}"] = gspn.exponential(1.0 + i)
            arcs += [(f"p{r}_{i}", f"t{r}_{i}"), (f"t{r}_{i}", f"p{r}_{(i + 1) % 3}")]
    net = gspn.Net.build("rings", places, transitions, arcs)
    work = lambda: gspn.analyze(net, max_states=200_000_000, max_memory_mib=16_000)
else:
    work = lambda: gspn.run(sys.argv[2], actions={"Patrol_A": lambda ctx: None}, time_scale=1.0)
print("ready", flush=True)
try:
    work()
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted %.3f" % time.monotonic(), flush=True)
"""


@pytest.mark.parametrize("what", ["analyze", "run"])
def test_ctrl_c_returns_within_a_second(what):
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, what, str(REPO / "plans" / "quickstart.toml")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert child.stdout.readline().strip() == "ready"
    time.sleep(1.5)  # well inside the work
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=30)
    line = out.strip().splitlines()[-1]
    assert line.startswith("interrupted"), (out, err)
    took = float(line.split()[1]) - sent
    assert took < 1.0, f"control came back {took:.3f} s after SIGINT"
    assert child.returncode == 0
