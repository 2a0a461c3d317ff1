"""The focused search (docs/semantics.md §7, "Search, focused"; ``ehatp.search.bounds``): a
hand-derived run on a small graph, bounds that are the least fixpoint after every revision,
the states it expands among those the search by ``f`` expands, and the same policies with it
as without it."""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field
from typing import Any

import pytest

import ehatp
from ehatp.epistemic.state import HUMAN, ROBOT
from ehatp.experiments import randomgen
from ehatp.model.grounding import ground_problem
from ehatp.search import andor
from ehatp.search import bounds as bounds_module
from ehatp.search.andor import search
from ehatp.search.bounds import INF, Bounds
from ehatp.search.graph import DEAD, EXPANDED, GOAL, OPEN, Graph

from .conftest import (
    EXAMPLES,
    TABLE1,
    Example,
    policy_text,
    random_policies_agree,
    same_policy_either_way,
)
from .test_atom_layout import layout_problem

# --- a hand-built graph --------------------------------------------------------------------


@dataclass
class _Node:
    turn: int
    h: float


@dataclass
class _Move:
    cost: int


@dataclass
class _Edge:
    move: _Move
    child: int


@dataclass
class _Graph:
    """What :class:`Bounds` reads of a :class:`Graph`: states (their ``turn``), statuses,
    edges and parents; ``expand`` plays a search's expansion from a table."""

    states: list[_Node] = field(default_factory=list)
    status: bytearray = field(default_factory=bytearray)
    edges: list[tuple[_Edge, ...]] = field(default_factory=list)
    up: list[list[int]] = field(default_factory=list)

    def add(self, turn: int, h: float) -> int:
        self.states.append(_Node(turn, h))
        self.status.append(OPEN)
        self.edges.append(())
        self.up.append([])
        return len(self.states) - 1

    def parents(self, n: int) -> list[int]:
        return self.up[n]

    def expand(self, n: int, status: int, moves: list[tuple[int, int]]) -> None:
        self.status[n] = status
        self.edges[n] = tuple(_Edge(_Move(cost), c) for cost, c in moves)
        for _, c in moves:
            self.up[c].append(n)


def _bounds(gr: _Graph) -> Bounds:
    return Bounds(gr, lambda node: node.h)  # type: ignore[arg-type]


def test_a_hand_derived_run_expands_only_the_best_partial_policy() -> None:
    # r (robot, h 2) has two options of cost 1: a (human, h 1) and b (robot, h 1).
    gr = _Graph()
    r = gr.add(ROBOT, 2)
    b = _bounds(gr)
    assert b.walk(r) == [r]
    a, y = gr.add(HUMAN, 1), gr.add(ROBOT, 1)
    gr.expand(r, EXPANDED, [(1, a), (1, y)])
    b.added()
    b.revise([r])
    # low(r) = min(1 + 1, 1 + 1) = 2, unchanged: both options tie, both are tips
    assert b.low[r] == 2 and b.walk(r) == [y, a]  # depth first: the last pushed first
    # a's branches: a goal-to-be g1 (h 0) and x (robot, h 4); y's one option: g2 at cost 3
    g1, x, g2 = gr.add(ROBOT, 0), gr.add(ROBOT, 4), gr.add(ROBOT, 0)
    gr.expand(a, EXPANDED, [(1, g1), (1, x)])
    gr.expand(y, EXPANDED, [(3, g2)])
    b.added()
    b.revise([y, a])
    # low(a) = max(1 + 0, 1 + 4) = 5, low(y) = 3 + 0 = 3, low(r) = min(1 + 5, 1 + 3) = 4:
    # the walk leaves a (and x, g1) and follows y to g2
    assert (b.low[a], b.low[y], b.low[r]) == (5, 3, 4)
    assert b.walk(r) == [g2]
    gr.expand(g2, GOAL, [])
    b.revise([g2])
    # g2 a goal: its bound 0 is its h; no tip left, the root's bound 4 is its value; x and g1
    # were never expanded
    assert b.walk(r) == [] and b.low[r] == 4
    assert gr.status[x] == gr.status[g1] == OPEN


def test_a_rise_through_a_cycle_without_exit_makes_the_bounds_infinite() -> None:
    # p and q (robot) reach each other at cost 1; p also reaches t (h 3), which turns out a
    # dead end: no finite policy is left, and the pass must not count around the cycle
    gr = _Graph()
    p = gr.add(ROBOT, 1)
    b = _bounds(gr)
    q, t = gr.add(ROBOT, 1), gr.add(ROBOT, 3)
    gr.expand(p, EXPANDED, [(1, q), (1, t)])
    b.added()
    b.revise([p])
    assert b.low[p] == 2  # min(1 + 1, 1 + 3)
    assert b.walk(p) == [q]  # as the search does: walk, expand the tips, revise
    gr.expand(q, EXPANDED, [(1, p)])
    b.revise([q])
    # the least fixpoint of p = min(1 + q, 1 + 3), q = 1 + p: p = 4, q = 5
    assert (b.low[p], b.low[q]) == (4, 5)
    assert b.walk(p) == [t]
    gr.expand(t, DEAD, [])
    b.revise([t])
    # t rises to infinity; p's least option was t's (1 + 3 = 4), so p is affected; q's only
    # option is p, so q is too; the pass over t, p and q finalises none of them
    assert b.low[t] == b.low[p] == b.low[q] == INF
    # every option of an infinite root ties, and nothing is left to expand
    assert b.walk(p) == []


def test_a_human_branch_raised_above_its_bound_is_carried_up() -> None:
    # h (human) has branches u and v (robot, h 1 each) at cost 1: low(h) = 2. v alone rises
    # to 5: h, whose greatest branch was u's, must rise to 6 all the same
    gr = _Graph()
    hn = gr.add(HUMAN, 2)
    b = _bounds(gr)
    u, v = gr.add(ROBOT, 1), gr.add(ROBOT, 1)
    gr.expand(hn, EXPANDED, [(1, u), (1, v)])
    b.added()
    b.revise([hn])
    assert b.low[hn] == 2
    assert b.walk(hn) == [v, u]
    w = gr.add(ROBOT, 4)
    gr.expand(v, EXPANDED, [(1, w)])
    b.added()
    b.revise([v])
    assert (b.low[v], b.low[hn]) == (5, 6)


def test_two_edges_into_one_child_count_twice() -> None:
    """Derived by hand: a human node hn has two branches into u (cost 1 each, u robot,
    h 1): low(hn) = 1 + 1 = 2. u's one option reaches w (cost 1, h 4): low(u) = 5, and hn,
    both of whose branches wait on u, rises to 1 + 5 = 6 (it would stay infinite if the pass
    counted one branch down for the two)."""
    gr = _Graph()
    hn = gr.add(HUMAN, 2)
    b = _bounds(gr)
    u = gr.add(ROBOT, 1)
    gr.expand(hn, EXPANDED, [(1, u), (1, u)])
    b.added()
    b.revise([hn])
    assert b.low[hn] == 2
    w = gr.add(ROBOT, 4)
    gr.expand(u, EXPANDED, [(1, w)])
    b.added()
    b.revise([u])
    assert (b.low[u], b.low[hn]) == (5, 6)


def test_a_robot_node_whose_tied_options_all_rise_is_affected() -> None:
    """Derived by hand: a robot node p has three options of cost 1: x (h 1) and twice y
    (h 1): low(p) = 2, tied three times. y's one option reaches q (cost 1, h 0): low(y) stays
    1. Then x reaches a goal-to-be at cost 3 (low(x) = 3) and q one at cost 5 (low(q) = 5,
    so low(y) = 6), in one revision: p's three tied options all rise, the two into y
    together, and low(p) = min(1 + 3, 1 + 6) = 4."""
    gr = _Graph()
    p = gr.add(ROBOT, 2)
    b = _bounds(gr)
    x, y = gr.add(ROBOT, 1), gr.add(ROBOT, 1)
    gr.expand(p, EXPANDED, [(1, x), (1, y), (1, y)])
    q = gr.add(ROBOT, 0)
    gr.expand(y, EXPANDED, [(1, q)])
    b.added()
    b.revise([p, y])
    assert (b.low[p], b.low[y]) == (2, 1)
    g1, g2 = gr.add(ROBOT, 0), gr.add(ROBOT, 0)
    gr.expand(x, EXPANDED, [(3, g1)])
    gr.expand(q, EXPANDED, [(5, g2)])
    b.added()
    b.revise([q, x])  # x's rise is met first: p still has y's two options then
    assert (b.low[x], b.low[q], b.low[y], b.low[p]) == (3, 5, 6, 4)


# --- the planner's own graphs ----------------------------------------------------------------


def _fixpoint(gr: Graph, h: list[float]) -> list[float]:
    """Knuth's pass over ``gr`` with each open node's value its ``h``: the bounds' exact
    least fixpoint, written again from the module's docstring."""
    n_nodes = len(gr.states)
    value = [INF] * n_nodes
    final = bytearray(n_nodes)
    remaining = [0] * n_nodes
    worst: list[Any] = [0] * n_nodes
    heap: list[tuple[float, int]] = []
    for n in range(n_nodes):
        s = gr.status[n]
        if s == GOAL:
            heap.append((0, n))
        elif s == OPEN:
            heap.append((h[n], n))
        elif s == EXPANDED and gr.states[n].turn != ROBOT:
            edges = gr.edges[n]
            remaining[n] = len(edges) if edges and all(e.child >= 0 for e in edges) else -1
    heapq.heapify(heap)
    while heap:
        v, n = heapq.heappop(heap)
        if final[n]:
            continue
        final[n], value[n] = 1, v
        for p in set(gr.parents(n)):
            if final[p] or gr.status[p] != EXPANDED:
                continue
            for e in gr.edges[p]:
                if e.child != n:
                    continue
                cand = v + e.move.cost
                if gr.states[p].turn == ROBOT:
                    heapq.heappush(heap, (cand, p))
                elif remaining[p] > 0:
                    remaining[p] -= 1
                    worst[p] = max(worst[p], cand)
                    if remaining[p] == 0:
                        heapq.heappush(heap, (worst[p], p))
    return value


def _check_bounds(monkeypatch: pytest.MonkeyPatch, problem: ehatp.Problem,
                  symmetry: bool = False) -> int:
    """Solve ``problem``, checking at every walk that every bound is the least fixpoint; how
    many walks were checked."""
    real = Bounds.walk
    checked = 0

    def walk(self: Bounds, root: int) -> list[int]:
        nonlocal checked
        gr = self.gr
        h = [self.hfn(es) for es in gr.states]
        assert self.low == _fixpoint(gr, h)
        checked += 1
        return real(self, root)

    monkeypatch.setattr(Bounds, "walk", walk)
    out = search(ground_problem(problem), symmetry=symmetry, max_states=20_000)
    assert out.status in ("solved", "unsolvable", "state-limit")
    return checked


@pytest.mark.parametrize("example", TABLE1, ids=str)
def test_bounds_are_the_least_fixpoint_after_every_revision(
        monkeypatch: pytest.MonkeyPatch, example: Example) -> None:
    assert _check_bounds(monkeypatch, ehatp.load(example.path)) > 3


@pytest.mark.slow  # random problems, each searched with every walk checked
def test_bounds_on_random_problems(monkeypatch: pytest.MonkeyPatch) -> None:
    checked = [_check_bounds(monkeypatch, randomgen.problem(seed)) for seed in range(150)]
    assert sum(1 for c in checked if c) >= 100


def test_no_bound_falls(monkeypatch: pytest.MonkeyPatch) -> None:
    """A consistent ``h`` only lets bounds rise: the whole-graph pass kept for a fall is never
    run on the examples."""
    made: list[Bounds] = []
    real = Bounds.__init__

    def init(self: Bounds, *args: Any) -> None:
        real(self, *args)
        made.append(self)

    monkeypatch.setattr(Bounds, "__init__", init)
    for e in EXAMPLES:
        search(ground_problem(ehatp.load(e.path)))
    assert made and all(b.full_passes == 0 for b in made)


def _expanded(problem: ehatp.Problem, focus: bool, symmetry: bool) -> set[Any]:
    out = search(ground_problem(problem), focus=focus, symmetry=symmetry)
    gr = out.graph
    return {gr.states[n] for n in range(len(gr.states)) if gr.status[n] != OPEN}


@pytest.mark.parametrize("example", TABLE1, ids=str)
def test_the_focused_search_expands_a_subset_of_the_search_by_f(example: Example) -> None:
    p = ehatp.load(example.path)
    for symmetry in (True, False):
        focused, by_f = _expanded(p, True, symmetry), _expanded(p, False, symmetry)
        assert focused <= by_f and len(focused) < len(by_f)


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_example_has_the_same_policy_focused_or_not(example: Example) -> None:
    same_policy_either_way(ehatp.load(example.path), "focus")


def test_random_problems_have_the_same_policy_focused_or_not() -> None:
    assert random_policies_agree(range(60), {"focus": True}, {"focus": False}) >= 20


@pytest.mark.slow  # 600 random problems, each solved four times
def test_many_random_problems_have_the_same_policy_focused_or_not() -> None:
    assert random_policies_agree(range(60, 660), {"focus": True}, {"focus": False},
                                 (None, False)) >= 400


def test_an_unsolvable_problem_is_explained_as_the_search_by_f_explains_it() -> None:
    # random problem 24 has no policy; the focused search proves it, then explores everything
    # reachable, as the search by f does, and says why in the same words
    p = randomgen.problem(24)
    on, off = policy_text(p, focus=True), policy_text(p, focus=False)
    assert on[0] == "unsolvable" and on == off
    assert on[1].startswith("no policy exists: the goal needs")
    # the same states explored, once: no second search
    for symmetry in (True, False):
        assert _expanded(p, True, symmetry) == _expanded(p, False, symmetry)


def test_a_human_with_no_task_is_searched_by_f(monkeypatch: pytest.MonkeyPatch) -> None:
    """§7, "Search, focused": a human with no task only passes, so every human node has one
    branch; there the search runs by f and builds no bounds, where a human with a task (P2) is
    searched focused. Either way the policy is the one the option ``focus=False`` gives."""
    made: list[int] = []

    class Spy(Bounds):
        def __init__(self, *args: Any, **kw: Any) -> None:
            made.append(1)
            super().__init__(*args, **kw)

    monkeypatch.setattr(andor, "Bounds", Spy)
    alone = layout_problem("a_big")
    assert not alone.human_agenda
    search(ground_problem(alone))
    assert made == []
    search(ground_problem(ehatp.load(TABLE1[1].path)))
    assert made == [1]
    same_policy_either_way(alone, "focus")


def test_the_module_names_no_switch() -> None:
    # options are arguments (solve(focus=...), --no-focus), never module-level switches
    assert not [k for k, v in vars(bounds_module).items()
                if k.isupper() and isinstance(v, bool)]


def test_a_long_revision_looks_at_the_limits() -> None:
    # a chain of 3,000 robot nodes, each of h 0, whose last turns out a dead end: the rise
    # travels up the whole chain, and the walks and passes call the budget's check on the way
    gr = _Graph()
    chain = [gr.add(ROBOT, 0) for _ in range(3000)]
    calls = 0

    def check() -> None:
        nonlocal calls
        calls += 1

    b = Bounds(gr, lambda node: node.h, check)  # type: ignore[arg-type]
    for x, y in zip(chain, chain[1:], strict=False):
        gr.expand(x, EXPANDED, [(1, y)])
    b.revise(chain[:-1])  # each rises to 1 + the next's 0, then up the chain
    assert b.low[chain[0]] == 2999 and calls > 0
    calls = 0
    assert b.walk(chain[0]) == [chain[-1]]
    gr.expand(chain[-1], DEAD, [])
    b.revise([chain[-1]])
    assert b.low[chain[0]] == INF and calls >= 4
