"""The notebook-style example runs end to end: model, analyse, synthesise, run, plot."""

from __future__ import annotations

import subprocess
import sys

from conftest import REPO


def test_home_cleaning_example(tmp_path):
    out = subprocess.run(
        [sys.executable, str(REPO / "python" / "examples" / "home_cleaning.py")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    # The optimum of the home plan (`plan-runner synthesize`: 3.2) and the policy analysed to it.
    assert "optimal reward rate 3.200000000" in out.stdout, out.stdout
    assert "analysed under it: {'cleaning': {'rate': 3.2" in out.stdout, out.stdout
    png = tmp_path / "home_cleaning.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "home_cleaning_policy.toml").read_text().count("[[policy]]") == 169
