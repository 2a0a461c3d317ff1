"""The ``ehatp`` command line: exit codes, one-line errors, show, validate, bench."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest
import typer
from typer.testing import CliRunner

import ehatp
from ehatp.cli.app import app
from ehatp.experiments import bench
from ehatp.experiments.examples import example, examples_dir
from ehatp.formats.lifted import expanded
from ehatp.formats.policy import Policy

from .conftest import TABLE1, big_problem

CUBES = examples_dir() / "cubes"
P1 = CUBES / "p1.toml"
runner = CliRunner()


def cli(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """Run the real console script, so stderr and tracebacks are what a user sees."""
    script = Path(sys.executable).with_name("ehatp")
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "ehatp.cli"]
    return subprocess.run([*cmd, *map(str, args)], capture_output=True, text=True, timeout=60)


def invoke(*args: str | Path) -> typer.testing.Result:
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def p2_policy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("pol") / "p2.json"
    assert invoke("solve", CUBES / "p2.toml", "--out", out).exit_code == 0
    return out


def variant(tmp_path: Path, name: str, old: str, new: str, source: Path = P1) -> Path:
    text = source.read_text(encoding="utf-8")
    assert old in text
    f = tmp_path / name
    f.write_text(text.replace(old, new, 1), encoding="utf-8")
    return f


# --- basics ----------------------------------------------------------------------------------


def test_version() -> None:
    r = invoke("--version")
    assert r.exit_code == 0
    assert r.stdout.strip() == f"ehatp {ehatp.__version__}"


def test_every_command_has_help() -> None:
    group = typer.main.get_command(app)
    paths = [[]] + [[c] for c in group.commands] + [["bench", "table1"]]  # type: ignore[attr-defined]
    assert {"solve", "show", "validate", "bench"} <= {p[0] for p in paths if p}
    for path in paths:
        r = invoke(*path, "--help")
        assert r.exit_code == 0, path
        assert "Usage" in r.stdout


def test_examples_are_found() -> None:
    assert (examples_dir() / "cubes" / "p1.toml").is_file()
    assert example("cubes/p6.toml") == CUBES / "p6.toml"


# --- solve -----------------------------------------------------------------------------------


def test_solve_prints_summary_and_writes_policy(tmp_path: Path) -> None:
    out = tmp_path / "p1.json"
    r = invoke("solve", P1, "--out", out)
    assert r.exit_code == 0, r.output
    for word in ("P1: solved", "states", "|W|", "leaves", "cost", "communications", "time"):
        assert word in r.stdout
    pol = Policy.read(out)
    assert pol.optimal and pol.problem == "P1"
    assert f"leaves          {pol.leaves}" in r.stdout


def test_solve_default_output_is_in_the_current_directory(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert invoke("solve", P1).exit_code == 0
    assert (tmp_path / "p1.policy.json").is_file()


def test_unsolvable_problem_exits_1_with_reason(tmp_path: Path) -> None:
    # a cube cannot be in two boxes at once
    f = tmp_path / "two-boxes.toml"
    f.write_text('goal = ["in(r, box1)", "in(r, box2)"]\n' + P1.read_text(encoding="utf-8"),
                 encoding="utf-8")
    out = tmp_path / "none.json"
    r = invoke("solve", f, "--out", out)
    assert r.exit_code == 1
    assert "no policy exists" in r.stdout
    assert "states" in r.stdout
    assert not out.exists()


def test_timeout_exits_1_with_partial_statistics(tmp_path: Path) -> None:
    r = invoke("solve", big_problem(tmp_path), "--timeout", "0", "--out", tmp_path / "t.json")
    assert r.exit_code == 1
    assert "time limit" in r.stdout and "generated" in r.stdout


def test_state_limit_keeps_best_policy_flagged_not_optimal(tmp_path: Path) -> None:
    out = tmp_path / "p6.json"
    r = invoke("solve", CUBES / "p6.toml", "--max-states", "300", "--no-symmetry", "--out", out)
    assert r.exit_code == 1
    assert "state limit" in r.stdout
    if out.exists():  # whether a policy is known by then is the planner's business
        assert Policy.read(out).optimal is False
        assert "NOT proven optimal" in r.stdout
    else:
        assert "none found" in r.stdout


# --- bad input: one line on stderr, exit 2 ---------------------------------------------------


def _one_line(r: subprocess.CompletedProcess[str], name: str) -> None:
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert "Traceback" not in r.stderr + r.stdout
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert name in lines[0]


@pytest.mark.parametrize("case", ["unknown predicate", "wrong arity", "unknown key", "missing",
                                  "bad toml", "domain error"])
def test_bad_problem_is_one_line_exit_2(case: str, tmp_path: Path) -> None:
    if case == "unknown predicate":
        f = variant(tmp_path, "pred.toml", '"on(r, mt)"', '"onn(r, mt)"')
    elif case == "wrong arity":
        f = variant(tmp_path, "arity.toml", '"on(r, mt)"', '"on(r)"')
    elif case == "unknown key":
        f = variant(tmp_path, "key.toml", "K = 2", 'K = 2\ncolour = "red"')
    elif case == "missing":
        f = tmp_path / "nowhere.toml"
    elif case == "bad toml":
        f = tmp_path / "broken.toml"
        f.write_text("[problem\nname = 1\n", encoding="utf-8")
    else:
        (tmp_path / "mydomain.py").write_text(
            "from ehatp import DomainError\nfrom ehatp.model.domain import domain_factory\n\n\n"
            "@domain_factory\ndef make(**options):\n"
            "    raise DomainError('predicate on declared twice')\n", encoding="utf-8")
        f = variant(tmp_path, "dom.toml", 'name = "cubes"\nturn_before_move = false',
                    'name = "mydomain.py:make"')
    r = cli("solve", f, "--out", tmp_path / "x.json")
    _one_line(r, f.name)
    assert not (tmp_path / "x.json").exists()
    if case == "domain error":  # the factory ran and its error names the line
        assert "is malformed at" in r.stderr and "mydomain.py:7" in r.stderr


@pytest.mark.parametrize("content", ["[1, 2]", '{"a": ', '{"format": "something-else"}',
                                     '{"format": "ehatp-policy", "version": 1}', None])
def test_bad_policy_is_one_line_exit_2(content: str | None, tmp_path: Path) -> None:
    f = tmp_path / "not-a-policy.json"
    if content is not None:
        f.write_text(content, encoding="utf-8")
    _one_line(cli("show", f), f.name)
    _one_line(cli("validate", P1, f), f.name)


def test_unknown_bench_instance_is_one_line() -> None:
    r = cli("bench", "table1", "--only", "P9")
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and "P9" in r.stderr


# --- show ------------------------------------------------------------------------------------


def test_show_prints_tree_and_timelines(p2_policy: Path) -> None:
    pol = expanded(Policy.read(p2_policy))  # lifted (format version 3): shown expanded
    r = invoke("show", p2_policy)
    assert r.exit_code == 0, r.output
    out = r.stdout
    assert "\x1b[" not in out  # plain text when not a terminal
    assert "Tree" in out and "Timelines" in out
    for n in pol.nodes:  # every node once, with its worlds
        assert len(re.findall(rf"#{n.id}\s+.*\sW={n.worlds}\b", out)) == 1, n
    for _, m in pol.edges():  # every move, in the domain's vocabulary
        assert re.search(rf"{re.escape(m.agent)}\s+{re.escape(m.action)}\s+"
                         rf"(W=|-> see node {m.to}\b)", out), m
    # a node reached by several paths is printed once; the other moves into it refer to it
    refs = re.findall(r"-> see node (\d+)", out)
    assert refs and len(refs) == sum(len(n.moves) for n in pol.nodes) - len(pol.nodes) + 1
    assert len(re.findall(r"GOAL$", out, re.M)) == sum(n.goal for n in pol.nodes)
    assert "H may do one of" in out and "apart" in out
    # one timeline per branch, with lanes while the agents are apart
    assert len(re.findall(r"^branch \d+ -> leaf #\d+", out, re.M)) == pol.leaves
    assert re.search(r"apart\s+R \| .+\n\s+H \| ", out)


def test_show_marks_communication(tmp_path: Path) -> None:
    out = tmp_path / "p4.json"
    assert invoke("solve", CUBES / "p4.toml", "--out", out).exit_code == 0
    pol = Policy.read(out)
    comms = [m for _, m in pol.edges() if m.kind in ("inform", "ask")]
    shown = invoke("show", out, "--no-timelines").stdout
    assert len(re.findall(r"  COMM\b", shown)) == len(comms)
    for m in comms:
        assert m.action in shown


def test_show_options(p2_policy: Path) -> None:
    no_tree = invoke("show", p2_policy, "--no-tree").stdout
    assert "Tree" not in no_tree and "branch 1" in no_tree
    details = invoke("show", p2_policy, "--no-timelines", "--details").stdout
    assert "unsure about" in details and "branch 1" not in details


# --- validate --------------------------------------------------------------------------------


def test_validate_exit_codes(p2_policy: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    problem = CUBES / "p2.toml"
    monkeypatch.setattr(ehatp, "validate", lambda p, q, **kw: SimpleNamespace(ok=True, message=""))
    r = invoke("validate", problem, p2_policy)
    assert r.exit_code == 0 and "valid" in r.stdout
    bad = SimpleNamespace(ok=False, message="node 7: place(w, box1) is not applicable")
    monkeypatch.setattr(ehatp, "validate", lambda p, q, **kw: bad)
    r = invoke("validate", problem, p2_policy)
    assert r.exit_code == 1 and bad.message in r.stdout


def test_validate_accepts_a_solved_policy(p2_policy: Path) -> None:
    pytest.importorskip("ehatp.check.validator")
    r = invoke("validate", CUBES / "p2.toml", p2_policy)
    assert r.exit_code == 0, r.output


# --- bench -----------------------------------------------------------------------------------


def test_bench_json_has_nine_rows(tmp_path: Path) -> None:
    out = tmp_path / "t1.json"
    r = invoke("bench", "table1", "--repeat", "1", "--json", out)
    rows = json.loads(out.read_text(encoding="utf-8"))
    assert [x["instance"] for x in rows] == [p.instance for p in bench.TABLE1]
    assert len(rows) == 9
    for x in rows:
        assert set(bench.REQUIRED_KEYS) <= x.keys()
    registered = {e.table1.instance: e for e in TABLE1 if e.table1}
    assert sorted(registered) == sorted(x["instance"] for x in rows)
    assert [x["paper_states"] for x in rows] == [218, 236, 1643, 2003, 4107, 5607, 603, 1054,
                                                 1800]
    assert rows[0]["paper_time_ms"] == 8900 and rows[5]["paper_time_ms"] == 12_530_000
    for x in rows:
        if x["solved"]:
            assert x["states"] >= x["distinct_states"] > 0 and x["time_ms"] > 0
            assert x["prototype_stored_ms"] > 0 and "speedup" not in x
        # the figures the registry records, ours and the paper's
        e = registered[x["instance"]]
        t = e.table1
        assert t is not None
        assert (x["states"], x["distinct_states"], x["max_worlds"], x["leaves"], x["cost"],
                x["communications"]) == (t.generated, t.distinct, e.worlds, e.leaves, e.cost,
                                         e.communications), x["instance"]
        assert (x["paper_states"], x["paper_max_worlds"], x["paper_leaves"]) == (
            t.paper_states, t.paper_worlds, t.paper_leaves), x["instance"]
    assert r.exit_code == (0 if all(x["solved"] for x in rows) else 1)
    assert "P1" in r.stdout and "Cooking 3" in r.stdout
    # stored figures are labelled as such and no ratio against them is printed
    assert "stored" in r.stdout and "speed-up" not in r.stdout and "faster" not in r.stdout


def test_benchmark_script_prints_the_table() -> None:
    script = Path(__file__).resolve().parents[1] / "benchmarks" / "table1.py"
    r = subprocess.run([sys.executable, str(script), "--repeat", "1", "--only", "P1"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert re.search(r"^P1\s+\d+\s+218\b", r.stdout, re.M)
