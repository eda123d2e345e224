"""gspn.run: Python functions as a plan's actions receive the agents and choose transitions."""

from __future__ import annotations

import json
from collections import Counter

import gspn
from conftest import REPO

QUICKSTART = REPO / "plans" / "quickstart.toml"


def fired(journal) -> Counter:
    counts: Counter = Counter()
    with open(journal, encoding="utf-8") as f:
        for line in f:
            e = json.loads(line)
            if e.get("event") == "fired":
                counts[e["transition_name"]] += 1
    return counts


def test_python_actions_receive_the_agents_and_choose(tmp_path):
    seen = []

    def patrol_a(ctx: gspn.ActionContext):
        seen.append((ctx.place, ctx.agent, tuple(ctx.outputs)))
        assert ctx.marking["Patrol_A"] >= 1
        return "T_A_done"  # the only way on, chosen explicitly

    async def decide(ctx):
        seen.append((ctx.place, ctx.agent, tuple(ctx.outputs)))
        return ("t_go_A", 0.25) if "t_go_A" in ctx.outputs else None

    journal = tmp_path / "run.jsonl"
    r = gspn.run(QUICKSTART, actions={"Patrol_A": patrol_a, "Decide": decide}, max_firings=50, journal=journal, seed=42)
    assert r.stopped == "max_firings" and r.firings == 50
    assert r.journal == str(journal)
    places = {p for p, _, _ in seen}
    assert places == {"Patrol_A", "Decide"}
    # Agents are the plan's two robots, ids 0 and 1.
    assert {a for _, a, _ in seen} <= {0, 1} and len({a for _, a, _ in seen}) == 2
    assert all(outs == ("T_A_done",) for p, _, outs in seen if p == "Patrol_A")
    counts = fired(journal)
    # Decide always answered t_go_A: the charger was never chosen.
    assert counts["t_charge"] == 0 and counts["t_go_A"] > 0
    again = gspn.run(QUICKSTART, actions={"Patrol_A": patrol_a, "Decide": decide}, max_firings=50, seed=42)
    assert again.final_marking == r.final_marking and again.time == r.time


def test_a_failing_action_follows_the_plan(tmp_path):
    def broken(ctx):
        raise RuntimeError("arm stuck")

    r = gspn.run(QUICKSTART, actions={"Patrol_B": broken}, max_firings=50, seed=1)
    assert r.stopped == "failure" and r.exit_code == 1, r.summary
    assert any("RuntimeError: arm stuck" in str(e) for e in r.summary["errors"]), r.summary
