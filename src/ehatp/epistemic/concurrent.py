"""Joint, compliant steps (docs/concurrent.md, the specification's rules C1-C12): the planner's
reading.

In ``[steps] mode = "concurrent"`` both agents act in every step. The search keeps its AND/OR
graph: a step is two moves of the graph,

- a *decision node* (C1: a node at the start of a step, ``pending`` empty, the human to
  move): one AND branch per human option ``h`` (C2, C5); its move costs nothing;
- a *reply node* (the same node with ``h`` chosen: ``pending`` holds it, the robot to move):
  one OR option per robot reply ``r`` admissible with ``h`` (C3); its move costs the step
  (C11: ``[steps] cost``, default 1, plus the communication it makes) and leads to the next
  decision node with both effects applied (C6) and the human's worlds updated (C7-C8).

A reply node records the true state, the worlds and ``k`` of the step's start (what the robot
saw when the human started), and the human agendas after ``h`` (what the robot learnt by
seeing it: C9). A question ``ask(phi)`` is a whole step (C3: its only reply is the robot's
truthful answer), so its move leads straight to the next decision node and costs the step and
the question.

With ``[steps] first = "robot"`` (C4) the roles of the two nodes swap: at the decision node
the robot chooses (OR: an action, ``wait`` or ``inform``, costing nothing but what it says),
at the reply node the human's options that go with it are the AND branches, each costing the
step; a human move the robot's choice makes impossible is a failure when the human did not
see the robot start (an unforeseeable conflict), and not an option when it did.

Turn-taking (:class:`~.semantics.Semantics`) is untouched: this class is used only when a
problem asks for joint steps (:func:`semantics_for`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

from mypy_extensions import mypyc_attr

from ..errors import InputError
from ..model.agenda import Agenda
from ..model.formula import Formula, Var
from ..model.grounded import FINISH, GOp, Grounded
from ..model.options import (
    Commute,
    InformWhere,
    Intentions,
    Passes,
    Speech,
    StepFirst,
    Witness,
)
from ..model.vocabulary import Agent
from .semantics import (
    ACTION,
    ASK,
    INFORM,
    PASS,
    WAIT,
    Move,
    Semantics,
    _hypotheses,
    _relabel,
)
from .state import HUMAN, ROBOT, EState, World, Worlds, normalize

H_ACTION, H_PASS = 0, 1  # what a reply node's ``pending`` starts with: the human's choice
# first = "robot": the robot's choice, (R_ACTION, op, index of its refinement at T),
# (R_WAIT,) or (R_INFORM, mask)
R_ACTION, R_WAIT, R_INFORM = 2, 3, 4


def semantics_for(grounded: Grounded) -> Semantics:
    """Return the transition rules the problem asks for: turn-taking (§4) by default, joint
    steps (C1-C12) under ``[steps] mode = "concurrent"``."""
    if grounded.problem.steps.concurrent:
        return ConcurrentSemantics(grounded)
    return Semantics(grounded)


def check_concurrent(grounded: Grounded) -> None:
    """Raise :class:`InputError` when the problem combines joint steps with a setting they do
    not read (docs/concurrent.md, "Open points"): speech with an action, the robot's
    question or announcement."""
    p = grounded.problem
    bad = []
    if p.communication.speech == Speech.WITH_ACTION:
        bad.append(('[communication] speech', 'leave speech out: a joint step already lets '
                    'the robot inform while the human acts'))
    if p.communication.robot_asks:
        bad.append(("[communication] robot_asks", "leave robot_asks out"))
    if p.communication.announce:
        bad.append(("[communication] announce", "leave announce out"))
    if bad:
        place, fix = bad[0]
        raise InputError(p.source, place, 'not supported with [steps] mode = "concurrent"', fix)


@mypyc_attr(allow_interpreted_subclasses=True)  # the executor's tracing class subclasses it
class ConcurrentSemantics(Semantics):
    """The rules C1-C12 of docs/concurrent.md (``first = "human"``: the compliant robot)."""

    passive_carried: ClassVar[bool] = False  # a step's reply node keeps the count (C4)

    def __init__(self, grounded: Grounded) -> None:
        check_concurrent(grounded)
        super().__init__(grounded)
        self.steps = grounded.problem.steps
        self._held: dict[tuple[Agent, int], frozenset[str]] = {}

    # -- C1: nodes ------------------------------------------------------------------------
    @property
    def first(self) -> Agent:
        """C4: who decides first in every step."""
        return ROBOT if self.steps.first == StepFirst.ROBOT else HUMAN

    def initial(self) -> EState:
        """C1: the root is a decision node (C4: the agent who decides first moves); who
        "starts" in turn-taking does not matter."""
        return super().initial()._replace(turn=self.first)

    def is_goal(self, es: EState) -> bool:
        """C10: a decision node that is a goal of §6 (a reply node never is: a step is under
        way)."""
        return not es.pending and super().is_goal(es)

    def moves(self, es: EState) -> list[Move]:
        """C4: ``first = "human"``: at a decision node the human's options (AND), at a reply
        node the robot's admissible replies (OR); ``first = "robot"``: the robot's options
        (OR), then the human's that go with the one chosen (AND)."""
        if self.first == ROBOT:
            return self.human_replies(es) if es.pending else self.robot_decisions(es)
        return self.replies(es) if es.pending else self.decisions(es)

    # -- C2, C5: the human's options ---------------------------------------------------------
    def robot_actions(self, es: EState) -> list[tuple[GOp, Agenda]]:
        """C2: the robot's real action options at the step's start: the first actions of its
        refinements under T, while co-present or ``k < K`` (C7.3: none once ``k = K``)."""
        if not (self.copresent(es.true) or es.k < self.K):
            return []
        return [(self.robot_op(op), rest) for op, rest in self.R.refine(es.robot_agenda, es.true)
                if op != FINISH]

    def may_pass(self, es: EState, acts: bool, asks: bool, robot_acts: bool) -> bool:
        """C5: whether one hypothesis of the human may pass: while co-present when the robot
        has a real action (else ``(pass, wait)`` would be the step), or when the human has
        nothing else to do (then the step needs a robot reply other than ``wait``); while
        apart only with nothing else to do; under ``[human] passes = "idle"`` only with
        nothing it could do."""
        if self.human_model.passes == Passes.IDLE:
            return not acts and not asks
        if self.copresent(es.true):
            return robot_acts or (not acts and not asks)
        return not acts

    def decisions(self, es: EState) -> list[Move]:
        """C2-C5, C10: the human's options at a decision node, one AND branch per distinct
        label over the hypotheses of ``A_H`` (§3-§4), each leading to the reply node where
        the robot, having seen the human start, replies.

        Pseudo-code::

            robot_acts = the robot's real actions at T (C2)
            for each hypothesis h of A_H:
                acts, asks = h's certain actions and questions on W (§4)
                pass is h's option by C5 (robot_acts, acts, asks, co-presence)
            action a:  fails (child None) if a does not hold in T (C10: a false belief);
                       else -> reply node (T, W, k unchanged; A_H := the agendas after a;
                       pending = (H_ACTION, a)), cost 0 (the reply pays the step)
            ask(phi):  the whole step (C3): W filtered on phi's value in T,
                       -> next decision node, cost c_step + c_ask
            pass:      -> reply node, pending = (H_PASS,), cost 0
        """
        acts, asks, passers = self.human_choices(es, bool(self.robot_actions(es)))
        out = self.each_action(es, acts, self.human_starts)
        for label, (phi, hs) in sorted(asks.items()):
            asked = self.ask(es, phi)
            out.append(Move(HUMAN, ASK, f"ask({label})", self.steps.cost + self.costs.ask,
                            asked._replace(turn=HUMAN, human_agendas=_hypotheses(hs),
                                           passive=0)))
        if passers:
            out.append(Move(HUMAN, PASS, "pass", 0,
                            es._replace(turn=ROBOT, human_agendas=_hypotheses(passers),
                                        pending=(H_PASS,))))
        return out

    def human_choices(self, es: EState, robot_acts: bool) -> tuple[
            dict[int, list[Agenda]], dict[str, tuple[Formula, list[Agenda]]], list[Agenda]]:
        """C2, C5 over the hypotheses of ``A_H`` (§3-§4): each action with the agendas after
        it, each question with its formula and the hypotheses that ask it, and the hypotheses
        that may pass (``robot_acts``: whether the robot does something real this step)."""
        acts: dict[int, list[Agenda]] = {}
        asks: dict[str, tuple[Formula, list[Agenda]]] = {}
        passers: list[Agenda] = []
        for h in es.human_agendas:
            h_acts, h_asks, _, _ = self.human_options(es._replace(forced=False), h)
            for op, rest in h_acts:
                acts.setdefault(op, []).append(rest)
            for label, phi in h_asks.items():
                asks.setdefault(label, (phi, []))[1].append(h)
            if self.may_pass(es, bool(h_acts), bool(h_asks), robot_acts):
                passers.append(h)
        return acts, asks, passers

    def each_action(self, es: EState, acts: dict[int, list[Agenda]],
                    make: Callable[[EState, GOp, tuple[Agenda, ...]], Move | None]
                    ) -> list[Move]:
        """§3-§4: one move per action label (``make``), keeping every agenda after it; under
        visible intentions one per refinement, a repeated label naming the agenda left."""
        out: list[Move] = []
        for op, rests in acts.items():
            gop = self.grounded.human.ops[op]
            if self.human_model.intentions == Intentions.VISIBLE:
                for rest in dict.fromkeys(rests):
                    move = make(es, gop, (rest,))
                    if move is not None and len(rests) > 1:
                        left = ", ".join(self.net.names_of(rest))
                        move = _relabel(move, f"{move.label} [{left}]")
                    if move is not None:
                        out.append(move)
            else:
                move = make(es, gop, _hypotheses(rests))
                if move is not None:
                    out.append(move)
        return out

    def human_starts(self, es: EState, op: GOp, rests: tuple[Agenda, ...]) -> Move:
        """C4, C10: the human starts ``op``: a failure when it does not hold in T (a false
        belief), else the reply node. The move's ``waits`` flag marks a step in which the
        human acts (C11's tie-break "human effort")."""
        if not op.pre(es.true):
            return Move(HUMAN, ACTION, op.name, 0, None, op.id,
                        failure=f"{self.names[HUMAN]} does {op.name} on a false belief")
        return Move(HUMAN, ACTION, op.name, 0,
                    es._replace(turn=ROBOT, human_agendas=rests, pending=(H_ACTION, op.id)),
                    op.id, waits=True)

    # -- C3: admissible replies -----------------------------------------------------------
    def held(self, agent: Agent, op: GOp) -> frozenset[str]:
        """C3 c: the resources ground action ``op`` of ``agent`` declares (the DSL's
        ``resources=``: parameters by their values, constants by name)."""
        key = (agent, op.id)
        r = self._held.get(key)
        if r is None:
            d = self.grounded.problem.domain
            model = d.robot if agent == ROBOT else d.human
            schema = model.operators.get(op.schema)
            out: set[str] = set()
            if schema is not None:
                for x in schema.resources:
                    if isinstance(x, Var):
                        out.add(op.args[schema.params.index(x)])
                    else:
                        out.add(x)
            r = self._held[key] = frozenset(out)
        return r

    def admissible(self, es: EState, hop: GOp, t_h: int, rop: GOp, rest: Agenda) -> bool:
        """C3: whether the robot's ``rop`` (leaving ``rest``) may run in the same step as the
        human's ``hop``: (a) ``rop`` is still an option after ``hop`` and ``hop`` still holds
        after ``rop``; (b) under ``commute = "state"`` both orders reach the same state;
        (c) they hold no common resource."""
        t = es.true
        if (rop.id, rest) not in self.R.refine(es.robot_agenda, t_h):
            return False
        t_r = rop.apply(t)
        if not hop.pre(t_r):
            return False
        if self.steps.commute == Commute.STATE and hop.apply(t_r) != rop.apply(t_h):
            return False
        return not (self.held(ROBOT, rop) & self.held(HUMAN, hop))

    def replies(self, es: EState) -> list[Move]:
        """C3-C9: the robot's replies at a reply node, each a whole step to the next decision
        node, costing ``[steps] cost`` (plus ``inform`` for an inform).

        Pseudo-code::

            h = the pending human move; T_h = h(T); W_h = h applied to every world
                (the inferable atoms h changed learnt, C7.1)
            witnessed = co-present in T and (in T_h, or witness = "start")   (C8)
            actions r (C2, C3): at T (co-present or k < K), admissible with h,
                and seen or k < K; T' = r(T_h)                               (C6)
            wait: unless h = pass (C3: (pass, wait) is never a step)
            inform(A): where the human hears it (witnessed, or inform = "anywhere"), A an
                informing set of the node after h (§5: judged on the human's next decision)
            each child: C7 (witnessed: the worlds that anticipated r after h advance, else
                revision; unseen: the product, k + 1), situation assessment on T', k reset
                when co-present (C7.4)
        """
        hop = self.grounded.human.ops[es.pending[1]] if es.pending[0] == H_ACTION else None
        t_h, worlds_h = self.human_did(es, hop)
        cop1 = self.copresent(t_h)
        witnessed = self.witnesses(es.true, t_h)
        c_step = self.steps.cost
        out: list[Move] = []
        for rop, rest in self.robot_actions(es):
            self.check()
            if not witnessed and es.k >= self.K:
                continue  # unseen past K (C7.3)
            if hop is not None and not self.admissible(es, hop, t_h, rop, rest):
                continue
            t2 = rop.apply(t_h)
            out.append(Move(ROBOT, ACTION, rop.name, c_step,
                            self.joint(es, t_h, worlds_h, t2, rest, rop, witnessed), rop.id))
        if hop is not None:
            out.append(Move(ROBOT, WAIT, "wait", c_step,
                            self.joint(es, t_h, worlds_h, t_h, es.robot_agenda, None, witnessed)))
        if witnessed or self.comm.inform == InformWhere.ANYWHERE:
            mid = EState(HUMAN, t_h, es.robot_agenda, es.human_agendas,
                         self.assess(t_h, worlds_h), 0 if cop1 else es.k, 0)
            for mask in self.informing_sets(mid):
                told = self.observe(t_h, mid.worlds, mask)
                out.append(Move(ROBOT, INFORM, self.inform_label(t_h, mask),
                                c_step + self.costs.inform,
                                self.informed(es, t_h, told), atoms=mask))
        return out

    def human_did(self, es: EState, hop: GOp | None) -> tuple[int, Worlds]:
        """C7.1: the true state and the worlds after the human's action ``hop`` (None: a
        pass): applied to every world, the inferable atoms it changed learnt."""
        if hop is None:
            return es.true, es.worlds
        t, t_h = es.true, hop.apply(es.true)
        inf = self.grounded.expand(t ^ t_h) & self.grounded.inferable_mask
        return t_h, normalize(((hop.apply(s) & ~inf) | (t_h & inf), ag) for s, ag in es.worlds)

    def witnesses(self, t: int, t_h: int) -> bool:
        """C8: whether the human witnesses the robot's action of a step that starts in ``t``
        and in which the human's own move leads to ``t_h``."""
        return self.copresent(t) and (self.copresent(t_h) or self.steps.witness == Witness.START)

    def informed(self, es: EState, t2: int, worlds: Worlds) -> EState:
        """§5, C7.4: the next step's start after a step in which the robot informed (heard:
        no world multiplied, ``k`` unchanged): situation assessment on ``t2``."""
        worlds = self.sees_done(t2, es.robot_agenda, self.assess(t2, worlds))
        return EState(self.first, t2, es.robot_agenda, es.human_agendas, worlds,
                      0 if self.copresent(t2) else es.k, 0)

    def joint(self, es: EState, t_h: int, worlds_h: Worlds, t2: int, rest: Agenda,
              rop: GOp | None, witnessed: bool) -> EState:
        """C6-C8: the decision node after the step: the robot's action ``rop`` (None: a wait)
        seen or not, situation assessment on ``t2`` and ``k``."""
        k = es.k
        if witnessed:
            if rop is None:
                worlds = worlds_h
            else:
                new: list[World] = []
                seen_op = self.anticipated_op(rop.id)
                for s, ag in worlds_h:
                    for _, r in self.RH.refine_to(ag, s, rop.id):
                        new.append((seen_op.apply(s), r))
                if not new:  # the human could not have expected it: revise (§4)
                    told = self.attributed(rest)
                    new = [(seen_op.apply(s), told) for s, _ in worlds_h]
                inf = self.grounded.expand(t_h ^ t2) & self.grounded.inferable_mask
                if inf:
                    new = [((s & ~inf) | (t2 & inf), a) for s, a in new]
                worlds = normalize(new)
        elif k < self.K:  # C7.3: unseen, the human imagines what the robot may have done
            worlds, k = self.product(worlds_h), k + 1
        else:
            worlds = worlds_h
        worlds = self.sees_done(t2, rest, self.assess(t2, worlds))
        return EState(self.first, t2, rest, es.human_agendas, worlds,
                      0 if self.copresent(t2) else k, 0)

    # -- C4, first = "robot": the robot decides, the human's moves go with it ----------------
    def robot_decisions(self, es: EState) -> list[Move]:
        """C2, C4 (``first = "robot"``): the robot's options at a decision node, each leading
        to the node where the human's moves that go with it are the branches: its real
        actions (co-present or ``k < K``), ``wait``, and ``inform(A)`` where it may inform
        (§5: judged on the step's start; said first, then the human moves). Only ``inform``
        costs here (its cost); the human's move pays the step. Two actions of one label (two
        methods that start alike) are told apart by the agenda each leaves: ``fetch [shelve]``
        (the robot commits to its method, and the human's moves are judged against it)."""
        t = es.true
        acts = self.robot_actions(es)
        names = [rop.name for rop, _ in acts]
        out = [Move(ROBOT, ACTION, rop.name if names.count(rop.name) == 1 else
                    f"{rop.name} [{', '.join(self.net.names_of(rest))}]", 0,
                    es._replace(turn=HUMAN, pending=(R_ACTION, rop.id, i)), rop.id)
               for i, (rop, rest) in enumerate(acts)]
        out.append(Move(ROBOT, WAIT, "wait", 0, es._replace(turn=HUMAN, pending=(R_WAIT,))))
        if self.together(t):
            for mask in self.informing_sets(es):
                out.append(Move(ROBOT, INFORM, self.inform_label(t, mask), self.costs.inform,
                                es._replace(turn=HUMAN, pending=(R_INFORM, mask)), atoms=mask))
        return out

    def human_replies(self, es: EState) -> list[Move]:
        """C3-C8, C10 (``first = "robot"``): the human's moves that go with the robot's
        chosen one, each a whole step (``[steps] cost``, a question adding ``ask``).

        Pseudo-code::

            r = the robot's pending move (an action with its rest, wait, or inform(A))
            W0 = W, or W told A for an inform (heard at the step's start)
            for each human action h (per label over A_H, on W; C2):
                h not applicable in T: a failure (C10: a false belief)
                seen = co-present in T and (in h(T), or witness = "start")      (C8)
                r an action not admissible with h (C3): seen: h is no option (the human
                    sees the robot start and adapts); unseen: a failure (C4)
                else the step (h, r): T' = r(h(T)), C7 as with the human first
            ask(phi): only beside wait (its step is the answer, C3)
            pass: beside a real action or an inform, never beside wait (C3, C5)
        """
        kind = es.pending[0]
        rop: GOp | None = None
        rest = es.robot_agenda
        worlds0 = es.worlds
        if kind == R_ACTION:
            rop, rest = self.robot_actions(es)[es.pending[2]]
        elif kind == R_INFORM:
            worlds0 = self.observe(es.true, es.worlds, es.pending[1])
        start = es._replace(worlds=worlds0)
        acts, asks, passers = self.human_choices(start, kind != R_WAIT)
        c_step = self.steps.cost

        def reply(es: EState, hop: GOp, rests: tuple[Agenda, ...]) -> Move | None:
            if not hop.pre(es.true):
                return Move(HUMAN, ACTION, hop.name, c_step, None, hop.id,
                            failure=f"{self.names[HUMAN]} does {hop.name} on a false belief")
            t_h, worlds_h = self.human_did(start, hop)
            seen = self.witnesses(es.true, t_h)
            after = es._replace(human_agendas=rests)
            if rop is not None:
                if not self.admissible(es, hop, t_h, rop, rest) or (
                        not seen and es.k >= self.K):
                    if seen:
                        return None
                    return Move(HUMAN, ACTION, hop.name, c_step, None, hop.id,
                                failure=f"{self.names[HUMAN]} does {hop.name}, unaware of "
                                        f"the robot's {rop.name}: they conflict")
                child = self.joint(after, t_h, worlds_h, rop.apply(t_h), rest, rop, seen)
            elif kind == R_INFORM:
                child = self.informed(after, t_h, worlds_h)
            else:
                child = self.joint(after, t_h, worlds_h, t_h, es.robot_agenda, None, seen)
            return Move(HUMAN, ACTION, hop.name, c_step, child, hop.id, waits=True)

        out = self.each_action(es, acts, reply)
        if kind == R_WAIT:
            for label, (phi, hs) in sorted(asks.items()):
                asked = self.ask(es, phi)
                out.append(Move(HUMAN, ASK, f"ask({label})", c_step + self.costs.ask,
                                asked._replace(turn=ROBOT, human_agendas=_hypotheses(hs),
                                               passive=0, pending=())))
        elif passers:
            after = es._replace(human_agendas=_hypotheses(passers))
            if rop is not None:
                child = self.joint(after, es.true, es.worlds, rop.apply(es.true), rest, rop,
                                   self.copresent(es.true))
            else:
                child = self.informed(after, es.true, worlds0)
            out.append(Move(HUMAN, PASS, "pass", c_step, child))
        return out


__all__ = ["H_ACTION", "H_PASS", "R_ACTION", "R_INFORM", "R_WAIT", "ConcurrentSemantics",
           "check_concurrent", "semantics_for"]
