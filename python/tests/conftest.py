"""Shared fixtures: the checkout, the shared fixtures beside it, and `plan-runner` (the CLI
the package must agree with)."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared" / "fixtures"


def plan_runner() -> Path:
    """`plan-runner` built from this checkout: $GSPN_PLAN_RUNNER, else the target directory's
    debug or release build (`cargo test` / the README's main command build them)."""
    given = os.environ.get("GSPN_PLAN_RUNNER")
    if given:
        return Path(given)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for profile in ("debug", "release"):
        exe = target / profile / "plan-runner"
        if exe.exists():
            return exe
    raise RuntimeError(f"no plan-runner under {target}: run `cargo build` first or set GSPN_PLAN_RUNNER")


def cli_json(*args: str) -> dict:
    out = subprocess.run(
        [str(plan_runner()), *args], capture_output=True, text=True, cwd=REPO, check=False
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


@pytest.fixture
def repo() -> Path:
    return REPO


@pytest.fixture
def shared() -> Path:
    if not SHARED.is_dir():
        pytest.fail(f"{SHARED}: ../shared (the fixtures) must sit beside the checkout")
    return SHARED
