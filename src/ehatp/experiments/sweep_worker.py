"""What one worker of ``ehatp sweep`` does with one instance: load, solve, validate, write the
policy, and return the row (a plain dict), whatever happens (docs/sweep.md).

This module is what the workers import (a local process, a Dask worker or a Ray worker): it
loads the planner and the validator but none of the command line. :func:`run_instance` never
raises for a problem of the instance: a bad file, a domain that fails, going over the
``--memory`` budget, running far past the time limit or an internal error each become a row
with ``status = "error"``. Isolation (see :class:`Watchdog` and :func:`memory_limit`):

* time: ``solve`` keeps its own time limit (``--timeout``) for all its work; if the instance is
  still running well after it (a domain that hangs while loading, native code), its watchdog
  leaves a note and ends the worker process; the executor's retry of the task then returns
  an error row at once;
* memory: ``solve``'s progress callback watches resident memory and stops the instance at
  the budget; in a process of its own (the local pool) the address space is also limited with
  ``RLIMIT_AS``, well above the budget, as a backstop, and restored after (a Dask or Ray
  worker, whose other threads must keep working, has the watch only);
* the driver's end: a local worker process ends by itself when the ``ehatp sweep`` process
  that started it ends, however it ends (:func:`end_with_driver`).
"""

from __future__ import annotations

import contextlib
import ctypes
import gc
import json
import multiprocessing
import multiprocessing.connection
import os
import signal
import socket
import sys
import threading
import time
import traceback
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from .. import __version__
from ..check.validator import validate
from ..errors import EhatpError, InputError
from ..formats.policy import num
from ..formats.problem_toml import loads
from ..search.limits import SolveStatus
from ..search.planner import solve

# Every row has these keys, in this order (None where they do not apply).
ROW_KEYS = ("key", "instance", "overrides", "problem", "status", "optimal", "cost", "worst_case",
            "expected", "communications", "leaves", "stats", "valid", "validation", "policy",
            "reason", "error", "error_kind", "time_s", "search_ms", "version")
Row = dict[str, Any]
"""A result row: one instance's outcome, its keys in :data:`ROW_KEYS` order."""
# statistics that describe the policy go to their own columns, times to time_s / search_ms
_POLICY_STATS = ("cost", "worst_case", "expected", "communications", "leaves")
_TIME_STATS = ("time_ms",)
KILLED_EXIT = 86  # the exit code of a worker its watchdog ended
ORPHAN_EXIT = 87  # the exit code of a local worker that outlived the sweep that started it
PR_SET_PDEATHSIG = 1  # linux/prctl.h
GB = 1 << 30


@dataclass(frozen=True)
class Task:
    """One instance, with everything a worker needs and nothing it has to look up: the problem
    text travels with the task; only a domain ``file.py`` beside the problem is read by the
    worker (from ``path``, so workers need the driver's filesystem for those)."""

    key: str  # sha256 of the problem text, overrides, domain file and ehatp version
    instance: str  # the path as the user gave it (rows show it)
    path: str  # absolute: where a domain file.py is looked for, and what errors name
    text: str
    overrides: Mapping[str, Any] = field(default_factory=dict)
    timeout: float | None = None  # seconds, passed to solve (None: the problem's limit)
    memory_gb: float | None = None  # memory the instance may add, in GiB
    memory_mode: str = "rlimit"  # "rlimit" (a process of its own) | "watch" (shared process)
    kill_after: float | None = None  # seconds; None: :func:`kill_after` of the time limit
    validate: bool = False
    policies: str | None = None  # folder for the policy files
    compress: bool = False  # write them gzip-compressed (KEY.json.gz)
    marks: str | None = None  # folder where a watchdog leaves a note before ending its worker
    driver_pid: int = 0  # never end this process (a worker thread inside the driver)
    driver_host: str = ""


def kill_after(timeout: float | None) -> float | None:
    """Seconds after which a still-running instance's worker process is ended: the time limit
    plus a quarter of it, at least 10 s more (``solve`` itself stops within 5 % and half a
    second of its limit; this is for what runs outside it, or does not return to Python)."""
    return None if timeout is None else timeout + max(10.0, timeout / 4)


class OverBudget(BaseException):
    """Raised by ``solve``'s progress callback over a watched ``--memory`` budget. A
    BaseException, so that nothing on the way turns it into something else."""


def empty_row(task: Task) -> dict[str, Any]:
    row: dict[str, Any] = dict.fromkeys(ROW_KEYS)
    row.update(key=task.key, instance=task.instance, overrides=dict(task.overrides),
               version=__version__)
    return row


def error_row(task: Task, kind: str, message: str, **extra: Any) -> dict[str, Any]:
    """A row for an instance that did not run to a result."""
    row = empty_row(task)
    row.update(status="error", error_kind=kind, error=" ".join(message.split()), **extra)
    return row


def mark_path(task: Task) -> Path | None:
    return None if task.marks is None else Path(task.marks) / f"{task.key}.killed"


def run_instance(task: Task) -> dict[str, Any]:
    """Load, solve (and validate) one instance; the row, never an exception for anything the
    instance does."""
    mark = mark_path(task)
    if mark is not None and mark.exists():  # its watchdog ended the previous attempt
        return error_row(task, "killed", mark.read_text(encoding="utf-8"))
    row = empty_row(task)
    t0 = time.perf_counter()
    budget = (f"the --memory budget of {task.memory_gb:g} GB" if task.memory_gb is not None
              else "the memory available")
    watchdog = Watchdog(task)
    try:
        with watchdog, memory_limit(task.memory_gb if task.memory_mode == "rlimit" else None):
            _solve_into(row, task, watchdog)
    except OverBudget:
        row.update(status="error", error_kind="memory",
                   error=f"out of memory: the instance needed more than {budget}")
    except EhatpError as e:
        msg = e.line() if isinstance(e, InputError) else f"{task.instance}: {e}"
        msg = msg.replace(task.path, task.instance)  # name the file as the user did
        row.update(status="error", error_kind="input", error=" ".join(msg.split()))
    except MemoryError:
        row.update(status="error", error_kind="memory",
                   error=f"out of memory: the instance needed more than {budget}")
    except RecursionError as e:
        row.update(status="error", error_kind="exception", error=f"RecursionError: {e}")
    except Exception as e:  # a bug in ehatp or in a domain module: the row says which
        what = " ".join((f"{type(e).__name__}: {e}" if str(e) else type(e).__name__).split())
        row.update(status="error", error_kind="exception", error=f"internal error: {what}",
                   traceback="".join(traceback.format_exception(e)))
    row["time_s"] = round(time.perf_counter() - t0, 3)
    if row["error_kind"] == "memory":
        gc.collect()  # what the failed search left behind, before the next instance
    return row


def _solve_into(row: dict[str, Any], task: Task, watchdog: Watchdog) -> None:
    if task.kill_after is not None or task.timeout is not None:  # a domain may hang too
        watchdog.arm(task.kill_after if task.kill_after is not None
                     else kill_after(task.timeout))
    prob = loads(task.text, task.path, task.overrides)
    row["problem"] = prob.name
    if task.kill_after is None and task.timeout is None:
        watchdog.arm(kill_after(prob.limits.timeout))
    # the budget is watched in every mode: a kernel limit reached inside CPython's exception
    # handling can leave the process spinning (CPython 3.11), so RLIMIT_AS is only a backstop
    watch = MemoryWatch(task.memory_gb) if task.memory_gb is not None else None
    with watch or contextlib.nullcontext():
        result = solve(prob, timeout=task.timeout, progress=watch)
    stats = {k: _plain(v) for k, v in result.stats.items()
             if k not in _POLICY_STATS and k not in _TIME_STATS}
    pol = result.policy
    if pol is not None:
        if task.validate:
            report = validate(prob, pol)
            row.update(valid=report.ok, validation=None if report.ok else report.message)
        if task.policies is not None:
            target = Path(task.policies) / f"{task.key}.json{'.gz' if task.compress else ''}"
            pol.write(target)  # whole or absent, even if two runs write it
            row["policy"] = str(target)
        row.update(cost=num(pol.cost), communications=pol.communications, leaves=pol.leaves,
                   worst_case=None if pol.worst_case is None else num(pol.worst_case),
                   expected=None if pol.expected is None else num(pol.expected))
    row.update(optimal=result.optimal, reason=result.reason, stats=stats,
               search_ms=result.stats.get("time_ms"), status=result.status)
    if result.status == SolveStatus.MEMORY_LIMIT and task.memory_gb is not None:
        # solve stopped cleanly on a MemoryError under --memory: an error row all the same,
        # with what solve could say
        row.update(status="error", error_kind="memory", error="out of memory: the instance "
                   f"needed more than the --memory budget of {task.memory_gb:g} GB")


def _plain(v: Any) -> Any:
    """A statistic as JSON has it (a Fraction as a number)."""
    if isinstance(v, Fraction | int | float):
        return num(v)
    try:
        json.dumps(v)
    except (TypeError, ValueError):
        return str(v)
    return v


# --- isolation -------------------------------------------------------------------------------


class Watchdog:
    """Ends the worker process if the instance is still running ``seconds`` (given to
    :meth:`arm`) after it started, first leaving a note (``<marks>/<key>.killed``) so that the
    executor's retry of the task returns an error row at once. Never ends the driver's own
    process (a Dask worker thread inside it, Ray's local mode). Its thread starts on entry,
    before any memory limit, and sleeps until armed and then until the deadline."""

    def __init__(self, task: Task) -> None:
        self.task = task
        self.cond = threading.Condition()
        self.deadline: float | None = None
        self.done = False
        self.thread: threading.Thread | None = None
        self.started = time.monotonic()

    def __enter__(self) -> Watchdog:
        inside_driver = (os.getpid() == self.task.driver_pid
                         and socket.gethostname() == self.task.driver_host)
        if not inside_driver:
            self.thread = threading.Thread(target=self._watch, daemon=True,
                                           name=f"ehatp-sweep-watchdog-{self.task.key[:8]}")
            self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        with self.cond:
            self.done = True
            self.cond.notify()
        if self.thread is not None:
            self.thread.join()

    def arm(self, seconds: float | None) -> None:
        """End the process ``seconds`` after the start (None: never)."""
        with self.cond:
            self.deadline = None if seconds is None else self.started + seconds
            self.cond.notify()

    def _watch(self) -> None:
        with self.cond:
            while not self.done:
                if self.deadline is None:
                    self.cond.wait()
                    continue
                left = self.deadline - time.monotonic()
                if left <= 0:
                    self._end(self.deadline - self.started)
                self.cond.wait(left)

    def _end(self, seconds: float) -> None:
        mark = mark_path(self.task)
        limit = "" if self.task.timeout is None else f" (--timeout {self.task.timeout:g} s)"
        if mark is not None:
            # no shared folder: the executor reports a lost worker instead
            with contextlib.suppress(OSError):
                mark.write_text(f"still running {seconds:g} s after it started{limit}: its "
                                "worker process was ended", encoding="utf-8")
        os._exit(KILLED_EXIT)


class MemoryWatch:
    """``solve``'s progress callback (about 20 calls a second, in every phase) where instances
    share their process: raises :class:`OverBudget` once the process's resident memory has
    grown by more than the budgets of the instances running in it, since the first of them
    started."""

    def __init__(self, gb: float) -> None:
        self.budget = int(gb * GB)

    def __enter__(self) -> MemoryWatch:
        _watched(+1)
        return self

    def __exit__(self, *exc: object) -> None:
        _watched(-1)

    def __call__(self, stats: Any, frontier: int) -> None:
        if resident() > _watch_base + max(_watching, 1) * self.budget:
            raise OverBudget


def resident() -> int:
    """This process's resident memory in bytes (Linux: /proc/self/statm), 0 if unknown."""
    return _statm(1)


def _statm(field_no: int) -> int:
    try:
        with open("/proc/self/statm", encoding="ascii") as f:
            return int(f.read().split()[field_no]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


_WATCH_LOCK = threading.Lock()
_watching = 0  # watched instances running in this process
_watch_base = 0


def _watched(delta: int) -> None:
    global _watching, _watch_base
    with _WATCH_LOCK:
        if _watching == 0:
            _release_free_heap()
            _watch_base = resident()
        _watching += delta


def _release_free_heap() -> None:
    """Give the heap the process no longer uses back to the system (glibc's ``malloc_trim``),
    so that the watch's base is what the process really holds: an instance reusing freed heap
    would otherwise grow past its budget without the resident memory showing it."""
    gc.collect()
    with contextlib.suppress(OSError, AttributeError):  # not glibc: the base is less exact
        ctypes.CDLL(None).malloc_trim(0)


_LOCK = threading.Lock()
_active = 0  # instances inside memory_limit in this process
_saved: tuple[int, int] | None = None
_base = 0


def address_space() -> int:
    """This process's address space in bytes (Linux: /proc/self/statm), 0 if unknown."""
    return _statm(0)


BACKSTOP = (4.0, 0.5)
"""The address-space backstop of a ``--memory GB`` budget in a process of its own: ``4 * GB +
0.5`` GiB. :class:`MemoryWatch` stops the instance at GB of resident memory first; the kernel
limit only catches what grows outside ``solve`` or between two looks."""


@contextmanager
def memory_limit(gb: float | None) -> Iterator[None]:
    """Let the address space grow by at most the backstop of ``gb`` GiB (:data:`BACKSTOP`) per
    running instance (RLIMIT_AS over what the process had when the first instance started),
    restored when the last one ends. Instances running as threads of one process share one
    limit (their budgets add up)."""
    if gb is None:
        yield
        return
    import resource

    global _active, _saved, _base
    with _LOCK:
        if _active == 0:
            _saved = resource.getrlimit(resource.RLIMIT_AS)
            _base = address_space()
        _active += 1
        soft, hard = _saved or (resource.RLIM_INFINITY, resource.RLIM_INFINITY)
        factor, extra = BACKSTOP
        want = _base + int(_active * (factor * gb + extra) * GB)
        for cap in (soft, hard):  # never above a limit the process already had
            if cap != resource.RLIM_INFINITY:
                want = min(want, cap)
        resource.setrlimit(resource.RLIMIT_AS, (want, hard))
    try:
        yield
    finally:
        with _LOCK:
            _active -= 1
            if _active == 0 and _saved is not None:
                resource.setrlimit(resource.RLIMIT_AS, _saved)


# --- the driver's end ------------------------------------------------------------------------


def end_with_driver() -> None:
    """Make this worker process end as soon as the process that started it (the ``ehatp sweep``
    driver) ends, even by SIGKILL: the initializer of the local pool's workers.

    A thread waits on the driver's sentinel (a pipe that only the driver holds open, which
    multiprocessing gives every child, forkserver or spawn, on every platform) and ends the
    process when it closes. A worker stuck in native code holding the GIL never lets that
    thread run, so on Linux the kernel is asked as well: ``PR_SET_PDEATHSIG`` sends SIGKILL
    when the worker's parent ends. Under forkserver that parent is the fork server, which
    stays up as long as any process holds its "alive" pipe, and every child inherits one; the
    worker closes its copy, so that the fork server ends with the driver, and the kernel then
    ends the worker."""
    parent = multiprocessing.parent_process()
    if parent is None:  # not a multiprocessing child: nothing to watch
        return
    if parent.pid != os.getppid():  # forked by the fork server
        _release_fork_server()
        _kill_with_parent()
    threading.Thread(target=_wait_for_driver, args=(parent.sentinel,), daemon=True,
                     name="ehatp-sweep-driver-watch").start()


def _wait_for_driver(sentinel: int) -> None:
    """Return never: end the process once ``sentinel`` says the driver has ended."""
    multiprocessing.connection.wait([sentinel])
    os._exit(ORPHAN_EXIT)


def _release_fork_server() -> None:
    """Close this process's copy of the fork server's "alive" pipe (multiprocessing hands one
    to every child it forks), so that the fork server ends when the driver does."""
    from multiprocessing import forkserver

    server = getattr(forkserver, "_forkserver", None)  # private: absent in another Python
    fd = getattr(server, "_forkserver_alive_fd", None)
    if isinstance(fd, int):
        with contextlib.suppress(OSError):
            os.close(fd)
        server._forkserver_alive_fd = None  # type: ignore[union-attr]


def _kill_with_parent() -> None:
    """Ask Linux to send this process SIGKILL when its parent ends (``prctl``); elsewhere, or
    without a C library, nothing (the driver watch alone acts)."""
    if not sys.platform.startswith("linux"):
        return
    ppid = os.getppid()
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    if os.getppid() != ppid:  # the parent ended before the request: nobody will signal
        os._exit(ORPHAN_EXIT)
