"""Limits that hold: one budget of time and memory for a whole solve (docs/semantics.md §7,
"Search": time and memory limits stop the work cleanly).

A :class:`Budget` is created when the work starts and passed to every long loop: the search,
the worst-case (Knuth) pass, the expected-cost pass, policy extraction and writing. Each loop
calls :meth:`Budget.check` often (every iteration, or every few hundred); the call is cheap and
looks at the clock and the resident set size only every ``POLL_S`` seconds. When a limit is
passed it raises :class:`LimitReached`, which the caller turns into a clean stop: partial
statistics and, if the root was solved, the best policy so far, marked not proven optimal.

Two deadlines: the search stops at ``timeout`` minus a reserve for what must follow it
(:meth:`Budget.search_should_stop`), and everything stops at the hard deadline, 5 % later plus
half a second, so the whole command stays within ``timeout`` + 5 % + 1 s. Memory is the
resident set size (``/proc/self/statm``, else the peak from :mod:`resource`): the search stops
while the values still fit, and a :class:`MemoryError` anywhere is a memory stop too.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from enum import StrEnum

from ..model.problem import Limits, parse_size
from .stats import Progress, Stats

POLL_S = 0.05  # how often the clock and the resident set size are looked at
GRACE_FRACTION, GRACE_S = 0.05, 0.2  # the hard deadline: timeout * 1.05 + 0.2 s
# what the values pass and extraction need after the search, per distinct state (rough
# measurements, generous): time, and memory beyond what the graph already holds
POST_S_PER_STATE = 12e-6
POST_BYTES_PER_STATE = 220
MEMORY_HEADROOM = 0.95  # the search stops when it would pass this fraction of max_memory



class SolveStatus(StrEnum):
    """How a solve ended (``Result.status``; the JSON and the command line write the value)."""

    SOLVED = "solved"  # a policy, proven optimal or not (``Result.optimal``)
    UNSOLVABLE = "unsolvable"  # no policy exists
    TIMEOUT = "timeout"
    STATE_LIMIT = "state-limit"
    MEMORY_LIMIT = "memory-limit"
    DEPTH_LIMIT = "depth-limit"  # no policy within max_depth moves (not a proof there is none)
    # the search over canonical states met a decision taken by name or index order: the
    # planner solves again without symmetry (never the status of a result)
    SYMMETRY_UNSAFE = "symmetry-unsafe"


LIMITS = (SolveStatus.TIMEOUT, SolveStatus.STATE_LIMIT, SolveStatus.MEMORY_LIMIT,
          SolveStatus.DEPTH_LIMIT)
"""The statuses of a solve a limit stopped."""
TIMEOUT, MEMORY = SolveStatus.TIMEOUT, SolveStatus.MEMORY_LIMIT


def format_size(n: int) -> str:
    """Bytes for people: ``1.5 GB``, ``300 MB``."""
    if n >= 1 << 30:
        return f"{n / (1 << 30):.1f} GB"
    return f"{n / (1 << 20):.0f} MB"


def resident_bytes() -> int:
    """This process's resident set size now (Linux), else its peak so far."""
    try:
        with open("/proc/self/statm", "rb") as f:
            return int(f.read().split()[1]) * _PAGE
    except (OSError, IndexError, ValueError):
        import resource

        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return peak if sys.platform == "darwin" else peak * 1024  # bytes there, else kB


def _page_size() -> int:
    try:
        return os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 4096


_PAGE = _page_size()


class LimitReached(Exception):
    """A limit stopped the work. ``status`` is ``"timeout"`` or ``"memory-limit"``;
    ``reason`` says which limit, in words."""

    def __init__(self, status: SolveStatus, reason: str) -> None:
        super().__init__(reason)
        self.status, self.reason = status, reason


class Budget:
    """The time and memory a solve may use, from ``start`` (default: now).

    ``on_poll`` is called at every poll (about 20 times a second) while work goes on, e.g. to
    refresh a progress line; ``phase`` names the work under way for it."""

    def __init__(self, timeout: float | None = None, max_memory: int | None = None, *,
                 start: float | None = None,
                 on_poll: Callable[[Budget], None] | None = None) -> None:
        self.start = time.perf_counter() if start is None else start
        self.timeout, self.max_memory = timeout, max_memory
        self.hard = (None if timeout is None
                     else self.start + timeout * (1 + GRACE_FRACTION) + GRACE_S)
        self.on_poll = on_poll
        self._phase = "search"
        self.rss = 0  # resident bytes at the last poll
        self._next = 0.0  # the next poll time

    @property
    def phase(self) -> str:
        """The work under way (for messages and progress); setting it makes the next check
        a poll, so every phase looks at the limits as it starts."""
        return self._phase

    @phase.setter
    def phase(self, name: str) -> None:
        self._phase = name
        self._next = 0.0

    def elapsed(self) -> float:
        return time.perf_counter() - self.start

    def check(self) -> None:
        """Raise :class:`LimitReached` past the hard deadline or above ``max_memory``; cheap
        between polls."""
        now = time.perf_counter()
        if now < self._next:
            return
        self._poll(now)

    def _poll(self, now: float) -> None:
        self._next = now + POLL_S
        if self.hard is not None and now > self.hard:
            raise self.timeout_reached()
        if self.max_memory is not None:
            self.rss = resident_bytes()
            if self.rss > self.max_memory:
                raise self.memory_reached()
        if self.on_poll is not None:
            self.on_poll(self)

    def search_should_stop(self, states: int, solved: bool) -> LimitReached | None:
        """At a poll, whether the search must stop now so that what follows it (values and
        extraction for ``states`` states, when the root is ``solved``) still fits; also raises
        past the hard limits like :meth:`check`. Cheap between polls."""
        now = time.perf_counter()
        if now < self._next:
            return None
        self._poll(now)
        if self.timeout is not None:
            reserve = min(states * POST_S_PER_STATE, 0.5 * self.timeout) if solved else 0.0
            if now - self.start + reserve > self.timeout:
                return self.timeout_reached()
        if self.max_memory is not None:
            need = states * POST_BYTES_PER_STATE if solved else 0
            if self.rss + need > self.max_memory * MEMORY_HEADROOM:
                return self.memory_reached()
        return None

    def timeout_reached(self) -> LimitReached:
        assert self.timeout is not None
        return LimitReached(TIMEOUT, f"time limit of {self.timeout:g} s reached after "
                                     f"{self.elapsed():.1f} s, during {self.phase}")

    def memory_reached(self) -> LimitReached:
        assert self.max_memory is not None
        return LimitReached(MEMORY, f"memory limit of {format_size(self.max_memory)} reached "
                                    f"(resident {format_size(self.rss)}, and what follows "
                                    f"needs more), during {self.phase}"
                            if self.rss <= self.max_memory else
                            f"memory limit of {format_size(self.max_memory)} reached "
                            f"(resident {format_size(self.rss)}), during {self.phase}")

    def out_of_memory(self) -> LimitReached:
        """A :class:`MemoryError` caught: the system refused memory before the limit."""
        what = (f"memory limit of {format_size(self.max_memory)}"
                if self.max_memory is not None else "memory")
        return LimitReached(MEMORY, f"{what} exhausted (out of memory during {self.phase})")


def start_budget(limits: Limits, stats: Stats, *, timeout: float | None = None,
                 max_memory: int | None = None, budget: Budget | None = None,
                 progress: Progress | None = None) -> Budget:
    """Return the budget a solve, or a search run on its own, works under -- the one place
    limits and progress are set up: ``budget`` when the caller shares one, else a new one of
    ``timeout`` seconds and ``max_memory`` bytes (each defaulting to ``limits``, the problem's
    ``[limits]``). With ``progress``, a budget without a poll hook gets one that brings
    ``stats`` up to date (time and phase) and calls ``progress(stats, stats.frontier)``."""
    if budget is None:
        budget = Budget(limits.timeout if timeout is None else timeout,
                        limits.max_memory if max_memory is None else max_memory)
    if progress is not None and budget.on_poll is None:
        report = progress

        def poll(b: Budget) -> None:
            stats.time_s, stats.phase = b.elapsed(), b.phase
            report(stats, stats.frontier)
        budget.on_poll = poll
    return budget


__all__ = ["LIMITS", "Budget", "LimitReached", "MEMORY", "SolveStatus", "TIMEOUT",
           "format_size", "parse_size", "resident_bytes", "start_budget"]
