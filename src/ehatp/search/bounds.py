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
from .values import CHECK_EVERY

INF = float("inf")
Kids = tuple[tuple[Cost, int], ...]  # a node's edges as (cost, child) pairs
Into = list[tuple[int, Cost, int]]  # the edges into a node as (parent, cost, how many)
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
        # per node, read off the graph once: whether the robot moves there, once expanded its
        # edges as (cost, child) pairs (a node's edges never change once it is expanded), and
        # the edges into it from the expanded nodes whose edges were read, as (parent, cost,
        # how many edges from that parent at that cost): a rise travels up them without
        # scanning each parent's edges for the child
        self._robot = bytearray()
        self._kids: list[Kids | None] = []
        self._into: list[Into] = []
        self.added()

    def added(self) -> None:
        """Give the nodes created since the last call their ``h`` as bound."""
        low, states, hfn = self.low, self.gr.states, self.hfn
        robot, kids, into = self._robot, self._kids, self._into
        for n in range(len(low), len(states)):
            es = states[n]
            low.append(hfn(es))
            robot.append(es.turn == ROBOT)
            kids.append(None)
            into.append([])

    def _kids_of(self, n: int) -> Kids:
        """Return the edges of the expanded (or goal, or dead) node ``n`` as (cost, child)
        pairs, in the graph's order (child -1: a failing move); the first time, also record
        them as edges into the children."""
        k = self._kids[n]
        if k is None:
            k = self._kids[n] = tuple([(e.move.cost, e.child) for e in self.gr.edges[n]])
            into = self._into
            if len({c for _, c in k}) == len(k):  # one edge per child, as nearly always
                for cost, c in k:
                    if c >= 0:
                        into[c].append((n, cost, 1))
            else:
                many: dict[tuple[Cost, int], int] = {}
                for pair in k:
                    if pair[1] >= 0:
                        many[pair] = many.get(pair, 0) + 1
                for (cost, c), m in many.items():
                    into[c].append((n, cost, m))
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
        open): §7's equation, as :func:`~.values.equation` has it, read off its (cost,
        child) pairs."""
        s = self.gr.status[n]
        if s == OPEN:
            return self.low[n]
        if s == GOAL:
            return 0
        low = self.low
        kids = self._kids[n] or self._kids_of(n)
        if self._robot[n]:  # the least option (a dead end has none: infinite)
            best: Bound = INF
            for k, c in kids:
                if c >= 0 and k + low[c] < best:
                    best = k + low[c]
            return best
        if not kids:
            return INF
        worst: Bound = 0
        for k, c in kids:
            if c < 0:
                return INF  # a failing branch
            if k + low[c] > worst:
                worst = k + low[c]
        return worst

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
            self.last_work += len(affected)
            raised = self._pass(affected)

    def _affected(self, raised: list[int]) -> set[int]:
        """Return ``raised`` and the nodes above whose bound only they give (:meth:`revise`):
        a human node one of whose greatest branches is affected, a robot node all of whose
        least options are."""
        low, robots, kids_, into = self.low, self._robot, self._kids, self._into
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
            # at most one entry per parent gives: its edges to x at one cost
            for p, k, gives in into[x]:
                lp = low[p]
                if k + lx != lp or lp == INF or p in affected:
                    continue  # an infinite bound: a rise cannot change it
                if robots[p]:
                    left = support.get(p)
                    if left is None:
                        left = 0
                        for k2, c in kids_[p] or self._kids_of(p):
                            if c >= 0 and k2 + low[c] == lp and c not in affected:
                                left += 1
                    else:
                        left -= gives
                    support[p] = left
                    if left > 0:
                        continue
                affected.add(p)
                stack.append(p)
        return affected

    def _pass(self, nodes: set[int]) -> list[int]:
        """Knuth's pass (:func:`~.values.knuth`) over ``nodes``, the bounds of the other nodes
        fixed: each of ``nodes`` gets the least fixpoint of its equation, infinite where the
        pass never finalises it. Return the human nodes outside ``nodes`` whose bound a node
        of ``nodes`` that rose now exceeds (found on the way up from it)."""
        gr, low, robots, kids_, into = self.gr, self.low, self._robot, self._kids, self._into
        status = gr.status
        heap: list[tuple[Bound, int]] = []
        # human nodes: [their children in nodes not finalised yet, their greatest branch so
        # far]
        waiting: dict[int, list[Bound]] = {}
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
            r = 0
            w: Bound = 0
            for k, c in kids:
                if c < 0:  # a failing branch: infinite
                    break
                if c in nodes:
                    r += 1
                elif k + low[c] > w:
                    w = k + low[c]
            else:
                if not kids:  # no branch: infinite
                    continue
                if r:
                    waiting[x] = [r, w]
                else:
                    heap.append((w, x))
        heapq.heapify(heap)
        final = dict.fromkeys(nodes, False)  # whether each of nodes is finalised
        done = 0
        exceeded: list[int] = []
        met: set[int] = set()
        check = self.check
        heappush, heappop = heapq.heappush, heapq.heappop
        while heap:
            v, x = heappop(heap)
            if final[x]:
                continue
            final[x] = True
            done += 1
            if not done & CHECK_EVERY:
                check()
            rose = low[x] != v
            low[x] = v
            for p, k, m in into[x]:
                f = final.get(p)
                if f is None:
                    # a human node left out whose bound x, risen, now exceeds (never one of
                    # infinite bound)
                    if rose and v + k > low[p] and not robots[p] and p not in met:
                        met.add(p)
                        exceeded.append(p)
                elif f:
                    continue
                elif robots[p]:
                    heappush(heap, (v + k, p))
                else:
                    wait = waiting.get(p)
                    if wait is not None:  # none: a failing branch, infinite
                        wait[0] -= m
                        if v + k > wait[1]:
                            wait[1] = v + k
                        if not wait[0]:
                            heappush(heap, (wait[1], p))
        for x, f in final.items():
            if not f and low[x] != INF:
                low[x] = INF
                for p, _, _ in into[x]:
                    if (p not in final and low[p] != INF and not robots[p]
                            and p not in met):
                        met.add(p)
                        exceeded.append(p)
        return exceeded

    def _whole_pass(self) -> None:
        """Recompute every expanded node's bound by a pass over the whole graph."""
        self.full_passes += 1
        status = self.gr.status
        done = {n for n in range(len(self.low)) if status[n] != OPEN}
        for n in done:
            self._kids_of(n)  # every edge into a node recorded
        self._pass(done)


def _never() -> None:
    """No limit to check."""
