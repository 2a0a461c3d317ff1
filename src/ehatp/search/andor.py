"""AND/OR graph search over epistemic states (docs/semantics.md §7, "Search").

For the worst case with its lower bound the search is *focused* by default
(:meth:`_Search._focus`, :mod:`.bounds`, §7 "Search, focused"): only the tips of the best
partial policy the bounds pick are expanded, and the policy is the one the search by ``f``
below chooses, from far fewer states. Otherwise (``focus=False``, expected cost, joint steps,
no bound, a human with no task), and after a depth cut, the search by ``f``:

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

The graph itself, its node statuses and edges, are :mod:`.graph`'s.
"""

from __future__ import annotations

import gc
import heapq
import time
from dataclasses import dataclass

from ..epistemic.classworlds import count
from ..epistemic.concurrent import semantics_for
from ..epistemic.semantics import DEAD_PASSIVE_RUN, PASSIVE_CARRIED, Move
from ..epistemic.state import ROBOT, EState
from ..errors import InputError
from ..model.grounded import Grounded
from ..model.options import ObjectiveKind
from ..model.problem import Cost
from . import heuristic as _heuristic
from .bounds import SPREAD, Bounds
from .classsemantics import ClassSemantics
from .graph import (
    DEAD,
    EXPANDED,
    GOAL,
    KIND_ORDER,
    NO_EDGES,
    OPEN,
    Edge,
    Graph,
    NodeStatus,
    move_key,
)
from .heuristic import Bound, Heuristic
from .interchangeable import detect
from .limits import Budget, LimitReached, SolveStatus, start_budget
from .stats import Progress, Stats
from .symmetry import SymSemantics, describe_classes
from .values import LiveWorst, Values, compute_values
from .worldclasses import ClassSymmetry

Entry = tuple[Bound, Cost, int]  # the queue's: (f, g, node id)
PASSIVE_FIELD = EState._fields.index("passive")
_make = tuple.__new__  # an EState from a tuple of its fields, as NamedTuple._make does


@dataclass
class SearchOutcome:
    """What :func:`search` found: the graph and its root, the statistics, how the search
    ended, the values when the root is solved, and whether the optimum is proven."""

    graph: Graph
    root: int
    stats: Stats
    status: SolveStatus
    values: Values | None
    optimal: bool
    reason: str = ""  # which limit stopped the search, in words


def search(grounded: Grounded, *, timeout: float | None = None, max_states: int | None = None,
           max_depth: int | None = None, progress: Progress | None = None,
           max_memory: int | None = None, budget: Budget | None = None,
           stats: Stats | None = None, symmetry: bool = False,
           heuristic: bool | None = None, focus: bool = True,
           world_classes: bool = False) -> SearchOutcome:
    """§7: explore from the root until the optimum is proven (worst case), everything
    reachable is explored (expected cost), or a limit is reached; then the values.

    Limits default to the problem's ``[limits]``; ``budget`` (time and memory for the whole
    solve, :class:`~.limits.Budget`) replaces ``timeout`` and ``max_memory`` when given.
    ``progress(stats, frontier)`` is called about 20 times a second; ``stats``, when given, is
    the object the search keeps its statistics in. With ``symmetry`` the nodes are canonical
    states (docs/semantics.md §3, "Symmetry"; :mod:`.symmetry`); when a decision taken by index
    or name order makes that unsound the search stops with status ``"symmetry-unsafe"`` (the
    planner then solves again without it). ``heuristic`` (default: on) orders a worst-case
    search by ``g + h`` (:mod:`.heuristic`); the policy is the same either way, fewer states are
    expanded with it. ``focus`` (default: on; worst case with the heuristic, and a human with a
    task, only) expands the tips of the best partial policy instead (:meth:`_Search._focus`,
    :mod:`.bounds`): the same policy again, far fewer states. A root proven to have no policy
    has everything reachable explored after, as the search by ``f`` explores it, whose whole
    graph says why (:mod:`.diagnose`); a state cut by the depth limit (§6: the depth of a state
    is over the paths found, which the focused search finds fewer of) sends the work back to the
    search by ``f``.

    In GTPyhop-style pseudo-code (``V``: the worst-case values kept up to date, the module's
    docstring proves the stopping rule)::

        search(problem):
            root = the initial state after the problem's opening moves (after)
            queue = [(h(root), 0, root)]; level = 0
            while queue:
                (f, g, n) = pop the least
                if n is expanded, or was reached since by a cheaper path: continue
                if f > level:
                    if the root is solved and V(root) < f: return solved, optimal
                    level = f
                if a limit is reached: stop (with the best policy so far, if any)
                expand n: a goal, a dead end, or its moves as edges, new children queued
                propagate "solved" upwards; from the first goal on, keep V up to date
            if the root is solved: values over the whole graph, solved
            elif the depth limit cut a state: depth-limit
            else: unsolvable
    """
    limits = grounded.problem.limits
    stats = Stats() if stats is None else stats
    started = time.perf_counter()
    budget = start_budget(limits, stats, timeout=timeout, max_memory=max_memory,
                          budget=budget, progress=progress)
    budget.phase = "search"
    # The graph only grows, of immutable states: the cycle collector would find no garbage
    # in it, yet walk all of it again and again as it grows (a third of Woodworking's
    # search). Paused for the search, back on after (what a cycle left meanwhile is then
    # collected).
    collecting = gc.isenabled()
    gc.disable()
    try:
        states_cap = limits.max_states if max_states is None else max_states
        depth_cap = limits.max_depth if max_depth is None else max_depth
        run = _Search(grounded, budget, stats, states_cap, depth_cap, symmetry=symmetry,
                      heuristic=_heuristic.enabled(heuristic), focus=focus,
                      world_classes=world_classes)
        run.run()
        if run.unfocus:  # a depth cut: the search by f decides what the limit cuts (§6)
            stats.restart()
            run = _Search(grounded, budget, stats, states_cap, depth_cap, symmetry=symmetry,
                          heuristic=_heuristic.enabled(heuristic), focus=False,
                          world_classes=world_classes)
            run.run()
    finally:
        if collecting:
            gc.enable()
    stats.time_s = time.perf_counter() - started  # the search alone, values included
    return SearchOutcome(run.graph, run.root, stats, run.status, run.values, run.optimal,
                         run.reason)


class _Search:
    """One run of :func:`search`, step by step: the root, the exploration in order of ``f``
    with its stopping rule and limits, then the values."""

    def __init__(self, grounded: Grounded, budget: Budget, stats: Stats, max_states: int,
                 max_depth: int, *, symmetry: bool, heuristic: bool, focus: bool,
                 world_classes: bool = False) -> None:
        self.budget, self.stats = budget, stats
        self.max_states, self.max_depth = max_states, max_depth
        # worst case: stop as soon as the optimum is proven; expected cost: explore everything
        self.early_stop = grounded.problem.objective.kind == ObjectiveKind.WORST_CASE
        # joint steps (docs/concurrent.md) have no lower bound nor symmetry reduction yet
        joint = grounded.problem.steps.concurrent
        sym = detect(grounded, budget.check) if symmetry and not joint else None
        self.sem = semantics_for(grounded) if sym is None else SymSemantics(grounded, sym)
        if sym is not None and world_classes:  # the human's worlds as classes (issue 17 §2)
            csym = ClassSymmetry(grounded, describe_classes(sym))
            if csym.classer.active:
                self.sem = ClassSemantics(grounded, csym)
        self.sem.bound(budget.check)
        # a human with no task only passes: the robot's bound looks one action ahead
        # (search/heuristic.py, "The robot alone")
        self.hfn = (Heuristic(grounded, None if grounded.human_agenda else self.sem.R)
                    if self.early_stop and heuristic and not joint else None)
        self.graph = Graph(self.sem)
        self.root = self._add_root(self._opening(grounded))
        # by f = g + h, then g (within a level as the uniform-cost search would: shallow
        # first), then node id (creation order)
        root_state = self.graph.states[self.root]
        self.heap: list[Entry] = [(self.hfn(root_state) if self.hfn is not None else 0, 0,
                                   self.root)]
        self.level: Bound = 0
        self.status, self.reason = SolveStatus.UNSOLVABLE, ""
        self.values: Values | None = None
        self.optimal = False
        self.live: LiveWorst | None = None  # worst-case values, kept from the first goal on
        # the focused search's lower bounds (worst case with the heuristic, and a human with a
        # task: one with none only passes, every human node has one branch, and the search by
        # f expands what the focused one would, without its revisions; §7, "Search, focused"),
        # and whether a depth cut sends the work back to the search by f
        self.bounds = (Bounds(self.graph, self.hfn, budget.check)
                       if focus and self.hfn is not None and grounded.human_agenda else None)
        self.unfocus = False

    def _opening(self, grounded: Grounded) -> EState:
        """Return the root's state: the initial state after the problem's opening moves
        (``[problem] after``, §4: each a move possible at that point)."""
        sem = self.sem
        root_state = sem.initial()
        for i, label in enumerate(grounded.problem.after):
            try:
                root_state = sem.follow(root_state, label).child  # type: ignore[assignment]
            except ValueError as e:
                raise InputError(grounded.problem.source, f"[problem] after, step {i + 1}",
                                 str(e), "give a move possible at that point") from None
        return root_state

    def _add_root(self, root_state: EState) -> int:
        """Return the root node's id: ``root_state``, or its canonical form over
        symmetry-reduced states (§3, the renaming kept to map the policy back)."""
        sem, gr, stats = self.sem, self.graph, self.stats
        if isinstance(sem, SymSemantics):
            sem.unsafe = ""  # the root is a real state: its own decisions are the real ones
            gr.sym = sem.sym
            root_state, gr.root_perm = sem.sym.canon(root_state)
        root = gr.add(root_state, 0, 0)
        stats.generated = stats.distinct = 1
        stats.max_worlds = count(root_state.worlds)
        return root

    def run(self) -> None:
        """Explore, then compute the values; a limit met in either, or a
        :class:`MemoryError`, is a clean stop (no values from a half-updated graph)."""
        try:
            if self._focus() if self.bounds is not None else self._explore():
                self._end_of_graph()
            if self.unfocus:
                return
            self._values()
        except LimitReached as e:
            self.status, self.reason, self.values, self.optimal = e.status, e.reason, None, False
        except MemoryError:
            self.live = self.values = None
            oom = self.budget.out_of_memory()
            self.status, self.reason, self.optimal = oom.status, oom.reason, False

    def _stop(self, status: SolveStatus, reason: str = "", optimal: bool = False) -> bool:
        """Record how the search ends; return True (the loop stops)."""
        self.status, self.reason, self.optimal = status, reason, optimal
        return True

    def _explore(self) -> bool:
        """Expand nodes in order of ``(f, g, id)`` until the stopping rule or a limit ends
        the search (False), or nothing is left to expand (True)."""
        gr, heap, hfn = self.graph, self.heap, self.hfn
        heappop, heappush = heapq.heappop, heapq.heappush
        # the robot alone looks one action ahead (search/heuristic.py): a node is queued by
        # the bound of its agendas and requeued, once out, by the whole bound if that is more,
        # so only the nodes that come out refine the robot's agenda for it; the order of
        # expansion is that of queueing by the whole bound
        look = hfn if hfn is not None and hfn.looks_ahead else None
        ahead: dict[int, Bound] = {}  # node -> its whole bound, once it came out
        while heap:
            f, g, n = heappop(heap)
            if gr.status[n] != OPEN or g > gr.g[n]:
                continue  # expanded already, or reached since by a cheaper path
            if look is not None:
                h = ahead.get(n)
                if h is None:
                    h = ahead[n] = look(gr.states[n])
                if g + h > f:
                    heappush(heap, (g + h, g, n))
                    continue
            if f > self.level:
                if self._proven(f):
                    return False
                self.level = f
            if self._limit_reached():
                return False
            _expand(gr, n, heap, self.stats, self.max_depth, hfn, self.max_states)
            if self._after_expansion(n):
                return False
        return True

    def _focus(self) -> bool:
        """§7, "Search", focused: expand the tips of the best partial policy
        (:mod:`.bounds`), a batch at a time, until it has none (True: the root's bound is
        then its value, or infinite once everything reachable is expanded) or a limit ends
        the search (False). In GTPyhop-style pseudo-code::

            focus(problem):
                low(root) = h(root)
                while the best partial policy has tips:
                    for each tip n, then their children the bounds follow, breadth first,
                            until the batch is SPREAD-th of the last revision's work:
                        expand n (new children: low = h)
                    revise the bounds (they only rise)
                return the root's bound is its value

        Why the policy is the one the search by ``f`` chooses: when the best partial policy
        has no tip, each node it reaches has its value as bound (an explored sub-policy
        costs it, and no policy costs less); a robot option it does not follow has
        ``cost + low(child)`` above the node's value, so it is worse whatever lies below;
        the options it follows are exactly those of the node's value. Those are the nodes
        and options the choices read (:func:`~.values.compute_values`), all explored, with
        the same values and the same sub-policies for the tie keys. Which nodes are expanded
        on the way changes only how soon that happens. Every node expanded has
        ``g + h <= low(root) <= V`` (a tip on the best partial policy; a node below one only
        if so), so the states expanded are among those the search by ``f`` expands."""
        gr, bounds, root = self.graph, self.bounds, self.root
        assert bounds is not None
        while True:
            tips = bounds.walk(root)
            if not tips:
                # proven: no policy; everything reachable is explored, as the search by f
                # explores it, so that the same graph says why (:mod:`.diagnose`)
                return self._exhaust() if not gr.solved[root] else True
            self.stats.frontier = len(tips)
            # the batch goes on below the tips, along the options the bounds follow, until it
            # is an eighth of the last revision's work (one revision per few tips, when a
            # few deep tips raise most of the graph's bounds round after round)
            target = max(len(tips), bounds.last_work // SPREAD)
            work = list(tips)
            queued = set(tips)
            # only below the root's bound (fixed until the revision): expanded by the search
            # by f as well
            top, low, gs = bounds.low[root], bounds.low, gr.g
            for n in work:
                if gr.status[n] != OPEN:
                    continue
                if self._step(n):
                    return False
                bounds.added()
                if len(work) < target:
                    for c in bounds.followed(n):
                        if c not in queued and gr.status[c] == OPEN and gs[c] + low[c] <= top:
                            queued.add(c)
                            work.append(c)
            bounds.revise([n for n in work if gr.status[n] != OPEN])

    def _exhaust(self) -> bool:
        """Expand every open node, in order of creation, until none is left (True), a limit
        stops the search or a depth cut sends it back to the search by ``f`` (False)."""
        gr = self.graph
        n = 0
        while n < len(gr.states):
            if gr.status[n] == OPEN and self._step(n):
                return False
            n += 1
        return True

    def _step(self, n: int) -> bool:
        """Expand node ``n`` for the focused search (no queue: its children are found by the
        walks); whether the search stops: a limit, an order-dependent decision (§3), or a
        depth cut, which sends the work back to the search by ``f``."""
        if self._limit_reached():
            return True
        _expand(self.graph, n, None, self.stats, self.max_depth, None, self.max_states)
        if self.graph.depth_cut:
            self.unfocus = True
            return True
        return self._after_expansion(n)

    def _proven(self, f: Bound) -> bool:
        """The stopping rule (the module's docstring): every node with a smaller ``f`` is
        expanded, so the optimum is proven when the root's value is below ``f``."""
        live, root = self.live, self.root
        if live is not None and self.graph.solved[root] and live.root_value(root) < f:
            return self._stop(SolveStatus.SOLVED, optimal=True)
        return False

    def _limit_reached(self) -> bool:
        """Whether time, memory (with what must follow the search) or ``max_states`` stop the
        search before the next expansion (§7, "Search"; :mod:`.limits`)."""
        stats = self.stats
        if self.bounds is None:
            stats.frontier = len(self.heap)
        stop = self.budget.search_should_stop(stats.distinct,
                                              bool(self.graph.solved[self.root]))
        if stop is not None:
            return self._stop(stop.status, stop.reason)
        if stats.distinct >= self.max_states:
            return self._stop(SolveStatus.STATE_LIMIT, self._state_limit())
        return False

    def _state_limit(self) -> str:
        """Return the state limit's reason, in words."""
        return f"state limit reached ({self.stats.distinct} distinct states)"

    def _after_expansion(self, n: int) -> bool:
        """After expanding ``n``: stop at the state limit (``n`` was left unexpanded) or an
        order-dependent decision (§3, "Symmetry"); else keep the worst-case values up to
        date, from the first goal on. Whether the search stops."""
        gr, sem = self.graph, self.sem
        if gr.status[n] == OPEN:  # one more state than the limit: n left unexpanded
            return self._stop(SolveStatus.STATE_LIMIT, self._state_limit())
        if isinstance(sem, SymSemantics) and sem.unsafe:
            return self._stop(SolveStatus.SYMMETRY_UNSAFE, sem.unsafe)
        if self.live is not None:
            self.live.expanded(n)
        elif self.early_stop and gr.status[n] == GOAL and self.bounds is None:
            # from the first goal on, not only once the root is solved: a search ordered
            # by g + h often solves the root by its very last expansions
            self.budget.phase = "search (first worst-case pass)"
            self.live = LiveWorst(gr, self.budget)
            self.budget.phase = "search"
        return False

    def _end_of_graph(self) -> None:
        """Everything reachable is expanded: solved (the values say whether optimal), cut by
        the depth limit (§6: a limit, not a proof that no policy exists), or unsolvable."""
        gr, root = self.graph, self.root
        if gr.solved[root]:
            self.values = compute_values(gr, root, budget=self.budget, live=self.live)
            self.live = None
            self._stop(SolveStatus.SOLVED, optimal=self.values.exact)
        elif gr.depth_cut:
            self._stop(SolveStatus.DEPTH_LIMIT,
                       f"depth limit reached ({len(gr.depth_cut)} states cut at "
                       f"{self.max_depth} moves) before a policy was found; raise "
                       "[limits] max_depth or --max-depth")

    def _values(self) -> None:
        """The values, where the explored graph has them and :meth:`_end_of_graph` did not
        compute them: after the stopping rule, or the best policy so far after a limit."""
        gr, root = self.graph, self.root
        if self.status in (SolveStatus.TIMEOUT, SolveStatus.STATE_LIMIT,
                           SolveStatus.MEMORY_LIMIT) and gr.solved[root]:
            self.values = compute_values(gr, root, budget=self.budget)  # not optimal
        elif self.status == SolveStatus.SOLVED and self.values is None:
            live, self.live = self.live, None  # its arrays are not needed any more
            self.values = compute_values(gr, root, budget=self.budget, live=live)


def _expand(gr: Graph, n: int, heap: list[Entry] | None, stats: Stats, max_depth: int,
            hfn: Heuristic | None = None, max_states: int | None = None) -> None:
    """Expand node ``n``: a goal, a dead end, or its moves as edges (new children queued by
    ``f`` on ``heap``; the focused search, which finds them by its walks, has none). Before
    adding a distinct state past ``max_states`` it stops and leaves ``n`` unexpanded
    (``OPEN``): the search then ends with at most that many, whatever order it expands
    in."""
    sem = gr.sem
    es = gr.states[n]
    stats.expanded += 1
    # the same state with another passive count, expanded already: not a goal either (§6
    # reads no count), and its moves are this node's (§4, PASSIVE_CARRIED)
    twin = _twin(gr, es) if gr.sym is None and sem.passive_carried else -1
    if twin < 0 and sem.is_goal(es):
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
    pairs = (_reused(gr, twin, es.passive) if twin >= 0 else
             [(move, move.child, -1) for move in sorted(sem.moves(es), key=move_key)])
    g0, d0 = gr.g[n], gr.depth[n] + 1
    index, gs, status, states, depth = gr.index, gr.g, gr.status, gr.states, gr.depth
    heappush = heapq.heappush
    sym = gr.sym
    edges: list[Edge] = []
    generated = solved = 0  # children generated; edges to a child solved already
    for move, child, c in pairs:
        if child is None:
            edges.append(Edge(gr.descriptor(move, -1), -1))
            continue
        generated += 1
        g1 = g0 + move.cost
        pid = 0
        if c < 0:
            if sym is not None:
                child, pid = sym.canon(child)
            c = index.get(child, -1)
            if c < 0:
                if max_states is not None and stats.distinct >= max_states:
                    stats.expanded -= 1
                    stats.generated += generated
                    return
                c = gr.add(child, g1, d0, n)
                stats.distinct += 1
                if count(child.worlds) > stats.max_worlds:
                    stats.max_worlds = count(child.worlds)
                if heap is not None:
                    heappush(heap, (g1 if hfn is None else g1 + hfn.quick(child), g1, c))
                edges.append(Edge(gr.descriptor(move, c), c, pid))
                continue
            move = gr.descriptor(move, c)
        # else: a child read off another node's edge, the same node with the same move
        if g1 < gs[c] and status[c] == OPEN:
            gs[c] = g1
            if heap is not None:
                heappush(heap, (g1 if hfn is None else g1 + hfn.quick(states[c]), g1, c))
        if d0 < depth[c]:
            _lower_depth(gr, c, d0, heap, max_depth, hfn)
        gr.add_parent(c, n)
        solved += gr.solved[c]
        edges.append(Edge(move, c, pid))
    stats.generated += generated
    gr.edges[n] = tuple(edges)
    status[n] = EXPANDED
    if es.turn != ROBOT:
        gr.pending[n] = len(edges) + (1 if not edges else 0)
    for _ in range(solved):
        _child_solved(gr, n)


def _twin(gr: Graph, es: EState) -> int:
    """Return an expanded node whose state is ``es`` with another count of consecutive passive
    moves (the least count first), or -1 when there is none."""
    p, index, status = es.passive, gr.index, gr.status
    # the same state with another count, as a plain tuple (equal to the EState, same hash)
    head, tail = es[:PASSIVE_FIELD], es[PASSIVE_FIELD + 1:]
    for q in range(DEAD_PASSIVE_RUN):
        if q != p:
            twin = index.get(head + (q,) + tail)  # type: ignore[call-overload]
            if twin is not None and status[twin] == EXPANDED:
                return int(twin)
    return -1


def _reused(gr: Graph, twin: int, p: int) -> list[tuple[Move, EState | None, int]]:
    """§3-§5: the moves of a node with ``p`` consecutive passive moves read off the expanded
    node ``twin`` whose state differs from its by that count only: the same moves in the same
    order, each child the same node, but for a move that carries the count
    (:data:`~ehatp.epistemic.semantics.PASSIVE_CARRIED`), whose child has the count ``p`` plus
    the move's. As ``(move, child state, child id)``; the id is -1 where the child is to be
    looked up. (The moves are in the canonical order, ties by child state: a carrying move's
    label is its node's alone, so the order is the same.)"""
    states = gr.states
    out: list[tuple[Move, EState | None, int]] = []
    for e in gr.edges[twin]:
        c = e.child
        if c < 0:
            out.append((e.move, None, -1))
            continue
        d = PASSIVE_CARRIED.get(e.move.kind)
        if d is None:
            out.append((e.move, states[c], c))
        else:
            cs = states[c]
            out.append((e.move, _make(EState, cs[:PASSIVE_FIELD] + (p + d,)
                                      + cs[PASSIVE_FIELD + 1:]), -1))
    return out


def _lower_depth(gr: Graph, c: int, d: int, heap: list[Entry] | None, max_depth: int,
                 hfn: Heuristic | None) -> None:
    """§6: a shorter path to ``c`` was found: its depth (the least number of moves from the
    root over the paths found) becomes ``d``, and so on down the expanded nodes below it; a
    node the depth limit had cut that is now above the limit is open again (the focused
    search, without ``heap``, has no such node: its first cut hands the work to the search
    by ``f``)::

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
                if heap is not None:
                    heapq.heappush(heap, (gx if hfn is None else gx + hfn.quick(gr.states[x]),
                                          gx, x))
        elif gr.status[x] == EXPANDED:
            stack.extend((e.child, dx + 1) for e in gr.edges[x] if e.child >= 0)


def _child_solved(gr: Graph, p: int) -> None:
    """§7: child of ``p`` just solved: a robot node is solved by one child, a human node by all
    of its children."""
    if gr.solved[p]:
        return
    if gr.is_robot(p):
        _mark_solved(gr, p)
    else:
        gr.pending[p] -= 1
        if gr.pending[p] == 0:
            _mark_solved(gr, p)


def _mark_solved(gr: Graph, n: int) -> None:
    """§7: node ``n`` is solved; propagate upwards to every expanded parent it solves (the
    paper's propagate step)."""
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


__all__ = ["DEAD", "EXPANDED", "GOAL", "KIND_ORDER", "NO_EDGES", "OPEN", "Edge", "Graph",
           "NodeStatus", "Progress", "SearchOutcome", "Stats", "search"]
