"""A lower bound on the worst-case cost still to pay from an epistemic state (docs/semantics.md
§7, "Search"), by which the worst-case search expands its nodes: ``f = g + h``, A*-style.

**The bound.** Computed once on the *lifted* models ``M_R`` and ``M_H`` (action and task schemas
by name), so it is the same for every ground instance of a schema and does not change under a
renaming of objects (§3, "Symmetry"):

- ``cost(a)`` of an action schema: its cost (``[costs.actions]``, else the domain's), or 0 when
  it has a done-condition — a done task is skipped for free (§1, "Refinement");
- ``cost(t)`` of an abstract task: 0 when it has a done-condition, else the least over its
  methods of the sum of their subtasks' costs; the greatest solution of these equations
  (iterated down from infinity, so recursion terminates). A task with no method that ever
  finishes costs infinity: refining it gives nothing, the agent is blocked on it for good;
- ``count``: the same with every action counting 1 (the least number of actions);
- an agenda's ``cost`` (``count``): the sum over its tasks, a block's members included (§1,
  "Partial order").

``h`` of a state is ``R + H``, a bound on the robot's moves plus a bound on the human's:

- ``R = max(cost_R(robot agenda), r * (count_H(human agenda) - [human to move] - [opening]))``
- ``H = max(cost_H(human agenda), h * (count_R(robot agenda) - [robot to move]))``

where ``r`` is the cheapest robot move other than the opening's ``silence`` (``wait``,
``inform``, any robot action) and ``h`` the cheapest human move (``pass``, ``ask``, any human
action); a negative product counts 0.

**Why it is a lower bound** (admissible: ``h(n) <= value(n)`` for every node, §7). Each term
rests on a rule of docs/semantics.md:

- *The agendas must be finished* (§6: the robot's agenda can finish under ``T``, the human's
  certainly finishes over ``W``), and *an agenda changes only by its agent's own action*
  (§4: ``tn_R := rest`` on a robot action, ``tn_H := rest`` on a human action; ``wait``,
  ``pass``, ``inform``, ``ask`` and the worlds' updates leave both agendas as they are).
- *Refinement never makes an agenda cheaper than its first action says* (§1): every result
  ``(a, rest)`` of ``refine`` (in one state, or over the worlds) has
  ``cost(agenda) <= cost(a) + cost(rest)`` — skipping a done task removes a task of cost 0,
  a method replaces a task by subtasks costing at least as much (each ground method is an
  instance of a lifted one, with the same subtask schemas), a block member refined in place
  keeps the other members (§1, "Partial order") — and a result ``FINISH`` has
  ``cost(agenda) = 0``. So the robot actions of any path to a goal cost at least
  ``cost_R`` of the robot's agenda, the human's actions at least ``cost_H`` of the human's,
  and likewise for ``count``. (The robot's moves that speak while acting cost more than the
  action, §5.)
- *The agents alternate* (§4: every robot move gives the turn to the human, every human move
  to the robot): on a path from a robot node, there are at most one robot move more than human
  moves; from a human node, at most as many robot moves as human moves. Every move but the
  opening's ``silence`` (§5, at the root only) costs at least ``r`` (robot) or ``h`` (human).
  So ``count_R`` robot actions still to do force ``count_R - [robot to move]`` human moves,
  and ``count_H`` human actions force ``count_H - [human to move]`` robot moves, one of which
  may be the free ``silence``.

Robot moves and human moves are different moves, so the two bounds add up. Done-conditions
evaluated in ``T`` or in the worlds, ``ask``, ``inform``, unseen actions and ``K``, counters,
state variables and every ``[human]`` / ``[communication]`` option leave these arguments
untouched: nothing here reads a state, only agendas, costs and whose turn it is.

**The robot alone: one action ahead** (``Heuristic(grounded, robot=...)``). When the human
has no task (``A_H = {()}``), it only passes (§4: no action and no question of its own), so
``T`` changes only by the robot's actions, and the robot's agenda only by them too: the next
robot action of any path from ``n`` is one of ``refine_R(tn_R, T)``, the options of the state
the robot is in now, taken in that state (§4). So its actions still cost at least

- ``front_cost = min over (a, rest) of refine_R(tn_R, T) of cost(a) + cost_R(rest)`` (0 for
  ``FINISH``; infinite with no option, since nothing will ever change ``T`` or ``tn_R``),

and likewise ``front_count`` with each action counting 1. Both are at least ``cost_R`` and
``count_R`` (the refinement step above), and replace them in ``R`` and ``H``. Consistency: a
robot action ``(a, rest)`` of cost ``k`` is one of the options, so ``front(n) <= k +
cost_R(rest) <= k + front(c)``; every other move (``wait``, ``inform``, ``pass``, ...)
leaves ``T`` and ``tn_R``, hence ``front``, as they are. ``refine_R`` commutes with a renaming
of objects (§3), so the bound still does not change under one. A refinement nested too deep
(§1, ``max_decomposition``) gives the agenda-only bound instead: the search says so itself
when it expands the node. (Two or three actions ahead, tried on the IPC domains: Entertainment
expands 11,814 and 10,554 states instead of 13,246, but po-Monroe takes 28 and 102 s instead
of 5.7, refining every option's options; one action is kept.)

**Consistency** (what the stopping rule needs): along every edge ``n -> c`` of cost ``k``,
``h(n) <= k + h(c)`` — an action lowers its own agent's ``cost`` by at most its cost and its
``count`` by at most 1, the other agent's bound only grows (whose turn it is flips), a move
that changes no agenda lowers only the mover's alternation term, by one move at most. And
``h = 0`` at a goal. Hence ``f = g + h`` never decreases along a path, the search pops nodes
in order of ``f``, each with its cheapest ``g`` (see :mod:`.andor` for the stopping rule).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from fractions import Fraction

from ..epistemic.state import ROBOT, EState
from ..errors import DomainError
from ..model.agenda import Agenda, Block
from ..model.domain import AgentModel, Operator
from ..model.grounded import FINISH, Grounded
from ..model.htn import Refiner
from ..model.problem import Cost

INF = float("inf")
Bound = Cost | float  # a cost, or INF: no way to finish

OVERRIDE: bool | None = None
"""Deprecated, goes in the next release: pass ``heuristic=`` to ``solve`` or ``search``
instead. When not None, turns the heuristic on (True) or off (False) in every worst-case search
whose caller does not say."""


def enabled(heuristic: bool | None) -> bool:
    """Return whether a worst-case search orders its nodes by ``g + h``: ``heuristic`` when
    the caller says, else yes (unless the deprecated :data:`OVERRIDE` says otherwise)."""
    if heuristic is not None:
        return heuristic
    if OVERRIDE is not None:
        warnings.warn("ehatp.search.heuristic.OVERRIDE is deprecated and goes in the next "
                      "release: pass heuristic=True/False to solve() or search()",
                      DeprecationWarning, stacklevel=3)
        return OVERRIDE
    return True


def least_costs(model: AgentModel, price: Callable[[Operator], Cost]) -> dict[str, Bound]:
    """§1 ("Refinement"): for each action and abstract task schema of ``model``, by name, a lower
    bound on what getting it out of an agenda costs: an action's ``price``, or 0 with a
    done-condition (a done task is skipped); an abstract task 0 with a done-condition, else the
    least over its methods of the sum of its subtasks' bounds. The greatest solution of these
    equations, iterated down from INF (INF: no method ever finishes the task, so refining it
    gives nothing for good). A subtask name the model does not know counts 0 (grounding refuses
    it, should the method ever be used)."""
    out: dict[str, Bound] = {}
    for name, op in model.operators.items():
        out[name] = 0 if op.done is not None else price(op)
    for name, t in model.tasks.items():
        out[name] = 0 if t.done is not None else INF
    methods = [(method.task.name, tuple(st.name for st in method.subtasks))
               for method in model.methods if method.task.done is None]
    # Bellman-Ford over the AND/OR task graph: after round k every task whose cheapest
    # decomposition tree is at most k deep has its value; with costs >= 0 a cheapest tree never
    # repeats a task on a branch, so len(tasks) + 1 rounds see no change
    for _ in range(len(model.tasks) + 2):
        changed = False
        for task, subs in methods:
            total: Bound = 0
            for s in subs:
                total = total + out.get(s, 0)
            if total < out[task]:
                out[task] = total
                changed = True
        if not changed:
            return out
    raise AssertionError("least_costs did not converge")  # pragma: no cover - see above


def _exact(c: int | float | Fraction) -> Cost:
    """A cost as the search adds it: a float becomes the Fraction it reads as (§7)."""
    return c if isinstance(c, int | Fraction) else Fraction(str(c))


class Heuristic:
    """``h`` of epistemic states (the module's docstring gives the bound and its proof, after
    docs/semantics.md §1, §4, §5, §6). Computed once per problem on the lifted models; an
    agenda's cost and count are cached, so ``h`` of a state is two dictionary lookups once its
    agendas have been seen. With ``robot`` (the robot's refiner, ``M_R``; for a human with no
    task only: the module's docstring, "The robot alone"), the robot's terms look one action
    ahead in ``T``."""

    def __init__(self, grounded: Grounded, robot: Refiner | None = None) -> None:
        p = grounded.problem
        d, c = p.domain, p.costs

        def price(op: Operator) -> Cost:
            return _exact(c.actions.get(op.name, op.cost))

        def one(op: Operator) -> Cost:
            return 1

        self._g = grounded  # its task names grow if tasks are grounded on demand
        self._robot = (least_costs(d.robot, price), least_costs(d.robot, one))
        self._human = (least_costs(d.human, price), least_costs(d.human, one))
        # the cheapest move of each agent (§4-§5; the opening's silence apart)
        self.robot_move: Cost = min([_exact(c.wait), _exact(c.inform),
                                     *([_exact(c.ask)] if p.communication.robot_asks else []),
                                     *(price(op) for op in d.robot.operators.values())])
        self.human_move: Cost = min([_exact(c.pass_), _exact(c.ask),
                                     *(price(op) for op in d.human.operators.values())])
        self._robot_agendas: dict[Agenda, tuple[Bound, Bound]] = {}
        self._human_agendas: dict[Agenda, tuple[Bound, Bound]] = {}
        self._robot_tasks: dict[int, tuple[Bound, Bound]] = {}  # task -> its bound
        self._human_tasks: dict[int, tuple[Bound, Bound]] = {}
        if robot is not None and grounded.human_agenda:
            raise ValueError("one action ahead is a bound only for a human with no task")
        self._front = robot

    @property
    def looks_ahead(self) -> bool:
        """Whether the robot's terms look one action ahead (the module's docstring)."""
        return self._front is not None

    def __call__(self, es: EState) -> Bound:
        """§6-§7: a lower bound on the worst-case cost from ``es`` to a goal (0 at a goal,
        INF when an agenda can never finish)."""
        return self._bound(es, self._front is not None)

    def quick(self, es: EState) -> Bound:
        """§7: the bound without looking ahead, from the agendas alone (at most ``self(es)``,
        consistent too): what the search queues a node by, reading the whole bound only when
        the node comes out of the queue (:mod:`.andor`)."""
        return self._bound(es, False)

    def _bound(self, es: EState, ahead: bool) -> Bound:
        if ahead:
            rc, rn = self.front(es.robot_agenda, es.true)
        else:
            rc, rn = (self._robot_agendas.get(es.robot_agenda)
                      or self.agenda(es.robot_agenda, True))
        # §3: the robot cannot tell the hypotheses apart, and a goal finishes one of them at
        # least (each bound is consistent, so their minimum is)
        hc, hn = self.human_bound(es.human_agendas)
        robot_turn = es.turn == ROBOT
        r: Bound = rc
        if hn and self.robot_move:
            x = self.robot_move * (hn - (0 if robot_turn else 1) - (1 if es.opening else 0))
            if x > r:
                r = x
        h: Bound = hc
        if rn and self.human_move:
            x = self.human_move * (rn - (1 if robot_turn else 0))
            if x > h:
                h = x
        return r + h

    def front(self, agenda: Agenda, t: int) -> tuple[Bound, Bound]:
        """§1, §4, §7, the robot alone (the module's docstring): the least, over the options
        ``(a, rest)`` of ``agenda`` in ``t`` (``M_R``), of ``a``'s cost plus ``rest``'s bound,
        and of 1 plus ``rest``'s count; (0, 0) when it can finish, INF with no option. The
        options are the refiner's, remembered per (agenda, state), which the search reads
        again when it expands the node."""
        assert self._front is not None
        try:
            options = self._front.refine(agenda, t)
        except DomainError:  # nested too deep: the search reports it where it expands
            return self.agenda(agenda, True)
        cost: Bound = INF
        count: Bound = INF
        for op, rest in options:
            if op == FINISH:
                return 0, 0
            rc, rn = self._robot_agendas.get(rest) or self.agenda(rest, True)
            price = self._g.robot.ops[op].cost  # what the move costs (§7)
            if price + rc < cost:
                cost = price + rc
            if 1 + rn < count:
                count = 1 + rn
        return cost, count

    def human_bound(self, agendas: tuple[Agenda, ...]) -> tuple[Bound, Bound]:
        """§3, §7: the least cost and count of finishing any hypothesis of ``A_H``."""
        if len(agendas) == 1:
            h = agendas[0]
            return self._human_agendas.get(h) or self.agenda(h, False)
        bounds = [self.agenda(h, False) for h in agendas]
        return min(c for c, _ in bounds), min(n for _, n in bounds)

    def agenda(self, agenda: Agenda, robot: bool) -> tuple[Bound, Bound]:
        """§1: the least cost and the least number of actions that finishing ``agenda`` takes
        its agent (the robot's with ``M_R``, else the human's with ``M_H``): the sums over its
        tasks, a block's members included."""
        cache = self._robot_agendas if robot else self._human_agendas
        r = cache.get(agenda)
        if r is None:
            tasks = self._robot_tasks if robot else self._human_tasks
            cost: Bound = 0
            count: Bound = 0
            for item in agenda:
                for t in ((member for member, _ in item) if isinstance(item, Block) else (item,)):
                    if t < 0:  # FINISH
                        continue
                    tc = tasks.get(t)
                    if tc is None:
                        tc = tasks[t] = self._task(t, robot)
                    cost = cost + tc[0]
                    count = count + tc[1]
            r = cache[agenda] = (cost, count)
        return r

    def _task(self, t: int, robot: bool) -> tuple[Bound, Bound]:
        """§1: the least cost and number of actions that finishing task ``t`` takes (its
        schema's, from the lifted model)."""
        costs, counts = self._robot if robot else self._human
        schema = self._g.task_names[t].partition("(")[0]
        return costs.get(schema, 0), counts.get(schema, 0)


__all__ = ["INF", "OVERRIDE", "Bound", "Heuristic", "enabled", "least_costs"]
