"""``ehatp ... | head``: a reader that goes away early ends the run quietly with exit code 141,
never 1 ("no policy") and never a traceback, whatever the command."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from ehatp.cli.common import EXIT_BROKEN_PIPE
from ehatp.experiments.examples import examples_dir

CUBES = examples_dir() / "cubes"


def command(*args: str | Path) -> list[str]:
    """Return the real console script's command line (``python -m ehatp.cli`` without one)."""
    script = Path(sys.executable).with_name("ehatp")
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "ehatp.cli"]
    return [*cmd, *map(str, args)]


def closed_early(*args: str | Path, read: int = 0) -> tuple[int, str]:
    """Run ``ehatp ARGS`` with stdout a real pipe whose reader reads ``read`` bytes and then
    closes it; return the exit code and what was written on stderr."""
    proc = subprocess.Popen(command(*args), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    if read:
        os.read(proc.stdout.fileno(), read)  # one read, not a buffered read-ahead
    proc.stdout.close()
    err = proc.stderr.read().decode()
    return proc.wait(timeout=120), err


@pytest.fixture(scope="module")
def p6_policy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("pipes") / "p6.json"
    done = subprocess.run(command("solve", CUBES / "p6.toml", "--out", out),
                          capture_output=True, timeout=120)
    assert done.returncode == 0
    return out


def test_the_exit_code_of_a_closed_pipe_is_141_as_a_shell_reports_sigpipe() -> None:
    assert EXIT_BROKEN_PIPE == 141


def test_solve_into_a_pipe_closed_at_once_exits_141_and_says_nothing() -> None:
    assert closed_early("solve", CUBES / "p2.toml") == (141, "")


def test_show_into_a_pipe_closed_at_once_exits_141_and_says_nothing(p6_policy: Path) -> None:
    assert closed_early("show", p6_policy) == (141, "")


def test_an_html_bigger_than_the_pipe_closed_after_a_line_exits_141(p6_policy: Path) -> None:
    # 75 kB: more than a pipe holds, so the write is still under way when the reader leaves
    assert closed_early("render", p6_policy, "--format", "html", read=100) == (141, "")


def test_bench_table1_into_a_pipe_closed_at_once_exits_141_and_says_nothing() -> None:
    assert closed_early("bench", "table1", "--repeat", "1", "--only", "P1") == (141, "")


def test_help_into_a_closed_pipe_exits_141_and_says_nothing() -> None:
    # typer prints the help with rich, which handles the broken pipe itself (exit 1)
    assert closed_early("--help") == (141, "")


def test_a_solve_that_finds_no_policy_still_exits_1_into_the_null_device(
        tmp_path: Path) -> None:
    # the null device is where a closed pipe's output is sent: an exit 1 there stays 1
    bad = tmp_path / "two-boxes.toml"  # a cube cannot be in two boxes at once
    bad.write_text('goal = ["in(r, box1)", "in(r, box2)"]\n'
                   + (CUBES / "p1.toml").read_text(encoding="utf-8"), encoding="utf-8")
    done = subprocess.run(command("solve", bad), stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, timeout=120)
    assert done.returncode == 1


def test_the_whole_output_through_an_open_pipe_still_exits_0(p6_policy: Path) -> None:
    done = subprocess.run(command("show", p6_policy), capture_output=True, timeout=120)
    assert done.returncode == 0
    assert done.stdout.startswith(b"Policy for P6")
