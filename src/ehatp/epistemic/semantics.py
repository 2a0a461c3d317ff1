"""The transition rules of ``docs/semantics.md``: who may do what, and what the human then
believes.

:class:`Semantics` turns an epistemic state into its labelled successors (:class:`Move`):
robot actions (witnessed, or multiplied into the product of anticipated events while the human
is away, up to K), robot ``wait`` and ``inform``, human actions (only those applicable in every
world), ``ask`` and ``pass``. Situation assessment runs on every new state.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from itertools import combinations
from typing import Any, ClassVar, NamedTuple, cast

from mypy_extensions import mypyc_attr

from ..model.agenda import Agenda, Networks
from ..model.formula import And, Formula, conj, ground_atoms
from ..model.grounded import FINISH, GOp, Grounded, bits, no_check
from ..model.htn import Refiner
from ..model.options import InformWhere, Intentions, Passes, Relevance, Speech
from ..model.problem import Cost
from ..model.vocabulary import Agent, MoveKind
from .state import HUMAN, ROBOT, EState, World, Worlds, normalize, states_of

# the move kinds by their old names (aliases of the enum's members)
ACTION, WAIT, PASS = MoveKind.ACTION, MoveKind.WAIT, MoveKind.PASS
INFORM, ASK, SILENCE = MoveKind.INFORM, MoveKind.ASK, MoveKind.SILENCE
ANSWER, ANNOUNCE = MoveKind.ANSWER, MoveKind.ANNOUNCE  # the human's answer; the robot's agenda
PASSIVE = (WAIT, PASS)
BLOCKED, HORIZON = -2, -3  # ends of a human plan other than FINISH (relevance "plan")
NOT_DONE = -4  # what a world whose robot agenda is blocked lets the human expect (§5)
ASK_INTENTION = "ask(intention)"
DEAD_PASSIVE_RUN = 3
PRODUCT_CACHE = 1 << 20
"""How many worlds the products :meth:`Semantics.product` remembers hold, then afresh."""
PASSIVE_CARRIED = {WAIT: 1, PASS: 1, SILENCE: 0, ANSWER: 0}
"""§3-§5 (turn-taking): how a move's child counts consecutive passive moves from its parent's
count ``p``: ``p + 1`` after ``wait`` or ``pass`` (said with an ``inform`` too), ``p`` after the
opening's ``silence`` or an ``answer``, 0 after any other move. No rule reads the count but the
dead end of §6, so a node's moves are those of the same node with count 0, each carrying child's
count raised by ``p`` (:attr:`Semantics.passive_carried`)."""


@dataclass(frozen=True, slots=True)
class Move:
    """One option of the agent to move: an OR choice for the robot, an AND branch for the
    human. ``child`` is None when the move fails (the human acts on a false belief)."""

    agent: Agent
    kind: MoveKind
    label: str
    cost: Cost
    child: EState | None
    op: int = -1
    atoms: int = 0  # inform: the atoms told
    failure: str = ""
    # a human pass made waiting: its agenda unfinished and no action it is sure of (§7 ties)
    waits: bool = False


class Call(NamedTuple):
    """A move in the domain's vocabulary: ``name`` and ``args`` split an operator call
    (``place``, ``("w", "box2")``); for ``inform`` the args are the literals told
    (``("link(a, b)", "not x")``), for ``ask`` the question; ``wait`` and ``pass`` have none.
    ``label`` is how policies and traces print the move."""

    name: str
    args: tuple[str, ...]
    label: str


def bits_of(mask: int) -> list[int]:
    """The indices of the set bits of ``m``, lowest first (atoms of a mask, §2)."""
    return list(bits(mask))


@mypyc_attr(allow_interpreted_subclasses=True)  # Python subclasses it (docs/compiled.md)
class Semantics:
    """The transition rules (docs/semantics.md §2-§6) over one ground problem."""

    passive_carried: ClassVar[bool] = True
    """Whether the moves follow :data:`PASSIVE_CARRIED` (turn-taking: they do)."""

    def __init__(self, grounded: Grounded) -> None:
        self.grounded = grounded
        p = grounded.problem
        self.K = p.K
        self.costs = p.costs
        self.human_model = p.human
        self.comm = p.communication
        self._plans: dict[tuple[Agenda, int, int], frozenset[tuple[int, ...]]] = {}
        self.names = (p.domain.robot_name, p.domain.human_name)
        limit = p.limits.max_decomposition
        self.net = Networks(grounded.task_names)  # partially ordered agendas (§1), shared
        self.R = Refiner(grounded.robot, grounded.task_names, limit, self.net)
        self.H = Refiner(grounded.human, grounded.task_names, limit, self.net)
        self.RH = (self.R if grounded.robot_seen_by_human is grounded.robot
                   else Refiner(grounded.robot_seen_by_human, grounded.task_names, limit, self.net))
        self._vis: dict[int, int] = {}
        self._cop: dict[int, bool] = {}
        self._succ: dict[World, tuple[World, ...]] = {}
        self._product: dict[Worlds, Worlds] = {}
        self._product_size = 0
        self._knows: dict[int, bool] = {}  # task -> whether M_R^H knows it (attributed)
        self._rops: dict[int, GOp] = {}  # robot actions met, as M_R and M_R^H have them
        self._seen_ops: dict[int, GOp] = {}
        self._inform: dict[tuple[int, Agenda, tuple[Agenda, ...], Worlds], tuple[int, ...]] = {}
        self.check: Callable[[], None] = no_check

    def __copy__(self) -> Semantics:
        """Every attribute shared, a Python subclass's too (``Executor.copy``; compiled, the
        default copy would drop those: docs/compiled.md)."""
        other = type(self).__new__(type(self))
        state = cast("dict[str, Any]", self.__getstate__() or {})  # compiled: Semantics's own
        for name, value in (state | getattr(self, "__dict__", {})).items():
            setattr(other, name, value)
        return other

    @property
    def g(self) -> Grounded:
        """The ground problem, by its older name (:attr:`grounded`)."""
        return self.grounded

    def bound(self, check: Callable[[], None]) -> None:
        """Have ``check`` called now and then while moves are computed (a time or memory
        limit raises from it: one expansion can be long, §7 "Search")."""
        self.check = check
        for r in (self.R, self.H, self.RH):
            r.check = check

    def follow(self, es: EState, label: str) -> Move:
        """§4: the move of the agent to move whose label is ``label`` (an agent name may lead,
        spaces are ignored); ValueError naming the options when there is none. Where several
        moves share a label (two robot methods that start with the same action), the label
        may be followed by the agenda the move leaves, in brackets -- ``fetch [shelve]`` --
        to name one (:meth:`trace_label` writes it); without, the first is taken. A ``pass``
        right after a forced wait, which a policy need not cover, is followed all the same."""
        head, _, rest = label.strip().partition(" ")
        if head in self.names and rest:
            if head != self.names[es.turn]:
                raise ValueError(f"{label!r} names {head}, but it is {self.names[es.turn]}'s "
                                 "turn")
            label = rest
        want = "".join(label.split())
        moves = self.legal_moves(es)
        found = next((move for move in moves if "".join(move.label.split()) == want), None)
        if found is None and want.endswith("]") and "[" in want:
            base, _, after = want[:-1].rpartition("[")
            found = next((move for move in moves if "".join(move.label.split()) == base
                          and move.child is not None and self._leaves(move.child) == after), None)
        if found is not None:
            if found.child is None:
                raise ValueError(f"{label!r} fails here: {found.failure}")
            return found
        who = self.names[es.turn]
        raise ValueError(f"{label!r} is not a move of {who} here; options: "
                         + ", ".join(move.label for move in moves))

    def legal_moves(self, es: EState) -> list[Move]:
        """§4: every move the agent to move can make: its options (:meth:`moves`) and, right
        after a forced robot wait, the human's ``pass`` the fairness rule leaves out -- a
        policy *need not cover* it, which does not make it impossible (an execution that met
        one is replayed, and ``execute --replan`` plans on from it)."""
        moves = self.moves(es)
        if es.turn == HUMAN and es.forced and not any(m.kind == PASS for m in moves):
            moves += [m for m in self.moves(es._replace(forced=False)) if m.kind == PASS]
        return moves

    def trace_label(self, es: EState, move: Move) -> str:
        """§4: ``move``'s label as :meth:`follow` reads it back from ``es`` to this very move:
        the label, followed by the agenda it leaves in brackets when another move of ``es``
        has the same label and leads elsewhere."""
        if move.agent != ROBOT or move.child is None:  # human labels are unique (§4)
            return move.label
        if not any(other.label == move.label and other.child != move.child
                   for other in self.moves(es)):
            return move.label
        return f"{move.label} [{', '.join(self.net.names_of(move.child.robot_agenda))}]"

    def _leaves(self, child: EState) -> str:
        """The robot agenda ``child`` holds, as :meth:`trace_label` writes it (spaces off)."""
        return "".join(",".join(self.net.names_of(child.robot_agenda)).split())

    def describe(self, move: Move) -> Call:
        """The move as name, arguments and label (§4-§5): the one translation used by the
        policy writer, the executor and the simulator."""
        grounded = self.grounded
        if move.op >= 0:
            op = (grounded.robot.ops if move.agent == ROBOT else grounded.human.ops)[move.op]
            return Call(op.schema, tuple(op.args), move.label)
        if move.kind == WAIT:
            return Call(WAIT, (), move.label)
        if move.kind == INFORM:
            assert move.child is not None  # informing never fails
            return Call(INFORM, self.literals(move.child.true, move.atoms), move.label)
        if move.kind == ASK:
            return Call(ASK, (move.label[len("ask("):-1],), move.label)
        return Call(move.kind, (), move.label)

    def literals(self, t: int, mask: int) -> tuple[str, ...]:
        """§5: the units of ``mask`` as ``t`` has them: ``a`` when true, ``not a`` when false,
        ``loc(r) = mt`` for a state variable, ``balls(b1) = 2`` for a counter."""
        return tuple(self.grounded.literals(t, mask))

    # -- basics ---------------------------------------------------------------------------
    def initial(self) -> EState:
        """§3-§5: the root: the designated world, the belief worlds after situation assessment
        (with the robot agendas the human can hold), under speech "with-action" an opening."""
        grounded = self.grounded
        turn = HUMAN if grounded.problem.starts == "human" else ROBOT
        init = grounded.init
        worlds = self.assess(init, normalize((s, self.attributed(ag))
                                             for s, ag in grounded.beliefs))
        worlds = self.sees_done(init, grounded.robot_agenda, worlds)
        es = EState(turn, init, grounded.robot_agenda, (grounded.human_agenda,), worlds, 0, 0)
        if (turn == HUMAN and self.comm.speech == Speech.WITH_ACTION
                and (self.copresent(grounded.init) or self.comm.inform == InformWhere.ANYWHERE)
                and self.informing_sets(es)):
            # §5: the robot may speak before the human's very first move
            es = es._replace(turn=ROBOT, opening=True)
        return es

    def copresent(self, t: int) -> bool:
        """§2: the domain's co-presence formula in the true state ``t`` (memoised)."""
        c = self._cop.get(t)
        if c is None:
            c = self._cop[t] = self.grounded.copresent(t)
        return c

    def visible(self, t: int) -> int:
        """§2: the mask of observable atoms whose visibility condition holds in ``t``."""
        v = self._vis.get(t)
        if v is None:
            v = self._vis[t] = self.grounded.visible_mask(t)
        return v

    def assess(self, t: int, worlds: Worlds) -> Worlds:
        """Situation assessment: keep the worlds that agree with ``t`` on every atom the human
        now sees; an atom no world agrees on is revised in all of them."""
        vm = self.visible(t)
        if not vm:
            return worlds
        tv = t & vm
        keep = [w for w in worlds if w[0] & vm == tv]
        if keep:
            return worlds if len(keep) == len(worlds) else tuple(keep)
        return self.observe(t, worlds, vm)

    def observe(self, t: int, worlds: Worlds, mask: int) -> Worlds:
        """§2, §5: learn ``t``'s value of each unit of ``mask`` (an atom; the observed bits
        of a state variable; a counter), one unit at a time in index order: filter the worlds
        on it, or revise it in every world when none agrees. A variable is revised to ``t``'s
        value when ``mask`` holds it, else each world becomes one world per value ``mask``
        does not show false (exactly one value, always)."""
        ws = list(worlds)
        grounded = self.grounded
        if not mask & grounded.multi_mask:
            for i in bits_of(mask):
                bit = 1 << i
                tb = t & bit
                keep = [w for w in ws if w[0] & bit == tb]
                ws = keep if keep else [((s & ~bit) | tb, a) for s, a in ws]
            return normalize(ws)
        for u in grounded.units(mask):
            part = u & mask
            tb = t & part
            keep = [w for w in ws if w[0] & part == tb]
            if keep:
                ws = keep
            elif tb or u not in grounded.unit_names or u in grounded.counter_max:
                whole = u if u in grounded.unit_names and u not in grounded.counter_max else part
                ws = [((s & ~whole) | (t & whole), a) for s, a in ws]
            else:  # "not this value" with no world agreeing: any value not seen false
                ws = [((s & ~u) | 1 << i, a) for s, a in ws for i in bits_of(u & ~part)]
        return normalize(ws)

    def robot_op(self, op: int) -> GOp:
        """§4: the robot action as it really is (M_R)."""
        r = self._rops.get(op)
        if r is None:  # an action refinement offered is grounded already: kept as it is
            r = self._rops[op] = self.grounded.robot.ops[op]
        return r

    def anticipated_op(self, op: int) -> GOp:
        """The robot action as the human understands it (M_R^H), else as it really is."""
        r = self._seen_ops.get(op)
        if r is None:
            r = self._seen_ops[op] = (self.grounded.robot_seen_by_human.ops.get(op)
                                      or self.grounded.robot.ops[op])
        return r

    def attributed(self, agenda: Agenda) -> Agenda:
        """§4: the robot agenda as the human holds it after revising its beliefs: the tasks of
        ``agenda`` its model of the robot (M_R^H) knows. A task M_R^H has no operator, method
        or done-condition for is dropped: the human can expect nothing of it."""
        model = self.grounded.robot_seen_by_human
        if model is self.grounded.robot:
            return agenda
        known = self._knows
        out: list[int] = []
        for t in agenda:
            if not isinstance(t, int):  # a block: what is left of it in canonical form
                return self.net.keep(agenda, self._knows_task)
            k = known.get(t)
            if k is None:
                k = self._knows_task(t)
            if k:
                out.append(t)
        return agenda if len(out) == len(agenda) else tuple(out)

    def _knows_task(self, t: int) -> bool:
        """§4: whether M_R^H has an operator, a method or a done-condition for task ``t``
        (memoised: that model is grounded whole)."""
        k = self._knows.get(t)
        if k is None:
            model = self.grounded.robot_seen_by_human
            k = self._knows[t] = (t in model.ops or bool(model.methods.get(t))
                                  or t in model.done)
        return k

    def successors(self, w: World) -> tuple[World, ...]:
        """The world itself (noop) and every event the human anticipates of the robot there."""
        r = self._succ.get(w)
        if r is None:
            s, ag = w
            out = [w]
            for op, rest in self.RH.refine(ag, s):
                if op != FINISH:
                    out.append((self.anticipated_op(op).apply(s), rest))
            r = self._succ[w] = tuple(out)
        return r

    def product(self, worlds: Worlds) -> Worlds:
        """§4: every world followed by the noop or an event the human anticipates of the
        robot; a non-anticipating human imagines nothing (``W`` unchanged). It reads ``W``
        alone: remembered per ``W`` (many true states share one), up to
        :data:`PRODUCT_CACHE` worlds held, then afresh."""
        if not self.human_model.anticipates:
            return worlds
        r = self._product.get(worlds)
        if r is None:
            r = normalize(x for w in worlds for x in self.successors(w))
            self._product_size += len(r)
            if self._product_size > PRODUCT_CACHE:
                self._product.clear()
                self._product_size = len(r)
            self._product[worlds] = r
        return r

    def sees_done(self, t: int, robot_agenda: Agenda, worlds: Worlds) -> Worlds:
        """§4: a non-anticipating human co-present with a robot whose agenda can finish under
        ``t`` sees that it is done: every world's robot agenda becomes empty."""
        if (self.human_model.anticipates or not self.copresent(t)
                or self.R.refine(robot_agenda, t)[:1] != ((FINISH, ()),)
                or all(not ag for _, ag in worlds)):
            return worlds
        return normalize((s, ()) for s, _ in worlds)

    # -- goal -----------------------------------------------------------------------------
    def robot_done(self, es: EState) -> bool:
        """§6: the robot's agenda can finish under T (M_R)."""
        return self.R.refine(es.robot_agenda, es.true)[:1] == ((FINISH, ()),)

    def human_done(self, es: EState) -> bool:
        """§6 (with §3's hypotheses): every human agenda of ``A_H`` certainly finishes over W
        (done in every world): the robot cannot otherwise know the task done."""
        states = states_of(es.worlds)
        full = (1 << len(states)) - 1
        return all(any(u.op == FINISH and u.worlds == full
                       for u in self.H.refine_in_all(h, states)) for h in es.human_agendas)

    def human_believes_robot_done(self, es: EState) -> bool:
        """§6: in every world the robot agenda the human attributes can finish (M_R^H)."""
        return all(self.RH.refine(ag, s)[:1] == ((FINISH, ()),) for s, ag in es.worlds)

    def is_goal(self, es: EState) -> bool:
        """§6: goal formula in T, both agendas finished, and the human believes the robot done."""
        return (self.grounded.goal(es.true) and self.robot_done(es) and self.human_done(es)
                and self.human_believes_robot_done(es))

    # -- moves ----------------------------------------------------------------------------
    def moves(self, es: EState) -> list[Move]:
        """§4: the options of the agent to move (robot: OR choices; human: AND branches)."""
        if es.turn == ROBOT:
            return self.robot_moves(es)
        return self.answers(es) if es.answering else self.human_moves(es)

    def together(self, t: int) -> bool:
        """§5: whether the robot can talk to the human in ``t`` (co-present, or anywhere)."""
        return self.copresent(t) or self.comm.inform == InformWhere.ANYWHERE

    def robot_moves(self, es: EState) -> list[Move]:
        """§4-§5: the robot's options: the first actions of its agenda (while co-present or
        k < K), ``wait``, and ``inform`` of a smallest relevant set (while co-present, or
        anywhere); with speech "with-action" also ``inform + action`` and ``inform + wait``;
        at a speech opening only ``inform`` and ``silence``."""
        t, cop = es.true, self.copresent(es.true)
        if es.opening:
            after = es._replace(turn=HUMAN, opening=False)
            opening = [Move(ROBOT, SILENCE, "silence", 0, after)]
            for mask in self.informing_sets(es):
                opening.append(Move(ROBOT, INFORM, self.inform_label(t, mask), self.costs.inform,
                                    self.inform(after._replace(turn=ROBOT), mask), atoms=mask))
            return opening
        out: list[Move] = []
        acts: list[tuple[GOp, Agenda]] = []
        if cop or es.k < self.K:
            acts = [(self.robot_op(op), rest) for op, rest in self.R.refine(es.robot_agenda, t)
                    if op != FINISH]
        for gop, rest in acts:
            self.check()
            out.append(Move(ROBOT, ACTION, gop.name, gop.cost,
                            self.robot_exec(es, gop, rest, cop), gop.id))
        forced = not acts or self.human_model.passes == Passes.PROTOTYPE
        waited = self.robot_wait(es, cop, forced)
        out.append(Move(ROBOT, WAIT, "wait", self.costs.wait, waited))
        if self.comm.speech == Speech.WITH_ACTION:
            # §5: what is said with a move is judged on the state the move leads to (the
            # human's next decision), told as the truth is then, and heard if the robot may
            # inform there
            for move in out[:len(acts) + 1]:
                assert move.child is not None
                if not self.together(move.child.true):
                    continue
                for mask in self.informing_sets(move.child):
                    out.append(Move(ROBOT, move.kind,
                                    f"{self.inform_label(move.child.true, mask)} + {move.label}",
                                    self.costs.inform + move.cost,
                                    self.inform(move.child._replace(turn=ROBOT), mask)._replace(
                                        passive=move.child.passive, forced=move.child.forced),
                                    move.op, atoms=mask))
        if not self.together(t):
            return out
        for mask in self.informing_sets(es):
            out.append(Move(ROBOT, INFORM, self.inform_label(t, mask), self.costs.inform,
                            self.inform(es, mask), atoms=mask))
        if self.comm.announce:
            said = self.announce(es)
            if said is not None:
                out.append(Move(ROBOT, ANNOUNCE, self.announce_label(es.robot_agenda),
                                self.costs.inform, said))
        if self.comm.robot_asks and len(es.human_agendas) > 1:
            out.append(Move(ROBOT, ASK, ASK_INTENTION, self.costs.ask,
                            es._replace(turn=HUMAN, answering=True, passive=0, forced=False)))
        return out

    def announce_label(self, agenda: Agenda) -> str:
        """§5: ``announce(t1, t2)``: the robot's agenda as the domain names its tasks."""
        return f"announce({', '.join(self.net.names_of(agenda))})"

    def announce(self, es: EState) -> EState | None:
        """§5 (``announce``): the robot tells the human the agenda it follows: the worlds
        whose attributed agenda is that one stay (an ``inform`` of the agenda); if none, every
        world takes it. None when it is not relevant: the human's expectations of the robot
        (read per world) already equal the truth's, or telling changes no world."""
        if self.robot_view(es.worlds) == self.robot_truth(es):
            return None
        told = self.attributed(es.robot_agenda)
        keep = tuple(w for w in es.worlds if w[1] == told)
        worlds = keep if keep else normalize((s, told) for s, _ in es.worlds)
        if worlds == es.worlds:
            return None
        return es._replace(turn=HUMAN, worlds=worlds, passive=0, forced=False)

    def answers(self, es: EState) -> list[Move]:
        """§5 (``robot_asks``): the human's truthful answers to the robot's question about
        its intention, one per hypothesis of ``A_H``: ``answer(t1, t2)`` names its agenda, the
        robot keeps that hypothesis, and it is the human's turn (the answer costs nothing: the
        robot's question took the robot's turn)."""
        return [Move(HUMAN, ANSWER, f"answer({', '.join(self.net.names_of(h))})", 0,
                     es._replace(answering=False, human_agendas=(h,)))
                for h in es.human_agendas]

    def robot_exec(self, es: EState, op: GOp, rest: Agenda, cop: bool) -> EState:
        """§4: the robot does ``op``: witnessed (worlds that expected it advance, else revision) or
        unseen (the product), then situation assessment."""
        t2 = op.apply(es.true)
        if cop:
            new: list[World] = []
            seen_op = self.anticipated_op(op.id)
            for s, ag in es.worlds:
                for _, r in self.RH.refine_to(ag, s, op.id):
                    new.append((seen_op.apply(s), r))
            if not new:  # the human could not have expected it: revise
                told = self.attributed(rest)
                new = [(seen_op.apply(s), told) for s, _ in es.worlds]
            inf = self.grounded.expand(es.true ^ t2) & self.grounded.inferable_mask
            if inf:
                keep, learnt = ~inf, t2 & inf
                new = [((s & keep) | learnt, a) for s, a in new]
            worlds, k = normalize(new), es.k
        else:
            worlds, k = self.product(es.worlds), es.k + 1
        worlds = self.sees_done(t2, rest, self.assess(t2, worlds))
        return EState(HUMAN, t2, rest, es.human_agendas, worlds,
                      0 if self.copresent(t2) else k, 0)

    def robot_wait(self, es: EState, cop: bool, forced: bool) -> EState:
        """§4: ``wait``; unseen, it is one of the events the human imagines. ``forced`` says
        the robot had no real action (what the human's pass rule reads)."""
        worlds, k = es.worlds, es.k
        if not cop and k < self.K:  # unseen, the wait is one of the events the human imagines
            worlds, k = self.assess(es.true, self.product(worlds)), k + 1
        return EState(HUMAN, es.true, es.robot_agenda, es.human_agendas, worlds, k,  # hot:
                      es.passive + 1, forced, es.opening, es.answering, es.pending)  # no _replace

    def human_options(self, es: EState, h: Agenda) -> tuple[
            list[tuple[int, Agenda]], dict[str, Formula], bool, bool]:
        """§4 for one human agenda ``h`` on W: its certain actions (op, rest), its questions
        (label -> the uncertain part asked, §5), whether it may ``pass`` under the pass rule,
        and whether such a pass is a wait (unfinished, no action it is sure of)."""
        cop = self.copresent(es.true)
        states = states_of(es.worlds)
        full = (1 << len(states)) - 1
        acts: list[tuple[int, Agenda]] = []
        asks: dict[str, Formula] = {}
        finished = False
        for op, rest, worlds, conds in self.H.refine_in_all(h, states):
            if worlds == full:
                if op != FINISH:
                    acts.append((op, rest))
                else:
                    finished = True
            elif cop and conds and self.comm.ask:
                phi = self.uncertain_part(conj(*conds), states)
                asks.setdefault(self.show(phi), phi)
        if self.human_model.passes == Passes.IDLE:  # the predecessor's human: only when idle
            may_pass = not acts and not asks
        elif cop:  # §4: no idling while a robot that has nothing to do waits for the human
            may_pass = not (es.forced and (acts or (
                asks and not self.human_model.passes_when_blocked)))
        else:
            may_pass = not acts
        return acts, asks, may_pass, not acts and not finished

    def human_moves(self, es: EState) -> list[Move]:
        """§4: the human's options on W: certain actions, ``ask`` of uncertain ones (§5), and
        ``pass`` under the pass rule, over the hypotheses of ``A_H`` (§3-§4): with hidden
        intentions one AND branch per distinct label, its child keeping every hypothesis
        (progressed by every refinement) for which the label was an option; with visible
        intentions one branch per refinement, labels that would repeat at the node followed
        by the agenda the human announces (``grab(c) [place_l(c)]``)."""
        acts: dict[int, list[Agenda]] = {}
        asks: dict[str, tuple[Formula, list[Agenda]]] = {}
        passers: list[Agenda] = []
        waits = False
        for h in es.human_agendas:
            h_acts, h_asks, may_pass, h_waits = self.human_options(es, h)
            for op, rest in h_acts:
                acts.setdefault(op, []).append(rest)
            for label, phi in h_asks.items():
                asks.setdefault(label, (phi, []))[1].append(h)
            if may_pass:
                passers.append(h)
                waits = waits or h_waits
        out: list[Move] = []
        if self.human_model.intentions == Intentions.VISIBLE:
            for op, rests in acts.items():
                gop = self.grounded.human.ops[op]
                for rest in dict.fromkeys(rests):
                    move = self.human_exec(es, gop, (rest,))
                    if len(rests) > 1:
                        left = ", ".join(self.net.names_of(rest))
                        move = _relabel(move, f"{move.label} [{left}]")
                    out.append(move)
        else:
            for op, rests in acts.items():
                out.append(self.human_exec(es, self.grounded.human.ops[op], _hypotheses(rests)))
        for label, (phi, hs) in sorted(asks.items()):
            out.append(Move(HUMAN, ASK, f"ask({label})", self.costs.ask,
                            self.ask(es, phi)._replace(human_agendas=_hypotheses(hs))))
        if passers:
            out.append(Move(HUMAN, PASS, "pass", self.costs.pass_, EState(  # no _replace: hot
                ROBOT, es.true, es.robot_agenda, _hypotheses(passers), es.worlds, es.k,
                es.passive + 1, False, es.opening, es.answering, es.pending), waits=waits))
        return out

    def human_exec(self, es: EState, op: GOp, rests: tuple[Agenda, ...]) -> Move:
        """§4: the human does ``op``: a failure when it does not hold in T (a false belief); else T
        and every world advance, inferable atoms are learned, then situation assessment.
        ``rests`` are the hypotheses after it (§3)."""
        t = es.true
        if not op.pre(t):
            false = [self.grounded.unit_name(u)
                     for u in self.grounded.units(self._unmet(op, t, es.worlds[0][0]))]
            why = f"{self.names[HUMAN]} does {op.name} on a false belief"
            return Move(HUMAN, ACTION, op.name, op.cost, None, op.id,
                        failure=why + (f" ({', '.join(false)})" if false else ""))
        t2 = op.apply(t)
        grounded, apply = self.grounded, op.apply
        inf = grounded.expand(t ^ t2) & grounded.inferable_mask
        if inf:  # the inferable atoms the action changed take their true values
            keep, learnt = ~inf, t2 & inf
            new = [((apply(s) & keep) | learnt, ag) for s, ag in es.worlds]
        else:
            new = [(apply(s), ag) for s, ag in es.worlds]
        worlds = self.sees_done(t2, es.robot_agenda, self.assess(t2, normalize(new)))
        k = 0 if self.copresent(t2) else es.k
        return Move(HUMAN, ACTION, op.name, op.cost,
                    EState(ROBOT, t2, es.robot_agenda, rests, worlds, k, 0), op.id)

    def _unmet(self, op: GOp, t: int, believed: int) -> int:
        """Atoms of the precondition on which the human's belief differs from the truth."""
        mask = 0
        for i in ground_atoms(op.pre_f):
            mask |= 1 << i
        return mask & (t ^ believed)

    # -- communication ------------------------------------------------------------------------
    def uncertain_part(self, phi: Formula, states: tuple[int, ...]) -> Formula:
        """§4: the conjuncts of ``phi`` whose value differs between the worlds, each once, in
        the order of their text: what the human is unsure of (a question is their set)."""
        parts = phi.args if isinstance(phi, And) else (phi,)
        keep: list[Formula] = []
        for p in parts:
            fn = self.grounded.compile(p)
            if p not in keep and len({fn(s) for s in states}) > 1:
                keep.append(p)
        return conj(*sorted(keep, key=self.show)) if keep else phi

    def show(self, f: Formula) -> str:
        """§4: a formula as the domain wrote it (derived predicates by name), for ``ask`` labels."""
        parts = f.args if isinstance(f, And) else (f,)
        reading = self.grounded.reading
        # str() of a formula is costly: only when the domain gave no reading
        return " and ".join(d if (d := reading(p)) is not None else str(p) for p in parts)

    def ask(self, es: EState, phi: Formula) -> EState:
        """§5: the robot answers ``ask(phi)`` truthfully: the worlds where ``phi`` differs from T
        are dropped."""
        fn = self.grounded.compile(phi)
        v = fn(es.true)
        keep = tuple(w for w in es.worlds if fn(w[0]) == v)
        if not keep:  # cannot happen for asks the human generates; revise to be safe
            mask = 0
            for i in ground_atoms(phi):
                mask |= 1 << i
            keep = self.observe(es.true, es.worlds, self.grounded.expand(mask))
        return es._replace(turn=ROBOT, worlds=keep, passive=0, forced=False)

    def inform(self, es: EState, mask: int) -> EState:
        """§5: the human learns ``T``'s value of the atoms of ``mask`` (heard even while
        apart: no world is multiplied, ``k`` does not change)."""
        return es._replace(turn=HUMAN, worlds=self.observe(es.true, es.worlds, mask), passive=0,
                           forced=False)

    def inform_label(self, t: int, mask: int) -> str:
        """§5: ``inform(a, not b)``: the literals of ``mask`` as T has them."""
        return f"inform({', '.join(self.literals(t, mask))})"

    def human_view(self, agenda: Agenda, states: tuple[int, ...]) -> frozenset[tuple[int, bool]]:
        """§5: the human's next options on ``states`` (action, certain?), for relevance."""
        full = (1 << len(states)) - 1
        return frozenset((u.op, u.worlds == full) for u in self.H.refine_in_all(agenda, states))

    def robot_view(self, worlds: Worlds) -> frozenset[int]:
        """§5, read per world: the robot options the human anticipates over ``worlds``
        (M_R^H), FINISH included; a world whose attributed agenda is unfinished but offers
        nothing now adds :data:`NOT_DONE` (the human there does not think the robot done)."""
        out: set[int] = set()
        for s, ag in worlds:
            opts = self.RH.refine(ag, s)
            if opts:
                out.update(op for op, _ in opts)
            else:
                out.add(NOT_DONE)
        return frozenset(out)

    def robot_truth(self, es: EState) -> frozenset[int]:
        """§5: the robot's real next options under T (M_R), FINISH included, or
        :data:`NOT_DONE` when its agenda is blocked: what :meth:`robot_view` is compared with."""
        opts = self.R.refine(es.robot_agenda, es.true)
        return frozenset(op for op, _ in opts) if opts else frozenset((NOT_DONE,))

    def plans(self, agenda: Agenda, s: int) -> frozenset[tuple[int, ...]]:
        """§5 (relevance "plan"): the sequences of human actions that refine ``agenda`` with
        ``M_H`` from the single state ``s``, each action applied, the robot idle, up to the end
        of the agenda (``FINISH``), a dead end (``BLOCKED``) or ``plan_horizon`` actions."""
        return self._plans_from(agenda, s, self.comm.plan_horizon)

    def _plans_from(self, agenda: Agenda, s: int, left: int) -> frozenset[tuple[int, ...]]:
        key = (agenda, s, left)
        r = self._plans.get(key)
        if r is None:
            out: set[tuple[int, ...]] = set()
            opts = self.H.refine(agenda, s) if left else ()
            if not left:
                out.add((HORIZON,))
            elif not opts:
                out.add((BLOCKED,))
            for op, rest in opts:
                if op == FINISH:
                    out.add((FINISH,))
                    continue
                s2 = self.grounded.human.ops[op].apply(s)
                out.update((op, *tail) for tail in self._plans_from(rest, s2, left - 1))
            r = self._plans[key] = frozenset(out)
        return r

    def _plans_differ(self, agendas: tuple[Agenda, ...], t: int, worlds: Worlds) -> bool:
        states = states_of(worlds)
        for agenda in agendas:
            want = self.plans(agenda, t)
            if any(self.plans(agenda, s) != want for s in states):
                return True
        return False

    def informing_sets(self, es: EState) -> tuple[int, ...]:
        """§5: the sets of units the robot may tell (as masks; empty when the divergence is
        irrelevant or cannot be fixed by telling atoms): under relevance "next" the set of
        :meth:`informing_set`; under "plan" its plan-fixing set and, when that is another or
        none, the set that fixes the next step as "next" finds it (so "plan" offers every
        option "next" does, and never solves fewer problems)."""
        key = (es.true, es.robot_agenda, es.human_agendas, es.worlds)
        r = self._inform.get(key)
        if r is None:
            nxt = self.informing_set(es, False)
            if self.comm.relevance == Relevance.PLAN:
                plan = self.informing_set(es, True)
                r = tuple(mask for mask in dict.fromkeys((plan, nxt)) if mask)
            else:
                r = (nxt,) if nxt else ()
            self._inform[key] = r
        return r

    def informing_set(self, es: EState, plan: bool) -> int:
        """§5: a smallest set of units -- atoms, state variables and counters, each told whole
        -- (as a mask) whose correction makes the human's next options (for every hypothesis
        of ``A_H``), its expectations of the robot (read per world, FINISH included) and, with
        ``plan`` (relevance "plan"), its plans, computed on W, equal those computed on the
        truth; failing that, the human's own (next options and plans) alone; 0 when the
        divergence is irrelevant or cannot be fixed by telling atoms. Among sets of one size:
        fewer remaining worlds, then telling what is true, then by name."""
        t = es.true
        states = states_of(es.worlds)
        div = 0
        for s in states:
            div |= s ^ t
        if not div:
            return 0
        h_diff = not self.human_views_fixed(es, es.worlds)
        r_diff = self.robot_view(es.worlds) != self.robot_truth(es)
        p_diff = plan and self._plans_differ(es.human_agendas, t, es.worlds)
        if not (h_diff or r_diff or p_diff):
            return 0
        grounded = self.grounded
        cands = grounded.units(div)  # an atom, or a variable or counter told whole
        # make every view equal (fixing one must not break another); failing that, the
        # human's own (next options and plans) alone
        targets = [True] + ([False] if h_diff or p_diff else [])
        for want_r in targets:
            for size in range(1, min(len(cands), self.comm.inform_max_atoms) + 1):
                best: tuple[int, int, list[str], int] | None = None
                for combo in combinations(cands, size):
                    mask = 0
                    for u in combo:
                        mask |= u
                    w2 = self.observe(t, es.worlds, mask)
                    if not self.fixes(es, w2, want_r, plan):
                        continue
                    # prefer fewer remaining worlds, then telling what is true (a value counts
                    # as true), then by name
                    told = sum(1 for u in combo if t & u or u in grounded.unit_names)
                    rank = (len(w2), -told, [grounded.unit_name(u) for u in combo], mask)
                    if best is None or rank < best:
                        best = rank
                if best is not None:
                    return best[3]
        return 0

    def human_views_fixed(self, es: EState, worlds: Worlds) -> bool:
        """§5: for every hypothesis of ``A_H``, the human's next options on ``worlds`` are
        those on the truth."""
        states = states_of(worlds)
        return all(self.human_view(h, states) == self.human_view(h, (es.true,))
                   for h in es.human_agendas)

    def fixes(self, es: EState, worlds: Worlds, want_r: bool, plan: bool) -> bool:
        """§5: whether the informed ``worlds`` make the human's views equal the truth's: its
        next options (every hypothesis), with ``want_r`` its expectations of the robot, with
        ``plan`` its plans."""
        if not self.human_views_fixed(es, worlds):
            return False
        if want_r and self.robot_view(worlds) != self.robot_truth(es):
            return False
        return not (plan and self._plans_differ(es.human_agendas, es.true, worlds))


def _hypotheses(agendas: Iterable[Agenda]) -> tuple[Agenda, ...]:
    """§3: a set of human agendas in canonical form (distinct, sorted)."""
    return tuple(sorted(set(agendas)))


def _relabel(move: Move, label: str) -> Move:
    """Return ``move`` under another label."""
    return Move(move.agent, move.kind, label, move.cost, move.child, move.op, move.atoms,
                move.failure, move.waits)
