"""Values on an explored AND/OR graph under the problem's objective, and the policy's choices
(docs/semantics.md §7, "Costs and optimality").

**Worst case** (the default): ``value(n)`` is the least fixpoint of: 0 at goals; ``min`` over a
robot node's edges and ``max`` over a human node's edges of ``cost(edge) + value(child)``;
infinite where no finite (acyclic) policy exists. It is computed with Knuth's generalisation of
Dijkstra's algorithm, backwards from the goals, so cycles never count as solved. Costs are
positive except the robot's zero-cost ``silence`` at a speech opening, so a chosen child is
always finalised before its parent and the policy is acyclic.

**Expected cost**: at a human node the weighted mean of ``cost(edge) + value(child)`` instead of
the maximum (``[objective.weights]``, by move label, else action name, else 1), over proper
acyclic policies only: a robot node's options are its *solvable* children (finite worst-case
value). See :func:`expected_order` for how cycles are handled.

**Ties** (§7): among robot options of equal value, the keys of ``[objective] ties`` in order:
``communications`` (``inform``/``ask`` moves and moves that speak while acting, in the whole
sub-policy), ``waits`` (human ``pass`` moves made waiting: its agenda unfinished, no action it
is sure of), ``length`` (the average branch length, decided choice by choice since the average
is not decomposable), ``worst-case`` / ``expected`` (that value of the chosen sub-policy); a
final tie goes to the first option in canonical order.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

from ..epistemic.semantics import ACTION, ASK, INFORM, WAIT, Move
from ..model.options import Objective, ObjectiveKind
from ..model.problem import Cost

if TYPE_CHECKING:
    from .andor import Graph

INF = float("inf")


@dataclass(frozen=True, slots=True)
class Tally:
    """Totals over a sub-policy (the chosen options below a node, every human branch)."""

    comms: int
    waits: int  # human passes made waiting for the robot or for information
    leaves: int
    length: int  # sum over leaves of their distance (in moves) from this node
    worst: Cost  # the sub-policy's worst-case cost
    mean: Cost | None  # its expected cost (None when neither objective nor ties need it)

    def key(self) -> tuple[int, int, Fraction]:
        """The default tie key: communications, waits, average branch length."""
        return (self.comms, self.waits, Fraction(self.length, self.leaves))


LEAF = Tally(0, 0, 1, 0, 0, 0)


@dataclass
class Values:
    value: list[Cost | float]  # under the objective; INF where no proper policy was found
    choice: dict[int, int]  # robot node -> index of the chosen edge
    tally: dict[int, Tally]  # the chosen sub-policy's totals
    worst: list[Cost | float]  # worst-case values (the same list as ``value`` for worst-case)
    exact: bool = True  # False: cycles restricted the expected-cost choices (§7)


def compute_values(gr: Graph, root: int, objective: Objective | None = None) -> Values:
    """§7: the values of ``gr`` under ``objective`` (default: the problem's), the robot's
    choice at every solved node and the totals of the chosen sub-policies."""
    obj = gr.sem.g.problem.objective if objective is None else objective
    worst, order = knuth(gr)
    n_nodes = len(worst)
    pos = [n_nodes] * n_nodes  # position in the Knuth order (n_nodes: never finalised)
    for i, n in enumerate(order):
        pos[n] = i
    need_mean = obj.kind == ObjectiveKind.EXPECTED or "expected" in obj.ties
    if obj.kind == ObjectiveKind.WORST_CASE:
        choice, tally = _choose(gr, order, lambda n, c: pos[c] < pos[n], obj, need_mean)
        return Values(worst, choice, tally, worst)
    if worst[root] == INF:
        return Values([INF] * n_nodes, {}, {}, worst)
    topo, allowed, exact = expected_order(gr, root, worst, pos)
    choice, tally = _choose(gr, topo, allowed, obj, need_mean)
    value: list[Cost | float] = [INF] * n_nodes
    for n, t in tally.items():
        assert t.mean is not None
        value[n] = t.mean
    return Values(value, choice, tally, worst, exact)


def knuth(gr: Graph) -> tuple[list[Cost | float], list[int]]:
    """§7, worst case: the least fixpoint of the min/max equations by Knuth's generalisation of
    Dijkstra's algorithm; returns the values and the order in which nodes were finalised
    (every child a node's value comes from is finalised before it)."""
    from .andor import GOAL

    n_nodes = len(gr.states)
    value: list[Cost | float] = [INF] * n_nodes
    final = [False] * n_nodes
    remaining = [0] * n_nodes
    worst: list[Cost] = [0] * n_nodes
    heap: list[tuple[Cost, int]] = []
    for n in range(n_nodes):
        if gr.status[n] == GOAL:
            heap.append((0, n))
        elif not gr.is_robot(n):
            edges = gr.edges[n]
            remaining[n] = len(edges) if all(e.child >= 0 for e in edges) and edges else -1
    heapq.heapify(heap)
    order: list[int] = []
    while heap:
        v, n = heapq.heappop(heap)
        if final[n]:
            continue
        final[n] = True
        value[n] = v
        order.append(n)
        for p in set(gr.parents[n]):
            if final[p]:
                continue
            for e in gr.edges[p]:
                if e.child != n:
                    continue
                cand = v + e.move.cost
                if gr.is_robot(p):
                    if cand < value[p]:
                        value[p] = cand
                        heapq.heappush(heap, (cand, p))
                elif remaining[p] > 0:
                    remaining[p] -= 1
                    if cand > worst[p]:
                        worst[p] = cand
                    if remaining[p] == 0:
                        heapq.heappush(heap, (worst[p], p))
    return value, order


def expected_order(gr: Graph, root: int, worst: list[Cost | float], pos: list[int]
                   ) -> tuple[list[int], Callable[[int, int], bool], bool]:
    """§7, expected cost: the order of the backward pass, the robot options it may take, and
    whether the result is exact.

    Only proper policies count, so the graph is the *solvable* one (nodes of finite worst-case
    value; a robot node keeps its solvable children, a human node all of its children). Its
    strongly connected components reachable from the root, children first, give the order.
    Without a cycle every option is allowed and the backward pass is exact. Inside a cycle an
    option is allowed only towards a child finalised earlier in the worst-case pass (a human
    node's children always are, and so is a robot node's worst-case choice), which breaks
    every cycle; the values are then those of the best such policy, not proven optimal.

    The backward pass over this order (:func:`_choose`), in GTPyhop-style pseudo-code::

        expected_values(graph, root):
            solvable = {n : worst(n) < inf}
            for each component C of solvable, reachable from root, children first:
                for n in C in worst-case finalisation order:
                    if n is a goal:
                        E(n) = 0
                    elif the human moves at n:
                        E(n) = sum(w(m) * (cost(m) + E(child(m))) for m in moves(n))
                               / sum(w(m) for m in moves(n))
                    else:
                        options = [m for m in moves(n) if child(m) in solvable
                                   and (child(m) not in C or finalised_before(child(m), n))]
                        choice(n) = argmin over options of
                                    (cost(m) + E(child(m)), tie keys, canonical order)
                        E(n) = cost(choice(n)) + E(child(choice(n)))
            exact = no component has a cycle
            return E, choice, exact
    """
    n_nodes = len(worst)
    kids: dict[int, list[int]] = {}

    def children(n: int) -> list[int]:
        ks = kids.get(n)
        if ks is None:
            ks = kids[n] = [e.child for e in gr.edges[n]
                            if e.child >= 0 and worst[e.child] != INF]
        return ks

    # Tarjan's strongly connected components, iteratively; components come out children first
    index = [-1] * n_nodes
    low = [0] * n_nodes
    on_stack = [False] * n_nodes
    comp = [-1] * n_nodes
    stack: list[int] = []
    order: list[int] = []
    exact = True
    counter = n_comps = 0
    index[root] = low[root] = counter
    counter += 1
    stack.append(root)
    on_stack[root] = True
    work: list[tuple[int, int]] = [(root, 0)]
    while work:
        n, i = work[-1]
        ks = children(n)
        if i < len(ks):
            work[-1] = (n, i + 1)
            c = ks[i]
            if index[c] < 0:
                index[c] = low[c] = counter
                counter += 1
                stack.append(c)
                on_stack[c] = True
                work.append((c, 0))
            elif on_stack[c] and index[c] < low[n]:
                low[n] = index[c]
            continue
        work.pop()
        if work and low[n] < low[work[-1][0]]:
            low[work[-1][0]] = low[n]
        if low[n] != index[n]:
            continue
        members: list[int] = []
        while True:
            x = stack.pop()
            on_stack[x] = False
            comp[x] = n_comps
            members.append(x)
            if x == n:
                break
        if len(members) > 1 or n in ks:
            exact = False
        members.sort(key=pos.__getitem__)
        order.extend(members)
        n_comps += 1

    def allowed(n: int, c: int) -> bool:
        return worst[c] != INF and (comp[c] != comp[n] or pos[c] < pos[n])

    return order, allowed, exact


def _choose(gr: Graph, order: list[int], allowed: Callable[[int, int], bool], obj: Objective,
            need_mean: bool) -> tuple[dict[int, int], dict[int, Tally]]:
    """Visit ``order`` (children before parents): pick each robot node's option among the
    ``allowed`` ones by the objective's value, then the tie keys, then canonical order; total
    each chosen sub-policy."""
    from .andor import GOAL

    expected = obj.kind == ObjectiveKind.EXPECTED
    getters = [_TIE_KEYS[k] for k in obj.ties]
    weights: dict[str, Fraction] = {}

    def weight(m: Move) -> Fraction:
        w = weights.get(m.label)
        if w is None:
            w = weights[m.label] = obj.weight(m.label, gr.sem.describe(m).name)
        return w

    choice: dict[int, int] = {}
    tally: dict[int, Tally] = {}
    for n in order:
        if gr.status[n] == GOAL:
            tally[n] = LEAF
            continue
        edges = gr.edges[n]
        if gr.is_robot(n):
            best: tuple[Cost, tuple[object, ...], int] | None = None
            best_t: Tally | None = None
            for i, e in enumerate(edges):
                c = e.child
                if c < 0 or c not in tally or not allowed(n, c):
                    continue
                t = _through(e.move, tally[c], need_mean)
                v = t.mean if expected else t.worst
                assert v is not None
                k = (v, tuple(get(t) for get in getters), i)
                if best is None or k < best:
                    best, best_t = k, t
            assert best is not None and best_t is not None
            choice[n] = best[2]
            tally[n] = best_t
        else:
            parts = [_through(e.move, tally[e.child], need_mean) for e in edges]
            mean: Cost | None = None
            if need_mean:
                mean = weighted_mean([weight(e.move) for e in edges],
                                     [p.mean for p in parts if p.mean is not None])
            tally[n] = Tally(sum(p.comms for p in parts), sum(p.waits for p in parts),
                             sum(p.leaves for p in parts), sum(p.length for p in parts),
                             max(p.worst for p in parts), mean)
    return choice, tally


_TIE_KEYS: dict[str, Callable[[Tally], object]] = {
    "communications": lambda t: t.comms,
    "waits": lambda t: t.waits,
    "length": lambda t: Fraction(t.length, t.leaves),
    "worst-case": lambda t: t.worst,
    "expected": lambda t: t.mean,
}


def weighted_mean(weights: list[Fraction], xs: list[Cost]) -> Cost:
    """§7: ``sum(w * x) / sum(w)``, exact (an int when whole)."""
    m = sum((w * x for w, x in zip(weights, xs, strict=True)), Fraction(0)) / sum(weights)
    return int(m) if isinstance(m, Fraction) and m.denominator == 1 else m


def speaks(m: Move) -> bool:
    """A communication (§7 ties): ``inform``, ``ask``, or a move that speaks while acting."""
    return m.kind in (INFORM, ASK) or (m.kind in (ACTION, WAIT) and m.atoms != 0)


def _through(m: Move, t: Tally, need_mean: bool) -> Tally:
    """The child's tally seen from its parent, one move ``m`` further up."""
    return Tally(t.comms + (1 if speaks(m) else 0), t.waits + (1 if m.waits else 0),
                 t.leaves, t.length + t.leaves, m.cost + t.worst,
                 m.cost + t.mean if need_mean and t.mean is not None else None)
