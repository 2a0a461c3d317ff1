"""The rules of docs/semantics.md as the validator re-implements them: refinement (§1),
observation and situation assessment (§2), the search node (§3), both agents' moves (§4) and the
goal (§6). Communication (§5) is :mod:`.communication`'s, partial order :mod:`.network`'s.

Written from the semantics document, not from the planner's code, so that a planner bug shows
up as a violation instead of being copied: it uses only the model layer (grounded atoms,
operators, methods, formulas) and plain sets and loops.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TypeVar

from ..model.formula import FALSE, And, Formula, StateFn, negate
from ..model.grounded import FINISH, GMethod, GModel, GOp, Grounded
from ..model.grounding import ground_problem
from ..model.options import Intentions, Passes
from ..model.problem import Problem
from ..model.vocabulary import HUMAN, ROBOT, Agent, MoveKind
from .network import Agenda, Block, Network

ACTION, WAIT, PASS = MoveKind.ACTION, MoveKind.WAIT, MoveKind.PASS
INFORM, ASK = MoveKind.INFORM, MoveKind.ASK
ANSWER, ANNOUNCE = MoveKind.ANSWER, MoveKind.ANNOUNCE  # the human's answer to the robot's ask; §5
SILENCE = MoveKind.SILENCE  # the robot's silent move at a speech opening (§5)

World = tuple[int, Agenda]  # (state, robot agenda the human attributes to the robot)
Worlds = frozenset[World]
_T = TypeVar("_T")


@dataclass(frozen=True)
class EState:
    """A search node of §3: (turn, T, robot agenda, the human agendas A_H the robot cannot
    tell apart, W, k, passive), with, at a human node, whether the robot's last move was a
    forced wait (§4) and whether the human is answering the robot's question (§5), and, at
    the initial robot node of a speech opening, that it is one (§5)."""

    turn: Agent
    true: int
    robot: Agenda
    humans: frozenset[Agenda]  # A_H, never empty (§3)
    worlds: Worlds
    k: int
    passive: int
    forced: bool = False
    opening: bool = False
    answering: bool = False
    # joint steps (docs/concurrent.md): at a reply node, the human's move the robot replies
    # to; empty at a step's start and in turn-taking
    pending: tuple[int, ...] = ()


@dataclass(frozen=True)
class Step:
    """One move and the node it leads to (``after`` is None when the human acts on a false
    belief: the branch fails)."""

    agent: Agent
    kind: MoveKind
    label: str
    cost: Fraction
    after: EState | None
    texts: tuple[str, ...] = ()  # ask: the conjuncts as printed, in any order
    act: str = ""  # the action part of the label ("wait", "place(w, box2)"); "" for the rest
    told: tuple[str, ...] = ()  # the literals said while acting (speech "with-action")


@dataclass(frozen=True)
class HResult:
    """One result of refining the human's agenda over a set of world states (§1)."""

    action: int  # FINISH when the agenda can be completed
    rest: Agenda
    states: frozenset[int]  # the worlds in which this way applies
    conds: tuple[Formula, ...]  # conditions found uncertain on the way



def _strictly_ends(agenda: Agenda, tail: Agenda) -> bool:
    """Whether ``agenda`` is ``tail`` with something in front of it."""
    return len(agenda) > len(tail) and agenda[len(agenda) - len(tail):] == tail


def _frac(x: object) -> Fraction:
    """Return a cost as an exact fraction: a float as the decimal that was written."""
    if isinstance(x, bool):
        raise TypeError("a cost cannot be a bool")
    if isinstance(x, int | Fraction):
        return Fraction(x)
    if isinstance(x, float):
        return Fraction(repr(x))  # the decimal that was written, not the binary float
    raise TypeError(f"not a number: {x!r}")


def _same(a: object, b: object) -> bool:
    """Equal as exact numbers; a float (a JSON number that is not whole, or a planner's float)
    is accepted within a relative 1e-9, since it cannot hold 1/3 exactly."""
    try:
        x, y = _frac(a), _frac(b)
    except TypeError:
        return False
    if x == y:
        return True
    if isinstance(a, float) or isinstance(b, float):
        return abs(x - y) <= Fraction(1, 10**9) * max(Fraction(1), abs(x), abs(y))
    return False


def _num(x: Fraction) -> str:
    return str(x.numerator) if x.denominator == 1 else str(float(x))



def _bits(mask: int) -> list[int]:
    return [i for i in range(mask.bit_length()) if mask >> i & 1]


def _dedupe(xs: Iterable[_T]) -> list[_T]:
    """``xs`` without repeats, in order (the items are hashable: a refinement can have
    100,000 results)."""
    return list(dict.fromkeys(xs))



def _no_check() -> None:
    """The check of a validation without limits: nothing."""


class Rules:
    """The rules of docs/semantics.md §1-§4 and §6 over one grounded problem."""

    def __init__(self, problem: Problem, check: Callable[[], None] | None = None) -> None:
        self.p = problem
        # called now and then while grounding and refining: a time or memory limit of the
        # caller's may raise from it to stop the check (the validator knows no limits itself)
        self.check: Callable[[], None] = check if check is not None else _no_check
        self._steps = 0
        # refine()'s answers: (model, agenda, state, tasks around) -> options
        self._refined: dict[tuple[int, Agenda, int, frozenset[int]], list[tuple[int, Agenda]]] = {}
        self._lives: dict[tuple[int, int], tuple[GMethod, ...]] = {}  # (model, task): _live
        self.grounded: Grounded = ground_problem(problem, check)
        self.names = (problem.domain.robot_name, problem.domain.human_name)
        self.K = problem.K
        self.atom_of = {a: i for i, a in enumerate(self.grounded.atoms)}
        self.net = Network(self.grounded.task_names)
        # §3: shown every observation that makes a move's node (situation assessment, an
        # inform heard): a lifted policy's check watches whether its order could matter
        self.watch: Callable[[Worlds, int, int], None] | None = None

    @property
    def g(self) -> Grounded:
        """The grounded problem (the older name of :attr:`grounded`)."""
        return self.grounded

    # -- §1: refinement ------------------------------------------------------------------------

    @staticmethod
    def done_of(model: GModel, t: int) -> tuple[Formula, StateFn] | None:
        """§1: a task's done-condition: the operator's own, or the abstract task's."""
        op = model.ops.get(t)
        if op is not None:
            return (op.done_f, op.done) if op.done_f is not None and op.done is not None else None
        return model.done.get(t)

    def _live(self, model: GModel, t: int) -> tuple[GMethod, ...] | None:
        """§1: task ``t``'s methods without those whose subtasks, in order, start with an
        action that can never apply (its precondition is false, it has no done-condition):
        refining such a method gives nothing in any state. None while a first subtask is not
        grounded yet (the walk grounds it when it gets there, in its order)."""
        key = (id(model), t)
        r = self._lives.get(key)
        if r is None:
            keep = []
            for method in model.methods.get(t, ()):
                if method.subtasks and method.order is None:
                    first = method.subtasks[0]
                    if not model.ready(first):
                        return None
                    op = model.ops.get(first)
                    if op is not None and op.done is None and op.pre_f == FALSE:
                        continue
                keep.append(method)
            r = self._lives[key] = tuple(keep)
        return r

    def refine(self, model: GModel, agenda: Agenda, s: int,
               around: frozenset[int] = frozenset()) -> list[tuple[int, Agenda]]:
        """§1: refine(agenda, S): (first primitive action, remaining agenda) pairs; FINISH
        when the agenda can be completed. A task met again at the front while it is being
        refined (before any action) is a loop, and that way is closed; ``around``: the tasks
        being refined around ``agenda`` (a block member's). Memoised: the answer depends on
        nothing else (a block member met again in the same state is refined once)."""
        key = (id(model), agenda, s, around)
        known = self._refined.get(key)
        if known is not None:
            return list(known)
        out: list[tuple[int, Agenda]] = []

        def go(ag: Agenda, depth: int, opened: tuple[tuple[int, Agenda], ...]) -> None:
            if depth > 10_000:
                raise RecursionError("refinement does not terminate")
            self._steps += 1
            if not self._steps & 1023:
                self.check()
            if not ag:
                out.append((FINISH, ()))
                return
            t, rest = ag[0], ag[1:]
            # a task opened in front of ``after`` is still being refined while the agenda is
            # more than ``after``
            still = tuple((u, after) for u, after in opened if _strictly_ends(ag, after))
            busy = around | {u for u, _ in still}
            if isinstance(t, Block):
                # §1 (Partial order): ready tasks that are done are removed first
                for i in t.ready():
                    done = self.done_of(model, t.tasks[i])
                    if done is not None and done[1](s):
                        go(self.drop(t, i) + rest, depth + 1, still)
                        return
                # then each ready task is refined in its place
                for i in t.ready():
                    for a, r in self.refine(model, (t.tasks[i],), s, frozenset(busy)):
                        if a == FINISH:
                            go(self.drop(t, i) + rest, depth + 1, still)
                        else:
                            out.append((a, self.put(t, i, r) + rest))
                return
            op = model.ops.get(t)
            done = self.done_of(model, t)
            if done is not None and done[1](s):
                go(rest, depth + 1, still)
                return
            if op is not None:
                if op.pre(s):
                    out.append((t, rest))
                return
            if t in busy:
                return  # a loop: refined again inside its own refinement
            live = self._live(model, t) if depth < 10_000 else None
            for method in model.methods.get(t, ()) if live is None else live:
                if method.pre(s):
                    go(self.subtasks(method) + rest, depth + 1, (*still, (t, rest)))

        go(agenda, 0, ())
        found = self._refined[key] = _dedupe(out)
        return list(found)

    def hrefine(self, agenda: Agenda, states: frozenset[int],
                conds0: tuple[Formula, ...] = (),
                around: frozenset[int] = frozenset()) -> list[HResult]:
        """§1: the human's refinement over a set of world states: a condition holding in some
        worlds only goes on in those worlds and is recorded as uncertain (``conds0``: the
        conditions already found uncertain before ``agenda``); loops are closed as in
        :meth:`refine`."""
        model = self.grounded.human
        out: list[HResult] = []

        def go(ag: Agenda, ws: frozenset[int], conds: tuple[Formula, ...], depth: int,
               opened: tuple[tuple[int, Agenda], ...] = ()) -> None:
            if depth > 10_000:
                raise RecursionError("refinement does not terminate")
            if not ag:
                out.append(HResult(FINISH, (), ws, conds))
                return
            t, rest = ag[0], ag[1:]
            still = tuple((u, after) for u, after in opened if _strictly_ends(ag, after))
            busy = around | {u for u, _ in still}
            if isinstance(t, Block):
                # §1 (Partial order): a ready task done in some worlds is removed in those
                for i in t.ready():
                    done = self.done_of(model, t.tasks[i])
                    if done is None:
                        continue
                    df, dfn = done
                    yes = frozenset(s for s in ws if dfn(s))
                    if yes == ws:
                        go(self.drop(t, i) + rest, ws, conds, depth + 1, still)
                        return
                    if yes:
                        go(self.drop(t, i) + rest, yes, (*conds, df), depth + 1, still)
                        ws, conds = ws - yes, (*conds, negate(df))
                for i in t.ready():
                    for r in self.hrefine((t.tasks[i],), ws, conds, frozenset(busy)):
                        if r.action == FINISH:
                            go(self.drop(t, i) + rest, r.states, r.conds, depth + 1, still)
                        else:
                            out.append(HResult(r.action, self.put(t, i, r.rest) + rest,
                                               r.states, r.conds))
                return
            op = model.ops.get(t)
            done = self.done_of(model, t)
            if done is not None:
                df, dfn = done
                yes = frozenset(s for s in ws if dfn(s))
                if yes == ws:
                    go(rest, ws, conds, depth + 1, still)
                    return
                if yes:  # done in some worlds: skip it there, refine it elsewhere
                    go(rest, yes, (*conds, df), depth + 1, still)
                    ws, conds = ws - yes, (*conds, negate(df))
            if op is not None:
                ok = frozenset(s for s in ws if op.pre(s))
                if ok:
                    out.append(HResult(t, rest, ok, conds if ok == ws else (*conds, op.pre_f)))
                return
            if t in busy:
                return  # a loop: refined again inside its own refinement
            for method in model.methods.get(t, ()):
                ok = frozenset(s for s in ws if method.pre(s))
                if ok:
                    go(self.subtasks(method) + rest, ok,
                       conds if ok == ws else (*conds, method.pre_f), depth + 1,
                       (*still, (t, rest)))

        go(agenda, states, conds0, 0)
        return _dedupe(out)

    # -- §1: partial order ---------------------------------------------------------------------

    def subtasks(self, method: GMethod) -> Agenda:
        """§1: a method's subtasks as an agenda: as listed, or (partially ordered) in canonical
        form."""
        if method.order is None:
            return method.subtasks
        pairs = {(i, j) for j, preds in enumerate(method.order) for i in _bits(preds)}
        return self.canon(list(method.subtasks), pairs)

    def canon(self, tasks: Sequence[int], before: set[tuple[int, int]]) -> Agenda:
        """§1: ``tasks`` under the order ``before`` in canonical form (:meth:`Network.canon`)."""
        return self.net.canon(tasks, before)

    def drop(self, b: Block, i: int) -> Agenda:
        """§1: the block once its task at position ``i`` is done (:meth:`Network.drop`)."""
        return self.net.drop(b, i)

    def put(self, b: Block, i: int, rest: Agenda) -> Agenda:
        """§1: the block once its task at ``i`` is refined into ``rest`` (:meth:`Network.put`)."""
        return self.net.put(b, i, rest)

    def shown(self, agenda: Agenda) -> list[str]:
        """An agenda as the policy file writes it (:meth:`Network.shown`)."""
        return self.net.shown(agenda)

    # -- §2: observation ---------------------------------------------------------------------

    def unit(self, i: int) -> int:
        """§2: the unit atom ``i`` belongs to, as a mask: the atom itself, or every atom of
        its state variable (one per value) or of its counter (one per bit)."""
        return self.grounded.unit_of.get(i, 1 << i)

    def units(self, mask: int) -> list[int]:
        """§2, §5: the units the atoms of ``m`` belong to, in index order."""
        out: list[int] = []
        for i in _bits(mask):
            u = self.unit(i)
            if u not in out:
                out.append(u)
        return out

    def is_variable(self, u: int) -> bool:
        """§2: whether the unit ``u`` is a state variable (one atom per value)."""
        return u in self.grounded.unit_names and u not in self.grounded.counter_max

    def say(self, t: int, u: int) -> str:
        """§5: unit ``u`` as ``t`` has it: ``a`` or ``not a`` for an atom, ``loc(r) = mt`` for
        a state variable, ``balls(b1) = 2`` for a counter."""
        g = self.grounded
        low = _bits(u)[0]
        if u in g.counter_max:
            return f"{g.unit_names[u]} = {(t & u) >> low}"
        if u in g.unit_names:
            return g.atoms[_bits(t & u)[0]]
        return g.atoms[low] if t >> low & 1 else f"not {g.atoms[low]}"

    def unit_name(self, u: int) -> str:
        """§5: the name informing sets are ranked by: the atom, or ``loc(r)``."""
        return self.grounded.unit_names.get(u) or self.grounded.atoms[_bits(u)[0]]

    def observe(self, worlds: Worlds, t: int, atoms: Iterable[int]) -> Worlds:
        """§2 and §5: learn T's value of the atoms, unit by unit in index order (an atom; the
        atoms of one state variable that are observed; a counter): keep the worlds that agree
        on them; if none does, revise every world: an atom or a counter takes T's value; a
        state variable takes T's value when it is among the observed atoms, else the world
        becomes one world per value of the variable not observed false (exactly one value)."""
        ws = set(worlds)
        parts: dict[int, int] = {}
        for i in atoms:
            u = self.unit(i)
            parts[u] = parts.get(u, 0) | 1 << i
        for u in sorted(parts):  # units are disjoint runs of atoms: this is index order
            part = parts[u]
            agree = {w for w in ws if (w[0] ^ t) & part == 0}
            if agree:
                ws = agree
            elif not self.is_variable(u):
                ws = {((s & ~part) | (t & part), ag) for s, ag in ws}
            elif t & part:
                ws = {((s & ~u) | (t & u), ag) for s, ag in ws}
            else:
                ws = {((s & ~u) | 1 << j, ag) for s, ag in ws for j in _bits(u & ~part)}
        return frozenset(ws)


    def sa(self, worlds: Worlds, t: int) -> Worlds:
        """§2: situation assessment (step 2; step 1 is the case where no revision happens)."""
        mask = self.grounded.visible_mask(t)
        if self.watch is not None:
            self.watch(worlds, t, mask)
        # a world that agrees with T on every unit seen leaves each unit some world that
        # agrees, so no unit revises and the unit-by-unit filter keeps exactly the worlds
        # that agree on all of them (and an empty mask keeps every world)
        agree = frozenset(w for w in worlds if (w[0] ^ t) & mask == 0)
        if agree:
            return agree
        return self.observe(worlds, t, _bits(mask))

    def cop(self, t: int) -> bool:
        """§2: co-presence, on the true state."""
        return bool(self.grounded.copresent(t))

    # -- §4: moves ---------------------------------------------------------------------------

    def rh_op(self, a: int) -> GOp:
        op = self.grounded.robot_seen_by_human.ops.get(a)
        return op if op is not None else self.grounded.robot.ops[a]

    def attributed(self, agenda: Agenda) -> Agenda:
        """The robot agenda as the human can hold it (§4): the tasks its model of the
        robot knows; a task M_R^H has no operator, method or done-condition for is dropped."""
        model = self.grounded.robot_seen_by_human

        def knows(x: int) -> bool:  # an operator, a method or a done-condition for it
            return x in model.ops or bool(model.methods.get(x)) or x in model.done

        out: list[int | Block] = []
        for t in agenda:
            if isinstance(t, Block):  # a block keeps the tasks M_R^H knows (§1)
                keep = [p for p, x in enumerate(t.tasks) if knows(x)]
                at = {p: k for k, p in enumerate(keep)}
                out.extend(self.canon([t.tasks[p] for p in keep],
                                      {(at[x], at[y]) for x, y in t.before
                                       if x in at and y in at}))
            elif knows(t):
                out.append(t)
        return tuple(out)

    def product(self, worlds: Worlds) -> Worlds:
        """§4: every world followed by the noop or a robot event the human anticipates there;
        a non-anticipating human (``[human] anticipates = false``) imagines nothing."""
        if not self.p.human.anticipates:
            return worlds
        out: set[World] = set(worlds)  # the noop
        for s, tn in worlds:
            for a, rest in self.refine(self.grounded.robot_seen_by_human, tn, s):
                if a != FINISH:
                    out.add((self.rh_op(a).apply(s), rest))
        return frozenset(out)

    def set_inferable(self, worlds: Worlds, old: int, new: int) -> Worlds:
        """§4: the inferable atoms an action changed in T are set in every world (a state
        variable or a counter whole)."""
        mask = 0
        for u in self.units(old ^ new):
            mask |= u
        mask &= self.grounded.inferable_mask
        return frozenset(((s & ~mask) | (new & mask), ag) for s, ag in worlds)

    def sees_robot_done(self, worlds: Worlds, true: int, robot: Agenda) -> Worlds:
        """§4, non-anticipating human: whenever co-present in T (the initial one included)
        with a robot agenda that can finish under T, it knows the robot is done (every world's
        robot agenda is empty)."""
        if (self.p.human.anticipates or not self.cop(true)
                or (FINISH, ()) not in self.refine(self.grounded.robot, robot, true)):
            return worlds
        return frozenset((s, ()) for s, _ in worlds)

    def advance(self, es: EState, kind: MoveKind, true: int, robot: Agenda,
                humans: frozenset[Agenda], worlds: Worlds, k: int,
                forced: bool = False) -> EState:
        """§3-§4: the node after a move: SA, k reset when co-present, the passive count."""
        worlds = self.sees_robot_done(self.sa(worlds, true), true, robot)
        if self.cop(true):
            k = 0
        passive = es.passive + 1 if kind in (WAIT, PASS) else 0
        if es.opening:  # §5: the opening gives the turn to the human, no passive move counted
            passive = es.passive
        return EState(es.turn.other, true, robot, humans, worlds, k, passive, forced)

    def initial(self) -> EState:
        """§1-§3: the initial node (the speech opening of §5 is :mod:`.communication`'s)."""
        g = self.grounded
        worlds = self.sa(frozenset((s, self.attributed(ag)) for s, ag in g.beliefs), g.init)
        # a non-anticipating human sees a robot with nothing left to do from the start, as
        # situation assessment runs on the initial state too ("whenever", §4)
        worlds = self.sees_robot_done(worlds, g.init, g.robot_agenda)
        turn = ROBOT if self.p.starts == "robot" else HUMAN
        return EState(turn, g.init, g.robot_agenda, frozenset({g.human_agenda}), worlds, 0, 0)

    def action_cost(self, agent: Agent, op: GOp) -> Fraction:
        model = self.p.domain.robot if agent == ROBOT else self.p.domain.human
        base = model.operators[op.schema].cost
        return _frac(self.p.costs.actions.get(op.schema, base))

    def robot_actions(self, es: EState) -> list[tuple[int, Agenda]]:
        """§4: the robot's real action options (FINISH excluded); none while apart at k = K."""
        if not (self.cop(es.true) or es.k < self.K):
            return []
        return [(a, r) for a, r in self.refine(self.grounded.robot, es.robot, es.true)
                if a != FINISH]

    def robot_act(self, es: EState, a: int, rest: Agenda) -> Step:
        """§4: the robot does action ``a``, leaving ``rest``: witnessed while co-present (the
        worlds that expected it advance, else every world is revised to the real agenda;
        inferable atoms are set), else unseen (the product, k + 1)."""
        g = self.grounded
        op = g.robot.ops[a]
        t2 = op.apply(es.true)
        k = es.k
        if self.cop(es.true):  # the human witnesses a
            seen: set[World] = set()
            for s, tn in es.worlds:
                for b, rest2 in self.refine(g.robot_seen_by_human, tn, s):
                    if b == a:
                        seen.add((self.rh_op(a).apply(s), rest2))
            if not seen:  # nobody expected it: revise, the robot's agenda is the real one
                told = self.attributed(rest)
                seen = {(self.rh_op(a).apply(s), told) for s, _ in es.worlds}
            worlds = self.set_inferable(frozenset(seen), es.true, t2)
        else:
            worlds, k = self.product(es.worlds), k + 1
        after = self.advance(es, ACTION, t2, rest, es.humans, worlds, k)
        name = g.task_names[a]
        return Step(ROBOT, ACTION, name, self.action_cost(ROBOT, op), after, act=name)

    def robot_wait(self, es: EState) -> Step:
        """§4: the robot's wait; forced when it had no real action (every wait is, under
        ``[human] passes = "prototype"``)."""
        worlds, k = es.worlds, es.k
        if not self.cop(es.true) and k < self.K:  # an unseen wait is an imagined event
            worlds, k = self.product(worlds), k + 1
        forced = self.p.human.passes == Passes.PROTOTYPE or not self.robot_actions(es)
        after = self.advance(es, WAIT, es.true, es.robot, es.humans, worlds, k, forced)
        return Step(ROBOT, WAIT, "wait", _frac(self.p.costs.wait), after, act="wait")


    def ordered(self, humans: Iterable[Agenda]) -> list[Agenda]:
        """The human agendas in the order of their names (a fixed order to go through A_H)."""
        return sorted(humans, key=self.shown)

    def conjuncts(self, conds: Sequence[Formula], states: frozenset[int]) -> list[Formula]:
        """The conjuncts of the uncertain conditions whose value differs between worlds, in
        the order of their text (§4: a question is the set of them)."""
        flat: list[Formula] = []
        for c in conds:
            flat.extend(c.args if isinstance(c, And) else (c,))
        out = []
        for f in _dedupe(flat):
            fn = self.grounded.compile(f)
            if len({bool(fn(s)) for s in states}) > 1:
                out.append(f)
        return sorted(out, key=self.text)

    def text(self, f: Formula) -> str:
        r = self.grounded.reading(f)
        return r if r is not None else str(f)

    def human_options(self, es: EState) -> list[Step]:
        """§4 (Human): the options of every hypothesis of A_H (certain actions, asks while
        co-present unless ``[communication] ask = false``, pass by the pass rule), grouped by
        label (§3-§4): one branch per action label, whose node keeps every way any hypothesis
        goes on after it; one per question, and one pass, keeping the hypotheses that had it.
        Under ``intentions = "visible"`` one branch per refinement, labels that would repeat
        at the node naming the intention: ``grab(c1) [place_l(c1)]``. (At an answering node
        the answers are the options, :meth:`.communication.Semantics.human_options`.)"""
        g = self.grounded
        states = frozenset(s for s, _ in es.worlds)
        cop = self.cop(es.true)
        acts: dict[int, list[Agenda]] = {}  # action -> every rest after it, in order found
        branches: list[tuple[int, Agenda]] = []  # (action, rest), each refinement once
        asks: dict[frozenset[Formula], tuple[list[Formula], list[Agenda]]] = {}
        passers: list[Agenda] = []
        for h in self.ordered(es.humans):
            results = self.hrefine(h, states)
            certain = _dedupe((r.action, r.rest) for r in results
                              if r.states == states and r.action != FINISH)
            for a, rest in certain:
                acts.setdefault(a, [])
                if rest not in acts[a]:
                    acts[a].append(rest)
                if (a, rest) not in branches:
                    branches.append((a, rest))
            mine: list[frozenset[Formula]] = []
            if cop and self.p.communication.ask:
                for r in results:
                    if r.states == states:
                        continue
                    phi = self.conjuncts(r.conds, states)
                    key = frozenset(phi)
                    if not phi or key in mine:
                        continue
                    mine.append(key)
                    asks.setdefault(key, (phi, []))[1].append(h)
            if self.may_pass(es, bool(certain), bool(mine), cop):
                passers.append(h)
        steps: list[Step] = []
        if self.p.human.intentions == Intentions.VISIBLE:
            for a, rest in branches:
                label = g.task_names[a]
                if len(acts[a]) > 1:
                    label = f"{label} [{', '.join(self.shown(rest))}]"
                steps.append(self.human_act(es, a, [rest], label))
        else:
            steps.extend(self.human_act(es, a, rests, g.task_names[a])
                         for a, rests in acts.items())
        for phi, hyps in asks.values():
            fns = [g.compile(f) for f in phi]
            want = all(fn(es.true) for fn in fns)
            # the robot answers truthfully: drop the worlds where phi differs from T
            worlds = frozenset(w for w in es.worlds if all(fn(w[0]) for fn in fns) == want)
            texts = tuple(self.text(f) for f in phi)
            after = self.advance(es, ASK, es.true, es.robot, frozenset(hyps), worlds, es.k)
            steps.append(Step(HUMAN, ASK, f"ask({' and '.join(texts)})",
                              _frac(self.p.costs.ask), after, texts))
        if passers:
            after = self.advance(es, PASS, es.true, es.robot, frozenset(passers), es.worlds,
                                 es.k)
            steps.append(Step(HUMAN, PASS, "pass", _frac(self.p.costs.pass_), after, act="pass"))
        return steps

    def human_act(self, es: EState, a: int, rests: Sequence[Agenda], label: str) -> Step:
        """§4: the human does ``a``; the robot, seeing it, keeps every agenda in ``rests``.
        None (the branch fails) when ``a`` is not applicable in T (a false belief)."""
        g = self.grounded
        op = g.human.ops[a]
        cost = self.action_cost(HUMAN, op)
        name = g.task_names[a]
        if not op.pre(es.true):
            return Step(HUMAN, ACTION, label, cost, None, act=name)
        t2 = op.apply(es.true)
        worlds = frozenset((op.apply(s), ag) for s, ag in es.worlds)
        worlds = self.set_inferable(worlds, es.true, t2)
        after = self.advance(es, ACTION, t2, es.robot, frozenset(rests), worlds, es.k)
        return Step(HUMAN, ACTION, label, cost, after, act=name)

    def may_pass(self, es: EState, certain: bool, asks: bool, cop: bool) -> bool:
        """§4: whether a human (one hypothesis) with a certain action or not, and a question
        to ask or not, may pass here."""
        if self.p.human.passes == Passes.IDLE:
            return not certain and not asks  # only with nothing it could do
        if not cop:
            return not certain  # while away, only with nothing else to do
        if es.forced and certain:
            return False  # right after a forced robot wait, a human that can act does not idle
        # a blocked human asks rather than waiting silently, unless it passes when blocked
        return not (es.forced and asks and not self.p.human.passes_when_blocked)
    # -- §6: goal ----------------------------------------------------------------------------

    def is_goal(self, es: EState) -> bool:
        """§6: the goal formula holds in T, the robot's agenda can finish under T, every human
        agenda of A_H certainly finishes over W, and in every world the robot agenda the human
        attributes can finish."""
        g = self.grounded
        if not g.goal(es.true):
            return False
        if (FINISH, ()) not in self.refine(g.robot, es.robot, es.true):
            return False
        if not all(self.human_done(h, es.worlds) for h in es.humans):
            return False  # §6: every hypothesis finished, or the robot cannot know it done
        return all((FINISH, ()) in self.refine(g.robot_seen_by_human, tn, s)
                   for s, tn in es.worlds)

    def human_done(self, agenda: Agenda, worlds: Worlds) -> bool:
        """§6: the human's agenda finishes in every world (H believes its task done)."""
        states = frozenset(s for s, _ in worlds)
        return any(r.action == FINISH and r.states == states
                   for r in self.hrefine(agenda, states))



__all__ = ["ACTION", "ANNOUNCE", "ANSWER", "ASK", "INFORM", "PASS", "SILENCE", "WAIT",
           "EState", "HResult", "Rules", "Step", "World", "Worlds"]
