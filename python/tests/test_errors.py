"""Bad input raises gspn.InputError (a ValueError) with the file, line and column."""

from __future__ import annotations

import subprocess

import pytest

import gspn
from conftest import REPO, plan_runner


def test_a_broken_net_names_its_line_and_column(tmp_path):
    bad = tmp_path / "bad.PNPRO"
    bad.write_text(
        '<project name="n" version="121"><gspn name="n"><nodes>\n'
        '  <place marking="1" name="p" x="1" y="1"/>\n'
        '  <transition name="t" type="EXP" delay="-2" x="3" y="1"/>\n'
        "</nodes><edges/></gspn></project>\n"
    )
    with pytest.raises(gspn.InputError) as e:
        gspn.load(bad)
    assert e.value.file == str(bad)
    assert e.value.line == 3 and e.value.column > 1
    assert "delay" in str(e.value) or "rate" in str(e.value)
    # The CLI names the same place.
    out = subprocess.run([str(plan_runner()), "check", str(bad)], capture_output=True, text=True)
    assert out.returncode == 2
    assert f"{bad}:{e.value.line}:{e.value.column}" in out.stderr, out.stderr
    assert isinstance(e.value, ValueError)


def test_a_bad_plan_key_is_located():
    with pytest.raises(gspn.InputError) as e:
        gspn.load(REPO / "tests" / "data" / "does-not-exist.toml")
    assert e.value.line is None and "does-not-exist.toml" in str(e.value)


def test_bad_arguments_raise_input_errors():
    net = gspn.load(REPO / "plans" / "quickstart.toml")
    with pytest.raises(gspn.InputError, match="transient: -1"):
        gspn.analyze(net, transient=[-1.0])
    with pytest.raises(gspn.InputError, match="unknown objective"):
        gspn.synthesize(REPO / "plans" / "home-cleaning" / "plan.toml", objective="fast-max")
    with pytest.raises(gspn.InputError, match="no place `Nowhere`"):
        gspn.run(net, actions={"Nowhere": lambda ctx: None}, max_firings=5)
