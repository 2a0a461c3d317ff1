"""Lower bounds on the worst-case values of a growing graph, and the tips of the best partial
policy they pick (docs/semantics.md §7, "Search": the focused search).

Every node of the explored graph has a lower bound ``low`` on its worst-case value: an open
node its heuristic ``h`` (:mod:`.heuristic`), a goal 0, a dead end infinity, an expanded node
the least fixpoint of the min/max equations of §7 over its children's bounds, exactly as
:func:`~.values.knuth` computes values with the open nodes' ``h`` as their values. Where no
open node remains below a node, its bound is its value on the explored graph.

The *best partial policy* follows, from the root, every branch of a human node and every
option of a robot node whose ``cost + low(child)`` equals the node's bound (all the tied ones);
its *tips* are the open nodes it reaches. Expanding a tip replaces its ``h`` by its equation,
which is at least ``h`` (``h`` is consistent: ``h(n) <= cost + h(c)`` on every edge), so
bounds only rise: the least fixpoint is monotone in the open nodes' values, and a rise travels
up only through the nodes whose value it supported (:meth:`Bounds.revise`).
"""

from __future__ import annotations

import heapq
from collections.abc import Callable

from ..epistemic.state import ROBOT
from ..model.problem import Cost
from .graph import EXPANDED, GOAL, OPEN, Graph
from .heuristic import Bound, Heuristic
from .values import CHECK_EVERY, equation

INF = float("inf")
Kids = tuple[tuple[Cost, int], ...]  # a node's edges as (cost, child) pairs
FEW_EDGES = 16  # a node with more edges is read through a table by child (Bounds._to)
SPREAD = 8  # a batch of expansions is at least 1/SPREAD of the last revision's work (nodes)


class Bounds:
    """The lower bounds ``low`` of every node of ``gr`` (the module's docstring), kept as the
    graph grows: :meth:`added` after nodes are created, :meth:`revise` after a batch of
    expansions."""

    def __init__(self, gr: Graph, hfn: Heuristic,
                 check: Callable[[], None] | None = None) -> None:
        self.gr = gr
        self.hfn = hfn
        # the budget's check (:mod:`.limits`), every CHECK_EVERY + 1 nodes a revision reads
        self.check = check if check is not None else _never
        self.low: list[Bound] = []
        self.last_work = 0  # the nodes the last revision recomputed
        self.full_passes = 0  # revisions done by a whole pass (a bound that fell: none expected)
        # per node, read off the graph once: whether the robot moves there, and once expanded
        # its edges as (cost, child) pairs (a node's edges never change once it is expanded)
        self._robot = bytearray()
        self._kids: list[Kids | None] = []
        self._by_child: dict[int, dict[int, Kids]] = {}  # nodes past FEW_EDGES (_to)
        self.added()

    def added(self) -> None:
        """Give the nodes created since the last call their ``h`` as bound."""
        low, states, hfn = self.low, self.gr.states, self.hfn
        robot, kids = self._robot, self._kids
        for n in range(len(low), len(states)):
            es = states[n]
            low.append(hfn(es))
            robot.append(es.turn == ROBOT)
            kids.append(None)

    def _kids_of(self, n: int) -> Kids:
        """Return the edges of the expanded (or goal, or dead) node ``n`` as (cost, child)
        pairs, in the graph's order (child -1: a failing move)."""
        k = self._kids[n]
        if k is None:
            k = self._kids[n] = tuple([(e.move.cost, e.child) for e in self.gr.edges[n]])
        return k

    def walk(self, root: int) -> list[int]:
        """Return the tips of the best partial policy from ``root`` (the module's docstring),
        in the order a depth-first walk meets them. With an infinite bound at the root every
        option ties: the walk then reaches everything reachable, as a search for a proof that
        no policy exists must."""
        low, status, robots, kids = self.low, self.gr.status, self._robot, self._kids
        seen = bytearray(len(low))
        seen[root] = 1
        stack = [root]
        tips: list[int] = []
        check, steps = self.check, 0
        while stack:
            steps += 1
            if not steps & CHECK_EVERY:
                check()
            n = stack.pop()
            s = status[n]
            if s == OPEN:
                tips.append(n)
                continue
            if s != EXPANDED:
                continue
            if robots[n]:
                v = low[n]
                for k, c in kids[n] or self._kids_of(n):
                    if c >= 0 and not seen[c] and k + low[c] == v:
                        seen[c] = 1
                        stack.append(c)
            else:
                for _, c in kids[n] or self._kids_of(n):
                    if c >= 0 and not seen[c]:
                        seen[c] = 1
                        stack.append(c)
        return tips

    def followed(self, n: int) -> list[int]:
        """Return the children the best partial policy follows from ``n`` on the current
        bounds, ``n``'s own equation included: a human node's every branch, a robot node's
        least options (none unless ``n`` is expanded)."""
        low = self.low
        if self.gr.status[n] != EXPANDED:
            return []
        kids = self._kids_of(n)
        if not self._robot[n]:
            return [c for _, c in kids if c >= 0]
        v = self._eval(n)
        return [c for k, c in kids if c >= 0 and k + low[c] == v]

    def _eval(self, n: int) -> Bound:
        """Return ``n``'s bound from its children's current bounds (its own ``h`` while
        open)."""
        if self.gr.status[n] == OPEN:
            return self.low[n]
        return equation(self.gr, n, self.low)  # a dead end has no edge: infinite

    def revise(self, expanded: list[int]) -> None:
        """The nodes ``expanded`` were just expanded (or became goals or dead ends): bring
        every bound back to the least fixpoint. In GTPyhop-style pseudo-code::

            revise(expanded):
                raised = the nodes of expanded whose equation now differs from their bound
                while raised:
                    affected = raised, and up through the parents whose bound affected
                        children give (cost + low(child) = low(parent)): a human node one
                        of whose greatest branches is affected, a robot node all of whose
                        least options are; infinite bounds stay
                    recompute the affected bounds by Knuth's pass, the others' fixed (an
                        affected node the pass never finalises: infinite)
                    raised = the human parents left out that a risen child now exceeds

        When the loop ends every node satisfies its equation: a robot node left out has its
        least option elsewhere (the affected only rise), a human node left out no child above
        its bound. With positive costs a finite solution is unique, and the bounds never pass
        the least fixpoint, so they are it. A bound that fell (which a consistent ``h`` rules
        out) is handled by a pass over the whole graph."""
        low = self.low
        raised: list[int] = []
        for n in expanded:
            v = self._eval(n)
            if v < low[n]:
                self._whole_pass()
                return
            if v != low[n]:
                raised.append(n)
        self.last_work = 0
        while raised:
            affected = self._affected(raised)
            before = {x: low[x] for x in affected}
            self.last_work += len(affected)
            self._pass(affected)
            raised = self._exceeded(affected, before)

    def _to(self, p: int, x: int) -> Kids:
        """Return (cost, child) pairs of ``p`` among which are all its edges to ``x``: all of
        them, or past :data:`FEW_EDGES` only those to ``x``, from a table of ``p``'s edges by
        child made once (a node with thousands of children, each revised, would otherwise be
        scanned once per child: IPC Woodworking's root has 14,581)."""
        kids = self._kids[p] or self._kids_of(p)
        if len(kids) <= FEW_EDGES:
            return kids
        by_child = self._by_child.get(p)
        if by_child is None:
            table: dict[int, list[tuple[Cost, int]]] = {}
            for pair in kids:
                table.setdefault(pair[1], []).append(pair)
            by_child = self._by_child[p] = {c: tuple(v) for c, v in table.items()}
        return by_child.get(x, ())

    def _affected(self, raised: list[int]) -> set[int]:
        """Return ``raised`` and the nodes above whose bound only they give (:meth:`revise`):
        a human node one of whose greatest branches is affected, a robot node all of whose
        least options are."""
        gr, low, robots, kids_, to = self.gr, self.low, self._robot, self._kids, self._to
        status, parents = gr.status, gr.parents
        affected = set(raised)
        support: dict[int, int] = {}  # robot nodes: their least options not affected yet
        stack = list(raised)
        check, steps = self.check, 0
        while stack:
            steps += 1
            if not steps & CHECK_EVERY:
                check()
            x = stack.pop()
            lx = low[x]
            ps = parents(x)
            for p in (set(ps) if len(ps) > 1 else ps):
                if p in affected or status[p] != EXPANDED:
                    continue
                lp = low[p]
                if lp == INF:
                    continue  # a rise cannot change it
                gives = 0
                kids = kids_[p] or self._kids_of(p)
                for k, c in (kids if len(kids) <= FEW_EDGES else to(p, x)):
                    if c == x and k + lx == lp:
                        gives += 1
                if not gives:
                    continue
                if robots[p]:
                    left = support.get(p)
                    if left is None:
                        left = 0
                        for k, c in kids:
                            if c >= 0 and c not in affected and k + low[c] == lp:
                                left += 1
                    else:
                        left -= gives
                    support[p] = left
                    if left > 0:
                        continue
                affected.add(p)
                stack.append(p)
        return affected

    def _exceeded(self, affected: set[int], before: dict[int, Bound]) -> list[int]:
        """Return the human nodes outside ``affected`` whose bound a risen child of
        ``affected`` now exceeds."""
        gr, low, robots, to = self.gr, self.low, self._robot, self._to
        status = gr.status
        out: list[int] = []
        met: set[int] = set()
        for x, was in before.items():
            lx = low[x]
            if lx == was:
                continue
            for p in gr.parents(x):
                if (p in affected or p in met or status[p] != EXPANDED
                        or robots[p] or low[p] == INF):
                    continue
                lp = low[p]
                for k, c in to(p, x):
                    if c == x and k + lx > lp:
                        met.add(p)
                        out.append(p)
                        break
        return out

    def _pass(self, nodes: set[int]) -> None:
        """Knuth's pass (:func:`~.values.knuth`) over ``nodes``, the bounds of the other nodes
        fixed: each of ``nodes`` gets the least fixpoint of its equation, infinite where the
        pass never finalises it."""
        gr, low, robots, kids_, to = self.gr, self.low, self._robot, self._kids, self._to
        status, parents = gr.status, gr.parents
        heap: list[tuple[Bound, int]] = []
        remaining: dict[int, int] = {}
        worst: dict[int, Bound] = {}
        for x in nodes:
            s = status[x]
            if s == GOAL:
                heap.append((0, x))
                continue
            if s != EXPANDED:  # a dead end (an open node is never affected)
                continue
            kids = kids_[x] or self._kids_of(x)
            if robots[x]:
                best: Bound = INF
                for k, c in kids:
                    if c >= 0 and c not in nodes and k + low[c] < best:
                        best = k + low[c]
                if best < INF:
                    heap.append((best, x))
                continue
            if not kids or any(c < 0 for _, c in kids):
                continue
            r = 0
            w: Bound = 0
            for k, c in kids:
                if c in nodes:
                    r += 1
                elif k + low[c] > w:
                    w = k + low[c]
            remaining[x], worst[x] = r, w
            if r == 0:
                heap.append((w, x))
        heapq.heapify(heap)
        final: set[int] = set()
        check = self.check
        heappush, heappop = heapq.heappush, heapq.heappop
        while heap:
            v, x = heappop(heap)
            if x in final:
                continue
            final.add(x)
            if not len(final) & CHECK_EVERY:
                check()
            low[x] = v
            ps = parents(x)
            for p in (set(ps) if len(ps) > 1 else ps):
                if p not in nodes or p in final:
                    continue
                robot = robots[p]
                kids = kids_[p] or self._kids_of(p)
                for k, c in (kids if len(kids) <= FEW_EDGES else to(p, x)):
                    if c != x:
                        continue
                    cand = v + k
                    if robot:
                        heappush(heap, (cand, p))
                    elif remaining.get(p, 0) > 0:  # none: a failing branch, infinite
                        remaining[p] -= 1
                        if cand > worst[p]:
                            worst[p] = cand
                        if remaining[p] == 0:
                            heappush(heap, (worst[p], p))
        for x in nodes:
            if x not in final:
                low[x] = INF

    def _whole_pass(self) -> None:
        """Recompute every expanded node's bound by a pass over the whole graph."""
        self.full_passes += 1
        status = self.gr.status
        self._pass({n for n in range(len(self.low)) if status[n] != OPEN})


def _never() -> None:
    """No limit to check."""
