"""The worst-case search's lower bound (``ehatp.search.heuristic``, docs/semantics.md §7,
"Search"): hand-derived values, a bound that never overestimates and never drops by more than a
move costs, and the same policies with it as without it."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import ehatp
from ehatp import Costs, Domain, Var
from ehatp.epistemic.semantics import Semantics
from ehatp.experiments import agreement, randomgen
from ehatp.model.grounding import ground_problem
from ehatp.search.andor import GOAL, search
from ehatp.search.heuristic import INF, Heuristic, least_costs
from ehatp.search.interchangeable import detect
from ehatp.search.values import knuth

from .conftest import (
    EXAMPLES_DIR,
    TABLE1,
    Example,
    random_policies_agree,
    same_policy_either_way,
)
from .scenarios import problem, walk


def chores() -> Domain:
    """A robot with actions ``a(x)`` (cost 1, makes ``did(x)``), ``b`` (cost 3) and ``c(x)``
    (cost 2, skipped once ``did(x)``), tasks to derive bounds by hand, and a human who may
    ``h(x)`` (cost 1)."""
    d = Domain("chores")
    thing = d.type("thing")
    x = Var("x", thing)
    did = d.predicate("did", x)
    r = d.robot
    a = r.action("a", x, effects=[did(x)])
    b = r.action("b", cost=3)
    c = r.action("c", x, cost=2, done=did(x))
    # a task with a done-condition: skipped for free, whatever its methods cost
    tidy = r.task("tidy", x, done=did(x))
    r.method(tidy, "slow", subtasks=[b(), b()])
    # two methods: the cheaper one counts (2 < 3); the fewest actions is the other one (1)
    two = r.task("two")
    r.method(two, "cheap", params=[x], subtasks=[a(x), a(x)])
    r.method(two, "dear", subtasks=[b()])
    # recursion: with a way out it costs nothing, without one it never finishes
    loop = r.task("loop")
    r.method(loop, "again", params=[x], subtasks=[a(x), loop()])
    r.method(loop, "stop")
    forever = r.task("forever")
    r.method(forever, "again", params=[x], subtasks=[a(x), forever()])
    # mutual recursion: ping is b then pong; pong is a then ping, or nothing
    ping, pong = r.task("ping"), r.task("pong")
    r.method(ping, "go", subtasks=[b(), pong()])
    r.method(pong, "go", params=[x], subtasks=[a(x), ping()])
    r.method(pong, "stop")
    # a task with no method at all: the robot is blocked on it for good
    r.task("stuck")
    # unordered subtasks: an agenda with a block (docs/semantics.md §1, "Partial order")
    three = r.task("three")
    r.method(three, "any", params=[x], subtasks=[a(x), b(), c(x)], order=[])
    d.human.action("h", x)
    return d


def price(op: object) -> int:
    return op.cost  # type: ignore[attr-defined, no-any-return]


def one(op: object) -> int:
    return 1


def test_least_costs_by_hand() -> None:
    costs = least_costs(chores().robot, price)
    assert costs == {"a": 1, "b": 3, "c": 0, "tidy": 0, "two": 2, "loop": 0, "forever": INF,
                     "ping": 3, "pong": 0, "stuck": INF, "three": 4}
    counts = least_costs(chores().robot, one)
    assert counts == {"a": 1, "b": 1, "c": 0, "tidy": 0, "two": 1, "loop": 0, "forever": INF,
                      "ping": 1, "pong": 0, "stuck": INF, "three": 2}


def test_problem_costs_replace_the_domains() -> None:
    p = problem(chores(), init=[], robot=["two"], objects={"thing": ["o1"]},
                costs=Costs(actions={"a": 5}))
    h = Heuristic(ground_problem(p))
    sem, es = walk(p)
    assert h.agenda(es.robot_agenda, robot=True) == (3, 1)  # b (3) beats a twice (10)


def robot_only(robot: list[str], starts: str = "robot") -> ehatp.Problem:
    return problem(chores(), init=[], robot=robot, starts=starts,
                   objects={"thing": ["o1", "o2", "o3"]})


@pytest.mark.parametrize(("starts", "want"), [("robot", 5), ("human", 6)])
def test_the_human_passes_between_the_robots_actions(starts: str, want: int) -> None:
    """Three actions of the robot, nothing for the human: robot and human alternate, so the
    human passes between them (and before them when it starts): the bound is the optimum."""
    p = robot_only(["a(o1)", "a(o2)", "a(o3)"], starts=starts)
    sem, es = walk(p)
    assert Heuristic(sem.g)(es) == want
    r = ehatp.solve(p)
    assert r.policy is not None and r.policy.cost == want


def test_the_robot_waits_between_the_humans_actions() -> None:
    p = problem(chores(), init=[], human=["h(o1)", "h(o2)"], starts="human",
                objects={"thing": ["o1", "o2"]})
    sem, es = walk(p)
    assert Heuristic(sem.g)(es) == 3  # h, wait, h
    r = ehatp.solve(p)
    # the human may pass first and after the robot's first wait (§4): a bound, not the cost
    assert r.policy is not None and r.policy.cost == 5


def test_done_conditions_cost_nothing() -> None:
    sem, es = walk(robot_only(["tidy(o1)", "c(o2)"]))
    assert Heuristic(sem.g)(es) == 0
    # Table 1's agendas are tasks with done-conditions: no bound at the root
    for example in TABLE1:
        sem, es = walk(ehatp.load(example.path))
        assert Heuristic(sem.g)(es) == 0, example.name


def test_a_task_that_never_finishes_is_infinite() -> None:
    for task in ("forever", "stuck"):
        p = robot_only([task])
        sem, es = walk(p)
        assert Heuristic(sem.g)(es) == INF
        r = ehatp.solve(p)
        assert r.status == "unsolvable"


def test_a_block_counts_every_member() -> None:
    sem, es = walk(robot_only(["three"]), "a(o1)", "pass")
    assert any(not isinstance(t, int) for t in es.robot_agenda)  # a block is left
    assert Heuristic(sem.g).agenda(es.robot_agenda, robot=True) == (3, 1)  # b; c(o1) is done


def test_the_robot_alone_looks_one_action_ahead() -> None:
    """Derived by hand ("The robot alone", search/heuristic.py). The robot must ``tidy(o1)``
    and the human has no task. On its own the agenda bounds nothing: ``tidy`` has a
    done-condition, so it may be skipped for free (0, and 0 actions). But ``did(o1)`` is
    false and only ``a(o1)`` makes it true, which ``tidy`` never does: the only option now is
    the method ``slow``'s first ``b`` (3), leaving ``b`` (3), so the robot's actions cost 6,
    2 of them, and the human passes between them once (1): h = 7, exactly the optimum
    (b, pass, b)."""
    p = robot_only(["tidy(o1)"])
    g = ground_problem(p)
    root = Semantics(g).initial()
    assert Heuristic(g)(root) == 0
    ahead = Heuristic(g, Semantics(g).R)
    assert ahead.front(root.robot_agenda, root.true) == (6, 2)
    assert ahead(root) == 7
    r = ehatp.solve(p)
    assert r.policy is not None and r.policy.cost == 7
    with pytest.raises(ValueError, match="no task"):
        Heuristic(ground_problem(problem(chores(), init=[], robot=["tidy(o1)"],
                                         human=["h(o1)"], objects={"thing": ["o1"]})),
                  Semantics(g).R)


def test_requeueing_by_the_whole_bound_expands_as_queueing_by_it(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The search queues a node by its agendas' bound and requeues it, once out, by the
    whole bound (search/andor.py): the same nodes in the same order as queueing every node by
    the whole bound, so the same counts and the same policy, on random problems whose human
    has no task."""
    problems = [dataclasses.replace(p, human_agenda=()) for p in
                (randomgen.problem(seed) for seed in range(40)) if not p.steps.concurrent]
    lazy = [ehatp.solve(p) for p in problems]
    monkeypatch.setattr(Heuristic, "quick", Heuristic.__call__)
    eager = [ehatp.solve(p) for p in problems]
    looked = 0
    for a, b in zip(lazy, eager, strict=True):
        assert a.status == b.status
        assert (a.policy.to_json() if a.policy else None) == (
            b.policy.to_json() if b.policy else None)  # statistics included
        looked += a.stats["expanded"] != a.stats["generated"]
    assert len(problems) >= 30 and looked


def test_fewer_states_with_the_bound_same_policy() -> None:
    p = robot_only(["two", "two", "a(o1)", "ping"])
    off = search(ground_problem(p), heuristic=False)
    on = search(ground_problem(p), heuristic=True)
    assert on.stats.expanded < off.stats.expanded
    assert on.values is not None and off.values is not None
    assert on.values.value[on.root] == off.values.value[off.root]


# -- the same results -------------------------------------------------------------------------

@pytest.mark.parametrize("example", TABLE1, ids=str)
def test_table1_policies_do_not_change(example: Example) -> None:
    same_policy_either_way(ehatp.load(example.path), "heuristic", (True, False))


@pytest.mark.slow  # 300 random problems, each solved twice
def test_random_policies_do_not_change() -> None:
    assert random_policies_agree(range(300), {"heuristic": True}, {"heuristic": False}) >= 100


def test_the_bound_does_not_change_under_renaming() -> None:
    """Computed on the lifted models, the bound of a state is its canonical form's (§3)."""
    p = ehatp.load(EXAMPLES_DIR / "cubes" / "x1-4cubes-k2.toml")
    g = ground_problem(p)
    sym = detect(g)
    assert sym is not None
    h = Heuristic(g)
    out = search(g, max_states=2000, heuristic=False)
    for es in out.graph.states:
        assert h(sym.canon(es)[0]) == h(es)


# -- a lower bound, and consistent ------------------------------------------------------------

SETTINGS = settings(max_examples=120, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])


@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_the_bound_never_overestimates(seed: int) -> None:
    """On random problems: ``h(root)`` is at most the optimal worst-case cost; on the explored
    graph, ``h`` is at most every node's value, 0 at goals, and drops along an edge by at most
    the edge's cost (consistency, on which the stopping rule rests). Joint steps
    (docs/concurrent.md) search without it."""
    p = randomgen.problem(seed)
    assume(not p.steps.concurrent)
    _bound_holds(p, seed)


@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_the_bound_one_action_ahead_never_overestimates(seed: int) -> None:
    """The same on random problems whose human is given no task, where the robot's bound
    looks one action ahead ("The robot alone")."""
    p = randomgen.problem(seed)
    assume(not p.steps.concurrent)
    _bound_holds(dataclasses.replace(p, human_agenda=()), seed)


def _bound_holds(p: ehatp.Problem, seed: int) -> None:
    """The bound the search uses on ``p`` (one action ahead when the human has no task)
    never overestimates a node's value, is 0 at goals and consistent."""
    g = ground_problem(p)
    h = Heuristic(g, None if g.human_agenda else Semantics(g).R)
    out = search(g, max_states=agreement.MAX_STATES, timeout=10, heuristic=True)
    gr = out.graph
    if out.status == "solved":
        assert out.values is not None
        assert h(gr.states[out.root]) <= out.values.worst[out.root]
    value, _ = knuth(gr)
    for n, es in enumerate(gr.states):
        hn = h(es)
        assert hn <= value[n], seed
        if gr.status[n] == GOAL:
            assert hn == 0, seed
        for e in gr.edges[n]:
            if e.child >= 0:
                assert hn <= e.move.cost + h(gr.states[e.child]), (seed, e.move.label)
