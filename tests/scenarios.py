"""Small hand-built scenarios whose right answers can be derived by hand."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from ehatp import (
    HIDDEN,
    INFERABLE,
    BeliefWorld,
    Communication,
    Costs,
    Domain,
    HumanModel,
    Objective,
    Problem,
    Var,
    observable,
)
from ehatp.epistemic.semantics import Semantics
from ehatp.epistemic.state import EState
from ehatp.model.grounding import ground_problem
from ehatp.model.problem import parse_call


def lab_domain(*, human_expects_robot: bool = True) -> Domain:
    """A lab (robot, lamps) and a hall. Lamps are observable from the lab, notes inferable
    (seen only when written in front of the human), secrets hidden. The human runs errands in
    the hall (one ``stroll`` per turn) and may ``use`` an item whose secret is set."""
    d = Domain("lab")
    Place, Item = d.type("place"), d.type("item")
    lab, hall = d.constant("lab", Place), d.constant("hall", Place)
    p, p2, i = Var("p", Place), Var("p2", Place), Var("i", Item)
    human_at = d.predicate("human_at", p)
    d.copresence = human_at(lab)
    lamp = d.predicate("lamp", i, observability=observable(human_at(lab)))
    note = d.predicate("note", i, observability=INFERABLE)
    secret = d.predicate("secret", i, observability=HIDDEN)
    used = d.predicate("used", i)
    strolled = d.predicate("strolled", i)

    r = d.robot
    set_lamp = r.action("set_lamp", i, pre=~lamp(i), effects=[lamp(i)])
    r.action("set_note", i, pre=~note(i), effects=[note(i)])
    r.action("set_secret", i, pre=~secret(i), effects=[secret(i)])
    # an abstract robot task with two ways to do it, for tie-break tests
    light = r.task("light", done=lamp("a") | lamp("b"))
    r.method(light, "a", subtasks=[set_lamp("a")])
    r.method(light, "b", subtasks=[set_lamp("b")])
    if not human_expects_robot:
        d.robot_seen_by_human = r.copy()
        for name in ("set_secret", "set_note", "set_lamp"):
            d.robot_seen_by_human.operators.pop(name)
        d.robot_seen_by_human.methods.clear()

    h = d.human
    go = h.action("go", p, p2, pre=human_at(p) & ~human_at(p2), effects=[human_at(p2),
                                                                     ~human_at(p)])
    stroll = h.action("stroll", i, pre=human_at(hall) & ~strolled(i), effects=[strolled(i)])
    use = h.action("use", i, pre=human_at(lab) & secret(i), effects=[used(i)])
    trip = h.task("trip", i)
    h.method(trip, "go", subtasks=[go(lab, hall), stroll(i), go(hall, lab)])
    long_trip = h.task("long_trip")
    h.method(long_trip, "go", subtasks=[go(lab, hall), stroll("s1"), stroll("s2"),
                                        stroll("s3"), go(hall, lab)])
    use_it = h.task("use_it", i, done=used(i))
    h.method(use_it, "use", subtasks=[use(i)])
    return d


def problem(domain: Domain, *, init: Iterable[str], robot: Iterable[str] = (),
            human: Iterable[str] = (), objects: Mapping[str, list[str]] | None = None,
            K: int = 2, starts: str = "human",
            beliefs: Iterable[tuple[Iterable[str], Iterable[str]]] | None = None,
            costs: Costs | None = None, human_model: HumanModel | None = None,
            communication: Communication | None = None, objective: Objective | None = None,
            goal: Iterable[str] = ()) -> Problem:
    def atom(s: str) -> tuple[str, tuple[str, ...]]:
        c = parse_call(s)
        assert c is not None, s
        return c

    worlds = (tuple(BeliefWorld(frozenset(map(atom, t)), frozenset(map(atom, f)))
                    for t, f in beliefs) if beliefs is not None else (BeliefWorld(),))
    return Problem(
        name="test", domain=domain,
        objects=dict(objects) if objects is not None else {"item": ["a", "b", "s1", "s2", "s3"]},
        init=frozenset(map(atom, init)), robot_agenda=tuple(map(atom, robot)),
        human_agenda=tuple(map(atom, human)), beliefs=worlds, starts=starts, K=K,
        costs=costs or Costs(), human=human_model or HumanModel(),
        communication=communication or Communication(), objective=objective or Objective(),
        goal=tuple((not g.startswith("not "), atom(g.removeprefix("not "))) for g in goal))


def walk(p: Problem, *labels: str) -> tuple[Semantics, EState]:
    """Follow moves by label from the initial state."""
    sem = Semantics(ground_problem(p))
    es = sem.initial()
    for label in labels:
        child = sem.follow(es, label).child
        assert child is not None
        es = child
    return sem, es


def world_atoms(sem: Semantics, es: EState) -> list[set[str]]:
    return [set(sem.g.state_atoms(s)) for s, _ in es.worlds]


def labels(sem: Semantics, es: EState) -> list[str]:
    return [m.label for m in sem.moves(es)]
