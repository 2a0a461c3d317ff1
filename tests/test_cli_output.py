"""What a command says about its output: ``render`` one line naming the file it wrote, its
format, the policy's nodes and its size; ``bench scaling`` one line per finished instance on
stderr, even when stderr is a pipe."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from ehatp.cli.app import app
from ehatp.cli.common import file_size, wrote_line
from ehatp.experiments.bench import progress_line
from ehatp.experiments.examples import examples_dir

CUBES = examples_dir() / "cubes"
runner = CliRunner()


def invoke(*args: str | Path) -> typer.testing.Result:
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def p2_policy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("out") / "p2.json"
    assert invoke("solve", CUBES / "p2.toml", "--out", out).exit_code == 0
    return out


def test_sizes_read_as_people_read_them() -> None:
    assert [file_size(n) for n in (0, 1, 999, 1000, 60_638, 999_949, 999_950, 41_200_000,
                                   3_000_000_000)] == [
        "0 bytes", "1 byte", "999 bytes", "1.0 kB", "60.6 kB", "999.9 kB", "1.0 MB", "41.2 MB",
        "3.0 GB"]


def test_the_wrote_line_names_command_file_contents_and_size() -> None:
    assert wrote_line("p2.html", 60_638, "HTML explorer of P2, 26 policy nodes", "render") == \
        "render: wrote p2.html: HTML explorer of P2, 26 policy nodes, 60.6 kB"
    assert wrote_line("t.xml", 512) == "wrote t.xml: 512 bytes"


def test_render_to_a_file_says_what_it_wrote(p2_policy: Path, tmp_path: Path) -> None:
    out = tmp_path / "p2.html"
    r = invoke("render", p2_policy, "--format", "html", "--out", out)
    assert r.exit_code == 0
    size = file_size(out.stat().st_size)
    # P2's lifted policy has 26 canonical nodes (`ehatp solve` says so)
    assert r.stderr == f"render: wrote {out}: HTML explorer of P2, 26 policy nodes, {size}\n"
    assert r.stdout == ""


def test_render_to_a_file_says_how_the_drawing_was_collapsed(p2_policy: Path,
                                                               tmp_path: Path) -> None:
    out = tmp_path / "p2.dot"
    r = invoke("render", p2_policy, "--max-nodes", "5", "--no-share", "--out", out)
    assert r.exit_code == 0
    size = file_size(out.stat().st_size)
    assert r.stderr.count("\n") == 1
    assert r.stderr.startswith(f"render: wrote {out}: Graphviz DOT of P2, 26 policy nodes "
                               "(collapsed: node budget 5 reached (")
    assert r.stderr.endswith(f")), {size}\n")


def test_render_to_stdout_says_nothing_on_stderr(p2_policy: Path) -> None:
    r = invoke("render", p2_policy)
    assert r.exit_code == 0
    assert r.stdout.startswith("digraph P2 {")
    assert r.stderr == ""


def test_a_finished_scaling_point_is_one_line() -> None:
    solved = {"instance": "cubes-c3-b2-opaque-k2", "status": "solved", "time_s": 0.0512,
              "distinct": 1204}
    assert progress_line(solved, 2, 40) == \
        "[3/40] cubes-c3-b2-opaque-k2: solved in 0.05 s, 1,204 distinct states"
    stopped = {"instance": "cubes-c12-b4-opaque-k8", "status": "timeout", "time_s": None,
               "distinct": None, "error": "time limit of 60 s reached"}
    assert progress_line(stopped, 39, 40) == \
        "[40/40] cubes-c12-b4-opaque-k8: timeout (time limit of 60 s reached)"


def test_bench_scaling_says_each_finished_instance_into_a_pipe() -> None:
    script = Path(sys.executable).with_name("ehatp")
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "ehatp.cli"]
    done = subprocess.run([*cmd, "bench", "scaling", "--only", "cubes-c3-b2-transparent-k2",
                           "--only", "cubes-c3-b2-opaque-k2", "--timeout", "30"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0
    lines = done.stderr.splitlines()
    assert len(lines) == 2
    # symmetric states counted as in the scaling table (docs/benchmarks.md)
    assert lines[0].startswith("bench scaling: [1/2] cubes-c3-b2-transparent-k2: solved in ")
    assert lines[0].endswith(" s, 109 distinct states")
    assert lines[1].startswith("bench scaling: [2/2] cubes-c3-b2-opaque-k2: solved in ")
    assert lines[1].endswith(" s, 119 distinct states")


@pytest.mark.parametrize(("fmt", "kind"), [("btcpp4", "BehaviorTree.CPP v4 XML"),
                                           ("py_trees", "py_trees module (Python)")])
def test_export_bt_to_a_file_says_what_it_wrote(p2_policy: Path, tmp_path: Path, fmt: str,
                                                kind: str) -> None:
    out = tmp_path / "p2.out"
    r = invoke("export", "bt", p2_policy, "--format", fmt, "--out", out)
    assert r.exit_code == 0
    size = file_size(out.stat().st_size)
    assert r.stderr == f"export bt: wrote {out}: {kind} of P2, 26 policy nodes, {size}\n"
    assert r.stdout == ""
