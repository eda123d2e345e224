"""How a Python callable answers for a place's agent in :func:`gspn.run` (called by the engine)."""

from __future__ import annotations

import asyncio
import inspect
from dataclasses import dataclass, field
from typing import Any, Callable


@dataclass(frozen=True)
class ActionContext:
    """What an action knows when it starts."""

    agent: int
    """The agent's id (0, 1, … in the order the run created them)."""
    robot: str | None
    """The agent's robot, when the plan names robots."""
    place: str
    """The action place."""
    marking: dict[str, int]
    """The marking when the action started (places with tokens)."""
    attempt: int
    """0 the first time, then 1, 2, … on retries."""
    time: float
    """Model time (seconds) when the action started."""
    seed: int
    """The run's seed."""
    outputs: list[str] = field(default_factory=list)
    """The transitions that take the agent on from this place: the names it may answer."""


def call(func: Callable[[ActionContext], Any], info: dict[str, Any]) -> tuple[str | None, float]:
    """Calls ``func`` with the context and normalises its answer to ``(transition, seconds)``.

    ``func`` may answer a transition name (fire it), ``None`` (let the policy or the net's
    rates decide), or a pair ``(name_or_None, seconds)``: the outcome takes effect that many
    model seconds later. An ``async def`` is run to completion on an event loop of its own.
    Exceptions propagate: the action fails with their message.
    """
    answer = func(ActionContext(**info))
    if inspect.isawaitable(answer):
        answer = asyncio.run(_awaited(answer))
    if answer is None or isinstance(answer, str):
        return answer, 0.0
    if isinstance(answer, tuple) and len(answer) == 2:
        name, seconds = answer
        if (name is None or isinstance(name, str)) and isinstance(seconds, (int, float)):
            if seconds < 0 or seconds != seconds:
                raise ValueError(f"an action's duration must be ≥ 0 seconds, not {seconds!r}")
            return name, float(seconds)
    raise TypeError(
        "an action answers a transition name, None, or (name_or_None, seconds); "
        f"got {answer!r}"
    )


async def _awaited(awaitable: Any) -> Any:
    return await awaitable
