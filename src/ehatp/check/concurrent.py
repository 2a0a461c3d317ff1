"""Joint, compliant steps as the validator reads them (docs/concurrent.md, rules C1-C12),
written again from the specification, not from the planner (it imports nothing of
``search/`` or ``epistemic/``).

A step of a concurrent policy is two policy moves: at a *decision node* the human's move
(``"step": "human"``, cost 0, one branch per option of the human, C2, C4, C5), which leads to
a *reply node* (the state of the step's start, the human's agendas after its move, the human's
move pending, the robot to move), whose one move is the robot's reply (``"step": "reply"``,
the step's cost, C3, C6-C9) to the next decision node. A question is a whole step
(``"step": "ask"``): the robot's answer is implied.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from fractions import Fraction

from ..model.formula import Var
from ..model.grounded import FINISH, GOp
from ..model.options import Commute, InformWhere, Passes, StepFirst, Witness
from ..model.problem import Problem
from ..model.vocabulary import HUMAN, ROBOT, Agent
from .communication import Semantics
from .network import Agenda
from .rules import ACTION, ASK, INFORM, PASS, WAIT, EState, Step, World, Worlds, _frac

STARTED, PASSED = 0, 1  # a reply node's pending human move: an action (with its id), a pass
# first = "robot": the robot's pending move: an action (its id and the index of its
# refinement at T), wait, inform (the mask told)
ACTED, WAITED, TOLD = 2, 3, 4


class JointRules(Semantics):
    """The validator's rules for ``[steps] mode = "concurrent"``, ``first = "human"``."""

    def __init__(self, problem: Problem, check: Callable[[], None] | None = None) -> None:
        super().__init__(problem, check)
        self.steps = problem.steps
        self.c_step = _frac(problem.steps.cost)

    # -- C1, C10 -------------------------------------------------------------------------------
    @property
    def first(self) -> Agent:
        """C4: who decides first in a step."""
        return ROBOT if self.steps.first == StepFirst.ROBOT else HUMAN

    def initial(self) -> EState:
        """C1, C4: the root is a step's start, where the agent who decides first moves."""
        return replace(super().initial(), turn=self.first)

    def is_goal(self, es: EState) -> bool:
        """C10: §6 at a step's start; a node in the middle of a step is never a goal."""
        return not es.pending and super().is_goal(es)

    def step_of(self, st: Step) -> str:
        """Return the ``step`` a policy move records for ``st`` (docs/policy-format.md): a
        question is ``ask``; the move of the agent who decides first is named after it
        (``human``, ``robot``), the other's is ``reply``."""
        if st.kind == ASK:
            return "ask"
        if st.agent == self.first:
            return "human" if st.agent == HUMAN else "robot"
        return "reply"

    # -- C2, C5: the human decides -----------------------------------------------------------
    def may_pass(self, es: EState, certain: bool, asks: bool, cop: bool) -> bool:
        """C5: co-present, the human may pass when the robot has a real action (a pass with
        nothing for the robot to do would make (pass, wait) the step), or when it has nothing
        else to do; apart, only with nothing else to do; ``passes = "idle"``: only with
        nothing it could do."""
        if self.p.human.passes == Passes.IDLE:
            return not certain and not asks
        if cop:
            robot_does = (es.pending[0] != WAITED if es.pending
                          else bool(self.robot_actions(es)))
            return robot_does or (not certain and not asks)
        return not certain

    def human_options(self, es: EState) -> list[Step]:
        """C2, C4: the human's options (§4, per label over A_H) as the first move of a step:
        an action or a pass leads to the reply node (nothing applied yet, cost 0); an action
        not applicable in T fails (C10); a question is the whole step, answered truthfully
        (C3), costing the step and the question."""
        if es.pending:
            return self.human_replies(es)
        g = self.grounded
        out: list[Step] = []
        for st in super().human_options(replace(es, forced=False)):
            if st.kind == ASK:
                assert st.after is not None
                out.append(replace(st, cost=self.c_step + _frac(self.p.costs.ask),
                                   after=replace(st.after, turn=HUMAN, passive=0)))
            elif st.after is None:
                out.append(replace(st, cost=Fraction(0)))
            else:
                pending = (STARTED, g.task_index[st.act]) if st.kind == ACTION else (PASSED,)
                out.append(replace(st, cost=Fraction(0),
                                   after=replace(es, turn=ROBOT, humans=st.after.humans,
                                                 pending=pending)))
        return out

    # -- C3: which replies go with the human's move -------------------------------------------
    def resources(self, model_ops: dict[str, object], op: GOp) -> set[str]:
        """C3 c: the resources the ground action ``op`` declares (parameters by value)."""
        schema = model_ops.get(op.schema)
        held = getattr(schema, "resources", ())
        params = getattr(schema, "params", ())
        return {op.args[params.index(x)] if isinstance(x, Var) else str(x) for x in held}

    def together(self, es: EState, h: GOp, t_h: int, a: int, rest: Agenda) -> bool:
        """C3: the robot's action ``a`` (leaving ``rest``) and the human's ``h`` in one step:
        ``a`` still a first action of the robot's agenda after ``h`` and ``h`` still
        applicable after ``a`` (a); the same state either way under ``commute = "state"``
        (b); no resource both declare (c)."""
        g = self.grounded
        r = g.robot.ops[a]
        if (a, rest) not in self.refine(g.robot, es.robot, t_h):
            return False
        if not h.pre(r.apply(es.true)):
            return False
        if self.steps.commute == Commute.STATE and h.apply(r.apply(es.true)) != r.apply(t_h):
            return False
        d = self.p.domain
        return not (self.resources(dict(d.robot.operators), r)
                    & self.resources(dict(d.human.operators), h))

    # -- C6-C9: the replies ------------------------------------------------------------------
    def replies(self, es: EState) -> tuple[list[Step], list[tuple[EState, bool]]]:
        """C3-C9: every reply the robot may make at reply node ``es`` (actions and wait), and
        where an inform may be heard: the node after the human's move, and whether the human
        hears there.

        Pseudo-code::

            T_h, W_h = T and every world after the human's action (inferable atoms learnt)
            seen = co-present in T and (co-present in T_h or witness = "start")      (C8)
            for each first action a of the robot's agenda in T (co-present or k < K):
                skip it unless (C3) it goes with the human's action, and unless seen or k < K
                T' = a(T_h); seen: the worlds that anticipate a after the human's move
                advance (else each is revised), inferable atoms learnt; unseen: the product
                of anticipated events, k + 1                                         (C7)
            wait, unless the human passed; unseen while k < K: the product, k + 1
            each: situation assessment on T', k = 0 when co-present               (C7.4)
        """
        g = self.grounded
        t = es.true
        h: GOp | None = None
        t_h, w_h = t, es.worlds
        if es.pending[0] == STARTED:
            h = g.human.ops[es.pending[1]]
            t_h = h.apply(t)
            w_h = self.set_inferable(frozenset((h.apply(s), ag) for s, ag in es.worlds), t, t_h)
        seen = self.cop(t) and (self.cop(t_h) or self.steps.witness == Witness.START)
        out: list[Step] = []
        for a, rest in self.robot_actions(es):
            if not seen and es.k >= self.K:
                continue
            if h is not None and not self.together(es, h, t_h, a, rest):
                continue
            name = g.task_names[a]
            out.append(Step(ROBOT, ACTION, name, self.c_step,
                            self.robot_did(es, a, rest, t_h, w_h, seen), act=name))
        if h is not None:
            out.append(Step(ROBOT, WAIT, "wait", self.c_step,
                            self.robot_waited(es, t_h, w_h, seen), act="wait"))
        heard = seen or self.p.communication.inform == InformWhere.ANYWHERE
        mid = EState(HUMAN, t_h, es.robot, es.humans, self.sa(w_h, t_h),
                     0 if self.cop(t_h) else es.k, 0)
        return out, [(mid, heard)]

    def robot_did(self, es: EState, a: int, rest: Agenda, t_h: int, w_h: Worlds,
                  seen: bool) -> EState:
        """C6-C7: the next step's start after the robot's action ``a`` (leaving ``rest``) in
        a step where the human's move led to ``t_h`` and ``w_h``: seen, the worlds that
        anticipate ``a`` advance by it (none: every world revised to the robot's agenda)
        and the inferable atoms it changed are learnt; unseen, the product, k + 1."""
        g = self.grounded
        t2 = g.robot.ops[a].apply(t_h)
        k = es.k
        if seen:
            ws: set[World] = set()
            for s, tn in w_h:
                for b, rest2 in self.refine(g.robot_seen_by_human, tn, s):
                    if b == a:
                        ws.add((self.rh_op(a).apply(s), rest2))
            if not ws:
                told = self.attributed(rest)
                ws = {(self.rh_op(a).apply(s), told) for s, _ in w_h}
            worlds = self.set_inferable(frozenset(ws), t_h, t2)
        else:
            worlds, k = self.product(w_h), k + 1
        return self.next_node(es, t2, rest, worlds, k)

    def robot_waited(self, es: EState, t_h: int, w_h: Worlds, seen: bool) -> EState:
        """C7: the next step's start after the robot waited: unseen while k < K, one of the
        events the human imagines (the product, k + 1)."""
        worlds, k = w_h, es.k
        if not seen and k < self.K:
            worlds, k = self.product(w_h), k + 1
        return self.next_node(es, t_h, es.robot, worlds, k)

    def next_node(self, es: EState, t2: int, robot: Agenda, worlds: Worlds, k: int) -> EState:
        """C7.4: the next step's start: situation assessment on ``t2``, a non-anticipating
        human seeing a finished robot, k reset when co-present."""
        worlds = self.sees_robot_done(self.sa(worlds, t2), t2, robot)
        return EState(self.first, t2, robot, es.humans, worlds, 0 if self.cop(t2) else k, 0)

    # -- C4, first = "robot" ----------------------------------------------------------------
    def robot_choices(self, es: EState) -> list[Step]:
        """C2, C4 (``first = "robot"``): the robot's actions and ``wait`` at a step's start,
        each leading to the node where the human's moves that go with it are checked; they
        cost nothing (the human's move pays the step). Two actions of one label are named by
        the agenda they leave, ``fetch [shelve]``. (Its informs: :meth:`robot_tells`.)"""
        g = self.grounded
        acts = self.robot_actions(es)
        names = [g.task_names[a] for a, _ in acts]
        out = []
        for i, (a, rest) in enumerate(acts):
            name = names[i]
            label = name if names.count(name) == 1 else f"{name} [{', '.join(self.shown(rest))}]"
            out.append(Step(ROBOT, ACTION, label, Fraction(0),
                            replace(es, turn=HUMAN, pending=(ACTED, a, i)), act=name))
        out.append(Step(ROBOT, WAIT, "wait", Fraction(0),
                        replace(es, turn=HUMAN, pending=(WAITED,)), act="wait"))
        return out

    def robot_tells(self, es: EState, units: list[int]) -> Step:
        """C2, §5 (``first = "robot"``): ``inform(A)`` at a step's start, heard before the
        human moves; it costs ``inform`` (the human's move pays the step)."""
        mask = 0
        for u in units:
            mask |= u
        label = f"inform({', '.join(self.literals(es.true, sorted(units)))})"
        return Step(ROBOT, INFORM, label, _frac(self.p.costs.inform),
                    replace(es, turn=HUMAN, pending=(TOLD, mask)))

    def human_replies(self, es: EState) -> list[Step]:
        """C3-C8, C10 (``first = "robot"``): the human's moves beside the robot's chosen one,
        each a whole step (``[steps] cost``; a question adds ``ask``).

        Pseudo-code::

            W0 = W, told A first when the robot informs
            each human action h (§4 on W0, per label): not applicable in T: fails (C10);
                seen = co-present in T and (in h(T), or witness = "start")         (C8)
                the robot's action a not going with h (C3), or unseen at k = K:
                    seen: h is no option (the human adapts); unseen: h fails (C4)
                else the step as with the human first (C6, C7)
            ask(phi) only beside wait; pass never beside wait (C3, C5)
        """
        g = self.grounded
        kind = es.pending[0]
        a, rest = -1, es.robot
        w0 = es.worlds
        if kind == ACTED:
            a, rest = self.robot_actions(es)[es.pending[2]]
        elif kind == TOLD:
            w0 = self.heard(es.worlds, es.true, self.units(es.pending[1]))
        start = replace(es, worlds=w0, forced=False)
        out: list[Step] = []
        for st in super().human_options(start):
            if st.kind == ASK:
                if kind == WAITED:
                    assert st.after is not None
                    out.append(replace(st, cost=self.c_step + _frac(self.p.costs.ask),
                                       after=replace(st.after, turn=ROBOT, passive=0,
                                                     pending=())))
                continue
            if st.kind == PASS:
                if kind == WAITED:
                    continue
                assert st.after is not None
                now = replace(es, humans=st.after.humans)
                after = (self.robot_did(now, a, rest, es.true, es.worlds, self.cop(es.true))
                         if kind == ACTED else
                         self.next_node(now, es.true, es.robot, w0, es.k))
                out.append(replace(st, cost=self.c_step, after=after))
                continue
            if st.after is None:
                out.append(replace(st, cost=self.c_step))
                continue
            h = g.human.ops[g.task_index[st.act]]
            t_h = h.apply(es.true)
            w_h = self.set_inferable(frozenset((h.apply(s), ag) for s, ag in w0), es.true, t_h)
            seen = self.cop(es.true) and (self.cop(t_h) or self.steps.witness == Witness.START)
            now = replace(es, humans=st.after.humans)
            if kind == ACTED:
                if not self.together(es, h, t_h, a, rest) or (not seen and es.k >= self.K):
                    if not seen:  # a conflict the human could not foresee
                        out.append(replace(st, cost=self.c_step, after=None))
                    continue
                after = self.robot_did(now, a, rest, t_h, w_h, seen)
            elif kind == TOLD:
                after = self.next_node(now, t_h, es.robot, w_h, es.k)
            else:
                after = self.robot_waited(now, t_h, w_h, seen)
            out.append(replace(st, cost=self.c_step, after=after))
        return out

    def robot_actions(self, es: EState) -> list[tuple[int, Agenda]]:
        """C2: the robot's real actions at the step's start (none apart at k = K)."""
        if not (self.cop(es.true) or es.k < self.K):
            return []
        return [(a, r) for a, r in self.refine(self.grounded.robot, es.robot, es.true)
                if a != FINISH]

    def inform_where(self, es: EState) -> str | None:
        """C8, §5: where a reply may inform is decided by :meth:`replies` (the human hears
        what it witnesses, or anywhere under ``inform = "anywhere"``)."""
        return None

    def joint_inform(self, mid: EState, units: list[int]) -> Step:
        """C2, §5: the robot's reply ``inform(A)``: the human hears while acting and learns
        the values of A after its move; the step costs ``[steps] cost`` plus ``inform``."""
        worlds = self.heard(mid.worlds, mid.true, units)
        label = f"inform({', '.join(self.literals(mid.true, sorted(units)))})"
        after = self.next_node(mid, mid.true, mid.robot, worlds, mid.k)
        return Step(ROBOT, INFORM, label, self.c_step + _frac(self.p.costs.inform), after)


__all__ = ["ACTED", "PASSED", "STARTED", "TOLD", "WAITED", "JointRules"]
