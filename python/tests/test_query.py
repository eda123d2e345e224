"""`gspn.query` answers what `plan-runner analyze --query … --json` prints (1e-9), with the
column of a bad query, and `max`/`min` through the synthesis engine."""

from __future__ import annotations

import math

import pytest

import gspn
from conftest import REPO, SHARED, cli_json

CYC3 = SHARED / "greatspn" / "cyc3" / "cyc3_ss.PNPRO"
HOME = REPO / "plans" / "home-cleaning" / "plan.toml"


def test_queries_equal_the_cli_on_cyc3():
    queries = ["S=? [P1>0]", "P=? [F<=1 P3>0]", "P=? [F P3>0]", "T=? [F P3>0]", "P=? [G<=0.5 P3=0]"]
    ours = gspn.query(gspn.load(CYC3), queries)
    args = [a for q in queries for a in ("--query", q)]
    theirs = cli_json("analyze", str(CYC3), *args, "--json")["queries"]
    assert [t["query"] for t in theirs] == queries
    for q, mine, t in zip(queries, ours, theirs):
        assert math.isclose(mine, t["value"], rel_tol=1e-9, abs_tol=1e-9), q
    # One query gives a float; P[F P3>0] from the initial marking is certain.
    assert gspn.query(CYC3, "P=? [F P3>0]") == pytest.approx(1.0, abs=1e-12)


def test_the_best_long_run_reward_is_the_synthesised_value():
    best = gspn.query(HOME, 'R{"cleaning"}max=? [S]')
    assert best == pytest.approx(gspn.synthesize(HOME, objective="lra-max").value, abs=1e-6)
    theirs = cli_json("analyze", str(HOME), "--query", 'R{"cleaning"}max=? [S]', "--json")
    assert math.isclose(best, theirs["queries"][0]["value"], rel_tol=1e-9, abs_tol=1e-9)


def test_a_bad_query_names_its_column():
    with pytest.raises(gspn.InputError) as e:
        gspn.query(CYC3, "P=? [F<=1 P9>0]")
    assert e.value.column == 11
    assert "P9" in str(e.value)
