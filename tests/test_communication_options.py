"""Each communication option turns an unsolvable problem into a solved one
(docs/semantics.md §5; `examples/communication/`), and the non-anticipating human (§4)."""

from __future__ import annotations

from dataclasses import replace

import pytest

import ehatp
from ehatp import Communication, HumanModel

from .conftest import EXAMPLES_DIR, example, solved
from .scenarios import lab_domain, problem, walk

EX = EXAMPLES_DIR / "communication"

CASES = [
    ("starts-on-false-belief.toml", "speech", "inform(not jar_on(k1), jar_on(k2))"),
    ("other-room.toml", "inform", "inform(not jar_on(p1), jar_on(p2))"),
    ("late-fatal.toml", "relevance", "inform(not jar_on(p1), jar_on(p2))"),
]


@pytest.mark.parametrize(("name", "option", "said"), CASES)
def test_option_solves_what_the_default_cannot(name: str, option: str, said: str) -> None:
    got = solved(EX / name)
    p, policy = got
    assert got.result.optimal, got.result.reason
    assert policy.communications == 1 == example(f"communication/{name[:-5]}").communications
    assert said in {m.action for _, m in policy.edges()}
    report = ehatp.validate(p, policy)
    assert report.ok, report.message
    default = replace(p, communication=replace(p.communication, **{
        option: getattr(Communication(), option)}))
    r0 = ehatp.solve(default)
    assert r0.status == "unsolvable" and "false belief" in r0.reason


def test_speech_opening_comes_before_the_humans_first_move() -> None:
    p = ehatp.load(EX / "starts-on-false-belief.toml")
    r = ehatp.solve(p)
    assert r.policy is not None
    first = r.policy.root.moves
    assert [(m.agent, m.kind) for m in first] == [("R", "inform")]


def test_inform_at_a_distance_is_heard_while_apart() -> None:
    p = ehatp.load(EX / "other-room.toml")
    sem, es = walk(p)
    assert not sem.copresent(es.true)
    inform = next(m for m in sem.moves(es) if m.kind == "inform")
    assert inform.child is not None
    assert len(inform.child.worlds) == 1 and inform.child.k == es.k


def test_speech_with_action_says_and_does_in_one_turn() -> None:
    # the robot sets a secret in front of the human, who wrongly believes b's secret is set
    p = problem(lab_domain(), init=["human_at(lab)"], human=["use_it(b)"],
                robot=["set_lamp(a)"], beliefs=[(["secret(b)"], [])], starts="robot",
                communication=Communication(speech="with-action"))  # type: ignore[arg-type]
    sem, es = walk(p)
    both = [m for m in sem.moves(es) if " + " in m.label]
    assert [m.label for m in both] == ["inform(not secret(b)) + set_lamp(a)",
                                       "inform(not secret(b)) + wait"]
    assert both[0].cost == 2 and both[0].child is not None
    assert len(both[0].child.worlds) == 1
    described = sem.describe(both[0])
    assert (described.name, described.args) == ("set_lamp", ("a",))


def test_without_questions_the_human_cannot_ask() -> None:
    base = dict(init=["human_at(lab)"], human=["use_it(a)"],
                beliefs=[([], []), (["secret(a)"], [])], starts="robot")
    sem, es = walk(problem(lab_domain(), **base), "wait")  # type: ignore[arg-type]
    assert "ask(secret(a))" in [m.label for m in sem.moves(es)]
    sem, es = walk(problem(lab_domain(), communication=Communication(ask=False),
                           **base), "wait")  # type: ignore[arg-type]
    assert [m.label for m in sem.moves(es)] == ["pass"]


def test_a_human_who_does_not_anticipate_imagines_nothing_while_away() -> None:
    kw = dict(init=["human_at(lab)"], human=["trip(s1)"], robot=["set_secret(a)"])
    sem, es = walk(problem(lab_domain(), **kw), "go(lab, hall)",  # type: ignore[arg-type]
                   "set_secret(a)")
    assert len(es.worlds) == 2  # did it, or not yet
    p = problem(lab_domain(), human_model=HumanModel(anticipates=False), **kw)  # type: ignore[arg-type]
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)")
    assert len(es.worlds) == 1 and not sem.g.state_atoms(es.worlds[0][0]).count("secret(a)")
    # back in the lab it sees the robot has finished, but not what it did (hidden)
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)", "stroll(s1)", "wait", "go(hall, lab)")
    assert sem.human_believes_robot_done(es)
    assert "secret(a)" not in sem.g.state_atoms(es.worlds[0][0])
    r = ehatp.solve(p)
    assert r.policy is not None
    assert ehatp.validate(p, r.policy).ok
