"""The independent validator: replays a policy and checks it against docs/semantics.md.

Written from the semantics document, not from the planner's code, so that a planner bug shows
up as a violation instead of being copied. It uses only the model layer (grounded atoms,
operators, methods, formulas) and re-implements refinement, situation assessment, world
updates, the product of unseen robot turns and both agents' options with plain sets and loops.

Every node of the policy is recomputed from the initial state (after the fixed opening
``policy.after``) and its recorded facts, move, cost and value are compared with the
recomputation. Checking stops at the first violation of a branch; other branches go on.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TypeVar

from ..model.formula import And, Formula, StateFn, negate
from ..model.grounding import FINISH, GModel, GOp, Grounded, ground_problem
from ..model.problem import Problem
from ..policy_format import Policy, PolicyNode

ROBOT, HUMAN = 0, 1
ACTION, WAIT, PASS, INFORM, ASK, START = "action", "wait", "pass", "inform", "ask", "start"

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
    """A search node of section 3: (turn, T, robot agenda, human agenda, W, k, passive)."""

    turn: int
    true: int
    robot: Agenda
    human: Agenda
    worlds: Worlds
    k: int
    passive: int


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


@dataclass(frozen=True)
class HResult:
    """One result of refining the human's agenda over a set of world states (section 1)."""

    action: int  # FINISH when the agenda can be completed
    rest: Agenda
    states: frozenset[int]  # the worlds in which this way applies
    conds: tuple[Formula, ...]  # conditions found uncertain on the way


def validate(problem: Problem, policy: Policy) -> Report:
    """Check ``policy`` against ``problem`` (see the module docstring)."""
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
    try:
        return abs(_frac(a) - _frac(b)) < Fraction(1, 10**9)
    except TypeError:
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

    # -- section 1: refinement -----------------------------------------------------------------

    @staticmethod
    def done_of(model: GModel, t: int) -> tuple[Formula, StateFn] | None:
        """A task's done-condition: the operator's own, or the abstract task's."""
        op = model.ops.get(t)
        if op is not None:
            return (op.done_f, op.done) if op.done_f is not None and op.done is not None else None
        return model.done.get(t)

    def refine(self, model: GModel, agenda: Agenda, s: int) -> list[tuple[int, Agenda]]:
        """refine(agenda, S): (first primitive action, remaining agenda) pairs; FINISH when
        the agenda can be completed."""
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
        """The human's refinement over a set of world states: a condition holding in some
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
        """Learn T's value of each atom, in order: keep the worlds that agree; if none does,
        set the atom to T's value in every world (belief revision)."""
        ws = set(worlds)
        for i in atoms:
            bit = 1 << i
            agree = {w for w in ws if (w[0] ^ t) & bit == 0}
            ws = agree or {((s & ~bit) | (t & bit), ag) for s, ag in ws}
        return frozenset(ws)

    def sa(self, worlds: Worlds, t: int) -> Worlds:
        # step 2 of section 2 (step 1 is the special case where no revision happens)
        return self.observe(worlds, t, _bits(self.g.visible_mask(t)))

    def cop(self, t: int) -> bool:
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
        out: set[World] = set(worlds)  # the noop
        for s, tn in worlds:
            for a, rest in self.refine(self.g.robot_seen_by_human, tn, s):
                if a != FINISH:
                    out.add((self.rh_op(a).apply(s), rest))
        return frozenset(out)

    def set_inferable(self, worlds: Worlds, old: int, new: int) -> Worlds:
        m = (old ^ new) & self.g.inferable_mask
        return frozenset(((s & ~m) | (new & m), ag) for s, ag in worlds)

    def advance(self, es: EState, kind: str, true: int, robot: Agenda, human: Agenda,
                worlds: Worlds, k: int) -> EState:
        worlds = self.sa(worlds, true)
        if self.cop(true):
            k = 0
        passive = es.passive + 1 if kind in (WAIT, PASS) else 0
        return EState(1 - es.turn, true, robot, human, worlds, k, passive)

    def initial(self) -> EState:
        g = self.g
        worlds = self.sa(frozenset((s, self.attributed(ag)) for s, ag in g.beliefs), g.init)
        turn = ROBOT if self.p.starts == "robot" else HUMAN
        return EState(turn, g.init, g.robot_agenda, g.human_agenda, worlds, 0, 0)

    def action_cost(self, agent: int, op: GOp) -> Fraction:
        model = self.p.domain.robot if agent == ROBOT else self.p.domain.human
        base = model.operators[op.schema].cost
        return _frac(self.p.costs.actions.get(op.schema, base))

    def robot_actions(self, es: EState) -> list[tuple[int, Agenda]]:
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
        return Step(ROBOT, ACTION, g.task_names[a], self.action_cost(ROBOT, op), after)

    def robot_wait(self, es: EState) -> Step:
        worlds, k = es.worlds, es.k
        if not self.cop(es.true) and k < self.K:  # an unseen wait is an imagined event
            worlds, k = self.product(worlds), k + 1
        after = self.advance(es, WAIT, es.true, es.robot, es.human, worlds, k)
        return Step(ROBOT, WAIT, "wait", _frac(self.p.costs.wait), after)

    def inform(self, es: EState, atoms: Sequence[int]) -> Step:
        worlds = self.observe(es.worlds, es.true, sorted(atoms))
        after = self.advance(es, INFORM, es.true, es.robot, es.human, worlds, es.k)
        told = (self.g.atoms[i] if es.true >> i & 1 else f"not {self.g.atoms[i]}"
                for i in sorted(atoms))
        label = f"inform({', '.join(told)})"
        return Step(ROBOT, INFORM, label, _frac(self.p.costs.inform), after)

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
            if not op.pre(es.true):
                steps.append(Step(HUMAN, ACTION, g.task_names[a], cost, None))
                continue
            t2 = op.apply(es.true)
            worlds = frozenset((op.apply(s), ag) for s, ag in es.worlds)
            worlds = self.set_inferable(worlds, es.true, t2)
            after = self.advance(es, ACTION, t2, es.robot, rest, worlds, es.k)
            steps.append(Step(HUMAN, ACTION, g.task_names[a], cost, after))
        asks: list[frozenset[Formula]] = []
        if cop:
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
        after_wait = es.passive > 0  # the robot's last move was a wait
        if cop:
            may_pass = not (after_wait and certain)
            if after_wait and asks and not self.p.human.passes_when_blocked:
                may_pass = False
        else:
            may_pass = not certain
        if may_pass:
            after = self.advance(es, PASS, es.true, es.robot, es.human, es.worlds, es.k)
            steps.append(Step(HUMAN, PASS, "pass", _frac(self.p.costs.pass_), after))
        return steps

    # -- section 5: relevance of a divergence --------------------------------------------------

    def human_view(self, agenda: Agenda, states: frozenset[int]) -> frozenset[tuple[int, Agenda,
                                                                                      bool]]:
        return frozenset((r.action, r.rest, r.states == states)
                         for r in self.hrefine(agenda, states))

    def views_differ(self, es: EState, worlds: Worlds) -> tuple[bool, bool]:
        """(human's options differ, anticipated robot actions differ) between W and T."""
        states = frozenset(s for s, _ in worlds)
        human = self.human_view(es.human, states) != self.human_view(es.human,
                                                                     frozenset({es.true}))
        # the robot's options include being done (FINISH): a divergence that hides from the
        # human that the robot has finished is relevant, since the goal needs H to believe it
        expected = {a for s, tn in worlds
                    for a, _ in self.refine(self.g.robot_seen_by_human, tn, s)}
        real = {a for a, _ in self.refine(self.g.robot, es.robot, es.true)}
        return human, expected != real

    def check_inform(self, es: EState, atoms: Sequence[int]) -> str | None:
        """Why ``inform(atoms)`` is not a legal robot option here (None when it is)."""
        g = self.g
        if not self.cop(es.true):
            return "inform is offered only while co-present"
        div = 0
        for s, _ in es.worlds:
            div |= s ^ es.true
        for i in atoms:
            if not div >> i & 1:
                return (f"every world already agrees with the truth on {g.atoms[i]}: "
                        "informing the human of what it believes is never generated")
        hd, rd = self.views_differ(es, es.worlds)
        if not (hd or rd):
            return "the divergence is not relevant (the human's and the anticipated robot's " \
                   "options on W equal those on T)"
        limit = self.p.communication.inform_max_atoms
        if len(atoms) > limit:
            return f"informs {len(atoms)} atoms, more than inform_max_atoms = {limit}"
        cands = _bits(div)

        def fixes(a: Sequence[int]) -> tuple[bool, bool]:
            w2 = self.observe(es.worlds, es.true, sorted(a))
            h, r = self.views_differ(es, w2)
            return not h, not r

        both = human = None
        for n in range(1, limit + 1):
            for sub in itertools.combinations(cands, n):
                fh, fr = fixes(sub)
                if fh and human is None:
                    human = n
                if fh and fr:
                    both = n
                    break
            if both is not None:
                break
        fh, fr = fixes(atoms)
        if both is not None:
            if not (fh and fr):
                return f"it does not make the human's views equal to the truth, yet a set of " \
                       f"{both} atom(s) does"
            if len(atoms) != both:
                return f"not a smallest fixing set: {len(atoms)} atoms where {both} suffice"
            return None
        if human is None:
            return "no set of at most inform_max_atoms atoms fixes the human's options"
        if not fh:
            return "it does not fix the human's options, yet a set of " \
                   f"{human} atom(s) does"
        if len(atoms) != human:
            return f"not a smallest set fixing the human's options: {len(atoms)} atoms " \
                   f"where {human} suffice"
        return None

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

    def fail(self, path: Sequence[str], rule: str) -> None:
        self.violations.append(f"branch [{', '.join(path)}]: {rule}")

    def name(self, agent: int) -> str:
        return self.sem.names[agent]

    def move_label(self, agent: int, label: str) -> str:
        return f"{self.name(agent)} {label}"

    # -- moves ---------------------------------------------------------------------------------

    def robot_steps(self, es: EState, label: str) -> list[Step] | str:
        """The robot moves a policy label can denote here, or why it is not an option."""
        sem, g = self.sem, self.sem.g
        if label == "wait":
            return [sem.robot_wait(es)]
        if label.startswith("inform("):
            parsed = sem.parse_inform(label)
            if isinstance(parsed, str):
                return parsed
            atoms = [i for i, _ in parsed]
            if len(set(atoms)) != len(atoms):
                return "an atom is told twice"
            if not sem.cop(es.true):
                return "inform is offered only while co-present"
            for i, value in parsed:  # the label tells literals of T
                if bool(es.true >> i & 1) != value:
                    return f"the label tells {g.atoms[i]} is {str(value).lower()}, but it is " \
                           f"{str(not value).lower()} in T"
            why = sem.check_inform(es, atoms)
            return why if why is not None else [sem.inform(es, atoms)]
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
        if not _same(child.cost, st.cost):
            self.fail(cpath, f"{where}: cost is {child.cost}, but the move costs "
                      f"{_num(st.cost)} under the problem's costs (section 7)")
            return False
        self.step_cost[child.id] = st.cost
        return True

    def call(self, st: Step) -> tuple[str, list[str]]:
        """The name and arguments a policy records for a move (docs/policy-format.md)."""
        g = self.sem.g
        if st.kind == ACTION:
            op = (g.robot if st.agent == ROBOT else g.human).ops[g.task_index[st.label]]
            return op.schema, list(op.args)
        if st.kind == INFORM:
            parsed = self.sem.parse_inform(st.label)
            assert not isinstance(parsed, str)
            return INFORM, [g.atoms[i] if v else f"not {g.atoms[i]}" for i, v in parsed]
        if st.kind == ASK:
            return ASK, [st.label[len("ask("):-1]]
        return st.kind, []

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

    def values(self) -> dict[int, Fraction | None]:
        """Worst-case cost-to-go from the validator's own move costs; None under a violation."""
        nodes = self.policy.nodes
        val: dict[int, Fraction | None] = {}
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
            if not node.children:
                val[n] = Fraction(0) if n in self.goals_reached else None
                continue
            parts: list[Fraction] = []
            for c in node.children:
                v, cost = val.get(c), self.step_cost.get(c)
                if v is None or cost is None:
                    break
                parts.append(cost + v)
            else:
                val[n] = max(parts) if parts else None
                continue
            val[n] = None
        return val

    def check_summary(self) -> None:
        pol = self.policy
        nodes = pol.nodes
        val = self.values()
        paths = self.paths()
        for n in sorted(val, key=lambda i: len(paths.get(i, []))):
            v = val[n]
            if v is not None and not _same(nodes[n].value, v):
                node = nodes[n]
                self.fail(paths.get(n, []), f"node {n} ({node.agent or ''} {node.action}): "
                          f"value is {node.value}, but its worst-case cost-to-go is {_num(v)}"
                          " (section 7)")
        root_value = val.get(0)
        if not _same(pol.cost, nodes[0].value):
            self.fail([], f"policy cost is {pol.cost}, but the root's value is "
                      f"{nodes[0].value}")
        elif root_value is not None and not _same(pol.cost, root_value):
            self.fail([], f"policy cost is {pol.cost}, but the worst-case cost is "
                      f"{_num(root_value)}")
        comms = sum(1 for n in nodes if n.kind in (INFORM, ASK))
        if pol.communications != comms:
            self.fail([], f"communications is {pol.communications}, but the policy has "
                      f"{comms} inform/ask moves")
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
