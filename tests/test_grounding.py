"""Grounding (docs/semantics.md §1, "Grounding"; §1 on static and shrinking predicates): method
bindings drawn from static relations, tasks grounded on demand past ``[limits] ground_ahead``,
and predicates nothing makes true folded to false. Each gives the same answers as grounding
everything ahead."""

from __future__ import annotations

from itertools import product
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ehatp
from ehatp import Domain, InputError, Problem, Var
from ehatp.model.grounding import ground_problem
from ehatp.model.problem import BeliefWorld, Limits
from ehatp.search.interchangeable import detect
from ehatp.search.planner import solve

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
LOCS = ["l0", "l1", "l2", "l3", "l4"]
ROADS = [("l0", "l1"), ("l1", "l2"), ("l2", "l3"), ("l3", "l4"), ("l1", "l3")]


def walk_domain() -> Domain:
    """The robot walks along one-way roads (static) to a goal; ``fresh`` is only ever
    deleted (a shrinking predicate): a place is worth a detour only while fresh."""
    d = Domain("walk")
    Loc = d.type("loc")
    a, b, g = Var("a", Loc), Var("b", Loc), Var("g", Loc)
    at = d.predicate("at", a)
    road = d.predicate("road", a, b)
    fresh = d.predicate("fresh", a)
    r = d.robot
    move = r.action("move", a, b, pre=at(a) & road(a, b), effects=[~at(a), at(b), ~fresh(b)])
    reach = r.task("reach", g, done=at(g))
    r.method(reach, "step", params=[a, b], pre=at(a) & road(a, b),
             subtasks=[move(a, b), reach(g)])
    visit = r.task("visit", g)
    r.method(visit, "fresh", params=[], pre=fresh(g), subtasks=[reach(g)])
    return d


def walk_problem(agenda: str = "reach", goal: str = "l4", ahead: int = Limits.ground_ahead,
                 beliefs: tuple[BeliefWorld, ...] = (BeliefWorld(),)) -> Problem:
    init = {("at", ("l0",)), ("fresh", ("l2",))} | {("road", rd) for rd in ROADS}
    return Problem(name="walk", domain=walk_domain(), objects={"loc": LOCS},
                   init=frozenset(init), robot_agenda=((agenda, (goal,)),), human_agenda=(),
                   beliefs=beliefs, limits=Limits(ground_ahead=ahead))


def test_method_bindings_are_drawn_from_static_relations() -> None:
    """A free parameter bound by a static relation takes only the values the initial state
    gives it, in the order of the product of the types' objects."""
    g = ground_problem(walk_problem())
    t = g.task_index["reach(l4)"]
    got = [m.name for m in g.robot.methods[t]]
    want = [f"reach.step({x}, {y})" for x, y in product(LOCS, LOCS) if (x, y) in ROADS]
    assert got == want
    # a move along no road is never grounded
    assert "move(l0, l2)" not in g.task_index and "move(l1, l3)" in g.task_index


def test_on_demand_grounding_grounds_a_task_when_asked() -> None:
    g = ground_problem(walk_problem(), ahead=0)
    m = g.robot
    assert m.lazy and not dict(m.methods) and not dict(m.ops)  # nothing yet
    t = g.task_index["reach(l4)"]
    assert len(m.methods[t]) == len(ROADS)  # asked: grounded now, with its subtasks reached
    assert set(dict(m.methods)) == {t} and not dict(m.ops)
    step = g.task_index["move(l0, l1)"]
    assert step in m.ops and m.ops[step].name == "move(l0, l1)"
    # grounded ahead, nothing is on demand
    assert not ground_problem(walk_problem()).robot.lazy


def test_on_demand_grounding_gives_the_same_policy() -> None:
    """On demand or ahead, the same policy (symmetry off: it needs the whole model); the
    examples too."""
    for ahead in (0, 1, 3):
        lazy, eager = solve(walk_problem(ahead=ahead)), solve(walk_problem())
        assert lazy.policy is not None and eager.policy is not None
        assert lazy.policy.to_json() == eager.policy.to_json()
        assert lazy.policy.cost == 6  # l0 -> l1 -> l3 -> l4, the human passing each turn
    for name in ("cubes/p4.toml", "cooking/cooking2.toml", "sally-anne/defer.toml"):
        runs = [solve(ehatp.load(EXAMPLES / name, overrides={
            "limits.ground_ahead": ahead, "limits.symmetry": False})) for ahead in (0, 1000)]
        assert runs[0].policy is not None and runs[1].policy is not None
        assert runs[0].policy.to_json() == runs[1].policy.to_json(), name


def test_symmetry_needs_the_whole_model() -> None:
    path = EXAMPLES / "cubes" / "x1-4cubes-k2.toml"
    assert detect(ground_problem(ehatp.load(path))) is not None
    assert detect(ground_problem(ehatp.load(path), ahead=0)) is None


def test_a_predicate_nothing_makes_true_folds_to_false() -> None:
    """``fresh`` is only deleted: visiting a place not fresh at the start has no method; a
    belief world in which it is fresh makes it a plain fluent again."""
    g = ground_problem(walk_problem("visit", "l2"))
    assert len(g.robot.methods[g.task_index["visit(l2)"]]) == 1
    g = ground_problem(walk_problem("visit", "l4"))
    assert g.robot.methods[g.task_index["visit(l4)"]] == ()
    assert solve(walk_problem("visit", "l4")).status == "unsolvable"
    fresh_l4 = BeliefWorld(true=frozenset({("fresh", ("l4",))}))
    g = ground_problem(walk_problem("visit", "l4", beliefs=(fresh_l4,)))
    assert len(g.robot.methods[g.task_index["visit(l4)"]]) == 1


def test_ground_ahead_is_a_problem_limit() -> None:
    path = EXAMPLES / "cubes" / "p1.toml"
    p = ehatp.load(path, overrides={"limits.ground_ahead": 0})
    assert p.limits.ground_ahead == 0 and ground_problem(p).robot.lazy
    assert ehatp.load(path).limits.ground_ahead == Limits.ground_ahead
    with pytest.raises(InputError, match=r"\[limits\] ground_ahead: expected a whole number >= 0"):
        ehatp.load(path, overrides={"limits.ground_ahead": -1})


def test_the_random_generator_draws_grounding_on_demand() -> None:
    from ehatp.experiments import agreement, randomgen

    drawn = [randomgen.problem(seed).limits.ground_ahead for seed in range(100)]
    assert {0, 2, Limits.ground_ahead} == set(drawn)
    lazy = [seed for seed, a in enumerate(drawn) if a == 0][:20]
    outcomes = [agreement.check(seed, determinism=True) for seed in lazy]
    assert not [o for o in outcomes if o.failed], [o for o in outcomes if o.failed]


def _turn_problem() -> Problem:
    """``go(a)`` has one method, binding ``b``, ``p`` and ``d`` in that order: ``next(a, b,
    d)`` is static, ``here(p)`` fluent (``step`` moves it)."""
    d = Domain("turns")
    Loc, Dir = d.type("loc"), d.type("dir")
    a, b, p, x = Var("a", Loc), Var("b", Loc), Var("p", Loc), Var("d", Dir)
    nxt = d.predicate("next", a, b, x)
    here = d.predicate("here", p)
    r = d.robot
    step = r.action("step", a, b, pre=here(a), effects=[~here(a), here(b)])
    go = r.task("go", a)
    r.method(go, "turn", params=[b, p, x], pre=nxt(a, b, x) & here(p), subtasks=[step(p, b)])
    init = {("here", ("l0",)), ("next", ("l0", "l1", "n")), ("next", ("l1", "l2", "e"))}
    return Problem(name="turns", domain=d, objects={"loc": ["l0", "l1", "l2"],
                                                    "dir": ["n", "e"]},
                   init=frozenset(init), robot_agenda=(("go", ("l0",)),), human_agenda=(),
                   beliefs=(BeliefWorld(),))


def test_a_static_atom_narrows_each_parameter_it_names_and_a_fluent_one_none() -> None:
    """Derived by hand: ``b`` takes the values a fact ``next(l0, b, _)`` has (l1 alone, the
    direction projected out); ``p`` every location, ``here(p)`` ruling nothing out before
    any action; ``d`` the directions of ``next(l0, l1, d)`` (n). So 1 + 3 + 3 values are
    tried, where reading ``next`` only at ``d`` would try 3 + 9 + 3."""
    from ehatp.model.bindings import Facts, binding_plan, bindings

    prob = _turn_problem()
    g = ground_problem(prob)
    got = [m.name for m in g.robot.methods[g.task_index["go(l0)"]]]
    assert got == ["go.turn(l1, l0, n)", "go.turn(l1, l1, n)", "go.turn(l1, l2, n)"]
    method = prob.domain.robot.methods[0]
    a = method.task.params[0]
    tried = 0

    def met() -> None:
        nonlocal tried
        tried += 1

    objects = prob.all_objects()
    facts = Facts(prob.init, {"next": 3, "here": 1}, objects)
    plan = binding_plan(method, {a}, {"next"}, lambda c: "here" in str(c))
    assert plan[0] == [[], [], [], []]  # no conjunct is read: next offers, here is fluent
    out = bindings(method, {a: "l0"}, plan, facts, lambda f, b: f, met)
    assert out == [("l1", "l0", "n"), ("l1", "l1", "n"), ("l1", "l2", "n")]
    assert tried == 7


_LOCS = ["l0", "l1", "l2", "l3"]
_FACTS = [(x, y) for x in _LOCS for y in _LOCS]


@settings(max_examples=150, deadline=None, derandomize=True)
@given(link=st.sets(st.sampled_from(_FACTS), max_size=10),
       three=st.sets(st.tuples(st.sampled_from(_LOCS), st.sampled_from(_LOCS),
                               st.sampled_from(_LOCS)), max_size=10),
       shape=st.lists(st.tuples(st.sampled_from(["link", "three", "not-link", "here",
                                                 "not-here", "eq"]),
                                st.lists(st.integers(0, 3), min_size=3, max_size=3)),
                      min_size=1, max_size=4))
def test_bindings_are_the_product_without_what_a_conjunct_folds_to_false(
        link: set[tuple[str, str]], three: set[tuple[str, str, str]],
        shape: list[tuple[str, list[int]]]) -> None:
    """The bindings of a method with three parameters ``x``, ``y``, ``z`` (task argument
    ``a``) are, by definition (§1, "Grounding"), the product of their types' objects in order
    without every tuple for which some conjunct of the precondition grounds to false; the
    enumeration that narrows by static facts and leaves fluent literals out must give exactly
    those, on random static relations and preconditions."""
    from ehatp.model.bindings import binding_plan, bindings
    from ehatp.model.formula import FALSE, And, Formula, conj, eq
    from ehatp.model.grounding import _Grounder

    d = Domain("rand")
    Loc = d.type("loc")
    a, x, y, z = (Var(n, Loc) for n in "axyz")
    terms = [a, x, y, z]
    lk = d.predicate("link", a, x)
    th = d.predicate("three", a, x, y)
    here = d.predicate("here", a)
    r = d.robot
    step = r.action("step", a, x, pre=here(a), effects=[~here(a), here(x)])
    parts: list[Formula] = []
    for kind, ix in shape:
        u, v, w = (terms[i] for i in ix)
        if kind == "link":
            parts.append(lk(u, v))
        elif kind == "three":
            parts.append(th(u, v, w))
        elif kind == "not-link":
            parts.append(~lk(u, v))
        elif kind == "here":
            parts.append(here(u))
        elif kind == "not-here":
            parts.append(~here(u))
        else:
            parts.append(eq(u, v))
    pre = conj(*parts)
    go = r.task("go", a)
    r.method(go, "m", params=[x, y, z], pre=pre, subtasks=[step(a, x)])
    init = ({("here", ("l0",))} | {("link", f) for f in link} | {("three", f) for f in three})
    prob = Problem(name="rand", domain=d, objects={"loc": _LOCS}, init=frozenset(init),
                   robot_agenda=(("go", ("l0",)),), human_agenda=(), beliefs=(BeliefWorld(),))
    gr = _Grounder(prob)
    gr.run()
    method = d.robot.methods[0]
    plan = binding_plan(method, {a}, gr.factual, gr.never_false)
    for start in _LOCS:
        tb = {a: start}
        got = bindings(method, tb, plan, gr.facts, gr.ground_f, lambda: None)
        conjuncts = list(method.pre.args) if isinstance(method.pre, And) else [method.pre]
        want = [vals for vals in product(_LOCS, repeat=3)
                if all(gr.ground_f(c, {**tb, x: vals[0], y: vals[1], z: vals[2]}) != FALSE
                       for c in conjuncts)]
        assert got == want
