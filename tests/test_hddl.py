"""HDDL import (docs/hddl.md): an agent's HTN from an HDDL domain and problem, with what HDDL
does not say in a sidecar; the report over the domains unified-planning ships (the IPC 2020
HTN track's) and tests/data/hddl's own."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import ehatp

pytest.importorskip("unified_planning", reason="ehatp[hddl] (unified-planning) not installed")
# unified-planning's reader calls a pyparsing name pyparsing now deprecates; the whole module is
# slow (the IPC domains: about 40 % of the suite), `make test-fast` leaves it out
pytestmark = [pytest.mark.filterwarnings("ignore:.*deprecated - use:DeprecationWarning"),
              pytest.mark.slow]

from ehatp.experiments import hddl_report  # noqa: E402
from ehatp.formats import hddl  # noqa: E402

DATA = Path(__file__).parent / "data" / "hddl"
ROOT = Path(__file__).resolve().parent.parent


def own(name: str, sidecar: str | None = None) -> hddl.Imported:
    return hddl.import_hddl(DATA / f"{name}-domain.hddl", DATA / f"{name}-p1.hddl",
                            sidecar=DATA / sidecar if sidecar else None)


def test_a_small_imported_domain_solves_and_validates() -> None:
    imp = own("transport")
    p = imp.problem()
    assert p.robot_agenda == (("top", ()),) and p.human_agenda == ()
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert ehatp.validate(p, r.policy).ok
    # the unordered initial network lets the truck take the parcel where it is first: six
    # robot actions (the other order needs eight), the human passing in between
    assert r.policy.cost == 11


def test_a_partially_ordered_method_keeps_its_order() -> None:
    imp = own("rover")
    assert "order=[(0, 1), (0, 2), (1, 3), (2, 3)]" in imp.source
    p = imp.problem()
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert ehatp.validate(p, r.policy).ok
    shown = {a for n in r.policy.nodes for a in n.robot_agenda}
    assert "{picture(r, crater) | sample(r, crater)}" in shown


def test_the_hddl_model_may_be_the_humans() -> None:
    """--agent human: the human does the rover's work, in either order where the method
    leaves it free, and the policy covers both; the robot has nothing to do."""
    p = hddl.import_hddl(DATA / "rover-domain.hddl", DATA / "rover-p1.hddl",
                         agent="human").problem()
    assert p.robot_agenda == () and p.starts == "human"
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert r.policy.leaves > 1  # the human's choices of order are branches of the policy
    assert ehatp.validate(p, r.policy).ok


def test_the_written_module_and_problem_are_what_solve_reads(tmp_path: Path) -> None:
    out = tmp_path / "toy.py"
    r = subprocess.run([sys.executable, "-m", "ehatp.cli", "import-hddl",
                        str(DATA / "transport-domain.hddl"), str(DATA / "transport-p1.hddl"),
                        "--out", str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert out.is_file() and (tmp_path / "toy.toml").is_file()
    text = out.read_text(encoding="utf-8")
    assert "@domain_factory" in text and 'd.type("truck", parent=locatable)' in text
    compile(text, str(out), "exec")
    p = ehatp.load(tmp_path / "toy.toml")
    res = ehatp.solve(p)
    assert res.policy is not None and res.policy.cost == 11
    assert ehatp.validate(p, res.policy).ok


def test_a_human_who_expects_nothing_of_the_robot(tmp_path: Path) -> None:
    """``[other] expects = "nothing"``: M_R^H is empty, so the human, who sees every action,
    entertains one world (it follows no plan of the robot's); the same cost, fewer worlds."""
    side = tmp_path / "side.toml"
    side.write_text('[other]\nexpects = "nothing"\n', encoding="utf-8")
    alone = hddl.import_hddl(DATA / "transport-domain.hddl", DATA / "transport-p1.hddl",
                             sidecar=side)
    assert "d.robot_seen_by_human = AgentModel(d.robot_name)" in alone.source
    p = alone.problem()
    assert not p.domain.robot_seen_by_human.tasks and not p.domain.robot_seen_by_human.operators
    r, watched = ehatp.solve(p), ehatp.solve(own("transport").problem())
    assert r.policy is not None and watched.policy is not None
    assert r.policy.cost == watched.policy.cost == 11
    assert r.stats["max_worlds"] == 1 < watched.stats["max_worlds"]
    assert ehatp.validate(p, r.policy).ok
    # written out, the module says it too, and loads
    out = tmp_path / "alone.py"
    alone.write(out)
    assert ehatp.solve(ehatp.load(tmp_path / "alone.toml")).policy is not None
    side.write_text('[other]\nexpects = "everything"\n', encoding="utf-8")
    with pytest.raises(hddl.HddlUnsupported, match="expects = 'everything'"):
        hddl.read_sidecar(side)
    side.write_text('[other]\nexpects = "nothing"\n', encoding="utf-8")
    with pytest.raises(hddl.HddlUnsupported, match="import the robot's model"):
        hddl.import_hddl(DATA / "transport-domain.hddl", DATA / "transport-p1.hddl",
                         agent="human", sidecar=side)


def test_the_sidecar_says_what_the_human_perceives_and_when_they_are_together() -> None:
    imp = own("transport", "transport-sidecar.toml")
    d = imp.domain()
    assert d.predicates["in"].observability == ehatp.HIDDEN
    assert d.predicates["at"].observability.kind == "observable"
    assert str(d.predicates["at"].observability.when) == "?p = a"
    p = imp.problem(d)
    assert p.K == 3
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert ehatp.validate(p, r.policy).ok
    # together only while the truck is at a: the human cannot see the robot finish elsewhere
    side = hddl.read_sidecar(DATA / "transport-sidecar.toml")
    side.copresence = ["at(t1, a)"]
    apart = hddl.import_hddl(DATA / "transport-domain.hddl", DATA / "transport-p1.hddl",
                             sidecar=side).problem()
    assert str(apart.domain.copresence) == "at(t1, a)"
    assert ehatp.solve(apart).status == "unsolvable"


def test_a_python_sidecar_gives_the_human_a_task(tmp_path: Path) -> None:
    imp = own("rover", "rover-sidecar.py")
    p = imp.problem()
    assert p.human_agenda == (("log", ()),)
    assert p.domain.predicates["sent"].observability == ehatp.HIDDEN
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert ehatp.validate(p, r.policy).ok
    # written out, the module runs the sidecar from its path relative to the module
    mod, prob = imp.write(tmp_path / "rover.py")
    assert "run_sidecar(d, __file__," in mod.read_text(encoding="utf-8")
    assert ehatp.solve(ehatp.load(prob)).status == "solved"


def test_what_cannot_map_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "d.hddl").write_text(
        "(define (domain fuel) (:requirements :typing :hierarchy :numeric-fluents)\n"
        " (:types truck) (:predicates (moved ?t - truck)) (:functions (fuel ?t - truck))\n"
        " (:task go :parameters (?t - truck))\n"
        " (:method m :parameters (?t - truck) :task (go ?t) :ordered-subtasks (and (move ?t)))"
        "\n (:action move :parameters (?t - truck) :precondition (> (fuel ?t) 0)\n"
        "  :effect (and (moved ?t) (decrease (fuel ?t) 1))))\n", encoding="utf-8")
    (tmp_path / "p.hddl").write_text(
        "(define (problem p) (:domain fuel) (:objects t - truck)\n"
        " (:htn :ordered-subtasks (and (go t))) (:init (= (fuel t) 3)))\n", encoding="utf-8")
    with pytest.raises(hddl.HddlUnsupported, match="numeric fluent fuel"):
        hddl.import_hddl(tmp_path / "d.hddl", tmp_path / "p.hddl")
    r = subprocess.run([sys.executable, "-m", "ehatp.cli", "import-hddl",
                        str(tmp_path / "d.hddl"), str(tmp_path / "p.hddl")],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "numeric fluent" in r.stderr
    bad = tmp_path / "side.toml"
    bad.write_text('[observability]\nat = "sometimes"\n', encoding="utf-8")
    with pytest.raises(hddl.HddlUnsupported, match="sometimes"):
        hddl.read_sidecar(bad)


def test_a_file_unified_planning_cannot_read_is_named_once_with_its_line(
        tmp_path: Path) -> None:
    """The error names the file that fails to parse (the domain, or the problem when the
    domain alone reads), once, at the line and column of the parse error; a sidecar's error
    names the sidecar, not the domain."""
    good = DATA / "transport-domain.hddl"
    broken = tmp_path / "broken.hddl"
    broken.write_text("(define (domain x)\n (:requirements :hierarchy) (:types a\n", "utf-8")

    def line(domain: Path, problem: Path, *extra: str) -> str:
        r = subprocess.run([sys.executable, "-m", "ehatp.cli", "import-hddl", str(domain),
                            str(problem), "--out", str(tmp_path / "m.py"), *extra],
                           capture_output=True, text=True, cwd=tmp_path, check=False)
        assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
        return r.stderr

    err = line(broken, DATA / "transport-p1.hddl")
    assert err.startswith(f"error: {broken}:") and err.count(str(broken)) == 1
    assert "unified-planning cannot read it" in err and "(line:" not in err
    err = line(good, broken)
    assert err.startswith(f"error: {broken}:") and str(good) not in err
    side = tmp_path / "side.toml"
    side.write_text('[resources]\nfly = ["?v"]\n', encoding="utf-8")
    err = line(good, DATA / "transport-p1.hddl", "--sidecar", str(side))
    assert err.startswith(f"error: {side}: [resources] names 'fly'") and str(good) not in err


def test_left_recursion_solves() -> None:
    """The IPC's transport reaches a place through itself (get-to before a drive): a task met
    again inside its own refinement before any action is a loop, closed (docs/semantics.md §1),
    so the drives taken are the paths without a repeated place; the policy validates."""
    shipped = {n: (d, p) for n, d, p in hddl_report.domains_shipped()}
    d, p = shipped["2020-to-Transport"]
    r = ehatp.solve(hddl.import_hddl(d, p).problem())
    assert r.status == "solved" and r.policy is not None
    row = hddl_report.check_domain("transport", d, p, timeout=30)
    assert row.stage == "validated", row.reason


# -- the report over the shipped domains ------------------------------------------------------

# Every shipped IPC domain the report validates is imported, solved, validated and walked on every
# branch by tests/test_every_policy_runs.py (the six written lifted by tests/test_policy_v3.py,
# lifted and expanded): solving them here again only doubled the suite's longest tests.


def test_the_report_script_runs(tmp_path: Path) -> None:
    out = tmp_path / "rows.json"
    r = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "hddl_report.py"),
                        "--only", "own/", "--only", "Towers", "--timeout", "30",
                        "--json", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    rows = json.loads(out.read_text(encoding="utf-8"))
    assert {row["name"] for row in rows} >= {"own/transport/p1", "own/rover/p1",
                                             "ipc/2020-to-Towers"}
    assert all(row["stage"] == "validated" for row in rows), rows
    assert "own: 2 domains, 2 map, 2 solve" in r.stdout
