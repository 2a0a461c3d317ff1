"""AND/OR graph search over epistemic states (docs/semantics.md §7, "Search").

Nodes are expanded in order of ``f = g + h``: their cheapest path cost from the root ``g`` plus,
for the worst-case objective, a lower bound ``h`` on the cost still to pay (:mod:`.heuristic`);
for expected cost ``h = 0``, so the order is ``g``'s, breadth-first when every move costs 1, as
in the paper's Algorithm 1. Within one ``f``, smaller ``g`` first, then creation order. Duplicates
are detected. A node is *solved* when it is a goal, a robot node with a solved child, or a human
node whose children are all solved; solved labels propagate upwards as they appear (the paper's
propagate step).

Stopping rule (§7), for the worst-case objective. From the first goal on, the worst-case values
are kept up to date as the graph grows (:class:`~.values.LiveWorst`, the same least fixpoint the
full pass computes), so the root's value V is at hand as soon as the root is solved. The search
stops, the optimum proven, when it is about to expand a node of a new ``f`` level and V is below
that ``f``. Proof: ``h`` is consistent (``h(n) <= cost + h(c)`` along every edge, and 0 at
goals), so ``f`` never decreases along a path; nodes leave the queue in order of ``f``, each
with its cheapest ``g`` ``g*``; when a node of ``f = F`` leaves it, every node the root reaches
with ``g* + h < F`` has been expanded. Every node ``x`` of a policy of value V' has
``g*(x) + h(x) <= g(its path in the policy) + value(x) <= V'`` (``h`` is a lower bound, and
every branch through ``x`` costs at most V'). So a policy cheaper than V would lie wholly in the
expanded graph, and V, a least fixpoint over that graph, would be at most its cost: there is
none. Nodes with ``f = V`` are expanded too, which keeps the chosen policy the one a search by
``g`` alone (``h = 0``) chooses: every node of an optimal policy, and of any option tied with one
at a node of it, has ``g* + value <= V``, so ``f <= V``; both searches expand those nodes, with
the same moves, the same values and the same tie keys (§7, "Ties"). Only the states counted
differ (and, with symmetry, whether an order-dependent decision met in a state only one search
expands sends it back to full states). Expected cost has no such bound (a cheap mean may hide a
long rare branch), so for it the whole reachable graph is explored before the values are
computed. State, time and memory limits stop either search (:mod:`.limits`; ``max_states`` is
never exceeded, an expansion that would is not made); the best policy found so far is then
returned, not proven optimal.

Memory: the graph keeps one :class:`EState` per distinct state, with the worlds tuples and true
states shared between the nodes that have equal ones; an edge keeps the child's id and a move
*descriptor* shared by every edge with the same move (its ``child`` state is not kept, except
for ``inform``, whose description reads the child's true state); per-node flags are bytes.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable
from dataclasses import dataclass

from ..epistemic.semantics import DEAD_PASSIVE_RUN, INFORM, Move, Semantics
from ..epistemic.state import ROBOT, EState, Worlds
from ..errors import InputError
from ..model.grounding import Grounded
from ..model.options import ObjectiveKind
from ..model.problem import Cost
from . import heuristic as _heuristic
from .heuristic import Bound, Heuristic
from .limits import Budget, LimitReached
from .symmetry import Symmetry, SymSemantics, detect
from .values import LiveWorst, Values, compute_values

OPEN, EXPANDED, GOAL, DEAD = 0, 1, 2, 3
KIND_ORDER = {"silence": -1, "action": 0, "inform": 1, "announce": 2, "ask": 3, "answer": 4,
              "wait": 5, "pass": 6}
Entry = tuple[Bound, Cost, int]  # the queue's: (f, g, node id)


@dataclass(slots=True)
class Edge:
    """One option (robot) or branch (human) of a node. ``move`` describes the move (shared by
    the edges of equal moves; its ``child`` state is not kept: None, or for ``inform`` the
    child node's state); ``child`` is the child node's id, -1 when the move fails. Over
    symmetry-reduced states (:mod:`.symmetry`), ``perm`` is the renaming (an id) that maps the
    move's real child to the child node's canonical state; 0 is none."""

    move: Move
    child: int
    perm: int = 0


NO_EDGES: tuple[Edge, ...] = ()


@dataclass
class Stats:
    generated: int = 0  # epistemic states generated (children created, duplicates included)
    distinct: int = 0  # distinct epistemic states
    expanded: int = 0
    max_worlds: int = 0  # largest |W| (the designated world is not counted separately)
    time_s: float = 0.0
    # for progress displays only (not reported): the work under way and the search frontier
    phase: str = "search"
    frontier: int = 0

    def as_dict(self) -> dict[str, int | float]:
        return {"generated": self.generated, "distinct": self.distinct,
                "expanded": self.expanded, "max_worlds": self.max_worlds,
                "time_ms": round(self.time_s * 1000, 1)}


class Graph:
    """The explored AND/OR graph, as parallel per-node arrays indexed by node id."""

    def __init__(self, sem: Semantics) -> None:
        self.sem = sem
        self.states: list[EState] = []
        self.index: dict[EState, int] = {}
        self.status = bytearray()  # OPEN, EXPANDED, GOAL or DEAD
        self.dead_why: dict[int, str] = {}
        self.edges: list[tuple[Edge, ...]] = []  # in canonical move order, once expanded
        # the parents, one entry per edge into the node: -1 for none, a node id for one, a
        # list beyond (most nodes have one parent)
        self._parents: list[int | list[int]] = []
        self.g: list[Cost] = []
        # §6: each node's least number of moves from the root over the paths found so far
        self.depth: list[int] = []
        self.depth_cut: set[int] = set()  # dead ends made by the depth limit alone
        self.solved = bytearray()
        self.pending: list[int] = []  # human nodes: unsolved edges left
        self._worlds: dict[Worlds, Worlds] = {}
        self._trues: dict[int, int] = {}
        self._moves: dict[tuple[object, ...], Move] = {}
        # search over canonical states (docs/semantics.md §3, "Symmetry"): the renamings, and
        # the one mapping the real root to the root node's state
        self.sym: Symmetry | None = None
        self.root_perm = 0

    def add(self, es: EState, g: Cost, depth: int, parent: int = -1) -> int:
        """A new node for ``es`` (worlds and true state shared with equal ones)."""
        w = self._worlds.setdefault(es.worlds, es.worlds)
        t = self._trues.setdefault(es.true, es.true)
        if w is not es.worlds or t is not es.true:
            es = es._replace(true=t, worlds=w)
        i = len(self.states)
        self.states.append(es)
        self.index[es] = i
        self.status.append(OPEN)
        self.edges.append(NO_EDGES)
        self._parents.append(parent)
        self.g.append(g)
        self.depth.append(depth)
        self.solved.append(0)
        self.pending.append(0)
        return i

    def add_parent(self, c: int, p: int) -> None:
        ps = self._parents[c]
        if isinstance(ps, list):
            ps.append(p)
        elif ps < 0:
            self._parents[c] = p
        else:
            self._parents[c] = [ps, p]

    def parents(self, n: int) -> list[int]:
        """One entry per edge into ``n`` (a parent with two edges to ``n`` is there twice)."""
        ps = self._parents[n]
        if isinstance(ps, list):
            return ps
        return [] if ps < 0 else [ps]

    def descriptor(self, m: Move, child: int) -> Move:
        """``m`` without its child state, shared between equal moves (see :class:`Edge`)."""
        if (m.kind == INFORM or m.atoms) and child >= 0:  # what is told reads the child's T
            return Move(m.agent, m.kind, m.label, m.cost, self.states[child], m.op, m.atoms,
                        m.failure, m.waits)
        key = (m.agent, m.kind, m.label, m.cost, m.op, m.atoms, m.failure, m.waits)
        d = self._moves.get(key)
        if d is None:
            d = self._moves[key] = Move(m.agent, m.kind, m.label, m.cost, None, m.op, m.atoms,
                                        m.failure, m.waits)
        return d

    def is_robot(self, n: int) -> bool:
        return self.states[n].turn == ROBOT


@dataclass
class SearchOutcome:
    graph: Graph
    root: int
    stats: Stats
    # "solved" | "unsolvable" | "timeout" | "state-limit" | "memory-limit" | "depth-limit"
    status: str
    values: Values | None
    optimal: bool
    reason: str = ""  # which limit stopped the search, in words


Progress = Callable[[Stats, int], None]


def search(grounded: Grounded, *, timeout: float | None = None, max_states: int | None = None,
           max_depth: int | None = None, progress: Progress | None = None,
           max_memory: int | None = None, budget: Budget | None = None,
           stats: Stats | None = None, symmetry: bool = False,
           heuristic: bool | None = None) -> SearchOutcome:
    """§7: explore from the root until the optimum is proven (worst case), everything
    reachable is explored (expected cost), or a limit is reached; then the values.

    Limits default to the problem's ``[limits]``; ``budget`` (time and memory for the whole
    solve, :class:`~.limits.Budget`) replaces ``timeout`` and ``max_memory`` when given.
    ``progress(stats, frontier)`` is called about 20 times a second; ``stats``, when given, is
    the object the search keeps its statistics in. With ``symmetry`` the nodes are canonical
    states (docs/semantics.md §3, "Symmetry"; :mod:`.symmetry`); when a decision taken by
    index or name order makes that unsound the search stops with status
    ``"symmetry-unsafe"`` (the planner then solves again without it). ``heuristic`` (default:
    on, unless :data:`.heuristic.OVERRIDE` says otherwise) orders a worst-case search by
    ``g + h`` (:mod:`.heuristic`); the policy is the same either way, fewer states are
    expanded with it."""
    limits = grounded.problem.limits
    max_states = limits.max_states if max_states is None else max_states
    max_depth = limits.max_depth if max_depth is None else max_depth
    stats = Stats() if stats is None else stats
    started = time.perf_counter()
    if budget is None:
        budget = Budget(limits.timeout if timeout is None else timeout,
                        limits.max_memory if max_memory is None else max_memory)
    if progress is not None and budget.on_poll is None:
        def poll(b: Budget) -> None:
            stats.time_s = b.elapsed()
            progress(stats, stats.frontier)
        budget.on_poll = poll
    budget.phase = "search"
    # worst case: stop as soon as the optimum is proven; expected cost: explore everything
    early_stop = grounded.problem.objective.kind == ObjectiveKind.WORST_CASE
    if heuristic is None:
        heuristic = _heuristic.OVERRIDE is not False
    hfn = Heuristic(grounded) if early_stop and heuristic else None
    sym = detect(grounded) if symmetry else None
    sem = Semantics(grounded) if sym is None else SymSemantics(grounded, sym)
    sem.bound(budget.check)
    gr = Graph(sem)
    root_state = sem.initial()
    for i, label in enumerate(grounded.problem.after):
        try:
            root_state = sem.follow(root_state, label).child  # type: ignore[assignment]
        except ValueError as e:
            raise InputError(grounded.problem.source, f"[problem] after, step {i + 1}", str(e),
                             "give a move possible at that point") from None
    if isinstance(sem, SymSemantics):
        sem.unsafe = ""  # the root is a real state: its own decisions are the real ones
        gr.sym = sem.sym
        root_state, gr.root_perm = sem.sym.canon(root_state)
    root = gr.add(root_state, 0, 0)
    stats.generated = stats.distinct = 1
    stats.max_worlds = len(root_state.worlds)
    # by f = g + h, then g (within a level as the uniform-cost search would: shallow first),
    # then node id (creation order)
    f0 = hfn(root_state) if hfn is not None else 0
    heap: list[Entry] = [(f0, 0, root)]
    level: Bound = 0
    status, reason = "unsolvable", ""
    values: Values | None = None
    optimal = False
    live: LiveWorst | None = None  # worst-case values, kept from the first goal on
    try:
        while heap:
            f, g, n = heapq.heappop(heap)
            if gr.status[n] != OPEN or g > gr.g[n]:
                continue  # expanded already, or reached since by a cheaper path
            if f > level:
                # every node with f < this one's is expanded: the optimum is proven when the
                # root's value is below it (see the module's docstring)
                if live is not None and gr.solved[root] and live.root_value(root) < f:
                    status, optimal = "solved", True
                    break
                level = f
            stats.frontier = len(heap)
            stop = budget.search_should_stop(stats.distinct, bool(gr.solved[root]))
            if stop is not None:
                status, reason = stop.status, stop.reason
                break
            if stats.distinct >= max_states:
                status, reason = "state-limit", f"state limit reached ({stats.distinct} " \
                                                "distinct states)"
                break
            _expand(gr, n, heap, stats, max_depth, hfn, max_states)
            if gr.status[n] == OPEN:  # one more state than the limit: n left unexpanded
                status, reason = "state-limit", f"state limit reached ({stats.distinct} " \
                                                "distinct states)"
                break
            if isinstance(sem, SymSemantics) and sem.unsafe:
                status, reason = "symmetry-unsafe", sem.unsafe
                break
            if live is not None:
                live.expanded(n)
            elif early_stop and gr.status[n] == GOAL:
                # from the first goal on, not only once the root is solved: a search ordered
                # by g + h often solves the root by its very last expansions
                budget.phase = "search (first worst-case pass)"
                live = LiveWorst(gr, budget)
                budget.phase = "search"
        else:
            if gr.solved[root]:
                values = compute_values(gr, root, budget=budget)
                status, optimal = "solved", values.exact
            elif gr.depth_cut:  # §6: a limit, not a proof that no policy exists
                status = "depth-limit"
                reason = (f"depth limit reached ({len(gr.depth_cut)} states cut at "
                          f"{max_depth} moves) before a policy was found; raise "
                          "[limits] max_depth or --max-depth")
        if status in ("timeout", "state-limit", "memory-limit") and gr.solved[root]:
            values = compute_values(gr, root, budget=budget)  # best so far, not optimal
        elif status == "solved" and values is None:
            live = None  # its arrays are not needed any more
            values = compute_values(gr, root, budget=budget)
    except LimitReached as e:
        status, reason, values, optimal = e.status, e.reason, None, False
    except MemoryError:  # the graph may be half-updated: no values from it
        live = values = None
        oom = budget.out_of_memory()
        status, reason, optimal = oom.status, oom.reason, False
    stats.time_s = time.perf_counter() - started  # the search alone, values included
    return SearchOutcome(gr, root, stats, status, values, optimal, reason)


def _move_key(m: Move) -> tuple[object, ...]:
    return (KIND_ORDER[m.kind], m.label, m.child is None, m.child or ())


def _expand(gr: Graph, n: int, heap: list[Entry], stats: Stats, max_depth: int,
            hfn: Heuristic | None = None, max_states: int | None = None) -> None:
    """Expand node ``n``: a goal, a dead end, or its moves as edges (new children queued by
    ``f``). Before adding a distinct state past ``max_states`` it stops and leaves ``n``
    unexpanded (``OPEN``): the search then ends with at most that many, whatever order it
    expands in."""
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
        gr.depth_cut.add(n)
        return
    moves = sorted(sem.moves(es), key=_move_key)
    g0, d0 = gr.g[n], gr.depth[n] + 1
    index, gs, status, states = gr.index, gr.g, gr.status, gr.states
    heappush = heapq.heappush
    sym = gr.sym
    edges: list[Edge] = []
    for m in moves:
        child = m.child
        if child is None:
            edges.append(Edge(gr.descriptor(m, -1), -1))
            continue
        stats.generated += 1
        pid = 0
        if sym is not None:
            child, pid = sym.canon(child)
        c = index.get(child)
        g1 = g0 + m.cost
        if c is None:
            if max_states is not None and stats.distinct >= max_states:
                stats.expanded -= 1
                return
            c = gr.add(child, g1, d0, n)
            stats.distinct += 1
            if len(child.worlds) > stats.max_worlds:
                stats.max_worlds = len(child.worlds)
            heappush(heap, (g1 if hfn is None else g1 + hfn(child), g1, c))
        else:
            if g1 < gs[c] and status[c] == OPEN:
                gs[c] = g1
                heappush(heap, (g1 if hfn is None else g1 + hfn(states[c]), g1, c))
            if d0 < gr.depth[c]:
                _lower_depth(gr, c, d0, heap, max_depth, hfn)
            gr.add_parent(c, n)
        edges.append(Edge(gr.descriptor(m, c), c, pid))
    gr.edges[n] = tuple(edges)
    gr.status[n] = EXPANDED
    if not gr.is_robot(n):
        gr.pending[n] = len(edges) + (1 if not edges else 0)
    for e in edges:
        if e.child >= 0 and gr.solved[e.child]:
            _child_solved(gr, n)


def _lower_depth(gr: Graph, c: int, d: int, heap: list[Entry], max_depth: int,
                 hfn: Heuristic | None) -> None:
    """§6: a shorter path to ``c`` was found: its depth (the least number of moves from the
    root over the paths found) becomes ``d``, and so on down the expanded nodes below it; a
    node the depth limit had cut that is now above the limit is open again::

        stack = [(c, d)]
        while stack: (x, d) = pop
            if d >= depth[x]: continue
            depth[x] = d
            if x was cut by the depth limit and d < max_depth: reopen x (queue it by f)
            elif x is expanded: push (y, d + 1) for each child y of x
    """
    stack = [(c, d)]
    while stack:
        x, dx = stack.pop()
        if dx >= gr.depth[x]:
            continue
        gr.depth[x] = dx
        if x in gr.depth_cut:
            if dx < max_depth:
                gr.depth_cut.discard(x)
                gr.status[x] = OPEN
                del gr.dead_why[x]
                gx = gr.g[x]
                heapq.heappush(heap, (gx if hfn is None else gx + hfn(gr.states[x]), gx, x))
        elif gr.status[x] == EXPANDED:
            stack.extend((e.child, dx + 1) for e in gr.edges[x] if e.child >= 0)


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
    gr.solved[n] = 1
    while stack:
        c = stack.pop()
        for p in gr.parents(c):
            if gr.solved[p] or gr.status[p] != EXPANDED:
                continue
            if gr.is_robot(p):
                gr.solved[p] = 1
                stack.append(p)
            else:
                gr.pending[p] -= 1
                if gr.pending[p] == 0:
                    gr.solved[p] = 1
                    stack.append(p)
