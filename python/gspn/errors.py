"""The exceptions gspn raises.

Every error of the engine is a :class:`GspnError`. Bad input (a file that does not parse, a
name that does not exist, an argument out of range) is an :class:`InputError`, which is also a
:class:`ValueError` and carries where the input was wrong::

    try:
        gspn.load("broken.PNPRO")
    except gspn.InputError as e:
        print(e.file, e.line, e.column)   # broken.PNPRO 12 7
"""

from __future__ import annotations

__all__ = ["GspnError", "InputError", "AnalysisError", "RunError"]


class GspnError(Exception):
    """Base class of every gspn error."""


class InputError(GspnError, ValueError):
    """Bad input: ``file``, ``line`` and ``column`` (from 1) say where, when it was a file."""

    def __init__(
        self,
        message: str,
        *,
        file: str | None = None,
        line: int | None = None,
        column: int | None = None,
    ) -> None:
        super().__init__(message)
        self.file = file
        self.line = line
        self.column = column


class AnalysisError(GspnError):
    """The analysis could not answer (too many states, no convergence, a singular chain)."""


class RunError(GspnError):
    """A run could not start or its backends failed."""
