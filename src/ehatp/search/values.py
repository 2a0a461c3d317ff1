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

**During the search** (§7, "Search"), :class:`LiveWorst` keeps the worst-case values of the
growing graph up to date, so that the stopping rule reads the root's value instead of redoing
the whole pass at every cost level.

Every long loop here calls ``budget.check()`` (:mod:`.limits`), so time and memory limits hold
inside the passes too.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction

from ..epistemic.concurrent import H_ACTION, R_ACTION
from ..epistemic.semantics import ACTION, ANNOUNCE, ASK, INFORM, WAIT, Move
from ..epistemic.state import HUMAN, ROBOT, EState
from ..model.options import Estimate, Metric, Objective, ObjectiveKind, TieKey
from ..model.problem import Cost
from .graph import GOAL, Edge, Graph
from .limits import Budget

INF = float("inf")
CHECK_EVERY = 1023  # budget.check() once per this many + 1 nodes


@dataclass
class Values:
    value: list[Cost | float]  # under the objective; INF where no proper policy was found
    # robot node -> index of the chosen edge, for the nodes of the chosen policy (those the
    # root reaches through the choices)
    choice: dict[int, int]
    worst: list[Cost | float]  # worst-case values (the same list as ``value`` for worst-case)
    exact: bool = True  # False: cycles restricted the expected-cost choices (§7)
    # kind = "preferences" (C11): each node's vector of the profile's metrics (None: not
    # reached by the backward pass); ``value`` is then the worst-case cost
    vector: list[Vector | None] | None = None


Vector = tuple[Cost, ...]


def compute_values(gr: Graph, root: int, objective: Objective | None = None,
                   budget: Budget | None = None, live: LiveWorst | None = None) -> Values:
    """§7: the values of ``gr`` under ``objective`` (default: the problem's) and the robot's
    choice at every node of the chosen policy. ``live``, the worst-case values the search kept
    up to date on ``gr``, spares the worst-case pass where it can (:meth:`LiveWorst.final`)."""
    obj = gr.sem.grounded.problem.objective if objective is None else objective
    if budget is not None:
        budget.phase = "values (worst case)"
    worst, order = knuth(gr, budget) if live is None else live.final(budget)
    n_nodes = len(worst)
    pos = [n_nodes] * n_nodes  # position in the Knuth order (n_nodes: never finalised)
    for i, n in enumerate(order):
        pos[n] = i
    need_mean = obj.kind == ObjectiveKind.EXPECTED or "expected" in obj.ties
    if obj.kind == ObjectiveKind.WORST_CASE:
        if budget is not None:
            budget.phase = "values (choices)"
        choice, _ = _choose(gr, _contenders(gr, root, worst, order, pos), lambda n, c:
                            pos[c] < pos[n], obj, need_mean, budget)
        return Values(worst, _reachable(gr, root, choice), worst)
    if worst[root] == INF:
        return Values([INF] * n_nodes, {}, worst)
    if budget is not None:
        budget.phase = "values (expected cost)"
    topo, allowed, exact = expected_order(gr, root, worst, pos, budget)
    if obj.kind == ObjectiveKind.PREFERENCES:
        if budget is not None:
            budget.phase = "values (preferences)"
        choice, vector = prefer(gr, topo, allowed, obj, budget)
        return Values(worst, _reachable(gr, root, choice), worst, exact, vector)
    choice, mean = _choose(gr, topo, allowed, obj, need_mean, budget)
    value: list[Cost | float] = [INF] * n_nodes
    assert mean is not None
    for n in topo:
        mc = mean[n]
        assert mc is not None
        value[n] = mc
    return Values(value, _reachable(gr, root, choice), worst, exact)


def _contenders(gr: Graph, root: int, worst: list[Cost | float], order: list[int],
                pos: list[int]) -> list[int]:
    """§7, worst case: the nodes of ``order`` (Knuth's) whose choices the policy can depend
    on, in that order: those the root reaches through every branch of a human node and, at a
    robot node, the options that may be chosen -- to a child finalised before it, of the
    node's value (an option of a greater value is never chosen, whatever the tie keys: they
    only order options of equal value). The totals of a chosen sub-policy are its nodes' own,
    so the choices of these nodes are what visiting every node of ``order`` gives."""
    seen = bytearray(len(worst))
    seen[root] = 1
    stack = [root]
    status, states, edges_of = gr.status, gr.states, gr.edges
    while stack:
        n = stack.pop()
        if status[n] == GOAL:
            continue
        robot, v = states[n].turn == ROBOT, worst[n]
        for e in edges_of[n]:
            c = e.child
            if c < 0 or seen[c] or robot and not (pos[c] < pos[n] and e.move.cost + worst[c] == v):
                continue
            seen[c] = 1
            stack.append(c)
    return [n for n in order if seen[n]]


def _reachable(gr: Graph, root: int, choice: dict[int, int]) -> dict[int, int]:
    """The choices of the nodes the root reaches through them (the policy's robot nodes)."""
    out: dict[int, int] = {}
    seen = {root}
    stack = [root]
    while stack:
        n = stack.pop()
        edges = gr.edges[n]
        i = choice.get(n)
        if i is not None:
            out[n] = i
            kids = [edges[i].child]
        elif gr.is_robot(n):
            continue  # a goal, or not solved
        else:
            kids = [e.child for e in edges]
        for c in kids:
            if c >= 0 and c not in seen:
                seen.add(c)
                stack.append(c)
    return out


def knuth(gr: Graph, budget: Budget | None = None) -> tuple[list[Cost | float], list[int]]:
    """§7, worst case: the least fixpoint of the min/max equations by Knuth's generalisation of
    Dijkstra's algorithm; returns the values and the order in which nodes were finalised
    (every child a node's value comes from is finalised before it). In GTPyhop-style
    pseudo-code::

        knuth(graph):
            queue = [(0, n) for every goal n]
            while queue:
                (v, n) = pop the least
                if n is final: continue
                value(n) = v; n is final
                for each edge p -> n of cost c, p not final:
                    if the robot moves at p: queue (v + c, p)
                    else:
                        worst(p) = max(worst(p), v + c)
                        if every child of p is final: queue (worst(p), p)
            return value (infinite where never final), the order of finalisation
    """
    n_nodes = len(gr.states)
    value: list[Cost | float] = [INF] * n_nodes
    final = bytearray(n_nodes)
    remaining = [0] * n_nodes
    worst: list[Cost] = [0] * n_nodes
    heap: list[tuple[Cost, int]] = []
    status, states, edges_of = gr.status, gr.states, gr.edges
    for n in range(n_nodes):
        if status[n] == GOAL:
            heap.append((0, n))
        elif states[n].turn != ROBOT:  # a human node
            edges = edges_of[n]
            remaining[n] = len(edges) if edges and all(e.child >= 0 for e in edges) else -1
        if budget is not None and not n & CHECK_EVERY:
            budget.check()
    heapq.heapify(heap)
    order: list[int] = []
    while heap:
        v, n = heapq.heappop(heap)
        if final[n]:
            continue
        final[n] = 1
        value[n] = v
        order.append(n)
        if budget is not None and not len(order) & CHECK_EVERY:
            budget.check()
        for p in set(gr.parents(n)):
            if final[p]:
                continue
            robot = states[p].turn == ROBOT
            for e in edges_of[p]:
                if e.child != n:
                    continue
                cand = v + e.move.cost
                if robot:
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


class LiveWorst:
    """§7, "Search": the worst-case values of a graph that grows, kept equal to what
    :func:`knuth` would compute on it now, so the stopping rule reads ``value[root]``.

    Created when the search meets its first goal (one full pass); then :meth:`expanded` after
    every expansion. Adding a node's edges can only lower values (a robot node gains options, a
    human node goes from no value to one), so an update is a Dijkstra-like wave of decreases
    from the expanded node up through its ancestors, in increasing order of the new values,
    each node re-evaluated from its children's current values. When the wave ends every node
    satisfies its min/max equation again, and with positive costs those equations have one
    solution only (a node below its least-fixpoint value would need a child further below, on
    and on, down a strictly decreasing chain), so the values are Knuth's exactly. The robot's
    zero-cost ``silence`` and the human's zero-cost ``answer`` keep this true (each leads to a
    human node that answers nothing, whose moves all cost more than 0); if any other move could
    cost 0 the root is recomputed by a full pass instead."""

    def __init__(self, gr: Graph, budget: Budget | None = None) -> None:
        self.gr = gr
        self.budget = budget
        self.value, _ = knuth(gr, budget)
        self.incremental = _positive_costs(gr)

    def expanded(self, n: int) -> None:
        """Node ``n`` was just expanded (its edges, possibly new nodes, are in the graph)."""
        value = self.value
        missing = len(self.gr.states) - len(value)
        if missing:
            value.extend([INF] * missing)
        if not self.incremental:
            return
        v = self._eval(n)
        if v < value[n]:
            self._lower(n, v)

    def final(self, budget: Budget | None = None) -> tuple[list[Cost | float], list[int]]:
        """What :func:`knuth` returns on the graph now. When every edge costs more than 0,
        read off the values kept: Knuth's algorithm then finalises the nodes in order of
        value, ties by node id, so the order is a sort. Proof: a node of value ``v`` is
        queued with ``v`` when the child its value comes from (a robot node's best option, a
        human node's last child) is finalised, and that child's value is ``v`` less a
        positive cost; nodes leave the queue by value, so every node of value ``v`` is queued
        with ``v`` before the first of them leaves it, and they leave it by id. Otherwise (a
        zero-cost ``silence`` or ``answer``, or values not kept incrementally), the pass
        itself."""
        gr, value = self.gr, self.value
        if (not self.incremental or len(value) != len(gr.states)
                or any(e.move.cost <= 0 for edges in gr.edges for e in edges)):
            return knuth(gr, budget)
        if budget is not None:
            budget.check()  # the phase looks at the limits as it starts (a poll)
        order = [n for n, v in enumerate(value) if v != INF]  # by id
        order.sort(key=value.__getitem__)  # by value: a stable sort keeps ties by id
        return value, order

    def root_value(self, root: int) -> Cost | float:
        if not self.incremental:
            self.value, _ = knuth(self.gr, self.budget)
        return self.value[root]

    def _eval(self, n: int) -> Cost | float:
        """``n``'s equation on the current values of its children."""
        return equation(self.gr, n, self.value)

    def _lower(self, n: int, v: Cost | float) -> None:
        """Lower ``n`` to ``v`` and let the decrease travel up through the ancestors, least new
        value first, each parent re-evaluated from its children (see the class docstring)."""
        gr, value = self.gr, self.value
        states, edges_of = gr.states, gr.edges
        heap: list[tuple[Cost | float, int]] = [(v, n)]
        while heap:
            v, x = heapq.heappop(heap)
            if v >= value[x]:
                continue  # stale: lowered further already
            value[x] = v
            for p in set(gr.parents(x)):
                if not edges_of[p]:
                    continue
                if states[p].turn == ROBOT:
                    cand: Cost | float = INF
                    for e in edges_of[p]:
                        if e.child == x and e.move.cost + v < cand:
                            cand = e.move.cost + v
                else:
                    cand = self._eval(p)
                if cand < value[p]:
                    heapq.heappush(heap, (cand, p))


def equation(gr: Graph, n: int, value: Sequence[Cost | float]) -> Cost | float:
    """§7, worst case: node ``n``'s equation on its children's ``value``: 0 at a goal, the
    least ``cost + value(child)`` over a robot node's options (infinite without one), the
    greatest over a human node's branches (infinite without a branch, or with one that
    fails)."""
    if gr.status[n] == GOAL:
        return 0
    edges = gr.edges[n]
    if gr.states[n].turn == ROBOT:  # robot: the best option
        best: Cost | float = INF
        for e in edges:
            if e.child >= 0:
                x = e.move.cost + value[e.child]
                if x < best:
                    best = x
        return best
    if not edges:
        return INF
    worst: Cost | float = 0
    for e in edges:
        if e.child < 0:
            return INF
        x = e.move.cost + value[e.child]
        if x > worst:
            worst = x
    return worst


def _positive_costs(gr: Graph) -> bool:
    """Whether every move but the robot's ``silence`` costs more than 0 (see LiveWorst)."""
    grounded = gr.sem.grounded
    c, d = grounded.problem.costs, grounded.problem.domain
    models = ((grounded.robot, d.robot), (grounded.human, d.human))
    return (min(c.inform, c.ask, c.wait, c.pass_) > 0
            and all(op.cost > 0 for model, _ in models for op in model.ops.values())
            and all(c.actions.get(name, op.cost) > 0  # on demand: the ops not grounded yet
                    for model, lifted in models if model.lazy
                    for name, op in lifted.operators.items()))


def expected_order(gr: Graph, root: int, worst: list[Cost | float], pos: list[int],
                   budget: Budget | None = None
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
    def solvable_children(n: int) -> list[int]:
        return [e.child for e in gr.edges[n] if e.child >= 0 and worst[e.child] != INF]

    order, comp, exact = _components(root, len(worst), solvable_children, pos, budget)

    def allowed(n: int, c: int) -> bool:
        return worst[c] != INF and (comp[c] != comp[n] or pos[c] < pos[n])

    return order, allowed, exact


def _components(root: int, n_nodes: int, children: Callable[[int], list[int]],
                pos: list[int], budget: Budget | None) -> tuple[list[int], list[int], bool]:
    """Return the strongly connected components of the graph ``children`` spans from
    ``root`` (Tarjan's algorithm, iteratively): their members, children's components first,
    each component's members by ``pos``; each node's component (-1: not reached); and whether
    no component has a cycle."""
    kids: dict[int, list[int]] = {}  # the children of the nodes on the work stack
    index = [-1] * n_nodes
    low = [0] * n_nodes
    on_stack = bytearray(n_nodes)
    comp = [-1] * n_nodes
    stack: list[int] = []
    order: list[int] = []
    exact = True
    counter = n_comps = 0
    index[root] = low[root] = counter
    counter += 1
    stack.append(root)
    on_stack[root] = 1
    work: list[tuple[int, int]] = [(root, 0)]
    steps = 0
    while work:
        steps += 1
        if budget is not None and not steps & CHECK_EVERY:
            budget.check()
        n, i = work[-1]
        ks = kids.get(n)
        if ks is None:
            ks = kids[n] = children(n)
        if i < len(ks):
            work[-1] = (n, i + 1)
            c = ks[i]
            if index[c] < 0:
                index[c] = low[c] = counter
                counter += 1
                stack.append(c)
                on_stack[c] = 1
                work.append((c, 0))
            elif on_stack[c] and index[c] < low[n]:
                low[n] = index[c]
            continue
        work.pop()
        del kids[n]
        if work and low[n] < low[work[-1][0]]:
            low[work[-1][0]] = low[n]
        if low[n] != index[n]:
            continue
        members: list[int] = []
        while True:
            x = stack.pop()
            on_stack[x] = 0
            comp[x] = n_comps
            members.append(x)
            if x == n:
                break
        if len(members) > 1 or n in ks:
            exact = False
        members.sort(key=pos.__getitem__)
        order.extend(members)
        n_comps += 1
    return order, comp, exact


def _choose(gr: Graph, order: list[int], allowed: Callable[[int, int], bool], obj: Objective,
            need_mean: bool, budget: Budget | None = None
            ) -> tuple[dict[int, int], list[Cost | None] | None]:
    """Visit ``order`` (children before parents): pick each robot node's option among the
    ``allowed`` ones by the objective's value, then the tie keys, then canonical order; total
    each chosen sub-policy (:class:`_Totals`). Return the choices and the expected costs
    (None unless ``need_mean``).

    In GTPyhop-style pseudo-code::

        choose(order):
            for n in order:
                if n is a goal: totals(n) = a leaf
                elif the robot moves at n:
                    choice(n) = argmin over allowed options m of
                                (cost(m) + value(child(m)), tie keys, canonical order)
                    totals(n) = totals(child(choice(n))) plus the move
                else:
                    totals(n) = the sums (worst case: the maximum; expected: the weighted
                                mean) over every branch m of totals(child(m)) plus the move
    """
    weights: dict[str, Fraction] = {}

    def weight(move: Move) -> Fraction:
        w = weights.get(move.label)
        if w is None:
            w = weights[move.label] = obj.weight(move.label, gr.sem.describe(move).name)
        return w

    totals = _Totals(len(gr.states), need_mean, obj)
    done = bytearray(len(gr.states))
    choice: dict[int, int] = {}
    status, states = gr.status, gr.states
    for step, n in enumerate(order):
        if budget is not None and not step & CHECK_EVERY:
            budget.check()
        done[n] = 1
        edges = gr.edges[n]
        if status[n] == GOAL:
            totals.goal(n)
        elif states[n].turn == ROBOT:
            i = choice[n] = totals.best_option(n, edges, done, allowed)
            totals.take(n, edges[i])
        else:
            totals.branches(n, edges, weight)
    return choice, totals.mean


class _Totals:
    """The chosen sub-policy below each node, totalled in arrays indexed by node for the
    choices and their tie keys (§7, "Ties"): its communications, waits, leaves and their summed
    length (in moves from the node), worst-case cost and, when ``need_mean``, expected cost."""

    def __init__(self, n_nodes: int, need_mean: bool, obj: Objective) -> None:
        self.expected = obj.kind == ObjectiveKind.EXPECTED
        self.ties = obj.ties
        self.comms = [0] * n_nodes
        self.waits = [0] * n_nodes
        self.leaves = [0] * n_nodes
        self.length = [0] * n_nodes  # sum over leaves of their distance (in moves)
        self.worst: list[Cost] = [0] * n_nodes
        self.mean: list[Cost | None] | None = [None] * n_nodes if need_mean else None

    def tie_key(self, move: Move, c: int) -> tuple[object, ...]:
        """Return the tie keys of the option ``move`` to ``c``, as seen from its parent."""
        out: list[object] = []
        for k in self.ties:
            if k == TieKey.COMMUNICATIONS:
                out.append(self.comms[c] + (1 if speaks(move) else 0))
            elif k == TieKey.WAITS:
                out.append(self.waits[c] + (1 if move.waits else 0))
            elif k == TieKey.LENGTH:
                out.append(Fraction(self.length[c] + self.leaves[c], self.leaves[c]))
            elif k == TieKey.WORST_CASE:
                out.append(move.cost + self.worst[c])
            else:  # expected
                assert self.mean is not None
                mc = self.mean[c]
                out.append(None if mc is None else move.cost + mc)
        return tuple(out)

    def goal(self, n: int) -> None:
        """A goal: one leaf, nothing left to pay."""
        self.leaves[n] = 1
        if self.mean is not None:
            self.mean[n] = 0

    def best_option(self, n: int, edges: tuple[Edge, ...], done: bytearray,
                    allowed: Callable[[int, int], bool]) -> int:
        """Return the index of robot node ``n``'s best option among the ``allowed`` edges to
        ``done`` children: least value under the objective, then least tie keys, then first
        in canonical order."""
        best_i = -1
        best_v: Cost = 0
        best_k: tuple[object, ...] | None = None
        worst, mean = self.worst, self.mean
        for i, e in enumerate(edges):
            c = e.child
            if c < 0 or not done[c] or not allowed(n, c):
                continue
            move = e.move
            if self.expected:
                assert mean is not None
                mc = mean[c]
                assert mc is not None
                v = move.cost + mc
            else:
                v = move.cost + worst[c]
            if best_i < 0 or v < best_v:
                best_i, best_v, best_k = i, v, None
            elif v == best_v and self.ties:
                if best_k is None:
                    b = edges[best_i]
                    best_k = self.tie_key(b.move, b.child)
                k = self.tie_key(move, c)
                if k < best_k:
                    best_i, best_k = i, k
        assert best_i >= 0
        return best_i

    def take(self, n: int, e: Edge) -> None:
        """Robot node ``n`` takes the option ``e``: its totals are the child's plus the
        move."""
        c, move = e.child, e.move
        self.comms[n] = self.comms[c] + (1 if speaks(move) else 0)
        self.waits[n] = self.waits[c] + (1 if move.waits else 0)
        self.leaves[n] = self.leaves[c]
        self.length[n] = self.length[c] + self.leaves[c]
        self.worst[n] = move.cost + self.worst[c]
        if self.mean is not None:
            mc = self.mean[c]
            self.mean[n] = None if mc is None else move.cost + mc

    def branches(self, n: int, edges: tuple[Edge, ...],
                 weight: Callable[[Move], Fraction]) -> None:
        """Human node ``n``: its totals are the sums over every branch (the worst case
        their maximum, the expected cost their mean by ``weight``)."""
        comms, waits, leaves, length, worst = (self.comms, self.waits, self.leaves,
                                               self.length, self.worst)
        sc = sw = sl = slen = 0
        wc: Cost = 0
        for e in edges:
            c, move = e.child, e.move
            sc += comms[c] + (1 if speaks(move) else 0)
            sw += waits[c] + (1 if move.waits else 0)
            sl += leaves[c]
            slen += length[c] + leaves[c]
            x = move.cost + worst[c]
            if x > wc:
                wc = x
        comms[n], waits[n], leaves[n], length[n], worst[n] = sc, sw, sl, slen, wc
        mean = self.mean
        if mean is not None:
            ms = [mean[e.child] for e in edges]
            mean[n] = weighted_mean([weight(e.move) for e in edges],
                                    [e.move.cost + mc for e, mc in zip(edges, ms, strict=True)
                                     if mc is not None])


def prefer(gr: Graph, order: list[int], allowed: Callable[[int, int], bool], obj: Objective,
           budget: Budget | None = None) -> tuple[dict[int, int], list[Vector | None]]:
    """C11, ``kind = "preferences"``: visit ``order`` (:func:`expected_order`: the solvable
    graph, children first) and give each node the vector of the profile's metrics
    (:func:`step_metrics`) of its sub-policy: a goal all zeros; a robot node the
    lexicographically least of its allowed options (a tie: the first in canonical order); a
    human node the lexicographically greatest of its branches (``estimate = "worst-case"``)
    or the least (``"optimistic"``, the authors' best-pair value: the policy still covers
    every branch). Every metric grows along a branch and never lowers a larger value below a
    smaller one, so the vector of a node is its worst (or best) branch's, and the choice at a
    robot node is optimal for the profile over the policies the order allows."""
    metrics = obj.metrics
    zero: Vector = tuple(0 for _ in metrics)
    optimistic = obj.estimate == Estimate.OPTIMISTIC
    vector: list[Vector | None] = [None] * len(gr.states)
    choice: dict[int, int] = {}
    status, states = gr.status, gr.states
    for step, n in enumerate(order):
        if budget is not None and not step & CHECK_EVERY:
            budget.check()
        if status[n] == GOAL:
            vector[n] = zero
            continue
        es = states[n]
        best: Vector | None = None
        best_i = -1
        robot = es.turn == ROBOT
        for i, e in enumerate(gr.edges[n]):
            c = e.child
            vc = vector[c] if c >= 0 else None
            if robot and (vc is None or not allowed(n, c)):
                continue
            assert vc is not None  # a human node's branches are all solvable, done first
            v = step_metrics(gr, es, e.move, metrics, vc)
            if best is None or (v < best if robot or optimistic else v > best):
                best, best_i = v, i
        assert best is not None
        vector[n] = best
        if robot:
            choice[n] = best_i
    return choice, vector


def step_metrics(gr: Graph, es: EState, move: Move, metrics: tuple[str, ...],
                 after: Vector) -> Vector:
    """C11: the profile's metrics from node ``es`` through ``move``, given ``after`` (those
    of the move's child). A move ends a step when it is the reply (the agent who does not
    decide first, C4) or a question (a whole step); the step adds ``[steps] cost`` to
    ``makespan``; ``human_end`` (the steps until the human's last action) adds it when the
    human acts in that step (its move, or with the human first the move the reply node holds
    pending) or acts later; ``human_effort`` counts the human's actions (one a step),
    ``effort`` both agents' actions, ``communications`` inform and ask moves. A metric the
    domain declares adds 1 at the move that ends a step in which an action it counts is done
    (either agent's: the reply, or the move the reply node holds pending) and its condition,
    compiled when the action was grounded, holds in ``es``'s true state (the step's start:
    a reply node keeps it)."""
    sem = gr.sem
    step = sem.grounded.problem.steps
    first = ROBOT if step.first.value == "robot" else HUMAN
    ends = move.kind == ASK or move.agent != first
    human = move.agent == HUMAN
    acts = move.kind == ACTION
    out: list[Cost] = []
    for m, x in zip(metrics, after, strict=True):
        if m == Metric.MAKESPAN:
            out.append(x + step.cost if ends else x)
        elif m == Metric.HUMAN_END:
            human_acts = (acts if human else bool(es.pending) and es.pending[0] == H_ACTION)
            out.append(x + step.cost if ends and (human_acts or x > 0) else x)
        elif m == Metric.HUMAN_EFFORT:
            out.append(x + 1 if human and acts else x)
        elif m == Metric.EFFORT:
            out.append(x + 1 if acts else x)
        elif m == Metric.COMMUNICATIONS:
            out.append(x + 1 if speaks(move) else x)
        else:  # a metric the domain declares
            out.append(x + 1 if ends and _counted(gr, es, move, m) else x)
    return tuple(out)


def _counted(gr: Graph, es: EState, move: Move, name: str) -> bool:
    """C11: whether the step ``move`` ends at ``es`` holds an action the domain's metric
    ``name`` counts, its condition true in the step's start state ``es.true``: the move's own
    action, or the first mover's, which the reply node holds pending (``(H_ACTION, op)``
    with the human first, ``(R_ACTION, op, i)`` with the robot first)."""
    g = gr.sem.grounded
    ops = []
    if move.kind == ACTION and move.op >= 0:
        ops.append((g.robot if move.agent == ROBOT else g.human).ops[move.op])
    pending = es.pending
    if pending and pending[0] == H_ACTION:
        ops.append(g.human.ops[pending[1]])
    elif pending and pending[0] == R_ACTION:
        ops.append(g.robot.ops[pending[1]])
    t = es.true
    return any(m == name and test(t) for op in ops for m, test in op.metrics)


def weighted_mean(weights: list[Fraction], xs: list[Cost]) -> Cost:
    """§7: ``sum(w * x) / sum(w)``, exact (an int when whole)."""
    mean = sum((w * x for w, x in zip(weights, xs, strict=True)), Fraction(0)) / sum(weights)
    return int(mean) if isinstance(mean, Fraction) and mean.denominator == 1 else mean


def speaks(move: Move) -> bool:
    """Return whether ``move`` is a communication (§7, "Ties"): ``inform``, ``ask``,
    ``announce``, or a move that speaks while acting."""
    return move.kind in (INFORM, ASK, ANNOUNCE) or (move.kind in (ACTION, WAIT)
                                                    and move.atoms != 0)
