"""AND/OR graph search over epistemic states.

Nodes are expanded in order of their cheapest path cost from the root ``g`` (breadth-first when
every move costs 1, as in the paper's Algorithm 1), with duplicate detection. A node is *solved*
when it is a goal, a robot node with a solved child, or a human node whose children are all
solved; solved labels propagate upwards as they appear (the paper's propagate step).

Stopping rule (docs/semantics.md §7, "Search"): for the worst-case objective, once the root is
solved, worst-case values are computed on the explored graph (:mod:`.values`). If the root's
value V is at most the ``g`` of every node expanded so far, the policy is optimal: a cheaper
policy only visits nodes with ``g`` below V, all of which are expanded. The result does not
depend on exploration order (values are a least fixpoint). Expected cost has no such bound (a
cheap mean may hide a long rare branch), so for it the whole reachable graph is explored before
the values are computed. Time and state limits stop either search; the best policy found so far
is then returned, not proven optimal.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from ..epistemic.semantics import DEAD_PASSIVE_RUN, Move, Semantics
from ..epistemic.state import ROBOT, EState
from ..errors import InputError
from ..model.grounding import Grounded
from ..model.options import ObjectiveKind
from ..model.problem import Cost
from .values import Values, compute_values

OPEN, EXPANDED, GOAL, DEAD = 0, 1, 2, 3
KIND_ORDER = {"silence": -1, "action": 0, "inform": 1, "ask": 2, "wait": 3, "pass": 4}


@dataclass(slots=True)
class Edge:
    move: Move
    child: int  # -1 when the move fails


@dataclass
class Stats:
    generated: int = 0  # epistemic states generated (children created, duplicates included)
    distinct: int = 0  # distinct epistemic states
    expanded: int = 0
    max_worlds: int = 0  # largest |W| (the designated world is not counted separately)
    time_s: float = 0.0

    def as_dict(self) -> dict[str, int | float]:
        return {"generated": self.generated, "distinct": self.distinct,
                "expanded": self.expanded, "max_worlds": self.max_worlds,
                "time_ms": round(self.time_s * 1000, 1)}


@dataclass
class Graph:
    sem: Semantics
    states: list[EState] = field(default_factory=list)
    index: dict[EState, int] = field(default_factory=dict)
    status: list[int] = field(default_factory=list)
    dead_why: dict[int, str] = field(default_factory=dict)
    edges: list[list[Edge]] = field(default_factory=list)
    parents: list[list[int]] = field(default_factory=list)  # one entry per edge into the node
    g: list[Cost] = field(default_factory=list)
    depth: list[int] = field(default_factory=list)
    solved: list[bool] = field(default_factory=list)
    pending: list[int] = field(default_factory=list)  # human nodes: unsolved edges left

    def add(self, es: EState, g: Cost, depth: int) -> int:
        i = len(self.states)
        self.states.append(es)
        self.index[es] = i
        self.status.append(OPEN)
        self.edges.append([])
        self.parents.append([])
        self.g.append(g)
        self.depth.append(depth)
        self.solved.append(False)
        self.pending.append(0)
        return i

    def is_robot(self, n: int) -> bool:
        return self.states[n].turn == ROBOT


@dataclass
class SearchOutcome:
    graph: Graph
    root: int
    stats: Stats
    status: str  # "solved" | "unsolvable" | "timeout" | "state-limit"
    values: Values | None
    optimal: bool


Progress = Callable[[Stats, int], None]


def search(grounded: Grounded, *, timeout: float | None = None, max_states: int | None = None,
           max_depth: int | None = None, progress: Progress | None = None) -> SearchOutcome:
    limits = grounded.problem.limits
    timeout = limits.timeout if timeout is None else timeout
    max_states = limits.max_states if max_states is None else max_states
    max_depth = limits.max_depth if max_depth is None else max_depth
    # worst case: stop as soon as the optimum is proven; expected cost: explore everything
    early_stop = grounded.problem.objective.kind == ObjectiveKind.WORST_CASE
    sem = Semantics(grounded)
    gr = Graph(sem)
    stats = Stats()
    start = time.perf_counter()
    root_state = sem.initial()
    for i, label in enumerate(grounded.problem.after):
        try:
            root_state = sem.follow(root_state, label).child  # type: ignore[assignment]
        except ValueError as e:
            raise InputError(grounded.problem.source, f"[problem] after, step {i + 1}", str(e),
                             "give a move possible at that point") from None
    root = gr.add(root_state, 0, 0)
    stats.generated = stats.distinct = 1
    stats.max_worlds = len(root_state.worlds)
    heap: list[tuple[Cost, int, int]] = [(0, 0, root)]
    level: Cost = 0
    status = "unsolvable"
    values: Values | None = None
    optimal = False
    while heap:
        g, _, n = heapq.heappop(heap)
        if gr.status[n] != OPEN or g > gr.g[n]:
            continue
        if g > level:
            # every node with g <= level is expanded: the optimum may be proven now
            if early_stop and gr.solved[root]:
                values = compute_values(gr, root)
                if values.value[root] <= level:
                    status, optimal = "solved", True
                    break
            level = g
        if stats.expanded & 255 == 0:
            elapsed = time.perf_counter() - start
            if progress is not None:
                stats.time_s = elapsed
                progress(stats, len(heap))
            if timeout is not None and elapsed > timeout:
                status = "timeout"
                break
        if stats.distinct >= max_states:
            status = "state-limit"
            break
        _expand(gr, n, heap, stats, max_depth)
    else:
        if gr.solved[root]:
            values = compute_values(gr, root)
            status, optimal = "solved", values.exact
    if status in ("timeout", "state-limit") and gr.solved[root]:
        values = compute_values(gr, root)  # best policy found so far, not proven optimal
    stats.time_s = time.perf_counter() - start
    return SearchOutcome(gr, root, stats, status, values, optimal)


def _expand(gr: Graph, n: int, heap: list[tuple[Cost, int, int]], stats: Stats,
            max_depth: int) -> None:
    sem = gr.sem
    es = gr.states[n]
    stats.expanded += 1
    if sem.is_goal(es):
        gr.status[n] = GOAL
        _mark_solved(gr, n)
        return
    if es.passive >= DEAD_PASSIVE_RUN:
        gr.status[n], gr.dead_why[n] = DEAD, "inactivity deadlock (three passive moves)"
        return
    if gr.depth[n] >= max_depth:
        gr.status[n], gr.dead_why[n] = DEAD, f"depth limit {max_depth} reached"
        return
    gr.status[n] = EXPANDED
    moves = sorted(sem.moves(es), key=lambda m: (KIND_ORDER[m.kind], m.label,
                                                 m.child is None, m.child or ()))
    g0, d0 = gr.g[n], gr.depth[n] + 1
    edges = gr.edges[n]
    for m in moves:
        if m.child is None:
            edges.append(Edge(m, -1))
            continue
        stats.generated += 1
        child = m.child
        c = gr.index.get(child)
        g1 = g0 + m.cost
        if c is None:
            c = gr.add(child, g1, d0)
            stats.distinct += 1
            if len(child.worlds) > stats.max_worlds:
                stats.max_worlds = len(child.worlds)
            heapq.heappush(heap, (g1, c, c))
        elif g1 < gr.g[c] and gr.status[c] == OPEN:
            gr.g[c], gr.depth[c] = g1, d0
            heapq.heappush(heap, (g1, c, c))
        edges.append(Edge(m, c))
        gr.parents[c].append(n)
    if not gr.is_robot(n):
        gr.pending[n] = len(edges) + (1 if not edges else 0)
    for e in edges:
        if e.child >= 0 and gr.solved[e.child]:
            _child_solved(gr, n)


def _child_solved(gr: Graph, p: int) -> None:
    if gr.solved[p]:
        return
    if gr.is_robot(p):
        _mark_solved(gr, p)
    else:
        gr.pending[p] -= 1
        if gr.pending[p] == 0:
            _mark_solved(gr, p)


def _mark_solved(gr: Graph, n: int) -> None:
    stack = [n]
    gr.solved[n] = True
    while stack:
        c = stack.pop()
        for p in gr.parents[c]:
            if gr.solved[p] or gr.status[p] != EXPANDED:
                continue
            if gr.is_robot(p):
                gr.solved[p] = True
                stack.append(p)
            else:
                gr.pending[p] -= 1
                if gr.pending[p] == 0:
                    gr.solved[p] = True
                    stack.append(p)
