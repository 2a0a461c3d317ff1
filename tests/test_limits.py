"""Limits that hold (docs/semantics.md §7, "Search"): a time or memory limit stops the whole
solve cleanly, whatever phase is under way, with partial statistics, and the best policy so
far when the root was solved. Bounds here are generous on purpose: no timing is measured."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

import ehatp
from ehatp.experiments.bench import GridPoint
from ehatp.formats.policy import Policy
from ehatp.formats.problem_toml import loads
from ehatp.model.problem import parse_size
from ehatp.search import andor, values
from ehatp.search.limits import Budget, LimitReached

from .conftest import big_problem

CUBES = Path(__file__).resolve().parents[1] / "examples" / "cubes"


def test_timeout_stops_the_search_of_a_big_problem(tmp_path: Path) -> None:
    p = ehatp.load(big_problem(tmp_path))
    t0 = time.perf_counter()
    r = ehatp.solve(p, timeout=0.5)
    assert time.perf_counter() - t0 < 0.5 + 5
    assert r.status == "timeout" and not r.optimal
    assert "time limit of 0.5 s" in r.reason
    assert r.stats["distinct"] > 1 and r.stats["expanded"] > 0


def test_timeout_stops_the_value_pass(monkeypatch: pytest.MonkeyPatch) -> None:
    # a slow backward pass: every node is checked, and each costs a twentieth of a second
    def slow_speaks(m: object) -> bool:
        time.sleep(0.05)
        return False

    monkeypatch.setattr(values, "speaks", slow_speaks)
    monkeypatch.setattr(values, "CHECK_EVERY", 0)
    t0 = time.perf_counter()
    r = ehatp.solve(ehatp.load(CUBES / "p6.toml"), timeout=1.0)
    assert time.perf_counter() - t0 < 1.0 + 5
    assert r.status == "timeout" and r.policy is None and not r.optimal
    assert "during values" in r.reason
    assert r.stats["distinct"] > 1


def test_timeout_in_extraction_after_a_finished_search_keeps_the_proven_policy(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from ehatp.search import policy

    real = policy.bits_of
    calls = [0]

    def slow_bits_of(m: int) -> list[int]:  # once per policy node: a slow extraction
        calls[0] += 1
        if calls[0] <= 8:
            time.sleep(0.2)
        return real(m)

    monkeypatch.setattr(policy, "bits_of", slow_bits_of)
    t0 = time.perf_counter()
    r = ehatp.solve(ehatp.load(CUBES / "p4.toml"), timeout=1.0)
    assert time.perf_counter() - t0 < 1.0 + 5
    # the search had proven the optimum: the policy is kept, and the cut phase named
    assert r.status == "solved" and r.optimal and r.policy is not None and r.policy.optimal
    assert "during extraction" in r.reason and "after the search had finished" in r.reason
    again = ehatp.solve(ehatp.load(CUBES / "p4.toml")).policy
    assert again is not None and r.policy.cost == again.cost


def test_a_stopped_write_leaves_no_file(tmp_path: Path) -> None:
    r = ehatp.solve(ehatp.load(CUBES / "p1.toml"))
    assert r.policy is not None

    def stop() -> None:
        raise LimitReached("timeout", "time limit")

    f = tmp_path / "p.json"
    with pytest.raises(LimitReached):
        r.policy.write(f, check=stop)
    assert not f.exists()
    r.policy.write(f, check=lambda: None)
    assert f.read_text(encoding="utf-8") == r.policy.to_json()


@pytest.mark.slow  # sleeps 2.2 s past its time limit
def _solve_cli_timing_out_while_writing(monkeypatch: pytest.MonkeyPatch, target: Path,
                                        *options: str) -> Any:
    from typer.testing import CliRunner

    from ehatp.cli import solve as solve_command
    from ehatp.cli.app import app

    real = solve_command.solve

    def solve_then_wait(*args: Any, **kwargs: Any) -> Any:
        out = real(*args, **kwargs)
        time.sleep(2.2)  # past the time limit (1.5 s + 5 % + 0.5 s) before writing starts
        return out

    monkeypatch.setattr(solve_command, "solve", solve_then_wait)
    return CliRunner().invoke(app, ["solve", str(CUBES / "p1.toml"), "--timeout", "1.5",
                                    "--out", str(target), *options])


def test_cli_timeout_during_writing_writes_nothing(monkeypatch: pytest.MonkeyPatch,
                                                   tmp_path: Path) -> None:
    target = tmp_path / "p.json"
    r = _solve_cli_timing_out_while_writing(monkeypatch, target, "--no-symmetry")
    assert r.exit_code == 1, r.output
    assert "time limit of 1.5 s" in r.stdout.splitlines()[0]
    assert "during writing" in r.stdout.splitlines()[0]
    assert not target.exists()


def test_cli_timeout_during_writing_a_lifted_policy_writes_what_was_proven(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # the search had finished and the lifted policy is small as the search: it is written
    target = tmp_path / "p.json"
    r = _solve_cli_timing_out_while_writing(monkeypatch, target)
    assert r.exit_code == 0, r.output
    first = r.stdout.splitlines()[0]
    assert "solved (optimal policy found)" in first and "during writing" in first
    assert "after the search had finished" in first
    written = Policy.load(target)
    assert written.optimal and written.symmetry is not None


def test_a_stop_after_the_root_is_solved_keeps_the_best_policy(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # a time limit striking as soon as the root is solved, before optimality is proven
    def stop_once_solved(self: Budget, states: int, solved: bool) -> LimitReached | None:
        return self.timeout_reached() if solved else None

    p = ehatp.load(CUBES / "p4.toml")
    best = ehatp.solve(p)
    monkeypatch.setattr(Budget, "search_should_stop", stop_once_solved)
    # without symmetry: reduced, p4's whole graph is explored by the time the root is solved
    r = ehatp.solve(p, timeout=1000, symmetry=False)
    assert r.status == "timeout" and not r.optimal
    assert r.policy is not None and not r.policy.optimal
    assert ehatp.validate(p, r.policy).ok
    assert best.optimal and best.policy is not None and r.policy.cost >= best.policy.cost


def test_memory_error_is_a_clean_stop(monkeypatch: pytest.MonkeyPatch) -> None:
    real = andor._expand
    calls = 0

    def failing(*args: object) -> None:
        nonlocal calls
        calls += 1
        if calls > 30:
            raise MemoryError
        real(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(andor, "_expand", failing)
    r = ehatp.solve(ehatp.load(CUBES / "p6.toml"))
    assert r.status == "memory-limit" and r.policy is None and not r.optimal
    assert "out of memory" in r.reason
    assert r.stats["expanded"] == 30


@pytest.mark.parametrize("limit", [1, 2, 7, 50, 333])
def test_state_limit_is_never_exceeded(limit: int) -> None:
    """An expansion that would add one distinct state too many is not made: the search ends
    with exactly ``max_states`` states (P6 has 208), whatever order it expands in."""
    r = ehatp.solve(ehatp.load(CUBES / "p6.toml"), max_states=limit, symmetry=False)
    assert r.status == "state-limit" and not r.optimal
    assert r.stats["distinct"] == limit and f"({limit} distinct states)" in r.reason


def test_memory_limit_below_the_start_stops_at_once() -> None:
    r = ehatp.solve(ehatp.load(CUBES / "p1.toml"), max_memory=1)
    assert r.status == "memory-limit" and r.policy is None
    assert "memory limit of" in r.reason


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    src = str(Path(__file__).resolve().parents[1] / "src")
    env = {**os.environ, "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "ehatp.cli", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def test_cli_max_memory_stops_cleanly_with_partial_statistics(tmp_path: Path) -> None:
    # a fresh process: its resident size starts small and only the search makes it grow
    r = _cli("solve", str(big_problem(tmp_path)), "--max-memory", "80M", cwd=tmp_path)
    assert r.returncode == 1, r.stderr
    first = r.stdout.splitlines()[0]
    assert "stopped early" in first and "memory limit of 80 MB" in first
    assert "states" in r.stdout and "generated" in r.stdout
    assert "Traceback" not in r.stderr


def test_cli_timeout_bounds_the_whole_command(tmp_path: Path) -> None:
    t0 = time.perf_counter()
    r = _cli("solve", str(big_problem(tmp_path)), "--timeout", "1", cwd=tmp_path)
    assert time.perf_counter() - t0 < 1 + 10  # start-up included, generously
    assert r.returncode == 1, r.stderr
    assert "time limit of 1 s" in r.stdout.splitlines()[0]


def test_cli_bad_memory_size_is_one_line(tmp_path: Path) -> None:
    r = _cli("solve", str(CUBES / "p1.toml"), "--max-memory", "lots", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr.strip().count("\n") == 0 and "--max-memory lots" in r.stderr


@pytest.mark.parametrize(("text", "n"), [("2G", 2 << 30), ("512M", 512 << 20),
                                         ("1.5GB", 3 << 29), ("800k", 800 << 10),
                                         ("1GiB", 1 << 30), (4096, 4096)])
def test_sizes(text: str | int, n: int) -> None:
    assert parse_size(text) == n


@pytest.mark.parametrize("text", ["", "lots", "-1G", "0", 0, True, "1X"])
def test_bad_sizes(text: str | int) -> None:
    with pytest.raises(ValueError):
        parse_size(text)


def test_toml_max_memory(tmp_path: Path) -> None:
    text = (CUBES / "p1.toml").read_text(encoding="utf-8")
    f = tmp_path / "p.toml"
    f.write_text(text + '\n[limits]\nmax_memory = "1G"\n', encoding="utf-8")
    assert ehatp.load(f).limits.max_memory == 1 << 30
    f.write_text(text + '\n[limits]\nmax_memory = "plenty"\n', encoding="utf-8")
    with pytest.raises(ehatp.InputError, match="max_memory"):
        ehatp.load(f)


def test_progress_covers_every_phase() -> None:
    phases: list[str] = []

    def progress(stats: andor.Stats, frontier: int) -> None:
        if not phases or phases[-1] != stats.phase:
            phases.append(stats.phase)

    r = ehatp.solve(ehatp.load(CUBES / "p4.toml"), progress=progress)
    assert r.optimal
    assert phases[:2] == ["grounding", "search"]
    assert {"values (worst case)", "values (choices)", "extraction"} <= set(phases)


def test_cli_progress_line_covers_writing(monkeypatch: pytest.MonkeyPatch,
                                          tmp_path: Path) -> None:
    import io

    from rich.console import Console
    from typer.testing import CliRunner

    from ehatp.cli import solve as solve_command
    from ehatp.cli.app import app

    shown: list[str] = []
    real_render = solve_command.LiveProgress.render

    def render(self: solve_command.LiveProgress, stats: andor.Stats, frontier: int) -> Any:
        text = real_render(self, stats, frontier)
        shown.append(stats.phase if stats.phase != "search" else text.plain)
        return text

    monkeypatch.setattr(solve_command, "SHOW_PROGRESS_AFTER_S", 0.0)
    monkeypatch.setattr(solve_command.LiveProgress, "render", render)
    monkeypatch.setattr(solve_command, "stderr_console",
                        lambda: Console(file=io.StringIO(), force_terminal=True))
    r = CliRunner().invoke(app, ["solve", str(CUBES / "p4.toml"), "--out",
                                     str(tmp_path / "p.json")])
    assert r.exit_code == 0, r.output
    assert shown[0] == "grounding" and "writing" in shown and "extraction" in shown
    assert any("states/s" in s for s in shown)  # the search's own line


# --- every phase of every long command (issue 18) -------------------------------------------


def test_a_write_stopped_half_way_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    r = ehatp.solve(ehatp.load(CUBES / "p1.toml"))
    assert r.policy is not None
    f = tmp_path / "p.json"
    f.write_text("the old file", encoding="utf-8")
    calls = 0

    def stop_on_second_call() -> None:  # after the header and some nodes are written
        nonlocal calls
        calls += 1
        if calls == 2:
            raise LimitReached("timeout", "time limit")

    big = Policy.from_dict(json.loads(r.policy.to_json()))
    big.nodes = big.nodes * 300  # more than 256 nodes: check is called between them
    with pytest.raises(LimitReached):
        big.write(f, check=stop_on_second_call)
    assert calls == 2
    assert f.read_text(encoding="utf-8") == "the old file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.json"]


def test_the_streamed_file_is_the_text_to_json_gives() -> None:
    r = ehatp.solve(ehatp.load(CUBES / "p2.toml"))
    assert r.policy is not None
    assert "".join(r.policy.iter_json()) == r.policy.to_json()
    assert r.policy.to_json().startswith('{\n "K": 2,\n "after": [],')
    assert r.policy.to_json().endswith(' ]\n}\n') or r.policy.to_json().endswith('}\n')


def test_validate_stops_at_its_memory_limit_with_no_verdict(tmp_path: Path) -> None:
    # any process holds more than 1 MB: the budget's first look, before the policy is read,
    # stops the check (deterministic, unlike a time limit on a check that may be quick)
    r = ehatp.solve(ehatp.load(CUBES / "p2.toml"))
    assert r.policy is not None
    pol = tmp_path / "p.json"
    r.policy.write(pol)
    out = _cli("validate", str(CUBES / "p2.toml"), str(pol), "--max-memory", "1M",
               cwd=tmp_path)
    assert out.returncode == 1, out.stderr
    line = out.stderr.strip()
    assert line.count("\n") == 0
    assert line.startswith(f"not checked: {pol}: memory limit of 1 MB reached"), line
    assert "no verdict" in line and "valid" not in out.stdout


def test_the_validator_looks_at_the_limit_while_it_checks(tmp_path: Path) -> None:
    # a policy of 559 nodes (the big problem solved with symmetry, expanded): the check the
    # caller gives is called while grounding, refining and walking, and what it raises stops
    # the validation and goes through unchanged
    problem = big_problem(tmp_path)
    text = problem.read_text(encoding="utf-8").replace("symmetry = false", "symmetry = true")
    p = loads(text, "big.toml")
    r = ehatp.solve(p, expand=True)
    assert r.policy is not None and len(r.policy.nodes) > 500
    calls = 0

    def count() -> None:
        nonlocal calls
        calls += 1

    assert ehatp.validate(p, r.policy, check=count).ok
    assert calls > 10
    stop_at = calls // 2

    def stop() -> None:
        nonlocal calls
        calls += 1
        if calls >= stop_at:
            raise LimitReached("timeout", "time limit of 1 s reached")

    calls = 0
    with pytest.raises(LimitReached):
        ehatp.validate(p, r.policy, check=stop)
    assert calls == stop_at


def test_validate_has_the_problems_limits_and_checks_in_time_when_they_allow(
        tmp_path: Path) -> None:
    r = ehatp.solve(ehatp.load(CUBES / "p2.toml"))
    assert r.policy is not None
    pol = tmp_path / "p.json"
    r.policy.write(pol)
    out = _cli("validate", str(CUBES / "p2.toml"), str(pol), "--timeout", "60",
               "--max-memory", "2G", cwd=tmp_path)
    assert out.returncode == 0 and out.stdout.startswith("valid:"), out.stderr


def test_the_watchdog_ends_work_that_cannot_stop_itself(tmp_path: Path) -> None:
    # the body ignores every budget (native code would): the backstop ends the process with
    # the command's exit code and one line, within the slack
    code = ("import time\nfrom ehatp.cli.limits import STANDALONE, guarded\n"
            "with guarded(STANDALONE, 'stuck work', 0.5, None, 7):\n    time.sleep(30)\n")
    src = str(Path(__file__).resolve().parents[1] / "src")
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, env={**os.environ, "PYTHONPATH": src})
    took = time.perf_counter() - t0
    assert out.returncode == 7
    assert out.stderr.strip() == ("stuck work: stopped, time limit of 0.5 s reached after "
                                  f"{out.stderr.split('after ')[1].split(' s')[0]} s, where "
                                  "the work could not stop itself; raise the limit")
    assert 0.5 * 1.1 + 0.75 <= took < 0.5 * 1.1 + 0.75 + 3


def test_the_watchdog_watches_resident_memory(tmp_path: Path) -> None:
    code = ("from ehatp.cli.limits import STANDALONE, guarded\nimport time\n"
            "with guarded(STANDALONE, 'greedy work', None, 200 << 20, 7):\n"
            "    hog = [bytearray(1 << 20) for _ in range(400)]\n    time.sleep(30)\n")
    src = str(Path(__file__).resolve().parents[1] / "src")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, env={**os.environ, "PYTHONPATH": src})
    assert out.returncode == 7
    assert "greedy work: stopped, memory limit of 200 MB reached" in out.stderr


@pytest.mark.slow  # about 3 s
@pytest.mark.parametrize(("cubes", "boxes"), [(40, 10), (80, 20)])
def test_a_timeout_stops_grounding_and_symmetry_detection_in_time(cubes: int,
                                                                  boxes: int) -> None:
    # grounding these takes far longer than 2 s (80 cubes / 20 boxes: minutes), and one
    # formula's grounding or one tried swap can take seconds: the limit is looked at inside
    p = loads(GridPoint("cubes", 2, cubes=cubes, boxes=boxes).toml(), "big.toml")
    t0 = time.perf_counter()
    r = ehatp.solve(p, timeout=2)
    took = time.perf_counter() - t0
    assert r.status == "timeout" and r.policy is None
    assert "time limit of 2 s" in r.reason
    assert took < 2 * 1.05 + 0.5 + 1.5  # the hard limit, and one step past it
