"""Worst-case values on an explored AND/OR graph, and the policy's choices.

``value(n)`` is the least fixpoint of: 0 at goals; ``min`` over a robot node's edges and
``max`` over a human node's edges of ``cost(edge) + value(child)``; infinite where no finite
(acyclic) policy exists. It is computed with Knuth's generalisation of Dijkstra's algorithm,
backwards from the goals, so cycles never count as solved.

Ties between robot options of equal worst-case cost are broken, in this order, by fewer
communications, fewer human passes, then the shorter average branch; the last rule is applied
choice by choice (the average is not decomposable), and a final tie goes to the first option in
canonical order. Positive costs make every chosen child's value strictly smaller than its
parent's, so processing nodes by value visits children first and the policy is acyclic.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

from ..epistemic.semantics import ASK, INFORM, PASS
from ..model.problem import Cost

if TYPE_CHECKING:
    from .andor import Graph

INF = float("inf")


@dataclass(frozen=True, slots=True)
class Tally:
    """Totals over a subtree of the policy."""

    comms: int
    passes: int
    leaves: int
    length: int  # sum over leaves of their distance from this node

    def key(self) -> tuple[int, int, Fraction]:
        return (self.comms, self.passes, Fraction(self.length, self.leaves))


@dataclass
class Values:
    value: list[Cost | float]
    choice: dict[int, int]  # robot node -> index of the chosen edge
    tally: dict[int, Tally]


def compute_values(gr: Graph, root: int) -> Values:
    from .andor import GOAL

    n_nodes = len(gr.states)
    value: list[Cost | float] = [INF] * n_nodes
    final = [False] * n_nodes
    remaining = [0] * n_nodes
    worst: list[Cost] = [0] * n_nodes
    # edge costs from parent to child (several edges may join the same pair)
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
    choice: dict[int, int] = {}
    tally: dict[int, Tally] = {}
    for n in order:
        if gr.status[n] == GOAL:
            tally[n] = Tally(0, 0, 1, 0)
            continue
        edges = gr.edges[n]
        if gr.is_robot(n):
            best: tuple[tuple[int, int, Fraction], int] | None = None
            for i, e in enumerate(edges):
                if e.child < 0 or not final[e.child] or e.move.cost + value[e.child] != value[n]:
                    continue
                t = _through(e.move.kind, tally[e.child])
                k = (t.key(), i)
                if best is None or k < best:
                    best = k
            assert best is not None
            choice[n] = best[1]
            tally[n] = _through(edges[best[1]].move.kind, tally[edges[best[1]].child])
        else:
            parts = [_through(e.move.kind, tally[e.child]) for e in edges]
            tally[n] = Tally(sum(p.comms for p in parts), sum(p.passes for p in parts),
                             sum(p.leaves for p in parts), sum(p.length for p in parts))
    return Values(value, choice, tally)


def _through(kind: str, t: Tally) -> Tally:
    """The child's tally seen from its parent, one edge of ``kind`` further up."""
    return Tally(t.comms + (1 if kind in (INFORM, ASK) else 0),
                 t.passes + (1 if kind == PASS else 0), t.leaves, t.length + t.leaves)
