"""The package answers what `plan-runner … --json` prints, number for number (1e-9)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import gspn
from conftest import REPO, SHARED, cli_json

NETS = [
    SHARED / "greatspn" / "cyc3" / "cyc3_ss.PNPRO",
    SHARED / "greatspn" / "cyc3" / "cyc3.PNPRO",
    SHARED / "greatspn" / "hallway.PNPRO",
    SHARED / "greatspn" / "inspection.PNPRO",
    REPO / "plans" / "nets" / "two_robot_patrol.xml",
    REPO / "plans" / "quickstart.toml",
    REPO / "plans" / "home-cleaning" / "plan.toml",
]


def close(a, b, path="") -> None:
    """Every number of `a` equals `b`'s to 1e-9 (relative above 1), every other value equal."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-9), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


@pytest.mark.parametrize("path", NETS, ids=lambda p: p.name)
def test_analyze_equals_the_cli(path):
    net = gspn.load(path)
    ours = gspn.analyze(net, transient=[0.5, 2.0], steady=True)
    theirs = cli_json("analyze", str(path), "--steady", "--transient", "0.5,2", "--json")
    close(ours.report, theirs)
    # The arrays follow the net's order and hold the same numbers.
    st = theirs["steady_state"]
    assert np.allclose(ours.steady.mean_tokens, [st["mean_tokens"][p.name] for p in net.places], rtol=0, atol=1e-12)
    assert ours.transient[1].time == 2.0


def test_cyc3_known_answers():
    # fixtures/greatspn/cyc3: E[P1] = 10/7, E[P3] = 4/7, every throughput 6/7.
    r = gspn.analyze(gspn.load(SHARED / "greatspn" / "cyc3" / "cyc3_ss.PNPRO"))
    m = r.steady.by_place()
    assert abs(m["P1"] - 10 / 7) < 1e-9 and abs(m["P3"] - 4 / 7) < 1e-9
    assert np.allclose(r.steady.throughput, 6 / 7, atol=1e-9)
    assert (r.state_space["reachable"], r.state_space["tangible"]) == (5, 3)


def test_synthesize_equals_the_cli(tmp_path):
    plan = REPO / "plans" / "home-cleaning" / "plan.toml"
    ours = gspn.synthesize(plan)
    rules = tmp_path / "rules.json"
    theirs = cli_json("synthesize", str(plan), "--json", "--rules-json", str(rules))
    assert math.isclose(ours.value, theirs["value"], rel_tol=1e-9, abs_tol=1e-12)
    assert ours.lower <= ours.value <= ours.upper
    assert ours.states == theirs["states"] and ours.choices == theirs["choices"]
    written = json.loads(rules.read_text())["rules"]
    assert theirs["exact_rules"] == len(written)
    assert [(r["marking"], r["choose"]) for r in ours.rules] == [
        (r["marking"], r["choose"]) for r in written
    ]


def test_a_written_policy_runs_and_is_analysed_like_the_cli(tmp_path):
    plan = REPO / "plans" / "home-cleaning" / "plan.toml"
    best = gspn.synthesize(plan)
    out = tmp_path / "optimal.toml"
    best.write(out)
    mine = tmp_path / "cli.toml"
    cli_json("synthesize", str(plan), "--json", "--out", str(mine))
    # Both plans analyse to the same long-run reward: the synthesised optimum.
    ours = gspn.analyze(out)
    theirs = cli_json("analyze", str(mine), "--json")
    rate = lambda rep: next(iter(rep["steady_state"]["rewards"].values()))["rate"]  # noqa: E731
    assert math.isclose(rate(ours.report), rate(theirs), rel_tol=1e-9)
    assert math.isclose(rate(ours.report), best.value, rel_tol=1e-6)


def test_simulate_equals_the_cli():
    path = REPO / "plans" / "quickstart.toml"
    ours = gspn.simulate(path, seed=7, runs=20, until=50.0)
    theirs = cli_json("simulate", str(path), "--seed", "7", "--runs", "20", "--until", "50", "--json")
    for name, e in ours.mean_tokens.items():
        assert math.isclose(e.mean, theirs["mean_tokens"][name], rel_tol=1e-12, abs_tol=1e-12)
        lo, hi = theirs["ci95"]["mean_tokens"][name]
        assert math.isclose(e.lo, lo, abs_tol=1e-12) and math.isclose(e.hi, hi, abs_tol=1e-12)
    trace = gspn.simulate(path, seed=7, steps=30)
    cli = cli_json("simulate", str(path), "--seed", "7", "--steps", "30", "--json")
    assert [s["transition"] for s in trace.steps] == [s["transition"] for s in cli["trace"]]


def test_a_net_built_in_code_round_trips_through_pnpro(tmp_path):
    net = gspn.Net.build(
        "on-off",
        places={"on": 1, "off": 0},
        transitions={"fail": gspn.exponential(1.0), "repair": gspn.exponential(3.0)},
        arcs=[("on", "fail"), ("fail", "off"), ("off", "repair"), ("repair", "on")],
    )
    r = gspn.analyze(net)
    assert abs(r.steady.by_place()["on"] - 0.75) < 1e-12
    path = tmp_path / "on-off.PNPRO"
    net.save(path)
    again = gspn.load(path)
    assert [p.name for p in again.places] == ["on", "off"]
    assert abs(gspn.analyze(again).steady.by_place()["on"] - 0.75) < 1e-12
    assert "<svg" in net._repr_svg_() and "repair" in net._repr_svg_()
    assert "pnml" in net.to_pnml()
