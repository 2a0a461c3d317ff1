"""``ehatp sweep`` stopped from outside: SIGTERM is Ctrl-C (stop, whole rows, exit 130), and
no worker outlives the sweep, even one SIGKILLed; ``--resume`` then completes it
(docs/sweep.md, "Stopping a sweep").

The sweeps run in a session of their own, so that "no process left" means no live process of
that process group (the test's own processes are in another). Linux only: processes are read
from /proc.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from ehatp.experiments import pools, sweep
from ehatp.experiments.examples import examples_dir

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(),
                                reason="reads processes from /proc (Linux)")

# a domain that sleeps in the workers for instances n > 2, as long as the environment says
# (the environment is not part of an instance's key, so a resume with no delay finds the
# same keys); the grid's own check runs in the driver and never sleeps
SLOW = """\
import multiprocessing
import os
import time

import ehatp
from ehatp.domains.cubes import make_domain


@ehatp.domain_factory
def make(n: int = 0, **options):
    if n > 2 and multiprocessing.parent_process() is not None:
        time.sleep(float(os.environ.get("EHATP_TEST_DELAY", "0")))
    return make_domain(**options)
"""
N = 6  # instances: 2 quick ones, then 4 that sleep


@pytest.fixture
def slow_sweep(tmp_path: Path) -> Path:
    """A folder with p1.toml on the sleeping domain and a grid of N values of n."""
    d = tmp_path / "slow"
    d.mkdir()
    (d / "slow.py").write_text(SLOW, encoding="utf-8")
    text = (examples_dir() / "cubes" / "p1.toml").read_text(encoding="utf-8")
    (d / "p1.toml").write_text(text.replace('name = "cubes"', 'name = "slow.py:make"'),
                               encoding="utf-8")
    (d / "grid.toml").write_text(f"domain.n = {list(range(1, N + 1))}\n", encoding="utf-8")
    return d


def ehatp_cmd() -> list[str]:
    script = Path(sys.executable).with_name("ehatp")
    return [str(script)] if script.exists() else [sys.executable, "-m", "ehatp.cli"]


def start_sweep(folder: Path, *extra: str, delay: float) -> subprocess.Popen[str]:
    """``ehatp sweep p1.toml --grid grid.toml --workers 2`` in a session of its own, once its
    first row is written."""
    out = folder / "rows.jsonl"
    proc = subprocess.Popen(
        [*ehatp_cmd(), "sweep", "p1.toml", "--grid", "grid.toml", "--workers", "2", "--out",
         out.name, *extra], cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, start_new_session=True, env={**os.environ, "EHATP_TEST_DELAY": str(delay)})
    until(lambda: out.exists() and out.read_bytes().count(b"\n") >= 1, 90,
          "the sweep wrote no row")
    return proc


def until(ok: Callable[[], bool], seconds: float, what: str) -> None:
    end = time.monotonic() + seconds
    while not ok():
        assert time.monotonic() < end, what
        time.sleep(0.1)


def stat(pid: int) -> list[str] | None:
    """The fields of /proc/PID/stat after the command name (state first), None if gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text(encoding="ascii", errors="replace")
    except OSError:
        return None
    return text.rpartition(")")[2].split()


def alive(pid: int) -> bool:
    fields = stat(pid)
    return fields is not None and fields[0] not in ("Z", "X")  # a zombie has ended


def group(pgid: int) -> list[int]:
    """The live processes of process group ``pgid``."""
    pids = [int(p.name) for p in Path("/proc").iterdir() if p.name.isdigit()]
    return [p for p in pids if (f := stat(p)) is not None and f[2] == str(pgid) and alive(p)]


def rows_in(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]


def resume(folder: Path) -> list[dict[str, Any]]:
    """Resume the sweep (no delay now); return its rows file's rows."""
    done = subprocess.run([*ehatp_cmd(), "sweep", "p1.toml", "--grid", "grid.toml", "--workers",
                           "2", "--out", "rows.jsonl", "--resume"], cwd=folder, text=True,
                          capture_output=True, timeout=120,
                          env={**os.environ, "EHATP_TEST_DELAY": "0"})
    assert done.returncode == 0, done.stderr
    return rows_in(folder / "rows.jsonl")


def expected_keys(folder: Path) -> set[str]:
    tasks = sweep.make_tasks([folder / "p1.toml"], sweep.read_grid(folder / "grid.toml"),
                             sweep.Settings())
    return {t.key for t in tasks}


@pytest.mark.slow
def test_sigterm_stops_a_sweep_like_ctrl_c_and_leaves_no_process(slow_sweep: Path) -> None:
    proc = start_sweep(slow_sweep, delay=120)
    time.sleep(0.5)  # the workers are in the sleeping instances now
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=20)
    assert proc.returncode == 130, err
    assert time.monotonic() - t0 < 10  # not the 120 s the running instances would take
    assert "interrupted:" in err and "--resume" in err
    until(lambda: not group(proc.pid), 5, f"processes left: {group(proc.pid)}")
    data = (slow_sweep / "rows.jsonl").read_bytes()
    assert data.endswith(b"\n")  # whole rows only
    before = rows_in(slow_sweep / "rows.jsonl")
    assert 1 <= len(before) < N
    after = resume(slow_sweep)
    assert after[:len(before)] == before
    assert len(after) == N and {r["key"] for r in after} == expected_keys(slow_sweep)
    assert {r["status"] for r in after} == {"solved"}


@pytest.mark.slow
def test_sigkill_of_the_sweep_ends_its_workers_and_resume_completes(slow_sweep: Path) -> None:
    proc = start_sweep(slow_sweep, delay=120)
    time.sleep(0.5)
    workers = [p for p in group(proc.pid) if p != proc.pid]
    assert workers  # the fork server and the workers at least
    proc.kill()
    proc.communicate(timeout=20)
    until(lambda: not group(proc.pid), 5, f"processes left: {group(proc.pid)}")
    before = rows_in(slow_sweep / "rows.jsonl")
    after = resume(slow_sweep)
    assert after[:len(before)] == before
    assert len(after) == N and {r["key"] for r in after} == expected_keys(slow_sweep)


DRIVER = """\
import concurrent.futures as cf, multiprocessing, re, sys, time
from ehatp.experiments.sweep_worker import end_with_driver

if __name__ == "__main__":
    ctx = multiprocessing.get_context(sys.argv[1])
    ex = cf.ProcessPoolExecutor(1, mp_context=ctx, initializer=end_with_driver)
    print(ex.submit(__import__("os").getpid).result(), flush=True)
    if sys.argv[2] == "gil":  # catastrophic backtracking: never releases the GIL
        ex.submit(re.match, r"(a+)+$", "a" * 60 + "b")
    else:
        ex.submit(time.sleep, 120)
    time.sleep(120)
"""


@pytest.mark.parametrize(("method", "work"), [
    ("forkserver", "sleep"), ("spawn", "sleep"),
    # only the kernel can end a worker that holds the GIL (PR_SET_PDEATHSIG)
    pytest.param("forkserver", "gil", marks=pytest.mark.skipif(
        not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")),
])
def test_a_worker_ends_when_its_driver_is_killed(tmp_path: Path, method: str,
                                                work: str) -> None:
    script = tmp_path / "driver.py"
    script.write_text(DRIVER, encoding="utf-8")
    proc = subprocess.Popen([sys.executable, str(script), method, work], text=True,
                            stdout=subprocess.PIPE, start_new_session=True)
    try:
        assert proc.stdout is not None
        worker = int(proc.stdout.readline())
        time.sleep(0.3)  # the worker is busy now
        assert alive(worker)
    finally:
        proc.kill()
        proc.wait(timeout=20)
    until(lambda: not alive(worker), 5, f"worker {worker} outlived its driver")
    until(lambda: not group(proc.pid), 5, f"processes left: {group(proc.pid)}")


def test_sigterm_raises_keyboard_interrupt_inside_the_block_only() -> None:
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt), pools.sigterm_as_interrupt():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler interrupts this
    assert signal.getsignal(signal.SIGTERM) == before


def test_an_interrupted_run_emits_the_rows_already_finished_and_aborts_the_pool() -> None:
    class Pool:
        name, slots, aborted = "fake", 2, False

        def submit(self, task: sweep.Task) -> cf.Future[sweep.Row]:
            fut: cf.Future[sweep.Row] = cf.Future()
            fut.set_result({"key": task.key})
            return fut

        def failure(self, task: sweep.Task, exc: BaseException) -> sweep.Row:
            raise AssertionError(exc)

        def restart(self) -> None: ...

        def abort(self) -> None:
            self.aborted = True

        def close(self) -> None: ...

    pool, rows = Pool(), []

    def emit(row: sweep.Row) -> None:
        rows.append(row)
        if len(rows) == 1:
            raise KeyboardInterrupt  # Ctrl-C just after the first row

    tasks = [sweep.Task(key=k, instance="p.toml", path="/p.toml", text="") for k in "abc"]
    with pytest.raises(KeyboardInterrupt):
        pools.run_tasks(tasks, pool, emit)
    assert sorted(r["key"] for r in rows) == ["a", "b"]  # both had finished; c never ran
    assert pool.aborted
