"""The independent validator: replays a policy and checks it against docs/semantics.md.

Written from the semantics document, not from the planner's code, so that a planner bug shows
up as a violation instead of being copied. It uses only the model layer (grounded atoms,
operators, methods, formulas) and re-implements refinement, situation assessment, world
updates, the product of unseen robot turns and both agents' options with plain sets and loops.

Every node of the policy is recomputed from the initial state (after the fixed opening
``policy.after``) and its recorded facts, move, cost and value are compared with the
recomputation. Checking stops at the first violation of a branch; other branches go on.

The problem's options are read as the document states them: the human's pass rule and whether
it anticipates unseen robot turns (``[human]``, §4), where and how the robot may inform and
whether the human asks (``[communication]``, §5), and the objective the values are under
(``[objective]``, §7). Both the worst-case and the expected value of every node are recomputed
from the validator's own move costs.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import TypeVar

from ..model.formula import And, Formula, StateFn, negate
from ..model.grounding import FINISH, GModel, GOp, Grounded, ground_problem
from ..model.options import InformWhere, ObjectiveKind, Passes, Relevance, Speech
from ..model.problem import Problem
from ..policy_format import Policy, PolicyNode

ROBOT, HUMAN = 0, 1
ACTION, WAIT, PASS, INFORM, ASK, START = "action", "wait", "pass", "inform", "ask", "start"
SILENCE = "silence"  # the robot's silent move at a speech opening (section 5)
BLOCKED = -2  # the end of a human plan where no action applies (relevance "plan", section 5)

Agenda = tuple[int, ...]
World = tuple[int, Agenda]  # (state, robot agenda the human attributes to the robot)
Worlds = frozenset[World]
_T = TypeVar("_T")


@dataclass
class Report:
    """The verdict: ``message`` is the first violation (branch and rule), or a summary."""

    ok: bool
    message: str
    violations: list[str] = field(default_factory=list)
    nodes_checked: int = 0
    branches_checked: int = 0

    def __bool__(self) -> bool:
        return self.ok

    def __str__(self) -> str:
        return self.message


@dataclass(frozen=True)
class EState:
    """A search node of section 3: (turn, T, robot agenda, human agenda, W, k, passive), with,
    at a human node, whether the robot's last move was a forced wait (section 4) and, at the
    initial robot node of a speech opening, that it is one (section 5)."""

    turn: int
    true: int
    robot: Agenda
    human: Agenda
    worlds: Worlds
    k: int
    passive: int
    forced: bool = False
    opening: bool = False


@dataclass(frozen=True)
class Step:
    """One move and the node it leads to (``after`` is None when the human acts on a false
    belief: the branch fails)."""

    agent: int
    kind: str
    label: str
    cost: Fraction
    after: EState | None
    texts: tuple[str, ...] = ()  # ask: the conjuncts as printed, in any order
    act: str = ""  # the action part of the label ("wait", "place(w, box2)"); "" for the rest
    told: tuple[str, ...] = ()  # the literals said while acting (speech "with-action")


@dataclass(frozen=True)
class HResult:
    """One result of refining the human's agenda over a set of world states (section 1)."""

    action: int  # FINISH when the agenda can be completed
    rest: Agenda
    states: frozenset[int]  # the worlds in which this way applies
    conds: tuple[Formula, ...]  # conditions found uncertain on the way


def validate(problem: Problem, policy: Policy) -> Report:
    """Check ``policy`` against ``problem``: every rule of docs/semantics.md, sections 1-7 (see
    the module docstring)."""
    return _Validator(problem, policy).run()


def _frac(x: object) -> Fraction:
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


def _bits(m: int) -> list[int]:
    return [i for i in range(m.bit_length()) if m >> i & 1]


def _dedupe(xs: Iterable[_T]) -> list[_T]:
    out: list[_T] = []
    for x in xs:
        if x not in out:
            out.append(x)
    return out


class _Semantics:
    """The rules of docs/semantics.md over one grounded problem."""

    def __init__(self, problem: Problem) -> None:
        self.p = problem
        self.g: Grounded = ground_problem(problem)
        g = self.g
        self.names = (problem.domain.robot_name, problem.domain.human_name)
        self.K = problem.K
        self.atom_of = {a: i for i, a in enumerate(g.atoms)}
        self._plans: dict[tuple[Agenda, int, int], frozenset[tuple[int, ...]]] = {}

    # -- section 1: refinement -----------------------------------------------------------------

    @staticmethod
    def done_of(model: GModel, t: int) -> tuple[Formula, StateFn] | None:
        """§1: a task's done-condition: the operator's own, or the abstract task's."""
        op = model.ops.get(t)
        if op is not None:
            return (op.done_f, op.done) if op.done_f is not None and op.done is not None else None
        return model.done.get(t)

    def refine(self, model: GModel, agenda: Agenda, s: int) -> list[tuple[int, Agenda]]:
        """§1: refine(agenda, S): (first primitive action, remaining agenda) pairs; FINISH
        when the agenda can be completed."""
        out: list[tuple[int, Agenda]] = []

        def go(ag: Agenda, depth: int) -> None:
            if depth > 10_000:
                raise RecursionError("refinement does not terminate")
            if not ag:
                out.append((FINISH, ()))
                return
            t, rest = ag[0], ag[1:]
            op = model.ops.get(t)
            done = self.done_of(model, t)
            if done is not None and done[1](s):
                go(rest, depth + 1)
                return
            if op is not None:
                if op.pre(s):
                    out.append((t, rest))
                return
            for m in model.methods.get(t, ()):
                if m.pre(s):
                    go(m.subtasks + rest, depth + 1)

        go(agenda, 0)
        return _dedupe(out)

    def hrefine(self, agenda: Agenda, states: frozenset[int]) -> list[HResult]:
        """§1: the human's refinement over a set of world states: a condition holding in some
        worlds only goes on in those worlds and is recorded as uncertain."""
        model = self.g.human
        out: list[HResult] = []

        def go(ag: Agenda, ws: frozenset[int], conds: tuple[Formula, ...], depth: int) -> None:
            if depth > 10_000:
                raise RecursionError("refinement does not terminate")
            if not ag:
                out.append(HResult(FINISH, (), ws, conds))
                return
            t, rest = ag[0], ag[1:]
            op = model.ops.get(t)
            done = self.done_of(model, t)
            if done is not None:
                df, dfn = done
                yes = frozenset(s for s in ws if dfn(s))
                if yes == ws:
                    go(rest, ws, conds, depth + 1)
                    return
                if yes:  # done in some worlds: skip it there, refine it elsewhere
                    go(rest, yes, (*conds, df), depth + 1)
                    ws, conds = ws - yes, (*conds, negate(df))
            if op is not None:
                ok = frozenset(s for s in ws if op.pre(s))
                if ok:
                    out.append(HResult(t, rest, ok, conds if ok == ws else (*conds, op.pre_f)))
                return
            for m in model.methods.get(t, ()):
                ok = frozenset(s for s in ws if m.pre(s))
                if ok:
                    go(m.subtasks + rest, ok, conds if ok == ws else (*conds, m.pre_f), depth + 1)

        go(agenda, states, (), 0)
        return _dedupe(out)

    # -- section 2: observation ----------------------------------------------------------------

    def observe(self, worlds: Worlds, t: int, atoms: Iterable[int]) -> Worlds:
        """§2 and §5: learn T's value of each atom, in order: keep the worlds that agree; if
        none does, set the atom to T's value in every world (belief revision)."""
        ws = set(worlds)
        for i in atoms:
            bit = 1 << i
            agree = {w for w in ws if (w[0] ^ t) & bit == 0}
            ws = agree or {((s & ~bit) | (t & bit), ag) for s, ag in ws}
        return frozenset(ws)

    def sa(self, worlds: Worlds, t: int) -> Worlds:
        """§2: situation assessment (step 2; step 1 is the case where no revision happens)."""
        return self.observe(worlds, t, _bits(self.g.visible_mask(t)))

    def cop(self, t: int) -> bool:
        """§2: co-presence, on the true state."""
        return bool(self.g.copresent(t))

    # -- section 4: moves ----------------------------------------------------------------------

    def rh_op(self, a: int) -> GOp:
        op = self.g.robot_seen_by_human.ops.get(a)
        return op if op is not None else self.g.robot.ops[a]

    def attributed(self, agenda: Agenda) -> Agenda:
        """The robot agenda as the human can hold it (section 4): the tasks its model of the
        robot knows; a task M_R^H has no operator, method or done-condition for is dropped."""
        m = self.g.robot_seen_by_human
        return tuple(t for t in agenda if t in m.ops or t in m.methods or t in m.done)

    def product(self, worlds: Worlds) -> Worlds:
        """§4: every world followed by the noop or a robot event the human anticipates there;
        a non-anticipating human (``[human] anticipates = false``) imagines nothing."""
        if not self.p.human.anticipates:
            return worlds
        out: set[World] = set(worlds)  # the noop
        for s, tn in worlds:
            for a, rest in self.refine(self.g.robot_seen_by_human, tn, s):
                if a != FINISH:
                    out.add((self.rh_op(a).apply(s), rest))
        return frozenset(out)

    def set_inferable(self, worlds: Worlds, old: int, new: int) -> Worlds:
        """§4: the inferable atoms an action changed in T are set in every world."""
        m = (old ^ new) & self.g.inferable_mask
        return frozenset(((s & ~m) | (new & m), ag) for s, ag in worlds)

    def sees_robot_done(self, worlds: Worlds, true: int, robot: Agenda) -> Worlds:
        """§4, non-anticipating human: whenever co-present in T (the initial one included)
        with a robot agenda that can finish under T, it knows the robot is done (every world's
        robot agenda is empty)."""
        if (self.p.human.anticipates or not self.cop(true)
                or (FINISH, ()) not in self.refine(self.g.robot, robot, true)):
            return worlds
        return frozenset((s, ()) for s, _ in worlds)

    def advance(self, es: EState, kind: str, true: int, robot: Agenda, human: Agenda,
                worlds: Worlds, k: int, forced: bool = False) -> EState:
        """§3-§4: the node after a move: SA, k reset when co-present, the passive count."""
        worlds = self.sees_robot_done(self.sa(worlds, true), true, robot)
        if self.cop(true):
            k = 0
        passive = es.passive + 1 if kind in (WAIT, PASS) else 0
        if es.opening:  # §5: the opening gives the turn to the human, no passive move counted
            passive = es.passive
        return EState(1 - es.turn, true, robot, human, worlds, k, passive, forced)

    def initial(self) -> EState:
        """§1-§3 and §5: the initial node; a robot opening turn when the human starts, the
        robot may speak while acting and an informing set exists in the initial state."""
        g = self.g
        worlds = self.sa(frozenset((s, self.attributed(ag)) for s, ag in g.beliefs), g.init)
        # a non-anticipating human sees a robot with nothing left to do from the start, as
        # situation assessment runs on the initial state too ("whenever", section 4)
        worlds = self.sees_robot_done(worlds, g.init, g.robot_agenda)
        turn = ROBOT if self.p.starts == "robot" else HUMAN
        es = EState(turn, g.init, g.robot_agenda, g.human_agenda, worlds, 0, 0)
        if turn == HUMAN and self.p.communication.speech == Speech.WITH_ACTION:
            opening = replace(es, turn=ROBOT, opening=True)
            if not isinstance(self.inform_search(opening), str):
                return opening
        return es

    def action_cost(self, agent: int, op: GOp) -> Fraction:
        model = self.p.domain.robot if agent == ROBOT else self.p.domain.human
        base = model.operators[op.schema].cost
        return _frac(self.p.costs.actions.get(op.schema, base))

    def robot_actions(self, es: EState) -> list[tuple[int, Agenda]]:
        """§4: the robot's real action options (FINISH excluded); none while apart at k = K."""
        if not (self.cop(es.true) or es.k < self.K):
            return []
        return [(a, r) for a, r in self.refine(self.g.robot, es.robot, es.true) if a != FINISH]

    def robot_act(self, es: EState, a: int, rest: Agenda) -> Step:
        g = self.g
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
        after = self.advance(es, ACTION, t2, rest, es.human, worlds, k)
        name = g.task_names[a]
        return Step(ROBOT, ACTION, name, self.action_cost(ROBOT, op), after, act=name)

    def robot_wait(self, es: EState) -> Step:
        """§4: the robot's wait; forced when it had no real action (every wait is, under
        ``[human] passes = "prototype"``)."""
        worlds, k = es.worlds, es.k
        if not self.cop(es.true) and k < self.K:  # an unseen wait is an imagined event
            worlds, k = self.product(worlds), k + 1
        forced = self.p.human.passes == Passes.PROTOTYPE or not self.robot_actions(es)
        after = self.advance(es, WAIT, es.true, es.robot, es.human, worlds, k, forced)
        return Step(ROBOT, WAIT, "wait", _frac(self.p.costs.wait), after, act="wait")

    def silence(self, es: EState) -> Step:
        """§5: the robot's silent move at a speech opening (cost 0, no effect)."""
        after = self.advance(es, SILENCE, es.true, es.robot, es.human, es.worlds, es.k)
        return Step(ROBOT, SILENCE, SILENCE, Fraction(0), after)

    def literals(self, t: int, atoms: Iterable[int]) -> tuple[str, ...]:
        return tuple(self.g.atoms[i] if t >> i & 1 else f"not {self.g.atoms[i]}"
                     for i in atoms)

    def inform(self, es: EState, atoms: Sequence[int]) -> Step:
        """§5: ``inform(A)``: the human learns T's value of every atom of A, nothing else is
        witnessed (k unchanged, no world multiplied, also while apart)."""
        worlds = self.observe(es.worlds, es.true, sorted(atoms))
        after = self.advance(es, INFORM, es.true, es.robot, es.human, worlds, es.k)
        label = f"inform({', '.join(self.literals(es.true, sorted(atoms)))})"
        return Step(ROBOT, INFORM, label, _frac(self.p.costs.inform), after)

    def informed(self, es: EState, atoms: Sequence[int]) -> EState:
        """The node as it is once the human has heard ``inform(atoms)``, before the action
        said with it runs (speech "with-action", section 5)."""
        return replace(es, worlds=self.observe(es.worlds, es.true, sorted(atoms)))

    def with_speech(self, es: EState, atoms: Sequence[int], st: Step) -> Step:
        """§5: ``inform(A) + a``: A is heard first, then ``st`` (computed from the informed
        node) runs as usual; the costs add up."""
        told = self.literals(es.true, atoms)
        label = f"inform({', '.join(told)}) + {st.act}"
        return Step(ROBOT, st.kind, label, _frac(self.p.costs.inform) + st.cost, st.after,
                    act=st.act, told=told)

    def conjuncts(self, conds: Sequence[Formula], states: frozenset[int]) -> list[Formula]:
        """The conjuncts of the uncertain conditions whose value differs between worlds."""
        flat: list[Formula] = []
        for c in conds:
            flat.extend(c.args if isinstance(c, And) else (c,))
        out = []
        for f in _dedupe(flat):
            fn = self.g.compile(f)
            if len({bool(fn(s)) for s in states}) > 1:
                out.append(f)
        return out

    def text(self, f: Formula) -> str:
        return self.g.display.get(f, str(f))

    def human_options(self, es: EState) -> list[Step]:
        """§4 (Human): certain actions, asks while co-present (unless ``[communication] ask =
        false``), and pass by the pass rule (forced waits, ``passes_when_blocked``)."""
        g = self.g
        states = frozenset(s for s, _ in es.worlds)
        results = self.hrefine(es.human, states)
        cop = self.cop(es.true)
        steps: list[Step] = []
        certain = _dedupe((r.action, r.rest) for r in results
                          if r.states == states and r.action != FINISH)
        for a, rest in certain:
            op = g.human.ops[a]
            cost = self.action_cost(HUMAN, op)
            name = g.task_names[a]
            if not op.pre(es.true):
                steps.append(Step(HUMAN, ACTION, name, cost, None, act=name))
                continue
            t2 = op.apply(es.true)
            worlds = frozenset((op.apply(s), ag) for s, ag in es.worlds)
            worlds = self.set_inferable(worlds, es.true, t2)
            after = self.advance(es, ACTION, t2, es.robot, rest, worlds, es.k)
            steps.append(Step(HUMAN, ACTION, name, cost, after, act=name))
        asks: list[frozenset[Formula]] = []
        if cop and self.p.communication.ask:
            for r in results:
                if r.states == states:
                    continue
                phi = self.conjuncts(r.conds, states)
                key = frozenset(phi)
                if not phi or key in asks:
                    continue
                asks.append(key)
                fns = [g.compile(f) for f in phi]
                want = all(fn(es.true) for fn in fns)
                # the robot answers truthfully: drop the worlds where phi differs from T
                worlds = frozenset(w for w in es.worlds
                                   if all(fn(w[0]) for fn in fns) == want)
                texts = tuple(self.text(f) for f in phi)
                after = self.advance(es, ASK, es.true, es.robot, es.human, worlds, es.k)
                steps.append(Step(HUMAN, ASK, f"ask({' and '.join(texts)})",
                                  _frac(self.p.costs.ask), after, texts))
        if cop:
            # right after a forced robot wait, a human with a certain action does not idle
            may_pass = not (es.forced and certain)
            if es.forced and asks and not self.p.human.passes_when_blocked:
                may_pass = False  # a blocked human asks rather than waiting silently
        else:
            may_pass = not certain
        if may_pass:
            after = self.advance(es, PASS, es.true, es.robot, es.human, es.worlds, es.k)
            steps.append(Step(HUMAN, PASS, "pass", _frac(self.p.costs.pass_), after, act="pass"))
        return steps

    # -- section 5: relevance of a divergence, the informing set -------------------------------

    def human_view(self, agenda: Agenda, states: frozenset[int]) -> frozenset[tuple[int, bool]]:
        """§5: the human's next actions on ``states``, each with whether it is certain (what
        it would choose; the method behind an action is not part of it)."""
        return frozenset((r.action, r.states == states) for r in self.hrefine(agenda, states))

    def plans(self, agenda: Agenda, s: int) -> frozenset[tuple[int, ...]]:
        """§5 (relevance "plan"): plans(S), the sequences of human actions refining ``agenda``
        with M_H in the single state S, each action applied and the robot idle, up to the end
        of the agenda (FINISH) or ``plan_horizon`` actions; a sequence that ends early where
        no action applies ends with BLOCKED."""
        memo = self._plans

        def go(ag: Agenda, st: int, n: int) -> frozenset[tuple[int, ...]]:
            key = (ag, st, n)
            got = memo.get(key)
            if got is not None:
                return got
            if n == 0:
                out: set[tuple[int, ...]] = {()}
            else:
                res = self.refine(self.g.human, ag, st)
                out = set() if res else {(BLOCKED,)}
                for a, rest in res:
                    if a == FINISH:
                        out.add((FINISH,))
                        continue
                    nxt = go(rest, self.g.human.ops[a].apply(st), n - 1)
                    out.update((a, *tail) for tail in nxt)
            memo[key] = frozenset(out)
            return memo[key]

        return go(agenda, s, self.p.communication.plan_horizon)

    def views_differ(self, es: EState, worlds: Worlds) -> tuple[bool, bool, bool]:
        """(human's options differ, anticipated robot options differ, human plans differ)
        between W and T; the third is always False under relevance "next"."""
        states = frozenset(s for s, _ in worlds)
        human = self.human_view(es.human, states) != self.human_view(es.human,
                                                                     frozenset({es.true}))
        # the robot's options include being done (FINISH): a divergence that hides from the
        # human that the robot has finished is relevant, since the goal needs H to believe it
        expected = {a for s, tn in worlds
                    for a, _ in self.refine(self.g.robot_seen_by_human, tn, s)}
        real = {a for a, _ in self.refine(self.g.robot, es.robot, es.true)}
        plans = False
        if self.p.communication.relevance == Relevance.PLAN:
            mine = self.plans(es.human, es.true)
            plans = any(self.plans(es.human, s) != mine for s in states)
        return human, expected != real, plans

    def inform_where(self, es: EState) -> str | None:
        """§5: why no ``inform`` may be offered here for where the agents are (None if it
        may). Under ``inform = "anywhere"`` an inform is heard while apart even at k = K: it
        is no robot turn the human imagines (no world multiplied, k unchanged), so the K bound
        of section 4, which limits what the robot does unseen, does not apply to it."""
        if self.cop(es.true) or self.p.communication.inform == InformWhere.ANYWHERE:
            return None
        return "inform is offered only while co-present"

    def inform_search(self, es: EState) -> tuple[str, int, list[tuple[int, ...]]] | str:
        """§5: the informing sets allowed here: (what they fix, their size, every smallest set
        that fixes it, in canonical order), or why no ``inform`` is offered.

        Sets fixing the human's options, the anticipated robot options (and, under relevance
        "plan", the plans) come first; failing those, sets fixing the human's options (and the
        plans) -- only when those differ: a set cannot fix what is not broken, and telling the
        human something that changes none of its options is not worth a move."""
        why = self.inform_where(es)
        if why is not None:
            return why
        plan = self.p.communication.relevance == Relevance.PLAN
        now = self.views_differ(es, es.worlds)
        if not any(now):
            return ("the divergence is not relevant (the human's and the anticipated robot's "
                    "options" + (" and the human's plans" if plan else "") +
                    " on W equal those on T)")
        div = 0
        for s, _ in es.worlds:
            div |= s ^ es.true
        cands = _bits(div)
        limit = self.p.communication.inform_max_atoms
        fixed: dict[tuple[int, ...], tuple[bool, bool, bool]] = {}
        for n in range(1, limit + 1):
            for sub in itertools.combinations(cands, n):
                h, r, p = self.views_differ(es, self.observe(es.worlds, es.true, sub))
                fixed[sub] = (not h, not r, not p)
        both = "the human's views" + (" and plans" if plan else "")
        alone = "the human's options" + (" and plans" if plan else "")
        tiers: list[tuple[str, Callable[[tuple[bool, bool, bool]], bool]]] = [(both, all)]
        if now[0] or now[2]:
            tiers.append((alone, lambda f: f[0] and f[2]))
        for what, test in tiers:
            for n in range(1, limit + 1):
                sets = [a for a, f in fixed.items() if len(a) == n and test(f)]
                if sets:
                    return what, n, sets
        if len(tiers) == 1:
            return (f"no set of at most inform_max_atoms = {limit} atoms fixes {both}, and the "
                    "human's options" + (" and plans" if plan else "") + " need no fixing")
        return f"no set of at most inform_max_atoms = {limit} atoms fixes {alone}"

    def check_inform(self, es: EState, atoms: Sequence[int]) -> str | None:
        """§5: why ``inform(atoms)`` is not a legal robot option here (None when it is)."""
        g = self.g
        why = self.inform_where(es)
        if why is not None:
            return why
        div = 0
        for s, _ in es.worlds:
            div |= s ^ es.true
        for i in atoms:
            if not div >> i & 1:
                return (f"every world already agrees with the truth on {g.atoms[i]}: "
                        "informing the human of what it believes is never generated")
        limit = self.p.communication.inform_max_atoms
        found = self.inform_search(es)
        if isinstance(found, str):
            return found
        if len(atoms) > limit:
            return f"informs {len(atoms)} atoms, more than inform_max_atoms = {limit}"
        what, n, sets = found
        mine = tuple(sorted(atoms))
        if mine in sets:
            return self.check_choice(es, mine, sets)
        h, r, p = self.views_differ(es, self.observe(es.worlds, es.true, mine))
        fixes = (not h and not p) if what.startswith("the human's options") else not (h or r or p)
        if not fixes:
            return f"it does not fix {what}, yet a set of {n} atom(s) does"
        if what.startswith("the human's options"):
            return f"not a smallest set fixing {what}: {len(atoms)} atoms where {n} suffice"
        return f"not a smallest fixing set: {len(atoms)} atoms where {n} suffice"

    def check_choice(self, es: EState, atoms: tuple[int, ...],
                     sets: list[tuple[int, ...]]) -> str | None:
        """§5: among smallest sets, the one leaving the fewest worlds, then telling more true
        atoms, then the first by atom names."""
        def key(a: tuple[int, ...]) -> tuple[int, int, tuple[str, ...]]:
            left = len(self.observe(es.worlds, es.true, a))
            return left, -sum(es.true >> i & 1 for i in a), tuple(self.g.atoms[i] for i in a)

        best = min(sets, key=key)
        if best == atoms:
            return None
        told = ", ".join(self.literals(es.true, best))
        return f"not the informing set the rules choose among smallest sets (fewest worlds " \
               f"left, then more true atoms, then atom names): inform({told})"

    # -- section 6: goal -----------------------------------------------------------------------

    def is_goal(self, es: EState) -> bool:
        g = self.g
        if not g.goal(es.true):
            return False
        if (FINISH, ()) not in self.refine(g.robot, es.robot, es.true):
            return False
        states = frozenset(s for s, _ in es.worlds)
        if not any(r.action == FINISH and r.states == states
                   for r in self.hrefine(es.human, states)):
            return False
        return all((FINISH, ()) in self.refine(g.robot_seen_by_human, tn, s)
                   for s, tn in es.worlds)

    # -- reading labels ------------------------------------------------------------------------

    def parse_inform(self, label: str) -> list[tuple[int, bool]] | str:
        """``inform(a, not b(x, y))`` -> (atom index, value the label states) pairs."""
        inner = label[len("inform("):-1] if label.startswith("inform(") and label.endswith(
            ")") else None
        if not inner:
            return f"cannot read {label!r} as inform(atom, ...)"
        out: list[tuple[int, bool]] = []
        buf = ""
        for tok in inner.split(", "):  # atoms contain ", " too: grow until one is known
            buf = f"{buf}, {tok}" if buf else tok
            neg = buf.startswith("not ")
            name = buf[4:] if neg else buf
            if name in self.atom_of:
                out.append((self.atom_of[name], not neg))
                buf = ""
        if buf or not out:
            return f"cannot read {label!r}: {buf!r} is not a fluent atom"
        return out


def _ask_matches(step: Step, label: str) -> bool:
    if step.label == label:
        return True
    if len(step.texts) > 7:
        return False
    return any(f"ask({' and '.join(p)})" == label for p in itertools.permutations(step.texts))


@dataclass
class _Item:
    node: PolicyNode
    es: EState
    path: list[str]


class _Validator:
    def __init__(self, problem: Problem, policy: Policy) -> None:
        self.problem = problem
        self.policy = policy
        self.sem = _Semantics(problem)
        self.violations: list[str] = []
        self.nodes_checked = 0
        self.branches_checked = 0
        self.goals_reached: set[int] = set()  # goal leaves whose branch checked out
        self.step_cost: dict[int, Fraction] = {}  # node id -> the cost of the move into it
        self.weight: dict[int, Fraction] = {}  # node id -> the move's weight (section 7)
        self.turn: dict[int, int] = {}  # node id -> who moves next there (checked nodes)

    def fail(self, path: Sequence[str], rule: str) -> None:
        self.violations.append(f"branch [{', '.join(path)}]: {rule}")

    def name(self, agent: int) -> str:
        return self.sem.names[agent]

    def move_label(self, agent: int, label: str) -> str:
        return f"{self.name(agent)} {label}"

    # -- moves ---------------------------------------------------------------------------------

    def robot_steps(self, es: EState, label: str) -> list[Step] | str:
        """The robot moves a policy label can denote here (§4, §5), or why it is not an
        option."""
        sem, g = self.sem, self.sem.g
        if es.opening:
            if label == SILENCE:
                return [sem.silence(es)]
            if not label.startswith("inform(") or " + " in label:
                return f"at the speech opening (section 5) the robot may only inform or stay " \
                       f"silent, not {label}"
            r = self.inform_atoms(es, label)
            return r if isinstance(r, str) else [sem.inform(es, r)]
        if label == SILENCE:
            return "silence is a move only at the speech opening, before the human's first " \
                   "move (section 5)"
        if " + " in label:
            if self.problem.communication.speech != Speech.WITH_ACTION:
                return 'speaking while acting needs [communication] speech = "with-action" ' \
                       '(section 5)'
            said, _, act = label.partition(" + ")
            if act.startswith("inform(") or act == SILENCE:
                return f"{act} cannot be said with an inform; only an action or wait can"
            r = self.inform_atoms(es, said)
            if isinstance(r, str):
                return r
            steps = self.robot_steps(sem.informed(es, r), act)
            if isinstance(steps, str):
                return steps
            return [sem.with_speech(es, r, st) for st in steps]
        if label == "wait":
            return [sem.robot_wait(es)]
        if label.startswith("inform("):
            r = self.inform_atoms(es, label)
            return r if isinstance(r, str) else [sem.inform(es, r)]
        if label == "pass" or label.startswith("ask("):
            return f"{label} is not a robot move"
        opts = [(a, r) for a, r in sem.robot_actions(es) if g.task_names[a] == label]
        if opts:
            return [sem.robot_act(es, a, r) for a, r in opts]
        if not (sem.cop(es.true) or es.k < sem.K):
            return f"the agents are apart and k = K = {sem.K}: only wait is allowed"
        tid = g.task_index.get(label)
        op = g.robot.ops.get(tid) if tid is not None else None
        if op is None:
            return f"{label} is not an action of {self.name(ROBOT)}"
        if not op.pre(es.true):
            return f"{label} is not applicable in T (its precondition does not hold)"
        agenda = [g.task_names[t] for t in es.robot]
        return f"{label} is not the first action of any refinement of the robot agenda " \
               f"{agenda} under T"

    def inform_atoms(self, es: EState, label: str) -> list[int] | str:
        """The atoms of ``inform(...)`` in label order, if it is a legal inform here (§5)."""
        sem, g = self.sem, self.sem.g
        parsed = sem.parse_inform(label)
        if isinstance(parsed, str):
            return parsed
        atoms = [i for i, _ in parsed]
        if len(set(atoms)) != len(atoms):
            return "an atom is told twice"
        why = sem.inform_where(es)
        if why is not None:
            return why
        for i, value in parsed:  # the label tells literals of T
            if bool(es.true >> i & 1) != value:
                return f"the label tells {g.atoms[i]} is {str(value).lower()}, but it is " \
                       f"{str(not value).lower()} in T"
        why = sem.check_inform(es, atoms)
        return why if why is not None else atoms

    def human_steps(self, es: EState, label: str,
                    options: list[Step] | None = None) -> list[Step]:
        """The human options a label denotes (several when methods differ in what is left)."""
        opts = options if options is not None else self.sem.human_options(es)
        return [o for o in opts if (_ask_matches(o, label) if o.kind == ASK else
                                    o.label == label)]

    # -- recorded facts ------------------------------------------------------------------------

    def facts(self, node: PolicyNode, es: EState, goal: bool) -> list[str]:
        sem, g = self.sem, self.sem.g
        bad: list[str] = []

        def cmp(what: str, got: object, want: object) -> None:
            if got != want:
                bad.append(f"{what} is {got!r}, expected {want!r}")

        if set(node.state) != set(g.state_atoms(es.true)):
            extra = sorted(set(node.state) - set(g.state_atoms(es.true)))
            missing = sorted(set(g.state_atoms(es.true)) - set(node.state))
            bad.append(f"state differs from the true state T (recorded but false: {extra}; "
                       f"true but not recorded: {missing})")
        cmp("robot_agenda", list(node.robot_agenda), [g.task_names[t] for t in es.robot])
        cmp("human_agenda", list(node.human_agenda), [g.task_names[t] for t in es.human])
        cmp("copresent", node.copresent, sem.cop(es.true))
        cmp("k", node.k, es.k)
        cmp("worlds", node.worlds, len(es.worlds))
        cmp("to_move", node.to_move, None if goal else self.name(es.turn))
        if (node.kind == START and not self.policy.after and es.turn == HUMAN and not goal
                and node.to_move == self.name(ROBOT)
                and self.problem.communication.speech == Speech.WITH_ACTION):
            why = sem.inform_search(replace(es, turn=ROBOT, opening=True))
            if isinstance(why, str):  # the robot may not open: say why (section 5)
                bad.append(f"no speech opening, since no informing set exists in the initial "
                           f"state: {why}")
        cmp("goal", node.goal, goal)
        div = 0
        diffs = []
        for s in {s for s, _ in es.worlds}:
            div |= s ^ es.true
            diffs.append((frozenset(g.mask_atoms(s & ~es.true)),
                          frozenset(g.mask_atoms(es.true & ~s))))
        want_div = {g.atoms[i] if es.true >> i & 1 else f"not {g.atoms[i]}" for i in _bits(div)}
        if set(node.divergence) != want_div:
            cmp("divergence", sorted(node.divergence), sorted(want_div))
        got_diffs = sorted((sorted(d.get("true", [])), sorted(d.get("false", [])))
                           for d in node.world_diffs)
        want_diffs = sorted((sorted(t), sorted(f)) for t, f in diffs)
        if got_diffs != want_diffs:
            bad.append(f"world_diffs (the worlds' differences from T) are {got_diffs}, "
                       f"expected {want_diffs}")
        return bad

    # -- the replay ----------------------------------------------------------------------------

    def replay_after(self) -> EState | None:
        sem = self.sem
        pol, prob = self.policy, self.problem
        if list(pol.after) != list(prob.after):
            i = next((j for j, (a, b) in enumerate(zip(pol.after, prob.after, strict=False))
                      if a != b), min(len(pol.after), len(prob.after)))
            got = pol.after[i] if i < len(pol.after) else "(nothing)"
            want = prob.after[i] if i < len(prob.after) else "(nothing)"
            self.fail(list(pol.after[:i]), f"opening: after[{i}] is {got!r}, but the problem "
                      f"fixes {want!r} (policy after {list(pol.after)} != problem after "
                      f"{list(prob.after)})")
        states = [sem.initial()]
        done: list[str] = []
        for i, mv in enumerate(pol.after):
            agent_name, _, label = mv.partition(" ")
            nxt: list[EState] = []
            why = ""
            for es in states:
                if agent_name != self.name(es.turn):
                    why = f"it is {self.name(es.turn)}'s turn, not {agent_name}'s"
                    continue
                if es.turn == ROBOT:
                    r = self.robot_steps(es, label)
                    if isinstance(r, str):
                        why = r
                        continue
                    steps = r
                else:
                    steps = self.human_steps(es, label)
                    if not steps:
                        why = f"{label} is not one of the human's options"
                        continue
                for st in steps:
                    if st.after is None:
                        why = f"{label} is not applicable in T: the human acts on a false belief"
                    elif st.after not in nxt:
                        nxt.append(st.after)
            if not nxt:
                self.fail(done, f"opening: after[{i}] {mv!r} is not a legal move: {why}")
                return None
            states = nxt
            done.append(mv)
        root = pol.root
        for es in states:  # an ambiguous opening is settled by the root's recorded agendas
            if not self.facts(root, es, sem.is_goal(es)):
                return es
        return states[0]

    def run(self) -> Report:
        pol, sem = self.policy, self.sem
        nodes = pol.nodes
        if not nodes:
            return self.report()
        if any(n.id != i for i, n in enumerate(nodes)):
            self.fail([], "node ids are not their positions in the node list")
            return self.report()
        if pol.problem != self.problem.name:
            self.fail([], f"the policy was planned for problem {pol.problem!r}, not for "
                      f"{self.problem.name!r}: solve this problem, or validate against the "
                      "policy's own problem")
            return self.report()
        if pol.K != sem.K:
            self.fail([], f"policy K is {pol.K}, the problem's is {sem.K}")
        if pol.agents != {"robot": sem.names[ROBOT], "human": sem.names[HUMAN]}:
            self.fail([], f"policy agents {pol.agents} are not the domain's")
        self.check_costs()
        self.check_objective()
        root_es = self.replay_after()
        if root_es is not None:
            root = nodes[0]
            if root.kind != START or root.agent is not None or not _same(root.cost, 0):
                self.fail([], "the root must be a start node with no agent and cost 0")
            else:
                self.walk(root_es)
        self.check_summary()
        return self.report()

    def check_costs(self) -> None:
        c = self.problem.costs
        want: dict[str, object] = {"inform": c.inform, "ask": c.ask, "wait": c.wait,
                                   "pass": c.pass_}
        got = self.policy.costs
        for key, v in want.items():
            if key not in got or not _same(got[key], v):
                self.fail([], f"policy costs[{key!r}] is {got.get(key)}, the problem's is {v}")
        acts = got.get("actions", {})
        if set(acts) != set(c.actions) or any(not _same(acts[a], c.actions[a]) for a in acts):
            self.fail([], f"policy costs['actions'] is {acts}, the problem's is "
                      f"{dict(c.actions)}")

    def walk(self, root_es: EState) -> None:
        nodes = self.policy.nodes
        seen: set[int] = set()
        stack = [_Item(nodes[0], root_es, [])]
        self.step_cost[0] = Fraction(0)
        while stack:
            it = stack.pop()
            node, es, path = it.node, it.es, it.path
            if node.id in seen:
                self.fail(path, f"node {node.id} is reached twice: the policy is not a tree")
                continue
            seen.add(node.id)
            self.nodes_checked += 1
            kids_ok = self.visit(node, es, path)
            for child, st in reversed(kids_ok):
                assert st.after is not None
                stack.append(_Item(child, st.after, [*path, self.move_label(st.agent,
                                                                           child.action)]))
        if not self.violations and len(seen) != len(nodes):
            self.fail([], f"{len(nodes) - len(seen)} node(s) are not reachable from the root")

    def visit(self, node: PolicyNode, es: EState, path: list[str]) -> list[tuple[PolicyNode,
                                                                                 Step]]:
        """Check one node; return the children to descend into with their moves."""
        sem = self.sem
        nodes = self.policy.nodes
        where = f"node {node.id} ({node.agent or ''} {node.action})".replace("( ", "(")
        goal = sem.is_goal(es)
        self.turn[node.id] = es.turn
        bad = self.facts(node, es, goal)
        if bad:
            self.fail(path, f"{where}: recorded facts differ from the semantics: "
                      + "; ".join(bad))
            self.branches_checked += 1
            return []
        if any(c < 0 or c >= len(nodes) for c in node.children):
            self.fail(path, f"{where}: a child id is out of range")
            self.branches_checked += 1
            return []
        kids = [nodes[c] for c in node.children]
        if goal:
            if kids:
                self.fail(path, f"{where}: a goal (section 6) must be a leaf, but it has "
                          f"{len(kids)} child(ren)")
                self.branches_checked += 1
            else:
                self.goals_reached.add(node.id)
                self.branches_checked += 1
            return []
        if not kids:
            self.fail(path, f"{where}: leaf that is not a goal (section 6): "
                      + self.why_not_goal(es))
            self.branches_checked += 1
            return []
        if es.passive >= 3:
            self.fail(path, f"{where}: dead end: third passive move (wait/pass) in a row and "
                      "not a goal (section 6)")
            self.branches_checked += 1
            return []
        if es.turn == ROBOT:
            return self.robot_node(node, es, path, kids, where)
        return self.human_node(node, es, path, kids, where)

    def why_not_goal(self, es: EState) -> str:
        sem, g = self.sem, self.sem.g
        if not g.goal(es.true):
            return "the goal formula does not hold in T"
        if (FINISH, ()) not in sem.refine(g.robot, es.robot, es.true):
            return "the robot's agenda cannot finish under T"
        states = frozenset(s for s, _ in es.worlds)
        if not any(r.action == FINISH and r.states == states
                   for r in sem.hrefine(es.human, states)):
            return "the human's agenda does not certainly finish over W"
        return "in some world the robot agenda the human attributes to the robot cannot finish"

    def check_move(self, child: PolicyNode, st: Step, path: list[str]) -> bool:
        lbl = self.move_label(st.agent, st.label)
        cpath = [*path, self.move_label(st.agent, child.action)]
        where = f"node {child.id} ({lbl})"
        if child.agent != self.name(st.agent):
            self.fail(cpath, f"{where}: agent is {child.agent!r}, expected "
                      f"{self.name(st.agent)!r}")
            return False
        if child.kind != st.kind:
            self.fail(cpath, f"{where}: kind is {child.kind!r}, expected {st.kind!r}")
            return False
        want_call = self.call(st)
        if (child.name, list(child.args)) != want_call:
            self.fail(cpath, f"{where}: name and args are {child.name!r} {list(child.args)}, "
                      f"expected {want_call[0]!r} {want_call[1]}")
            return False
        if list(child.told) != list(st.told):
            self.fail(cpath, f"{where}: told is {list(child.told)}, but the move says "
                      + (f"{list(st.told)}" if st.told else "nothing")
                      + " (speech, section 5)")
            return False
        if not _same(child.cost, st.cost):
            self.fail(cpath, f"{where}: cost is {child.cost}, but the move costs "
                      f"{_num(st.cost)} under the problem's costs (section 7)")
            return False
        self.step_cost[child.id] = st.cost
        self.weight[child.id] = self.problem.objective.weight(child.action, want_call[0])
        return True

    def call(self, st: Step) -> tuple[str, list[str]]:
        """The name and arguments a policy records for a move (docs/policy-format.md)."""
        g = self.sem.g
        if st.kind == ACTION:
            op = (g.robot if st.agent == ROBOT else g.human).ops[g.task_index[st.act]]
            return op.schema, list(op.args)
        if st.kind == INFORM:
            parsed = self.sem.parse_inform(st.label)
            assert not isinstance(parsed, str)
            return INFORM, [g.atoms[i] if v else f"not {g.atoms[i]}" for i, v in parsed]
        if st.kind == ASK:
            return ASK, [st.label[len("ask("):-1]]
        return st.kind, []  # wait, pass, silence (also a wait said with an inform)

    def robot_node(self, node: PolicyNode, es: EState, path: list[str],
                   kids: list[PolicyNode], where: str) -> list[tuple[PolicyNode, Step]]:
        g = self.sem.g
        if len(kids) != 1:
            self.fail(path, f"{where}: a robot node must have exactly one child (an OR "
                      f"choice), it has {len(kids)}: {[k.action for k in kids]}")
            self.branches_checked += 1
            return []
        child = kids[0]
        cpath = [*path, self.move_label(ROBOT, child.action)]
        r = self.robot_steps(es, child.action)
        if isinstance(r, str):
            self.fail(cpath, f"node {child.id} (R {child.action}): not a legal robot option "
                      f"(section 4): {r}")
            self.branches_checked += 1
            return []
        # one action may arise from several refinements: the recorded agenda tells which
        st = next((s for s in r if s.after is not None and [g.task_names[t] for t in
                                                            s.after.robot] == child.robot_agenda),
                  r[0])
        if not self.check_move(child, st, path):
            self.branches_checked += 1
            return []
        return [(child, st)]

    def human_node(self, node: PolicyNode, es: EState, path: list[str],
                   kids: list[PolicyNode], where: str) -> list[tuple[PolicyNode, Step]]:
        g = self.sem.g
        options = self.sem.human_options(es)
        used: list[Step] = []
        out: list[tuple[PolicyNode, Step]] = []
        for child in kids:
            cpath = [*path, self.move_label(HUMAN, child.action)]
            matches = self.human_steps(es, child.action, options)
            if not matches:
                self.fail(cpath, f"node {child.id} (H {child.action}): extra human branch: "
                          f"not one of the human's options (section 4) "
                          f"{[o.label for o in options]}")
                self.branches_checked += 1
                continue
            st = next((m for m in matches if m.after is not None
                       and [g.task_names[t] for t in m.after.human] == child.human_agenda
                       and m not in used), None)
            if st is None:
                st = next((m for m in matches if m not in used), matches[0])
            if st in used:
                self.fail(cpath, f"node {child.id} (H {child.action}): duplicate human "
                          "branch: this option is already covered")
                self.branches_checked += 1
                continue
            used.append(st)
            if st.after is None:
                self.fail(cpath, f"node {child.id} (H {child.action}): the human's action is "
                          "not applicable in T: the branch fails (acting on a false belief)")
                self.branches_checked += 1
                continue
            if not self.check_move(child, st, path):
                self.branches_checked += 1
                continue
            out.append((child, st))
        for o in options:
            if o in used:
                continue
            if o.after is None:
                self.fail(path, f"{where}: dead end: the human may do {o.label}, certain over "
                          "its worlds, which fails in T (acting on a false belief)")
            else:
                self.fail(path, f"{where}: missing human branch {self.name(HUMAN)} {o.label} "
                          "(every human option is an AND branch, section 4)")
        return out

    # -- values and the summary ----------------------------------------------------------------

    def values(self) -> tuple[dict[int, Fraction | None], dict[int, Fraction | None]]:
        """§7: the worst-case and the expected cost-to-go of every node, from the validator's
        own move costs and the problem's weights; None under a violation."""
        nodes = self.policy.nodes
        worst: dict[int, Fraction | None] = {}
        mean: dict[int, Fraction | None] = {}
        order: list[int] = []
        stack, seen = [0], set()
        while stack:
            n = stack.pop()
            if n in seen or n < 0 or n >= len(nodes):
                continue
            seen.add(n)
            order.append(n)
            stack.extend(nodes[n].children)
        for n in reversed(order):
            node = nodes[n]
            worst[n] = mean[n] = None
            if not node.children:
                if n in self.goals_reached:
                    worst[n] = mean[n] = Fraction(0)
                continue
            turn = self.turn.get(n)
            if turn is None or (turn == ROBOT and len(node.children) != 1):
                continue
            parts: list[tuple[Fraction, Fraction, Fraction]] = []
            for c in node.children:
                w, m, cost = worst.get(c), mean.get(c), self.step_cost.get(c)
                if w is None or m is None or cost is None:
                    break
                parts.append((cost + w, cost + m, self.weight.get(c, Fraction(1))))
            else:
                worst[n] = max(p[0] for p in parts)
                total = sum((p[2] for p in parts), Fraction(0))
                mean[n] = sum((p[2] * p[1] for p in parts), Fraction(0)) / total
        return worst, mean

    def check_objective(self) -> None:
        """§7: the policy's objective is the problem's (kind, and weights and ties if given)."""
        got, want = self.policy.objective, self.problem.objective
        kind = got.get("kind") if isinstance(got, dict) else None
        if kind != want.kind.value:
            self.fail([], f"policy objective kind is {kind!r}, but the problem's objective is "
                      f"{want.kind.value!r} (section 7)")
            return
        weights = got.get("weights")
        if weights is not None:
            mine = {"".join(str(k).split()): v for k, v in dict(weights).items()}
            if set(mine) != set(want.weights) or any(not _same(mine[k], want.weights[k])
                                                     for k in mine):
                theirs = ", ".join(f"{k!r}: {_num(v)}" for k, v in want.weights.items())
                self.fail([], f"policy objective weights are {dict(weights)}, but the "
                          f"problem's are {{{theirs}}} (section 7)")
        ties = got.get("ties")
        if ties is not None and list(ties) != list(want.ties):
            self.fail([], f"policy objective ties are {list(ties)}, but the problem's are "
                      f"{list(want.ties)} (section 7)")

    def check_summary(self) -> None:
        pol = self.policy
        nodes = pol.nodes
        worst, mean = self.values()
        expected = self.problem.objective.kind == ObjectiveKind.EXPECTED
        val, what = (mean, "expected") if expected else (worst, "worst-case")
        paths = self.paths()
        for n in sorted(val, key=lambda i: len(paths.get(i, []))):
            v = val[n]
            if v is not None and not _same(nodes[n].value, v):
                node = nodes[n]
                who = f"{node.agent} {node.action}" if node.agent else node.action
                self.fail(paths.get(n, []), f"node {n} ({who}): value is {node.value}, but "
                          f"its {what} cost-to-go is {_num(v)} (section 7)")
        root_value = val.get(0)
        if not _same(pol.cost, nodes[0].value):
            self.fail([], f"policy cost is {pol.cost}, but the root's value is "
                      f"{nodes[0].value}")
        elif root_value is not None and not _same(pol.cost, root_value):
            self.fail([], f"policy cost is {pol.cost}, but the {what} cost is "
                      f"{_num(root_value)}")
        for name, got, want in (("worst_case", pol.worst_case, worst.get(0)),
                                ("expected", pol.expected, mean.get(0))):
            if got is not None and want is not None and not _same(got, want):
                self.fail([], f"policy {name} is {got}, but the policy's "
                          f"{name.replace('_', '-')} cost is {_num(want)} (section 7)")
        comms = sum(1 for n in nodes if n.kind in (INFORM, ASK) or n.told)
        if pol.communications != comms:
            self.fail([], f"communications is {pol.communications}, but the policy has "
                      f"{comms} inform/ask moves and moves said with an inform")
        leaves = sum(1 for n in nodes if not n.children)
        if pol.leaves != leaves:
            self.fail([], f"leaves is {pol.leaves}, but the policy has {leaves} leaves")

    def paths(self) -> dict[int, list[str]]:
        nodes = self.policy.nodes
        out: dict[int, list[str]] = {0: []}
        stack = [0]
        while stack:
            n = stack.pop()
            for c in nodes[n].children:
                if 0 <= c < len(nodes) and c not in out:
                    out[c] = [*out[n], f"{nodes[c].agent} {nodes[c].action}"]
                    stack.append(c)
        return out

    def report(self) -> Report:
        if self.violations:
            return Report(False, self.violations[0], list(self.violations), self.nodes_checked,
                          self.branches_checked)
        return Report(True, f"valid: {self.nodes_checked} nodes, {self.branches_checked} "
                      "branches checked", [], self.nodes_checked, self.branches_checked)


__all__ = ["Report", "validate"]
