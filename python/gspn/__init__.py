"""gspn: multi-robot plans as generalized stochastic Petri nets.

Model, analyse exactly, synthesise optimal policies, simulate and run plans — the engine of
``plan-runner``, from Python::

    import gspn

    net = gspn.load("plans/nets/two_robot_patrol.xml")
    result = gspn.analyze(net)
    print(result.steady.by_place())
    print(gspn.query(net, "P=? [F<=10 Patrol_A=1]"))

    best = gspn.synthesize("plans/home-cleaning/plan.toml")
    print(best.value, best.lower, best.upper)

    def patrol(ctx):
        return None                       # let the net's rates decide

    gspn.run("plans/quickstart.toml", actions={"Patrol_A": patrol}, max_firings=50)

Workers for ``plan-runner`` (actions as Python functions in a process of their own) use
:mod:`gspn.worker`, which needs only the standard library.

The engine (``gspn._native``) is loaded on first use, so ``gspn.worker`` and
``gspn.errors`` import without it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .errors import AnalysisError, GspnError, InputError, RunError

__version__ = "0.1.0"

_API = (
    "Net",
    "Place",
    "Transition",
    "Arc",
    "immediate",
    "exponential",
    "load",
    "analyze",
    "query",
    "synthesize",
    "simulate",
    "run",
    "Analysis",
    "Measures",
    "Synthesis",
    "Simulation",
    "Estimate",
    "RunResult",
)

__all__ = [*_API, "ActionContext", "GspnError", "InputError", "AnalysisError", "RunError"]

if TYPE_CHECKING:
    from ._actions import ActionContext
    from ._api import (
        Analysis,
        Arc,
        Estimate,
        Measures,
        Net,
        Place,
        RunResult,
        Simulation,
        Synthesis,
        Transition,
        analyze,
        exponential,
        immediate,
        load,
        query,
        run,
        simulate,
        synthesize,
    )


def __getattr__(name: str) -> Any:
    if name in _API:
        from . import _api

        return getattr(_api, name)
    if name == "ActionContext":
        from ._actions import ActionContext

        return ActionContext
    raise AttributeError(f"module 'gspn' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
