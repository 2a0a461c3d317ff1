"""What a solve counts (docs/semantics.md §7, "Search"), typed: the live :class:`Stats` the
search updates and a progress display reads, and the :class:`SolveStats` a
:class:`~ehatp.search.planner.Result` reports (its keys and values are those of the JSON
``stats`` of a policy file, ``time_ms`` apart)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TypedDict

from ..model.problem import Cost


class SolveStats(TypedDict, total=False):
    """A solve's statistics, as ``Result.stats`` holds them (a plain dict at run time)."""

    generated: int  # epistemic states generated (children created, duplicates included)
    distinct: int  # distinct epistemic states
    expanded: int  # states expanded
    max_worlds: int  # largest |W| (the designated world is not counted separately)
    time_ms: float  # the search's time, values included
    atoms: int  # ground atoms of the problem
    # the policy's figures, when there is one
    cost: Cost
    communications: int
    leaves: int
    worst_case: Cost | None
    expected: Cost | None


@dataclass
class Stats:
    """The search's counters while it runs; :meth:`as_dict` gives those a result reports."""

    generated: int = 0  # epistemic states generated (children created, duplicates included)
    distinct: int = 0  # distinct epistemic states
    expanded: int = 0
    max_worlds: int = 0  # largest |W| (the designated world is not counted separately)
    time_s: float = 0.0
    # for progress displays only (not reported): the work under way and the search frontier
    phase: str = "search"
    frontier: int = 0

    def as_dict(self) -> SolveStats:
        """Return the counters a result reports (the time in milliseconds, to 0.1 ms)."""
        return {"generated": self.generated, "distinct": self.distinct,
                "expanded": self.expanded, "max_worlds": self.max_worlds,
                "time_ms": round(self.time_s * 1000, 1)}

    def restart(self) -> None:
        """The counters start again (a search without symmetry after one with it); the time
        and the phase go on."""
        self.generated = self.distinct = self.expanded = self.max_worlds = self.frontier = 0


Progress = Callable[[Stats, int], None]
"""``progress(stats, frontier)``: called about 20 times a second while a solve works."""


__all__ = ["Progress", "SolveStats", "Stats"]
