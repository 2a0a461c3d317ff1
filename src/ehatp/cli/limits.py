"""The backstop behind a long command's ``--timeout`` and ``--max-memory``.

Each long command (``solve``, ``validate``) works under a :class:`~ehatp.search.limits.Budget`
that its enumerations check, and stops itself with a one-line reason. :func:`guarded` is what
holds when that check is not reached in time (native code, a single enumeration the work cannot
interrupt): a watchdog thread that watches the clock and the resident memory, and a kernel CPU
limit (``RLIMIT_CPU``) in case the interpreter itself is stuck. Either ends the process with
the command's limit exit code and one line saying which limit. Resident memory is watched
rather than capped with ``RLIMIT_AS``: under an address-space cap CPython 3.11 can spin in its
exception handling instead of stopping.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any


class Standalone:
    """The mark :func:`~ehatp.cli.app.main` hands its commands (typer's ``ctx.obj``): this run
    is the ``ehatp`` process itself, so the backstop may end it. A command run in another
    program's process (a test's ``CliRunner``, a notebook) gets no such mark, and its limits
    are the budget's alone."""


STANDALONE = Standalone()

SLACK_FRACTION, SLACK_S = 0.10, 0.75
"""The backstop ends the process at ``limit * (1 + SLACK_FRACTION) + SLACK_S`` after the
command started it: past the budget's own hard limit (5 % + 0.2 s) by a step the work cannot
interrupt (parsing a few megabytes of JSON), so the command's own one-line stop comes first."""

WATCH_EVERY_S = 0.1  # how often the watchdog looks


class _Watchdog:
    """The thread of :func:`guarded`."""

    def __init__(self, what: str, timeout: float | None, max_memory: int | None,
                 exit_code: int) -> None:
        self.what, self.exit_code = what, exit_code
        self.start = time.monotonic()
        self.deadline = (None if timeout is None
                         else self.start + timeout * (1 + SLACK_FRACTION) + SLACK_S)
        self.timeout = timeout
        self.max_memory = max_memory
        self.memory_cap = (None if max_memory is None
                           else int(max_memory * (1 + SLACK_FRACTION)))
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._watch, daemon=True,
                                       name="ehatp-limits-watchdog")

    def _watch(self) -> None:
        from ..search.limits import format_size, resident_bytes

        while not self.stop.wait(WATCH_EVERY_S):
            if self.deadline is not None and time.monotonic() > self.deadline:
                assert self.timeout is not None
                self._end(f"time limit of {self.timeout:g} s reached after "
                          f"{time.monotonic() - self.start:.1f} s")
            if self.memory_cap is not None:
                rss = resident_bytes()
                if rss > self.memory_cap:
                    assert self.max_memory is not None
                    self._end(f"memory limit of {format_size(self.max_memory)} reached "
                              f"(resident {format_size(rss)})")

    def _end(self, reason: str) -> None:
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.write(f"{self.what}: stopped, {reason}, where the work could not stop "
                             "itself; raise the limit\n")
            sys.stderr.flush()
        os._exit(self.exit_code)


@contextlib.contextmanager
def guarded(process: Any, what: str, timeout: float | None, max_memory: int | None,
            exit_code: int) -> Iterator[None]:
    """Run the body under the backstop of ``timeout`` seconds and ``max_memory`` resident
    bytes (None: no such limit): past either, plus :data:`SLACK_FRACTION` and
    :data:`SLACK_S`, the process prints one line naming ``what`` and the limit and exits with
    ``exit_code``; a kernel CPU limit a little further on ends an interpreter too stuck for
    its own watchdog. Both are lifted when the body ends. Only when ``process`` is
    :data:`STANDALONE` (the command's ``ctx.obj``): a command run inside another program
    never ends that program."""
    if not isinstance(process, Standalone) or (timeout is None and max_memory is None):
        yield
        return
    dog = _Watchdog(what, timeout, max_memory, exit_code)
    old_cpu = _cpu_limit(timeout)
    dog.thread.start()
    try:
        yield
    finally:
        dog.stop.set()
        dog.thread.join()
        _restore_cpu_limit(old_cpu)


def _cpu_limit(timeout: float | None) -> tuple[int, int] | None:
    """Set the kernel's CPU-time limit a little past the watchdog's; return the old one."""
    if timeout is None:
        return None
    try:
        import resource
    except ImportError:  # not on this platform: the watchdog alone
        return None
    old = resource.getrlimit(resource.RLIMIT_CPU)
    used = sum(os.times()[:2])
    soft = int(used + timeout * (1 + 2 * SLACK_FRACTION) + 2 * SLACK_S) + 1
    hard = old[1]
    if hard != resource.RLIM_INFINITY and soft > hard:
        return None
    with contextlib.suppress(ValueError, OSError):
        resource.setrlimit(resource.RLIMIT_CPU, (soft, hard))
        return old
    return None


def _restore_cpu_limit(old: tuple[int, int] | None) -> None:
    if old is None:
        return
    import resource

    with contextlib.suppress(ValueError, OSError):
        resource.setrlimit(resource.RLIMIT_CPU, old)


__all__ = ["SLACK_FRACTION", "SLACK_S", "STANDALONE", "Standalone", "guarded"]
