"""Where planner and validator once read the rules differently (docs/semantics.md §4-§5), and
what a policy file says of each move. Each scenario is small enough to derive by hand."""

from __future__ import annotations

import subprocess
import sys

import pytest

import ehatp
from ehatp import HIDDEN, Domain, Var, observable

from .scenarios import problem, walk


def fridge_domain(*, human_knows_subtasks: bool) -> Domain:
    """The robot chills a drink (``cold`` is hidden) while the human runs an errand.

    The human believes chilling needs ``power`` (false in reality), so away from the robot it
    cannot imagine the drink being chilled; with ``human_knows_subtasks`` false, the human's
    model of the robot knows only the top task ``serve`` and its done-condition."""
    d = Domain("fridge")
    Place = d.type("place")
    lab, hall = d.constant("lab", Place), d.constant("hall", Place)
    p, p2 = Var("p", Place), Var("p2", Place)
    human_at = d.predicate("human_at", p)
    d.copresence = human_at(lab)
    cold = d.predicate("cold", observability=HIDDEN)
    shelved = d.predicate("shelved", observability=HIDDEN)
    power = d.predicate("power", observability=HIDDEN)
    errand = d.predicate("errand", observability=observable(human_at(lab)))

    r = d.robot
    chill = r.action("chill", pre=~cold(), effects=[cold()])
    shelve = r.action("shelve", pre=cold() & ~shelved(), effects=[shelved()])
    cool = r.task("cool", done=cold())
    r.method(cool, "chill", subtasks=[chill()])
    serve = r.task("serve", done=cold() & shelved())
    r.method(serve, "both", subtasks=[cool(), shelve()])
    rh = r.copy()
    if human_knows_subtasks:
        # the human's estimate: chilling needs power
        rh.methods = [m for m in rh.methods if m.task.name != "cool"]
        rh.method(cool, "chill", pre=power(), subtasks=[chill()])
    else:
        rh.methods = []
        rh.tasks = {"serve": serve}
        rh.operators = {}
    d.robot_seen_by_human = rh

    h = d.human
    go = h.action("go", p, p2, pre=human_at(p) & ~human_at(p2),
                  effects=[human_at(p2), ~human_at(p)])
    run = h.action("run", pre=human_at(hall) & ~errand(), effects=[errand()])
    trip = h.task("trip", done=errand() & human_at(lab))
    h.method(trip, "go", subtasks=[go(lab, hall), run(), go(hall, lab)])
    return d


def fridge(*, human_knows_subtasks: bool = True, robot: tuple[str, ...] = ("cool",),
           after: tuple[str, ...] = ()) -> ehatp.Problem:
    p = problem(fridge_domain(human_knows_subtasks=human_knows_subtasks),
                init=["human_at(lab)"], robot=robot, human=["trip"], objects={})
    p.after = after
    return p


def test_a_divergence_hiding_that_the_robot_is_done_is_relevant() -> None:
    # R chills unseen; the human cannot imagine it (no power), so back in the lab its only
    # world has the robot blocked on `cool`, while in truth the robot is done (FINISH). The
    # robot's options include being done: the divergence is relevant, and informing `cold`
    # is the smallest fix (§5). Before, the validator dropped FINISH and called it irrelevant.
    sem, es = walk(fridge(), "go(lab, hall)", "chill", "run", "wait", "go(hall, lab)")
    assert sem.copresent(es.true) and len(es.worlds) == 1
    assert "inform(cold)" in [m.label for m in sem.moves(es)]
    p = fridge(after=("H go(lab, hall)", "R chill"))
    r = ehatp.solve(p)
    assert r.policy is not None
    assert "inform(cold)" in {m.action for _, m in r.policy.edges()}
    report = ehatp.validate(p, r.policy)
    assert report.ok, report.message


def test_unknown_task_of_the_real_agenda_is_dropped_not_a_crash() -> None:
    # M_R^H knows only `serve` (and its done-condition). R chills in front of the human, which
    # nobody expected: the human revises its worlds with the real remaining agenda, keeping
    # only the tasks its model of the robot knows (§4): `shelve` is dropped, nothing is left.
    p = fridge(human_knows_subtasks=False, robot=("serve",))
    p.starts = "robot"
    sem, es = walk(p, "chill")
    assert [ag for _, ag in es.worlds] == [()]
    assert es.robot_agenda == (sem.g.task_index["shelve"],)
    r = ehatp.solve(p)
    assert r.policy is not None
    report = ehatp.validate(p, r.policy)
    assert report.ok, report.message


def test_inform_of_an_atom_with_arguments_records_whole_literals() -> None:
    d = Domain("links")
    Node = d.type("node")
    a, b = Var("a", Node), Var("b", Node)
    d.copresence = d.predicate("here")()
    link = d.predicate("link", a, b, observability=HIDDEN)
    d.robot.action("connect", a, b, pre=~link(a, b), effects=[link(a, b)])
    d.human.action("use", a, b, pre=link(a, b), effects=[~link(a, b)])
    d.human.action("idle")
    p = problem(d, init=["here", "link(x, y)"], robot=[], human=["use(x, y)"],
                objects={"node": ["x", "y"]}, beliefs=[([], ["link(x, y)"])], starts="robot")
    r = ehatp.solve(p)
    assert r.policy is not None
    told = [m for _, m in r.policy.edges() if m.kind == "inform"]
    assert told and told[0].name == "inform" and told[0].args == ["link(x, y)"]
    assert ehatp.validate(p, r.policy).ok
    # the validator checks name and args too
    told[0].args = ["link(x", "y)"]
    report = ehatp.validate(p, r.policy)
    assert not report.ok and "name and args" in report.message


def test_validator_rejects_a_policy_of_another_problem() -> None:
    p = fridge()
    r = ehatp.solve(p)
    assert r.policy is not None
    r.policy.problem = "P7"
    report = ehatp.validate(p, r.policy)
    assert not report.ok and "planned for problem 'P7'" in report.message


def test_an_opening_step_naming_the_wrong_agent_is_refused() -> None:
    sem, es = walk(fridge())
    with pytest.raises(ValueError, match="H's turn"):
        sem.follow(es, "R go(lab, hall)")
    p = fridge(after=("R go(lab, hall)",))
    with pytest.raises(ehatp.InputError, match="after, step 1"):
        ehatp.solve(p)


def test_importing_the_validator_does_not_load_the_planner() -> None:
    code = ("import sys, ehatp.check.validator, ehatp.formats.policy; "
            "print(sorted(m for m in sys.modules if m.startswith(('ehatp.search', "
            "'ehatp.epistemic', 'ehatp.tools'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"



def _ask_labels(policy: ehatp.Policy) -> list[list[str]]:
    return [[m.action for m in n.moves if m.action.startswith("ask(")] for n in policy.nodes]


def test_one_set_of_uncertain_conditions_met_in_two_orders_is_one_question() -> None:
    """Derived by hand from §4 (random seed 121773 of the agreement benchmark, where planner
    and validator read it differently). The human has two hypotheses, ``take(y), take(x),
    take(y)`` and ``take(x), take(y), take(y)``; co-present after ``h0`` and the robot's
    ``r0``, both find ``mark(x)`` and ``mark(y)`` uncertain, in opposite orders. A question is
    the set of its conjuncts, printed in the order of their text: one branch
    ``ask(not mark(x) and not mark(y))`` (kept by both hypotheses), never a second with the
    same two conjuncts the other way round; the validator agrees and the policy runs."""
    from ehatp.check.validator import validate
    from ehatp.experiments.randomgen import build, draw
    from ehatp.run.walk import walk_policy

    p = build(draw(121773))
    r = ehatp.solve(p)
    assert r.policy is not None
    for labels in _ask_labels(r.policy):
        sets = [frozenset(x.strip() for x in a[4:-1].split(" and ")) for a in labels]
        assert len(sets) == len(set(sets)), labels
        for a in labels:
            parts = a[4:-1].split(" and ")
            assert parts == sorted(parts), a
    assert any("ask(not mark(x) and not mark(y))" in labels
               for labels in _ask_labels(r.policy))
    assert validate(p, r.policy).ok
    assert walk_policy(p, r.policy).ok


def test_a_conjunction_that_simplifies_to_one_conjunct_reads_as_that_conjunct() -> None:
    """Derived by hand (random seed 121709, in joint steps). The human's method ``c0`` needs
    ``a2``; the robot's ``r0`` needs ``a2 & a3``, where ``a3`` is always true and folds away,
    so both ground to the one atom ``a2``. Which model was grounded first used to decide how
    that atom read, and the validator (grounding in another order) asked ``ask(a2 and a3)``
    where the planner asked ``ask(a2)``. A conjunction that simplifies to one of its conjuncts
    reads as that conjunct: the human's question is ``ask(a2)`` both ways."""
    from ehatp.check.validator import validate
    from ehatp.experiments.randomgen import build, draw

    p = build(draw(121709))
    r = ehatp.solve(p)
    assert r.policy is not None
    assert "ask(a2)" in _ask_labels(r.policy)[0]
    report = validate(p, r.policy)
    assert report.ok, report.message
