"""The one outcome enum of every algorithm (search, re-timing, tracking, a query).

A string enum, so ``status == "solved"`` and the JSON files' ``"status"`` values keep
working. No solution is a status, never an exception (:mod:`gfuzzy.errors`).
"""

from __future__ import annotations

import enum

__all__ = ["Status"]


class Status(str, enum.Enum):
    """Outcome of a query or of one algorithm run (docs/formats.md section 2).

    SOLVED: an answer (a planned, re-timed or tracked trajectory that reached its goal);
    NO_PATH: none exists within the limits searched; INVALID_QUERY: the start or goal is
    unusable; TIMEOUT: the time budget (or, for tracking, the simulated time) ran out.
    """

    SOLVED = "solved"
    NO_PATH = "no_path"
    INVALID_QUERY = "invalid_query"
    TIMEOUT = "timeout"

    def __str__(self) -> str:
        return self.value
