"""The objective is a choice (docs/semantics.md §7): worst case or expected cost, weights, tie
keys, and the two costs every policy reports."""

from __future__ import annotations

import dataclasses
import json
from fractions import Fraction
from pathlib import Path

import pytest
from typer.testing import CliRunner

import ehatp
from ehatp import Communication, Costs, Domain, Objective, ObjectiveKind, Problem, Speech
from ehatp.cli.app import app
from ehatp.experiments.examples import examples_dir
from ehatp.formats.policy import Policy
from ehatp.search.planner import Result

from .conftest import EXAMPLES, Example
from .scenarios import lab_domain, problem

WORST, EXPECTED = ObjectiveKind.WORST_CASE, ObjectiveKind.EXPECTED


# --- a hand-derived choice ------------------------------------------------------------------

GAMBLE_DOMAIN = '''
from ehatp import Domain


def gamble():
    """The robot does ``a`` or ``b`` (cost 1); then the human finishes with one of two moves:
    ``quick`` or ``slow`` after ``a``, ``left`` or ``right`` after ``b``."""
    d = Domain("gamble", robot="R", human="H")
    did_a, did_b, done = d.predicate("did_a")(), d.predicate("did_b")(), d.predicate("done")()
    job = d.robot.task("job", done=did_a | did_b)
    for name, flag in (("a", did_a), ("b", did_b)):
        act = d.robot.action(name, pre=~did_a & ~did_b, effects=[flag])
        d.robot.method(job, name, subtasks=[act()])
    react = d.human.task("react", done=done)
    for name, pre in (("quick", did_a), ("slow", did_a), ("left", did_b), ("right", did_b)):
        act = d.human.action(name, pre=pre & ~done, effects=[done])
        d.human.method(react, name, subtasks=[act()])
    return d


domain = gamble()
'''


def gamble_domain() -> Domain:
    scope: dict[str, object] = {}
    exec(GAMBLE_DOMAIN, scope)  # the same source the CLI test writes as domain.py
    d = scope["domain"]
    assert isinstance(d, Domain)
    return d


def gamble(a: tuple[int, int], b: tuple[int, int], objective: Objective) -> Problem:
    """Human branch costs ``a`` = (quick, slow) after the robot's ``a``, ``b`` = (left, right)
    after its ``b``."""
    costs = Costs(actions={"quick": a[0], "slow": a[1], "left": b[0], "right": b[1]})
    return problem(gamble_domain(), init=[], robot=["job"], human=["react"], objects={},
                   starts="robot", costs=costs, objective=objective)


def solved(p: Problem) -> tuple[Result, Policy]:
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None, r.reason
    return r, r.policy


def robot_first(policy: Policy) -> str:
    return policy.root.moves[0].action


# By hand. After the robot's action the human (co-present, not after a forced wait) may also
# pass; the robot, its agenda done, can then only wait, a forced wait after which the human
# must finish. So after ``a`` with human costs (x, y) the branches cost x, y and 1 + 1 + x or
# 1 + 1 + y (pass, wait, finish):
#   worst case  1 + max(x, y, 2 + max(x, y))              = 3 + max(x, y)
#   expected    1 + (x + y + 2 + (x + y) / 2) / 3          (equal weights)
# Options {1, 9} and {6, 6}: worst case 12 against 9; expected 1 + 17/3 = 20/3 against
# 1 + 20/3 = 23/3. The worst case picks b, the expected cost a.


def test_the_objectives_pick_different_robot_actions_with_values_by_hand() -> None:
    r, wc = solved(gamble((1, 9), (6, 6), Objective(WORST)))
    assert robot_first(wc) == "b" and r.optimal
    assert (wc.cost, wc.worst_case, wc.expected) == (9, 9, Fraction(23, 3))
    r, ex = solved(gamble((1, 9), (6, 6), Objective(EXPECTED)))
    assert robot_first(ex) == "a" and r.optimal
    assert (ex.cost, ex.worst_case, ex.expected) == (Fraction(20, 3), 12, Fraction(20, 3))
    assert r.stats["worst_case"] == 12 and r.stats["expected"] == Fraction(20, 3)
    # node values are the objective's: after a, 17/3 at the human node, 5 after pass + wait
    assert [n.value for n in ex.nodes if n.to_move == "H"] == [Fraction(17, 3), 5]
    assert [n.value for n in wc.nodes if n.to_move == "H"] == [8, 6]
    assert ex.objective == {"kind": "expected", "weights": {},
                            "ties": ["communications", "waits", "length"]}
    assert wc.objective["kind"] == "worst-case"


def test_weights_change_the_expected_choice() -> None:
    # slow three times as likely: after a, the forced wait's node is (1 + 3 * 9) / 4 = 7 and
    # the human node (1 + 3 * 9 + (2 + 7)) / 5 = 37 / 5, so a costs 42/5 > 23/3: b wins
    heavy = Objective(EXPECTED, weights={"slow": Fraction(3)})
    _, pol = solved(gamble((1, 9), (6, 6), heavy))
    assert robot_first(pol) == "b" and pol.expected == Fraction(23, 3)
    assert pol.objective["weights"] == {"slow": 3}
    # the same weights on a's tree, recomputed on the policy itself
    _, forced_a = solved(gamble((1, 9), (60, 60), heavy))
    assert robot_first(forced_a) == "a" and forced_a.expected == Fraction(42, 5)
    # a light slow branch only strengthens a
    _, light = solved(gamble((1, 9), (6, 6), Objective(EXPECTED, weights={"slow": Fraction(1, 4)})))
    assert robot_first(light) == "a"


# --- ties -----------------------------------------------------------------------------------


def test_the_worst_case_tie_key_reorders_an_expected_choice() -> None:
    # {1, 9} and {4, 6}: the same expected cost 1 + 17/3, worst cases 12 and 9. Both options
    # have no communication, one pass and equal branch lengths: by default the tie goes to the
    # first in canonical order (a); with "worst-case" first, to b
    default = Objective(EXPECTED)
    _, pol = solved(gamble((1, 9), (4, 6), default))
    assert robot_first(pol) == "a" and (pol.expected, pol.worst_case) == (Fraction(20, 3), 12)
    careful = Objective(EXPECTED, ties=("worst-case", "communications", "waits", "length"))
    _, pol = solved(gamble((1, 9), (4, 6), careful))
    assert robot_first(pol) == "b" and (pol.expected, pol.worst_case) == (Fraction(20, 3), 9)
    assert pol.objective["ties"] == list(careful.ties)


def test_the_expected_tie_key_reorders_a_worst_case_choice() -> None:
    # {9, 9} and {1, 9}: worst case 12 both; expected 1 + 29/3 against 1 + 17/3
    _, pol = solved(gamble((9, 9), (1, 9), Objective(WORST)))
    assert robot_first(pol) == "a" and pol.expected == Fraction(32, 3)
    _, pol = solved(gamble((9, 9), (1, 9), Objective(WORST, ties=("expected",))))
    assert robot_first(pol) == "b" and (pol.cost, pol.expected) == (12, Fraction(20, 3))


# --- communications -------------------------------------------------------------------------


def test_a_move_that_speaks_while_acting_is_told_and_counted() -> None:
    # the human wrongly believes b's secret is set and would use b at once; with speech
    # "with-action" the robot corrects it while doing its first task
    p = problem(lab_domain(), init=["human_at(lab)"], human=["use_it(b)"],
                robot=["set_lamp(a)", "set_secret(b)"], beliefs=[(["secret(b)"], [])],
                starts="robot", communication=Communication(speech=Speech.WITH_ACTION))
    for kind in (ObjectiveKind.WORST_CASE, ObjectiveKind.EXPECTED):  # turns: not preferences
        _, pol = solved(with_kind(p, kind))
        first = pol.root.moves[0]
        assert (first.kind, first.action) == ("action", "inform(not secret(b)) + set_lamp(a)")
        assert first.told == ["not secret(b)"] and first.name == "set_lamp"
        others = [m.told for _, m in pol.edges() if m is not first]
        assert others == [[]] * len(others)
        assert pol.communications == 1


# --- cycles ---------------------------------------------------------------------------------


def lamp_problem(kind: ObjectiveKind) -> Problem:
    """The robot may switch a lamp on and off for ever (its task recurses) before locking it
    on; the human reads once the lamp is on, or passes: the solvable graph has a cycle."""
    d = Domain("lamp", robot="R", human="H")
    lamp, locked, read = d.predicate("lamp")(), d.predicate("locked")(), d.predicate("read")()
    fiddle = d.robot.task("fiddle", done=locked)
    on = d.robot.action("switch_on", pre=~lamp, effects=[lamp])
    off = d.robot.action("switch_off", pre=lamp, effects=[~lamp])
    lock = d.robot.action("lock", pre=lamp & ~locked, effects=[locked])
    d.robot.method(fiddle, "on", subtasks=[on(), fiddle()])
    d.robot.method(fiddle, "off", subtasks=[off(), fiddle()])
    d.robot.method(fiddle, "lock", subtasks=[lock()])
    reading = d.human.task("reading", done=read)
    d.human.method(reading, "read", subtasks=[d.human.action("read", pre=lamp & ~read,
                                                             effects=[read])()])
    return problem(d, init=[], robot=["fiddle"], human=["reading"], objects={},
                   starts="robot", objective=Objective(kind))


def test_a_cycle_in_the_solvable_graph_is_reported_as_not_proven_optimal() -> None:
    r, pol = solved(lamp_problem(EXPECTED))
    assert not r.optimal and not pol.optimal and "cycles" in r.reason
    assert pol.expected is not None and pol.worst_case is not None
    assert pol.expected <= pol.worst_case
    r_wc, wc = solved(lamp_problem(WORST))
    assert r_wc.optimal  # the worst case has no such caveat
    assert wc.expected is not None and pol.expected <= wc.expected


# --- every shipped example ------------------------------------------------------------------


def with_kind(p: Problem, kind: ObjectiveKind) -> Problem:
    return dataclasses.replace(p, objective=dataclasses.replace(p.objective, kind=kind))


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_expected_optimum_on_every_example(example: Example) -> None:
    p = ehatp.load(example.path)
    _, ex = solved(with_kind(p, EXPECTED))
    _, wc = solved(with_kind(p, WORST))
    report = ehatp.validate(with_kind(p, EXPECTED), ex)  # recomputes both values (§7)
    assert report.ok, report.message
    assert ex.expected is not None and ex.worst_case is not None
    assert wc.expected is not None and wc.worst_case is not None
    assert ex.cost == ex.expected and wc.cost == wc.worst_case
    assert ex.expected <= ex.worst_case and wc.expected <= wc.worst_case
    assert ex.expected <= wc.expected  # the expected optimum beats the worst-case policy's mean
    assert wc.worst_case <= ex.worst_case  # and the other way round
    assert ex.nodes[0].value == ex.expected and wc.nodes[0].value == wc.worst_case


# --- command line ---------------------------------------------------------------------------


def gamble_file(tmp_path: Path, kind: str) -> Path:
    (tmp_path / "domain.py").write_text(GAMBLE_DOMAIN, encoding="utf-8")
    f = tmp_path / "gamble.toml"
    f.write_text(f'''[problem]
name = "gamble"
starts = "robot"

[domain]
name = "domain.py:domain"

[init]
true = []

[agenda]
robot = ["job"]
human = ["react"]

[costs.actions]
quick = 1
slow = 9
left = 6
right = 6

[objective]
kind = "{kind}"
''', encoding="utf-8")
    return f


def test_the_command_line_objective_overrides_the_file(tmp_path: Path) -> None:
    runner = CliRunner()
    f = gamble_file(tmp_path, "worst-case")
    out = tmp_path / "p.json"
    r = runner.invoke(app, ["solve", str(f), "--out", str(out), "--objective", "expected"])
    assert r.exit_code == 0, r.output
    v = runner.invoke(app, ["validate", str(f), str(out), "--objective", "expected"])
    assert v.exit_code == 0, v.output
    data = json.loads(out.read_text())
    assert data["objective"]["kind"] == "expected"
    assert (data["worst_case"], data["cost"]) == (12, data["expected"])
    assert data["expected"] == pytest.approx(20 / 3)
    lines = r.stdout.splitlines()
    assert any(ln.split() == ["worst", "case", "12"] for ln in lines), r.stdout
    assert any(ln.split()[:2] == ["expected", "cost"] and "(20/3)" in ln
               and ln.endswith("(optimised)") for ln in lines), r.stdout
    # and the other way round: the file says expected, the command line worst-case
    f = gamble_file(tmp_path, "expected")
    r = runner.invoke(app, ["solve", str(f), "--out", str(out), "--objective", "worst-case"])
    assert r.exit_code == 0, r.output
    assert json.loads(out.read_text())["objective"]["kind"] == "worst-case"
    assert any(ln.split() == ["worst", "case", "9", "(optimised)"]
               for ln in r.stdout.splitlines()), r.stdout
    # without the option, the file's objective holds; show prints both costs
    r = runner.invoke(app, ["solve", str(f), "--out", str(out)])
    assert r.exit_code == 0 and json.loads(out.read_text())["objective"]["kind"] == "expected"
    r = runner.invoke(app, ["show", str(out), "--no-tree", "--no-timelines"])
    assert r.exit_code == 0
    assert "worst-case cost 12, expected cost 6.66667 (optimised)" in r.stdout


def test_deprecated_spellings_print_a_note_on_stderr(tmp_path: Path) -> None:
    f = gamble_file(tmp_path, "expected")
    f.write_text(f.read_text() + "\n[options]\ninform_max_atoms = 2\n", encoding="utf-8")
    out = tmp_path / "p.json"
    r = CliRunner().invoke(app, ["solve", str(f), "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "note: [options] inform_max_atoms is deprecated" in r.stderr
    assert "note:" not in r.stdout
    r = CliRunner().invoke(app, ["validate", str(f), str(out)])
    assert "note: [options] inform_max_atoms is deprecated" in r.stderr


# --- determinism ----------------------------------------------------------------------------


@pytest.mark.parametrize("kind", [WORST, EXPECTED])
def test_policies_are_byte_identical_run_to_run(kind: ObjectiveKind) -> None:
    for p in (gamble((1, 9), (4, 6), Objective(kind)), lamp_problem(kind),
              ehatp.load(examples_dir() / "cooking" / "cooking1.toml")):
        p = with_kind(p, kind)
        first, second = solved(p)[1], solved(p)[1]
        assert first.to_json() == second.to_json()
        report = ehatp.validate(p, first)
        assert report.ok, report.message
