"""Where a sweep's instances run (:mod:`ehatp.experiments.sweep`, ``ehatp sweep --executor``):
a local process pool, a Dask cluster or a Ray cluster, and the loop that runs the tasks on one,
emitting each row as it arrives, through lost workers and interruptions (docs/sweep.md).

Why not joblib: ``Parallel`` ends the whole run when one worker process dies, and cannot say
which task it was running. Every pool here hands out one ``concurrent.futures.Future`` per
task instead (a ``ProcessPoolExecutor``, Dask's ``Client.get_executor()``, Ray's
``ObjectRef.future()``), so a lost worker costs its own row only.
"""

from __future__ import annotations

import concurrent.futures as cf
import importlib
import logging
import multiprocessing
import os
import signal
import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager, suppress
from enum import StrEnum
from typing import Any, Protocol

from ..errors import InputError
from .sweep_worker import Row, Task, end_with_driver, error_row, run_instance


class ExecutorKind(StrEnum):
    local = "local"
    dask = "dask"
    ray = "ray"


# --- executors -------------------------------------------------------------------------------


class WorkerLost(Exception):
    """The pool lost a worker process: the tasks it was running must run again."""


class ExecutorFailed(Exception):
    """The executor itself failed (not an instance): the sweep stops, --resume goes on."""


class Pool(Protocol):
    """Where tasks run: one future per task, and what a failed future means."""

    name: str
    slots: int  # tasks kept in flight

    def submit(self, task: Task) -> cf.Future[Row]: ...

    def failure(self, task: Task, exc: BaseException) -> Row:
        """The row for a task whose future raised; :class:`WorkerLost` to run it again, or
        :class:`ExecutorFailed` to stop."""
        ...

    def restart(self) -> None: ...

    def abort(self) -> None:
        """Stop at once, the tasks running included (the sweep was interrupted); then
        :meth:`close` has nothing left to wait for."""
        ...

    def close(self) -> None: ...


def default_workers() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


class LocalPool:
    """Worker processes on this machine (``concurrent.futures.ProcessPoolExecutor``, started by
    forkserver where there is one, else spawn; never ``max_tasks_per_child``, which hangs on
    Python 3.11). A dead worker breaks the whole pool: :meth:`restart` makes a new one. Each
    worker ends by itself when this process ends (:func:`sweep_worker.end_with_driver`)."""

    name = "local"

    def __init__(self, workers: int) -> None:
        self.slots = workers
        methods = multiprocessing.get_all_start_methods()
        self.ctx = multiprocessing.get_context("forkserver" if "forkserver" in methods
                                               else "spawn")
        if "forkserver" in methods:
            self.ctx.set_forkserver_preload(["ehatp.experiments.sweep_worker"])
        self.ex = self._new()

    def _new(self) -> cf.ProcessPoolExecutor:
        return cf.ProcessPoolExecutor(max_workers=self.slots, mp_context=self.ctx,
                                      initializer=end_with_driver)

    def submit(self, task: Task) -> cf.Future[Row]:
        return self.ex.submit(run_instance, task)

    def failure(self, task: Task, exc: BaseException) -> Row:
        if isinstance(exc, BrokenProcessPool):
            raise WorkerLost from exc
        raise ExecutorFailed(f"{type(exc).__name__}: {exc}") from exc

    def restart(self) -> None:
        self.ex.shutdown(wait=True, cancel_futures=True)
        self.ex = self._new()

    def abort(self) -> None:
        """End the worker processes (SIGTERM, then SIGKILL after 2 s): ``shutdown`` alone
        would wait for the instances running (Python 3.11 has no ``terminate_workers``)."""
        procs = list((getattr(self.ex, "_processes", None) or {}).values())
        self.ex.shutdown(wait=False, cancel_futures=True)
        for p in procs:
            with suppress(OSError, ValueError):
                p.terminate()
        for p in procs:
            with suppress(OSError, ValueError, AssertionError):
                p.join(2)
                if p.is_alive():
                    p.kill()
                    p.join(2)

    def close(self) -> None:
        self.ex.shutdown(wait=True, cancel_futures=True)


class DaskPool:
    """A Dask cluster: the scheduler at ``address`` (any deployment, e.g. dask-jobqueue on
    Slurm), else a ``LocalCluster`` of ``workers`` single-threaded processes."""

    name = "dask"

    def __init__(self, workers: int, address: str | None) -> None:
        try:
            distributed = importlib.import_module("distributed")
        except ImportError:
            raise InputError("--executor dask", "", "needs Dask's distributed scheduler, which "
                             "is not installed", "pip install 'ehatp[dask]'") from None
        self.distributed = distributed
        self.cluster: Any = None
        logging.getLogger("distributed").setLevel(logging.ERROR)
        if address:
            try:
                self.client: Any = distributed.Client(address, timeout="10s")
            except (OSError, TimeoutError, ValueError) as e:
                raise InputError(f"--address {address}", "", f"no Dask scheduler answers there "
                                 f"({' '.join(str(e).split())})", "start one (dask scheduler, "
                                 "or a dask-jobqueue cluster) and give its address") from None
        else:
            self.cluster = distributed.LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True,
                dashboard_address=None, silence_logs=logging.ERROR)
            self.client = distributed.Client(self.cluster)
        self.executor = self.client.get_executor(pure=False)
        threads = sum(self.client.nthreads().values())
        self.slots = max(64, 4 * threads)

    def submit(self, task: Task) -> cf.Future[Row]:
        fut: cf.Future[Row] = self.executor.submit(run_instance, task)
        return fut

    def failure(self, task: Task, exc: BaseException) -> Row:
        if isinstance(exc, self.distributed.KilledWorker):
            return error_row(task, "crashed", "the Dask workers running it died (the system "
                             "may have ended them for lack of memory): "
                             f"{' '.join(str(exc).split())}")
        raise ExecutorFailed(f"{type(exc).__name__}: {exc}") from exc

    def restart(self) -> None:
        """Dask restarts lost workers itself."""

    def abort(self) -> None:
        """Cancel the tasks and stop the cluster started here (its worker processes go with
        it); a running task of a cluster at ``--address`` runs to its end (Dask cannot stop
        it), but its row is not waited for."""
        self.close()  # shutdown(wait=False) cancels the futures

    def close(self) -> None:
        if self.client.status == "closed":
            return
        self.executor.shutdown(wait=False)
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


class RayPool:
    """A Ray cluster: the one at ``address`` (``auto``, ``ray://host:10001``), else a local
    Ray started (and stopped) here with ``workers`` CPUs."""

    name = "ray"

    def __init__(self, workers: int, address: str | None) -> None:
        try:
            ray = importlib.import_module("ray")
        except ImportError:
            raise InputError("--executor ray", "", "needs Ray, which is not installed",
                             "pip install 'ehatp[ray]'") from None
        self.ray = ray
        self.owned = not ray.is_initialized()
        if self.owned:
            try:
                ray.init(address=address, num_cpus=None if address else workers,
                         include_dashboard=False, log_to_driver=False,
                         logging_level=logging.ERROR, configure_logging=True)
            except (ConnectionError, RuntimeError, ValueError) as e:
                raise InputError(f"--address {address}", "", f"cannot join a Ray cluster there "
                                 f"({' '.join(str(e).split())})",
                                 "start one (ray start --head) and give its address") from None
        self.remote = ray.remote(num_cpus=1, max_retries=1)(run_instance)
        self.running: dict[cf.Future[Row], Any] = {}  # the ObjectRef behind each future
        cpus = int(ray.cluster_resources().get("CPU", workers))
        self.slots = max(64, 4 * cpus)

    def submit(self, task: Task) -> cf.Future[Row]:
        ref = self.remote.remote(task)
        fut: cf.Future[Row] = ref.future()
        self.running[fut] = ref
        fut.add_done_callback(lambda f: self.running.pop(f, None))
        return fut

    def failure(self, task: Task, exc: BaseException) -> Row:
        errors = self.ray.exceptions
        if isinstance(exc, errors.WorkerCrashedError | errors.OutOfMemoryError
                      | errors.NodeDiedError):
            return error_row(task, "crashed", "the Ray worker running it died (the system may "
                             "have ended it for lack of memory): "
                             f"{type(exc).__name__}")
        raise ExecutorFailed(f"{type(exc).__name__}: {exc}") from exc

    def restart(self) -> None:
        """Ray restarts lost workers itself."""

    def abort(self) -> None:
        """Cancel the running tasks (their worker processes are ended) and stop the Ray
        started here."""
        for ref in list(self.running.values()):
            with suppress(Exception):  # a task that ended meanwhile, a lost connection
                self.ray.cancel(ref, force=True)
        self.close()

    def close(self) -> None:
        if self.owned and self.ray.is_initialized():
            self.ray.shutdown()


def open_pool(kind: ExecutorKind, workers: int, address: str | None) -> Pool:
    """The executor named on the command line (:class:`InputError` if it cannot start)."""
    if kind is ExecutorKind.local:
        if address:
            raise InputError("--address", "", "the local executor takes no address",
                             "use --executor dask or --executor ray with --address")
        return LocalPool(workers)
    if kind is ExecutorKind.dask:
        return DaskPool(workers, address)
    return RayPool(workers, address)


# --- running ---------------------------------------------------------------------------------


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM (what ``timeout``, Slurm's ``scancel`` and CI cancellation
    send) raises :class:`KeyboardInterrupt` as Ctrl-C does, so both stop a sweep the same
    way; outside the main thread (where no handler can be set) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    before = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, before)


def run_tasks(tasks: Iterable[Task], pool: Pool, emit: Callable[[Row], None]) -> None:
    """Run every task on ``pool`` and ``emit`` each row as it arrives. When the pool loses a
    worker, the tasks that were in flight run again one at a time; one that loses its worker
    even alone becomes a ``crashed`` error row (one ended by its watchdog returns its
    ``killed`` row at once). :class:`ExecutorFailed` stops the run.

    Ctrl-C or SIGTERM (:func:`sigterm_as_interrupt`) emits the rows already finished, stops
    the pool at once (:meth:`Pool.abort`) and raises :class:`KeyboardInterrupt`: every row
    emitted is whole, and the instances not emitted run on ``--resume``."""
    with sigterm_as_interrupt():
        try:
            _run_tasks(tasks, pool, emit)
        except KeyboardInterrupt:
            pool.abort()
            raise


def _run_tasks(tasks: Iterable[Task], pool: Pool, emit: Callable[[Row], None]) -> None:
    queue = deque(tasks)
    suspects: deque[Task] = deque()
    inflight: dict[cf.Future[Row], Task] = {}
    solo: Task | None = None  # a suspect running alone

    def settle(fut: cf.Future[Row], task: Task, lost: list[Task]) -> None:
        try:
            row = fut.result()
        except Exception as e:  # the pool says what it means
            try:
                row = pool.failure(task, e)
            except WorkerLost:
                lost.append(task)
                return
        emit(row)

    try:
        while queue or suspects or inflight:
            if suspects and not inflight:
                solo = suspects.popleft()
                inflight[pool.submit(solo)] = solo
            elif not suspects:
                solo = None
                while queue and len(inflight) < pool.slots:
                    t = queue.popleft()
                    inflight[pool.submit(t)] = t
            done, _ = cf.wait(inflight, return_when=cf.FIRST_COMPLETED)
            lost: list[Task] = []
            for fut in done:
                settle(fut, inflight.pop(fut), lost)
            if not lost:
                continue
            for fut, task in list(inflight.items()):  # a broken pool fails them all
                settle(fut, task, lost)
            inflight.clear()
            pool.restart()
            if solo is not None and lost == [solo]:
                emit(error_row(solo, "crashed", "its worker process died while it ran alone "
                               "(the system may have ended it for lack of memory, or native "
                               "code crashed)"))
            else:
                suspects.extend(lost)
            solo = None
    except KeyboardInterrupt:
        for fut in list(inflight):  # finished, not emitted yet
            if fut.done() and not fut.cancelled() and fut.exception() is None:
                emit(fut.result())
                del inflight[fut]
        raise
    finally:
        for fut in inflight:
            fut.cancel()
