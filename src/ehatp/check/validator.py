"""The independent validator: replays a policy and checks it against docs/semantics.md.

Written from the semantics document, not from the planner's code, so that a planner bug shows
up as a violation instead of being copied. It uses only the model layer (grounded atoms,
operators, methods, formulas) and re-implements refinement, situation assessment, world
updates, the product of unseen robot turns and both agents' options with plain sets and loops.

Every node of the policy is recomputed from the initial state (after the fixed opening
``policy.after``) and its recorded facts, the moves out of it, their costs and its value are
compared with the recomputation. Checking stops at the first violation of a branch; other
branches go on. The policy is a graph (docs/policy-format.md): a node reached again by another
path is not checked again, but the state recomputed along that path must equal the one of its
first visit, so the replay is linear in the policy's nodes and moves, and so are the values and
the branch counts, computed over the graph children first.

The problem's options are read as the document states them: the human's pass rule, whether
it anticipates unseen robot turns and whether the robot sees its method choices (``[human]``,
§3-§4), where and how the robot may inform, announce or ask and whether the human asks
(``[communication]``, §5), and the objective the values are under (``[objective]``, §7). Both
the worst-case and the expected value of every node are recomputed from the validator's own
move costs.

What the robot observes (§3): it sees the human's actions, never its methods, so a node holds
the set A_H of human agendas that fit what it saw, and the human's options are grouped by label
(one AND branch per label). The policy must be executable by a robot that sees only that: a
robot node has one move, a human node never two moves with the same label (that would branch
on a hidden choice), and each recorded edge leads to the node of the move it names, also when
several robot moves share a label.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import TypeVar

from ..model.formula import And, Formula, StateFn, negate
from ..model.grounding import FINISH, GMethod, GModel, GOp, Grounded, ground_problem
from ..model.options import InformWhere, Intentions, ObjectiveKind, Passes, Relevance, Speech
from ..model.problem import Problem
from ..model.vocabulary import HUMAN, ROBOT, Agent, MoveKind
from ..policy_format import Policy, PolicyMove, PolicyNode

ACTION, WAIT, PASS = MoveKind.ACTION, MoveKind.WAIT, MoveKind.PASS
INFORM, ASK = MoveKind.INFORM, MoveKind.ASK
ANSWER, ANNOUNCE = MoveKind.ANSWER, MoveKind.ANNOUNCE  # the human's answer to the robot's ask; §5
SILENCE = MoveKind.SILENCE  # the robot's silent move at a speech opening (§5)
COMMUNICATIONS = (INFORM, ASK, ANNOUNCE)  # the moves counted as communications (§5)
BLOCKED = -2  # the end of a human plan where no action applies (relevance "plan", section 5)
NOT_DONE = -3  # §5: what a blocked, unfinished robot agenda offers: "the robot is not done"
INTENTION = "ask(intention)"  # the robot's question (robot_asks, §5)


@dataclass(frozen=True)
class Block:
    """A partially ordered part of an agenda (section 1, "Partial order"): its tasks, and the
    pairs (i, j) of positions where task i comes before task j (transitively closed). Built
    only by :meth:`_Semantics.canon`, so equal task networks are equal blocks."""

    tasks: tuple[int, ...]
    before: frozenset[tuple[int, int]]

    def ready(self) -> list[int]:
        """The positions of the tasks no other task of the block comes before."""
        later = {j for _, j in self.before}
        return [i for i in range(len(self.tasks)) if i not in later]


Agenda = tuple["int | Block", ...]
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
    """One result of refining the human's agenda over a set of world states (section 1)."""

    action: int  # FINISH when the agenda can be completed
    rest: Agenda
    states: frozenset[int]  # the worlds in which this way applies
    conds: tuple[Formula, ...]  # conditions found uncertain on the way


def validate(problem: Problem, policy: Policy) -> Report:
    """Check ``policy`` against ``problem``: every rule of docs/semantics.md, sections 1-7 (see
    the module docstring)."""
    return _Validator(problem, policy).run()


def _orders_up_to_twins(run: list[int], tasks: Sequence[int], keep: list[int],
                        before: set[tuple[int, int]]) -> list[tuple[int, ...]]:
    """The orders of ``run``, one of each set that only swaps twins (same task, same tasks
    before and after it: swapping them gives the same block)."""
    def twin(i: int) -> tuple[int, frozenset[int], frozenset[int]]:
        return (tasks[i], frozenset(j for j in keep if (j, i) in before),
                frozenset(j for j in keep if (i, j) in before))

    seen: set[tuple[tuple[int, frozenset[int], frozenset[int]], ...]] = set()
    out = []
    for order in itertools.permutations(run):
        look = tuple(twin(i) for i in order)
        if look not in seen:
            seen.add(look)
            out.append(order)
    return out


def _strictly_ends(agenda: Agenda, tail: Agenda) -> bool:
    """Whether ``agenda`` is ``tail`` with something in front of it."""
    return len(agenda) > len(tail) and agenda[len(agenda) - len(tail):] == tail


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
    """``xs`` without repeats, in order (the items are hashable: a refinement can have
    100,000 results)."""
    return list(dict.fromkeys(xs))


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

    def refine(self, model: GModel, agenda: Agenda, s: int,
               around: frozenset[int] = frozenset()) -> list[tuple[int, Agenda]]:
        """§1: refine(agenda, S): (first primitive action, remaining agenda) pairs; FINISH
        when the agenda can be completed. A task met again at the front while it is being
        refined (before any action) is a loop, and that way is closed; ``around``: the tasks
        being refined around ``agenda`` (a block member's)."""
        out: list[tuple[int, Agenda]] = []

        def go(ag: Agenda, depth: int, opened: tuple[tuple[int, Agenda], ...]) -> None:
            if depth > 10_000:
                raise RecursionError("refinement does not terminate")
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
            for m in model.methods.get(t, ()):
                if m.pre(s):
                    go(self.subtasks(m) + rest, depth + 1, (*still, (t, rest)))

        go(agenda, 0, ())
        return _dedupe(out)

    def hrefine(self, agenda: Agenda, states: frozenset[int],
                conds0: tuple[Formula, ...] = (),
                around: frozenset[int] = frozenset()) -> list[HResult]:
        """§1: the human's refinement over a set of world states: a condition holding in some
        worlds only goes on in those worlds and is recorded as uncertain (``conds0``: the
        conditions already found uncertain before ``agenda``); loops are closed as in
        :meth:`refine`."""
        model = self.g.human
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
            for m in model.methods.get(t, ()):
                ok = frozenset(s for s in ws if m.pre(s))
                if ok:
                    go(self.subtasks(m) + rest, ok, conds if ok == ws else (*conds, m.pre_f),
                       depth + 1, (*still, (t, rest)))

        go(agenda, states, conds0, 0)
        return _dedupe(out)

    # -- section 1: partial order --------------------------------------------------------------

    def subtasks(self, m: GMethod) -> Agenda:
        """§1: a method's subtasks as an agenda: as listed, or (partially ordered) in canonical
        form."""
        if m.order is None:
            return m.subtasks
        pairs = {(i, j) for j, preds in enumerate(m.order) for i in _bits(preds)}
        return self.canon(list(m.subtasks), pairs)

    def canon(self, tasks: Sequence[int], before: set[tuple[int, int]]) -> Agenda:
        """§1 (Partial order): the tasks ``tasks`` under the order ``before`` (pairs of
        positions, transitively closed) as an agenda in canonical form: cut into parts, each
        wholly before the next, as small as possible; a part of one task is that task, a larger
        one a block, its tasks in the order of :meth:`member_order`."""
        out: list[int | Block] = []
        left = list(range(len(tasks)))
        while left:
            # the first part holds a task nothing precedes, and with any task in it every task
            # that does not come after it
            x = next(i for i in left if not any((j, i) in before for j in left))
            part = {x}
            todo = [x]
            while todo:
                y = todo.pop()
                for z in left:
                    if z not in part and (y, z) not in before:
                        part.add(z)
                        todo.append(z)
            keep = [i for i in left if i in part]
            if len(keep) == 1:
                out.append(tasks[keep[0]])
            else:
                order = self.member_order(tasks, before, keep)
                pos = {i: k for k, i in enumerate(order)}
                out.append(Block(tuple(tasks[i] for i in order),
                                 frozenset((pos[i], pos[j]) for i, j in before
                                           if i in pos and j in pos)))
            left = [i for i in left if i not in part]
        return tuple(out)

    def member_order(self, tasks: Sequence[int], before: set[tuple[int, int]],
                     keep: list[int]) -> list[int]:
        """§1: the order of a block's members: by task name; tasks of the same name in the
        order that makes the list, member by member, of the sorted positions of the members
        before it smallest."""
        names = self.g.task_names
        by_name: dict[str, list[int]] = {}
        for i in keep:
            by_name.setdefault(names[tasks[i]], []).append(i)
        runs = [by_name[n] for n in sorted(by_name)]
        if math.prod(math.factorial(len(r)) for r in runs) > 720:
            # too many orders to try: by rank from below, then from above; only the
            # occurrences whose ranks tie are tried in every order (section 1)
            low = self.rank(tasks, keep, lambda a, b: (a, b) in before)
            high = self.rank(tasks, keep, lambda a, b: (b, a) in before)
            split: list[list[int]] = []
            for r in runs:
                for key in sorted({(low[i], high[i]) for i in r}):
                    split.append([i for i in r if (low[i], high[i]) == key])
            runs = split
        best: tuple[list[tuple[int, ...]], list[int]] | None = None
        for choice in itertools.product(*(_orders_up_to_twins(r, tasks, keep, before)
                                          for r in runs)):
            order = [i for run in choice for i in run]
            at = {i: k for k, i in enumerate(order)}
            code = [tuple(sorted(at[j] for j in keep if (j, i) in before)) for i in order]
            if best is None or code < best[0]:
                best = (code, order)
        assert best is not None
        return best[1]

    def rank(self, tasks: Sequence[int], keep: list[int],
             below: Callable[[int, int], bool]) -> dict[int, tuple[int, int]]:
        """Section 1: each member's rank, ``below(a, b)`` saying a is under b: by the number of
        members under it, then by (its task's name, the sorted ranks of those under it)."""
        under = {i: [j for j in keep if below(j, i)] for i in keep}
        out: dict[int, tuple[int, int]] = {}
        for level in sorted({len(u) for u in under.values()}):
            members = [i for i in keep if len(under[i]) == level]
            key = {i: (self.g.task_names[tasks[i]], sorted(out[j] for j in under[i]))
                   for i in members}
            values = sorted({(k[0], tuple(k[1])) for k in key.values()})
            for i in members:
                out[i] = (level, values.index((key[i][0], tuple(key[i][1]))))
        return out

    def drop(self, b: Block, i: int) -> Agenda:
        """§1: the block once its task at position ``i`` is done."""
        def at(p: int) -> int:
            return p if p < i else p - 1

        return self.canon([t for p, t in enumerate(b.tasks) if p != i],
                          {(at(x), at(y)) for x, y in b.before if i not in (x, y)})

    def put(self, b: Block, i: int, rest: Agenda) -> Agenda:
        """§1: the block once its task at position ``i`` is refined into ``rest``: the tasks of
        ``rest`` (in its order, a block's in the block's) take its place, keep their own order,
        come after what came before it and before what came after it."""
        new: list[int] = []
        inner: set[tuple[int, int]] = set()
        for it in rest:
            base = len(new)
            if isinstance(it, Block):
                new.extend(it.tasks)
                inner |= {(base + x, base + y) for x, y in it.before}
            else:
                new.append(it)
            inner |= {(p, q) for p in range(base) for q in range(base, len(new))}
        n = len(new)

        def at(p: int) -> int:
            return p if p < i else p + n - 1

        pairs = {(i + x, i + y) for x, y in inner}
        for x, y in b.before:
            if x == i:
                pairs |= {(i + k, at(y)) for k in range(n)}
            elif y == i:
                pairs |= {(at(x), i + k) for k in range(n)}
            else:
                pairs.add((at(x), at(y)))
        tasks = [*b.tasks[:i], *new, *b.tasks[i + 1:]]
        return self.canon(tasks, pairs)

    def shown(self, agenda: Agenda) -> list[str]:
        """An agenda as the policy file writes it: tasks by name, a block in words (§1)."""
        return [self.block_text(t) if isinstance(t, Block) else self.g.task_names[t]
                for t in agenda]

    def block_text(self, b: Block) -> str:
        """§1: ``{x | y}`` for tasks in any order, ``x < y`` for one before the other, nested;
        an order that is neither as ``{a | b | c | d; a < c, b < c, b < d}``."""
        names = self.g.task_names

        def linked(i: int, j: int) -> bool:
            return (i, j) in b.before or (j, i) in b.before

        def par(ps: list[int]) -> str:
            groups: list[list[int]] = []
            for p in ps:
                if any(linked(p, q) for g in groups for q in g):
                    touching = [g for g in groups if any(linked(p, q) for q in g)]
                    merged = sorted([p, *(q for g in touching for q in g)])
                    groups = [g for g in groups if g not in touching] + [merged]
                else:
                    groups.append([p])
            groups.sort(key=lambda g: g[0])
            if len(groups) == 1:
                return ser(ps)
            return "{" + " | ".join(ser(g) for g in groups) + "}"

        def ser(ps: list[int]) -> str:
            if len(ps) == 1:
                return names[b.tasks[ps[0]]]
            parts = [[p for p in ps if p in part] for part in self._cuts(b, ps)]
            if len(parts) > 1:
                return " < ".join(par(part) for part in parts)
            pairs = [f"{names[b.tasks[p]]} < {names[b.tasks[q]]}" for p in ps for q in ps
                     if (p, q) in b.before
                     and not any((p, r) in b.before and (r, q) in b.before for r in ps)]
            return "{" + " | ".join(names[b.tasks[p]] for p in ps) + "; " + ", ".join(pairs) + "}"

        return par(list(range(len(b.tasks))))

    @staticmethod
    def _cuts(b: Block, ps: list[int]) -> list[set[int]]:
        """The positions ``ps`` of ``b`` cut into parts each wholly before the next."""
        out: list[set[int]] = []
        left = list(ps)
        while left:
            x = next(i for i in left if not any((j, i) in b.before for j in left))
            part = {x}
            todo = [x]
            while todo:
                y = todo.pop()
                for z in left:
                    if z not in part and (y, z) not in b.before:
                        part.add(z)
                        todo.append(z)
            out.append(part)
            left = [i for i in left if i not in part]
        return out

    # -- section 2: observation ----------------------------------------------------------------

    def unit(self, i: int) -> int:
        """§2: the unit atom ``i`` belongs to, as a mask: the atom itself, or every atom of
        its state variable (one per value) or of its counter (one per bit)."""
        return self.g.unit_of.get(i, 1 << i)

    def units(self, m: int) -> list[int]:
        """§2, §5: the units the atoms of ``m`` belong to, in index order."""
        out: list[int] = []
        for i in _bits(m):
            u = self.unit(i)
            if u not in out:
                out.append(u)
        return out

    def is_variable(self, u: int) -> bool:
        """§2: whether the unit ``u`` is a state variable (one atom per value)."""
        return u in self.g.unit_names and u not in self.g.counter_max

    def say(self, t: int, u: int) -> str:
        """§5: unit ``u`` as ``t`` has it: ``a`` or ``not a`` for an atom, ``loc(r) = mt`` for
        a state variable, ``balls(b1) = 2`` for a counter."""
        g = self.g
        low = _bits(u)[0]
        if u in g.counter_max:
            return f"{g.unit_names[u]} = {(t & u) >> low}"
        if u in g.unit_names:
            return g.atoms[_bits(t & u)[0]]
        return g.atoms[low] if t >> low & 1 else f"not {g.atoms[low]}"

    def unit_name(self, u: int) -> str:
        """§5: the name informing sets are ranked by: the atom, or ``loc(r)``."""
        return self.g.unit_names.get(u) or self.g.atoms[_bits(u)[0]]

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

    def tell(self, worlds: Worlds, t: int, units: Iterable[int]) -> Worlds:
        """§5: the human learns T's value of every unit (an atom, a variable, a counter)."""
        return self.observe(worlds, t, [i for u in sorted(units) for i in _bits(u)])

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

        def knows(x: int) -> bool:  # an operator, a method or a done-condition for it
            return x in m.ops or bool(m.methods.get(x)) or x in m.done

        out: list[int | Block] = []
        for t in agenda:
            if isinstance(t, Block):  # a block keeps the tasks M_R^H knows (section 1)
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
            for a, rest in self.refine(self.g.robot_seen_by_human, tn, s):
                if a != FINISH:
                    out.add((self.rh_op(a).apply(s), rest))
        return frozenset(out)

    def set_inferable(self, worlds: Worlds, old: int, new: int) -> Worlds:
        """§4: the inferable atoms an action changed in T are set in every world (a state
        variable or a counter whole)."""
        m = 0
        for u in self.units(old ^ new):
            m |= u
        m &= self.g.inferable_mask
        return frozenset(((s & ~m) | (new & m), ag) for s, ag in worlds)

    def sees_robot_done(self, worlds: Worlds, true: int, robot: Agenda) -> Worlds:
        """§4, non-anticipating human: whenever co-present in T (the initial one included)
        with a robot agenda that can finish under T, it knows the robot is done (every world's
        robot agenda is empty)."""
        if (self.p.human.anticipates or not self.cop(true)
                or (FINISH, ()) not in self.refine(self.g.robot, robot, true)):
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
        """§1-§3 and §5: the initial node; a robot opening turn when the human starts, the
        robot may speak while acting and an informing set exists in the initial state."""
        g = self.g
        worlds = self.sa(frozenset((s, self.attributed(ag)) for s, ag in g.beliefs), g.init)
        # a non-anticipating human sees a robot with nothing left to do from the start, as
        # situation assessment runs on the initial state too ("whenever", section 4)
        worlds = self.sees_robot_done(worlds, g.init, g.robot_agenda)
        turn = ROBOT if self.p.starts == "robot" else HUMAN
        es = EState(turn, g.init, g.robot_agenda, frozenset({g.human_agenda}), worlds, 0, 0)
        if turn == HUMAN and self.p.communication.speech == Speech.WITH_ACTION:
            opening = replace(es, turn=ROBOT, opening=True)
            if not isinstance(self.inform_found(opening), str):
                return opening
        return es

    def action_cost(self, agent: Agent, op: GOp) -> Fraction:
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

    def silence(self, es: EState) -> Step:
        """§5: the robot's silent move at a speech opening (cost 0, no effect)."""
        after = self.advance(es, SILENCE, es.true, es.robot, es.humans, es.worlds, es.k)
        return Step(ROBOT, SILENCE, "silence", Fraction(0), after)

    def literals(self, t: int, units: Iterable[int]) -> tuple[str, ...]:
        return tuple(self.say(t, u) for u in units)

    def inform(self, es: EState, units: Sequence[int]) -> Step:
        """§5: ``inform(A)``: the human learns T's value of every unit of A (an atom, a state
        variable, a counter), nothing else is witnessed (k unchanged, no world multiplied,
        also while apart)."""
        worlds = self.tell(es.worlds, es.true, units)
        after = self.advance(es, INFORM, es.true, es.robot, es.humans, worlds, es.k)
        label = f"inform({', '.join(self.literals(es.true, sorted(units)))})"
        return Step(ROBOT, INFORM, label, _frac(self.p.costs.inform), after)

    def with_speech(self, units: Sequence[int], st: Step) -> Step:
        """§5: ``inform(A) + a``: said with the action (or wait) ``st`` and judged on the node
        it leads to: the human learns the values A has in the true state after ``st`` (T'), in
        its worlds after ``st``; the costs add up."""
        assert st.after is not None
        after = st.after
        told = self.literals(after.true, units)
        label = f"inform({', '.join(told)}) + {st.act}"
        heard = replace(after, worlds=self.tell(after.worlds, after.true, units))
        return Step(ROBOT, st.kind, label, _frac(self.p.costs.inform) + st.cost, heard,
                    act=st.act, told=told)

    def talk_where(self, es: EState, what: str) -> str | None:
        """§5: why the robot may not talk (``what``: inform, ask, announce) here for where the
        agents are (None if it may): while co-present, or anywhere under ``inform =
        "anywhere"``."""
        if self.cop(es.true) or self.p.communication.inform == InformWhere.ANYWHERE:
            return None
        return f"{what} is offered only while co-present"

    def robot_ask(self, es: EState) -> Step | str:
        """§5 (``robot_asks``): the robot asks the human what it is about to do, when more than
        one human agenda fits what it saw; the human answers at once (an answering node: same
        T, W, robot agenda and k, no passive move)."""
        if not self.p.communication.robot_asks:
            return "the robot asks the human's intention only under [communication] " \
                   "robot_asks = true (§5)"
        if len(es.humans) < 2:
            return "only one human agenda fits what the robot saw: there is nothing to ask (§5)"
        why = self.talk_where(es, "asking")
        if why is not None:
            return why
        after = replace(es, turn=HUMAN, passive=0, forced=False, answering=True)
        return Step(ROBOT, ASK, INTENTION, _frac(self.p.costs.ask), after)

    def answers(self, es: EState) -> list[Step]:
        """§5: at an answering node the human tells which agenda it follows (cost 0, no turn
        spent): then it is the human's turn, with that one agenda."""
        out = []
        for h in self.ordered(es.humans):
            after = replace(es, answering=False, humans=frozenset({h}))
            out.append(Step(HUMAN, ANSWER, f"answer({', '.join(self.shown(h))})", Fraction(0),
                            after))
        return out

    def announce(self, es: EState) -> Step | str:
        """§5 (``announce``): the robot tells its own agenda: the worlds whose attributed robot
        agenda is the announced one stay; if none, every world's agenda becomes it. Offered
        where the robot options the human expects differ from the robot's real ones (read per
        world) and the announcement changes the worlds."""
        if not self.p.communication.announce:
            return "the robot announces its agenda only under [communication] announce = " \
                   "true (§5)"
        why = self.talk_where(es, "announce")
        if why is not None:
            return why
        if self.robot_view(es.worlds) == self.true_robot_view(es):
            return "the robot options the human expects equal the robot's real ones: the " \
                   "divergence is not relevant (§5)"
        mine = self.attributed(es.robot)
        worlds = frozenset(w for w in es.worlds if w[1] == mine)
        if not worlds:
            worlds = frozenset((s, mine) for s, _ in es.worlds)
        if worlds == es.worlds:
            return "announcing changes none of the human's worlds (§5)"
        after = self.advance(es, ANNOUNCE, es.true, es.robot, es.humans, worlds, es.k)
        label = f"announce({', '.join(self.shown(es.robot))})"
        return Step(ROBOT, ANNOUNCE, label, _frac(self.p.costs.inform), after)

    def ordered(self, humans: Iterable[Agenda]) -> list[Agenda]:
        """The human agendas in the order of their names (a fixed order to go through A_H)."""
        return sorted(humans, key=self.shown)

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
        """§4 (Human): the options of every hypothesis of A_H (certain actions, asks while
        co-present unless ``[communication] ask = false``, pass by the pass rule), grouped by
        label (§3-§4): one branch per action label, whose node keeps every way any hypothesis
        goes on after it; one per question, and one pass, keeping the hypotheses that had it.
        Under ``intentions = "visible"`` one branch per refinement, labels that would repeat
        at the node naming the intention: ``grab(c1) [place_l(c1)]``. At an answering node,
        the answers (§5)."""
        if es.answering:
            return self.answers(es)
        g = self.g
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
        g = self.g
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

    def robot_view(self, worlds: Worlds) -> frozenset[int]:
        """§5: the robot options the human expects, read per world: the first actions of the
        attributed agenda under each world's state with M_R^H (FINISH when it can finish); a
        world whose agenda is unfinished and offers no option contributes NOT_DONE."""
        out: set[int] = set()
        for s, tn in worlds:
            ops = {a for a, _ in self.refine(self.g.robot_seen_by_human, tn, s)}
            out |= ops or {NOT_DONE}
        return frozenset(out)

    def true_robot_view(self, es: EState) -> frozenset[int]:
        """§5: the robot's real options: the first actions of its agenda under T with M_R
        (FINISH when it can finish), or NOT_DONE when it is unfinished and blocked."""
        ops = frozenset(a for a, _ in self.refine(self.g.robot, es.robot, es.true))
        return ops or frozenset({NOT_DONE})

    def views_differ(self, es: EState, worlds: Worlds, plan: bool) -> tuple[bool, bool, bool]:
        """(human's options differ, anticipated robot options differ, human plans differ)
        between W and T, the human's for some hypothesis of A_H (§5); the third only when
        ``plan`` (relevance "plan")."""
        states = frozenset(s for s, _ in worlds)
        truth = frozenset({es.true})
        human = any(self.human_view(h, states) != self.human_view(h, truth) for h in es.humans)
        # the robot's options include being done (FINISH): a divergence that hides from the
        # human that the robot has finished is relevant, since the goal needs H to believe it
        robot = self.robot_view(worlds) != self.true_robot_view(es)
        plans = plan and any(self.plans(h, s) != self.plans(h, es.true)
                             for h in es.humans for s in states)
        return human, robot, plans

    def inform_where(self, es: EState) -> str | None:
        """§5: why no ``inform`` may be offered here for where the agents are (None if it
        may). Under ``inform = "anywhere"`` an inform is heard while apart even at k = K: it
        is no robot turn the human imagines (no world multiplied, k unchanged), so the K bound
        of section 4, which limits what the robot does unseen, does not apply to it."""
        return self.talk_where(es, "inform")

    def inform_found(self, es: EState) -> list[tuple[str, int, list[tuple[int, ...]], bool]] | str:
        """§5: the informing searches that find sets here, or why no ``inform`` is offered.
        Under relevance "plan", the sets fixing the plans and, beside them, the sets that fix
        the next step as under "next": "plan" never offers less than "next"."""
        plan = self.p.communication.relevance == Relevance.PLAN
        first = self.inform_search(es, plan)
        found = [] if isinstance(first, str) else [(*first, plan)]
        if plan:
            nxt = self.inform_search(es, False)
            if not isinstance(nxt, str):
                found.append((*nxt, False))
        if not found:
            assert isinstance(first, str)
            return first
        return found

    def inform_search(self, es: EState, plan: bool
                      ) -> tuple[str, int, list[tuple[int, ...]]] | str:
        """§5: the informing sets of one relevance reading (``plan``: relevance "plan", else
        "next"): (what they fix, their size, every smallest set that fixes it, in canonical
        order), or why no such ``inform`` is offered.

        Sets fixing the human's options, the anticipated robot options (and, under relevance
        "plan", the plans) come first; failing those, sets fixing the human's options (and the
        plans) -- only when those differ: a set cannot fix what is not broken, and telling the
        human something that changes none of its options is not worth a move."""
        why = self.inform_where(es)
        if why is not None:
            return why
        now = self.views_differ(es, es.worlds, plan)
        if not any(now):
            return ("the divergence is not relevant (the human's and the anticipated robot's "
                    "options" + (" and the human's plans" if plan else "") +
                    " on W equal those on T)")
        div = 0
        for s, _ in es.worlds:
            div |= s ^ es.true
        cands = self.units(div)  # an atom, or a state variable or counter told whole
        limit = self.p.communication.inform_max_atoms
        fixed: dict[tuple[int, ...], tuple[bool, bool, bool]] = {}
        for n in range(1, limit + 1):
            for sub in itertools.combinations(cands, n):
                h, r, p = self.views_differ(es, self.tell(es.worlds, es.true, sub), plan)
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
        """§5: why ``inform(atoms)`` (units, as masks) is not a legal robot option here (None
        when it is): it must be the set one of the informing searches chooses."""
        why = self.inform_where(es)
        if why is not None:
            return why
        div = 0
        for s, _ in es.worlds:
            div |= s ^ es.true
        for u in atoms:
            if not div & u:
                return (f"every world already agrees with the truth on {self.unit_name(u)}: "
                        "informing the human of what it believes is never generated")
        limit = self.p.communication.inform_max_atoms
        found = self.inform_found(es)
        if isinstance(found, str):
            return found
        if len(atoms) > limit:
            return f"informs {len(atoms)} atoms, more than inform_max_atoms = {limit}"
        mine = tuple(sorted(atoms))
        choices = [self.check_choice(es, mine, sets) for _, _, sets, _ in found if mine in sets]
        if choices:
            return None if None in choices else choices[0]
        what, n, _, plan = found[0]
        h, r, p = self.views_differ(es, self.tell(es.worlds, es.true, mine), plan)
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
            left = len(self.tell(es.worlds, es.true, a))
            told_true = sum(1 for u in a if es.true & u or u in self.g.unit_names)  # a value
            return left, -told_true, tuple(self.unit_name(u) for u in a)

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
        if not all(self.human_done(h, es.worlds) for h in es.humans):
            return False  # §6: every hypothesis finished, or the robot cannot know it done
        return all((FINISH, ()) in self.refine(g.robot_seen_by_human, tn, s)
                   for s, tn in es.worlds)

    def human_done(self, agenda: Agenda, worlds: Worlds) -> bool:
        """§6: the human's agenda finishes in every world (H believes its task done)."""
        states = frozenset(s for s, _ in worlds)
        return any(r.action == FINISH and r.states == states
                   for r in self.hrefine(agenda, states))

    # -- reading labels ------------------------------------------------------------------------

    def parse_inform(self, label: str) -> list[tuple[int, str]] | str:
        """``inform(a, not b(x, y), loc(r) = mt, balls(b1) = 2)`` -> (unit, literal as
        written) pairs: an atom told true or false, a state variable's or counter's value."""
        inner = label[len("inform("):-1] if label.startswith("inform(") and label.endswith(
            ")") else None
        if not inner:
            return f"cannot read {label!r} as inform(atom, ...)"
        g = self.g
        valued = {name: u for u, name in g.unit_names.items()}
        out: list[tuple[int, str]] = []
        buf = ""
        for tok in inner.split(", "):  # atoms contain ", " too: grow until one is known
            buf = f"{buf}, {tok}" if buf else tok
            head, eq_, value = buf.rpartition(" = ")
            u = valued.get(head) if eq_ else None
            if u is not None:
                top = g.counter_max.get(u)
                if (buf in self.atom_of and self.unit(self.atom_of[buf]) == u if top is None
                        else value.isdigit() and int(value) <= top):
                    out.append((u, buf))
                    buf = ""
                continue
            neg = buf.startswith("not ")
            name = buf[4:] if neg else buf
            i = self.atom_of.get(name)
            if i is not None and self.unit(i) == 1 << i:
                out.append((1 << i, buf))
                buf = ""
        if buf or not out:
            return f"cannot read {label!r}: {buf!r} is not a fluent atom or a value"
        return out


def _differences(a: EState, b: EState, sem: _Semantics) -> str:
    """What tells two states of section 3 apart, in the domain's words."""
    g = sem.g
    out = []
    if a.turn != b.turn:
        out.append(f"{sem.names[a.turn]} moved next then, {sem.names[b.turn]} now")
    if a.true != b.true:
        out.append("the true state T differs on " + ", ".join(g.mask_atoms(a.true ^ b.true)))
    if a.robot != b.robot:
        out.append(f"the robot agenda is {sem.shown(a.robot)} then, {sem.shown(b.robot)} now")
    if a.humans != b.humans:
        out.append(f"the human agendas are {[sem.shown(h) for h in sem.ordered(a.humans)]} "
                   f"then, {[sem.shown(h) for h in sem.ordered(b.humans)]} now")
    if a.worlds != b.worlds:
        out.append(f"the human's worlds differ ({len(a.worlds)} then, {len(b.worlds)} now)")
    for what, i, j in (("k", a.k, b.k), ("the passive count", a.passive, b.passive)):
        if i != j:
            out.append(f"{what} is {i} then, {j} now")
    if a.forced != b.forced:
        out.append("the robot's last wait was forced on one path only (section 4)")
    if a.opening != b.opening:
        out.append("it is the speech opening on one path only (section 5)")
    if a.answering != b.answering:
        out.append("the human answers the robot's question on one path only (§5)")
    return "; ".join(out)


def _ask_matches(step: Step, label: str) -> bool:
    if step.label == label:
        return True
    if len(step.texts) > 7:
        return False
    return any(f"ask({' and '.join(p)})" == label for p in itertools.permutations(step.texts))


@dataclass
class _Item:
    """A node to check: the state the replay reached it in, the path there, the move into it."""

    node: PolicyNode
    es: EState
    path: list[str]
    move: PolicyMove | None


class _Validator:
    def __init__(self, problem: Problem, policy: Policy) -> None:
        self.problem = problem
        self.policy = policy
        self.sem = _Semantics(problem)
        self.violations: list[str] = []
        self.nodes_checked = 0
        self.goals_reached: set[int] = set()  # goal leaves whose branch checked out
        # (node id, move index) -> the move's cost and weight (section 7), for checked moves
        self.step_cost: dict[tuple[int, int], Fraction] = {}
        self.weight: dict[tuple[int, int], Fraction] = {}
        self.turn: dict[int, int] = {}  # node id -> who moves next there (checked nodes)
        # the DAG walk: the state each node was first reached in, and by which path
        self.first: dict[int, EState] = {}
        self.path_of: dict[int, list[str]] = {}
        # branches checked, counted over the graph: where a branch's check ends at a node,
        # and the children a node's branches go on into
        self.ends: dict[int, int] = {}
        self.goes_on: dict[int, list[int]] = {}

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
            if act.startswith(("inform(", "ask(", "announce(")) or act == SILENCE:
                return f"{act} cannot be said with an inform; only an action or wait can"
            steps = self.robot_steps(es, act)
            if isinstance(steps, str):
                return steps
            # §5: what is said with a move is judged on the node the move leads to (the
            # human's next decision), with the values of the true state after it
            out: list[Step] = []
            why = ""
            for st in steps:
                assert st.after is not None  # robot moves never fail
                r = self.inform_atoms(st.after, said, f" after {act} (§5, with-action)")
                if isinstance(r, str):
                    why = why or r
                else:
                    out.append(sem.with_speech(r, st))
            return out or why
        if label == "wait":
            return [sem.robot_wait(es)]
        if label.startswith("inform("):
            r = self.inform_atoms(es, label)
            return r if isinstance(r, str) else [sem.inform(es, r)]
        if label == INTENTION:
            asked = sem.robot_ask(es)
            return asked if isinstance(asked, str) else [asked]
        if label.startswith("announce("):
            want = f"announce({', '.join(sem.shown(es.robot))})"
            if label != want:
                return f"the robot may announce only its own agenda, {want} (§5)"
            said_it = sem.announce(es)
            return said_it if isinstance(said_it, str) else [said_it]
        if label == "pass" or label.startswith(("ask(", "answer(")):
            return f"{label} is not a robot move"
        opts = [(a, r) for a, r in sem.robot_actions(es) if g.task_names[a] == label]
        if opts:
            return [sem.robot_act(es, a, r) for a, r in opts]
        if not (sem.cop(es.true) or es.k < sem.K):
            return f"the agents are apart and k = K = {sem.K}: only wait is allowed"
        tid = g.task_index.get(label)
        op = g.robot.ops.get(tid) if tid is not None else None
        if op is None:
            if label.partition("(")[0] in self.problem.domain.robot.operators:
                return (f"{label} is not applicable in T (nor anywhere: no refinement of "
                        f"{self.name(ROBOT)}'s agenda reaches it)")
            return f"{label} is not an action of {self.name(ROBOT)}"
        if not op.pre(es.true):
            return f"{label} is not applicable in T (its precondition does not hold)"
        agenda = sem.shown(es.robot)
        return f"{label} is not the first action of any refinement of the robot agenda " \
               f"{agenda} under T"

    def inform_atoms(self, es: EState, label: str, when: str = "") -> list[int] | str:
        """The units of ``inform(...)`` (atoms, state variables, counters, as masks) in label
        order, if it is a legal inform at ``es`` (§5; ``when`` says which state the label's
        values are read in, in messages: T, or T after the action it is said with)."""
        sem = self.sem
        parsed = sem.parse_inform(label)
        if isinstance(parsed, str):
            return parsed
        units = [u for u, _ in parsed]
        if len(set(units)) != len(units):
            return "an atom is told twice"
        why = sem.inform_where(es)
        if why is not None:
            return why
        for u, said in parsed:  # the label tells literals (values) of T
            truth = sem.say(es.true, u)
            if said != truth:
                if u in sem.g.unit_names:
                    return f"the label tells {said}, but T has {truth}{when}"
                value = not said.startswith("not ")
                name = said[4:] if not value else said
                return f"the label tells {name} is {str(value).lower()}, but it is " \
                       f"{str(not value).lower()} in T{when}"
        why = sem.check_inform(es, units)
        return units if why is None else why + when

    def human_steps(self, es: EState, label: str,
                    options: list[Step] | None = None) -> list[Step]:
        """The human option a label denotes (§4: labels are unique at a node; a question
        matches in any order of its conjuncts)."""
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
        cmp("robot_agenda", list(node.robot_agenda), sem.shown(es.robot))
        want_h = sorted(sem.shown(h) for h in es.humans)
        got_h = sorted(list(h) for h in node.human_agendas)
        if len(want_h) == 1 and len(got_h) == 1:
            cmp("human_agenda", list(node.human_agenda), want_h[0])
        elif got_h != want_h:
            bad.append(f"hypotheses (the human agendas the robot cannot tell apart, §3) are "
                       f"{got_h}, expected {want_h}")
        if len(node.hypotheses) > 1 and list(node.human_agenda) != list(node.hypotheses[0]):
            bad.append(f"human_agenda is {list(node.human_agenda)}, but a node with hypotheses "
                       f"records the first of them, {list(node.hypotheses[0])}")
        cmp("copresent", node.copresent, sem.cop(es.true))
        cmp("k", node.k, es.k)
        cmp("worlds", node.worlds, len(es.worlds))
        cmp("to_move", node.to_move, None if goal else self.name(es.turn))
        if (node.id == 0 and not self.policy.after and es.turn == HUMAN and not goal
                and node.to_move == self.name(ROBOT)
                and self.problem.communication.speech == Speech.WITH_ACTION):
            why = sem.inform_found(replace(es, turn=ROBOT, opening=True))
            if isinstance(why, str):  # the robot may not open: say why (section 5)
                bad.append(f"no speech opening, since no informing set exists in the initial "
                           f"state: {why}")
        cmp("goal", node.goal, goal)
        div = 0
        diffs = []
        t = es.true
        for s in {s for s, _ in es.worlds}:
            div |= s ^ t
            # atoms true in the world only, and true in T only; a counter by its values
            counters = [u for u in sem.units(s ^ t) if u in g.counter_max]
            plain = s ^ t
            for u in counters:
                plain &= ~u
            diffs.append((frozenset([*g.mask_atoms(s & plain), *(sem.say(s, u) for u in counters)]),
                          frozenset([*g.mask_atoms(t & plain),
                                     *(sem.say(t, u) for u in counters)])))
        want_div = {sem.say(t, u) for u in sem.units(div)}
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
                    base, bracket, names = label.rstrip().rpartition(" [")
                    if isinstance(r, str) and bracket and names.endswith("]"):
                        # §4: "fetch [shelve]" names the move by the agenda it leaves
                        r = self.robot_steps(es, base)
                        if not isinstance(r, str):
                            left = "".join(names[:-1].split())
                            r = [st for st in r if st.after is not None and "".join(
                                ",".join(sem.shown(st.after.robot)).split()) == left]
                    if isinstance(r, str):
                        why = r
                        continue
                    steps = r
                else:
                    steps = self.human_steps(es, label)
                    if not steps and label.strip() == PASS and es.forced:
                        # §4: a pass the fairness rule need not cover may still have happened
                        steps = self.human_steps(replace(es, forced=False), label)
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
        found = self.order()
        order = found if isinstance(found, list) else None
        if root_es is not None:
            self.walk(root_es)
        if order is None:
            self.fail([], f"node {found} is its own descendant: the policy has a cycle "
                      "(section 7: policies are acyclic)")
        elif len(order) != len(nodes):
            self.fail([], f"{len(nodes) - len(order)} node(s) are not reachable from the root")
        self.check_summary(order)
        return self.report(order)

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

    def order(self) -> list[int] | int:
        """The nodes reachable from the root, children before parents, or a node on a cycle
        of moves (a policy is acyclic, section 7)."""
        nodes = self.policy.nodes
        state: dict[int, int] = {0: 1}  # 1: on the stack, 2: done
        post: list[int] = []
        stack = [(0, 0)]
        while stack:
            i, j = stack[-1]
            kids = [c for c in nodes[i].children if 0 <= c < len(nodes)]
            if j == len(kids):
                stack.pop()
                state[i] = 2
                post.append(i)
                continue
            stack[-1] = (i, j + 1)
            c = kids[j]
            if state.get(c) == 1:
                return c
            if c not in state:
                state[c] = 1
                stack.append((c, 0))
        return post

    def walk(self, root_es: EState) -> None:
        """Replay the policy depth-first from the root. A node reached again by another path
        is not checked again: the state recomputed along the new path must equal the one of
        its first visit (then everything below follows as before), so the walk is linear in
        the policy's nodes and moves however many branches share them."""
        nodes = self.policy.nodes
        self.first[0], self.path_of[0] = root_es, []
        stack = [_Item(nodes[0], root_es, [], None)]
        while stack:
            it = stack.pop()
            node = it.node
            self.nodes_checked += 1
            kids_ok = self.visit(node, it.es, it.path, it.move)
            goes_on = self.goes_on.setdefault(node.id, [])
            for j, st in reversed(kids_ok):
                assert st.after is not None
                move = node.moves[j]
                child = nodes[move.to]
                path = [*it.path, self.move_label(st.agent, move.action)]
                seen = self.first.get(child.id)
                if seen is None:
                    self.first[child.id], self.path_of[child.id] = st.after, path
                    stack.append(_Item(child, st.after, path, move))
                elif seen != st.after:
                    self.fail(path, f"node {child.id} is shared, but this path reaches it in "
                              "another state than its first one (by "
                              f"[{', '.join(self.path_of[child.id])}]): "
                              + _differences(seen, st.after, self.sem))
                    self.end(node.id)
                    continue
                goes_on.append(child.id)

    def end(self, node: int) -> None:
        """One branch's check ends at ``node`` (a leaf, or at a violation)."""
        self.ends[node] = self.ends.get(node, 0) + 1

    def branches_checked(self, order: list[int] | None) -> int:
        """Branches checked, each to its end or its first violation, counted over the graph
        (a node's count is the sum of its children's, plus the branches ending there)."""
        if order is None:
            return sum(self.ends.values())
        count: dict[int, int] = {}
        for n in order:  # children first
            count[n] = self.ends.get(n, 0) + sum(count.get(c, 0)
                                                 for c in self.goes_on.get(n, []))
        return count.get(0, 0)

    def visit(self, node: PolicyNode, es: EState, path: list[str],
              move: PolicyMove | None) -> list[tuple[int, Step]]:
        """Check one node reached by ``move``; return the moves to follow (by index) with the
        steps the semantics gives for them."""
        sem = self.sem
        nodes = self.policy.nodes
        where = (f"node {node.id} (start)" if move is None
                 else f"node {node.id} ({move.agent} {move.action})")
        goal = sem.is_goal(es)
        self.turn[node.id] = es.turn
        bad = self.facts(node, es, goal)
        if bad:
            self.fail(path, f"{where}: recorded facts differ from the semantics: "
                      + "; ".join(bad))
            self.end(node.id)
            return []
        if any(c < 0 or c >= len(nodes) for c in node.children):
            self.fail(path, f"{where}: a move leads to a node id out of range")
            self.end(node.id)
            return []
        if goal:
            if node.moves:
                self.fail(path, f"{where}: a goal (section 6) must be a leaf, but it has "
                          f"{len(node.moves)} move(s)")
            else:
                self.goals_reached.add(node.id)
            self.end(node.id)
            return []
        if not node.moves:
            self.fail(path, f"{where}: leaf that is not a goal (section 6): "
                      + self.why_not_goal(es))
            self.end(node.id)
            return []
        if es.passive >= 3:
            self.fail(path, f"{where}: dead end: third passive move (wait/pass) in a row and "
                      "not a goal (section 6)")
            self.end(node.id)
            return []
        if es.turn == ROBOT:
            return self.robot_node(node, es, path, where)
        return self.human_node(node, es, path, where)

    def why_not_goal(self, es: EState) -> str:
        sem, g = self.sem, self.sem.g
        if not g.goal(es.true):
            return "the goal formula does not hold in T"
        if (FINISH, ()) not in sem.refine(g.robot, es.robot, es.true):
            return "the robot's agenda cannot finish under T"
        for h in sem.ordered(es.humans):
            if not sem.human_done(h, es.worlds):
                which = f" {sem.shown(h)}" if len(es.humans) > 1 else ""
                return f"the human's agenda{which} does not certainly finish over W"
        return "in some world the robot agenda the human attributes to the robot cannot finish"

    def check_move(self, node: PolicyNode, j: int, st: Step, path: list[str]) -> bool:
        """The recorded move ``node.moves[j]`` is the move ``st`` of the semantics: agent,
        kind, name and arguments, what was said with it, and cost (sections 4, 5, 7)."""
        move = node.moves[j]
        child = self.policy.nodes[move.to]
        lbl = self.move_label(st.agent, st.label)
        cpath = [*path, self.move_label(st.agent, move.action)]
        where = f"node {child.id} ({lbl})"
        if move.agent != self.name(st.agent):
            self.fail(cpath, f"{where}: agent is {move.agent!r}, expected "
                      f"{self.name(st.agent)!r}")
            return False
        if move.kind != st.kind:
            self.fail(cpath, f"{where}: kind is {move.kind!r}, expected {str(st.kind)!r}")
            return False
        want_call = self.call(st)
        if (move.name, list(move.args)) != want_call:
            self.fail(cpath, f"{where}: name and args are {move.name!r} {list(move.args)}, "
                      f"expected {str(want_call[0])!r} {want_call[1]}")
            return False
        if list(move.told) != list(st.told):
            self.fail(cpath, f"{where}: told is {list(move.told)}, but the move says "
                      + (f"{list(st.told)}" if st.told else "nothing")
                      + " (speech, section 5)")
            return False
        if not _same(move.cost, st.cost):
            self.fail(cpath, f"{where}: cost is {move.cost}, but the move costs "
                      f"{_num(st.cost)} under the problem's costs (section 7)")
            return False
        self.step_cost[node.id, j] = st.cost
        self.weight[node.id, j] = self.problem.objective.weight(move.action, want_call[0])
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
            return INFORM, [said for _, said in parsed]
        if st.kind == ASK:
            return ASK, [st.label[len("ask("):-1]]
        # wait, pass, silence (also a wait said with an inform), answer, announce
        return st.kind, []

    def robot_node(self, node: PolicyNode, es: EState, path: list[str],
                   where: str) -> list[tuple[int, Step]]:
        if len(node.moves) != 1:
            self.fail(path, f"{where}: a robot node must have exactly one move (its child: "
                      f"an OR choice), it has {len(node.moves)}: "
                      f"{[m.action for m in node.moves]}")
            self.end(node.id)
            return []
        move = node.moves[0]
        child = self.policy.nodes[move.to]
        cpath = [*path, self.move_label(ROBOT, move.action)]
        r = self.robot_steps(es, move.action)
        if isinstance(r, str):
            self.fail(cpath, f"node {child.id} (R {move.action}): not a legal robot option "
                      f"(section 4): {r}")
            self.end(node.id)
            return []
        st = self.recorded(child, r)
        if st is None:
            # §4: one label, several moves (robot methods starting with the same action):
            # the recorded edge must lead to the node of one of them
            sem = self.sem
            ways = [(sem.shown(s.after.robot), sorted(sem.shown(h) for h in s.after.humans))
                    for s in r if s.after is not None]
            self.fail(cpath, f"node {child.id} (R {move.action}): the recorded edge is none of "
                      f"the {len(r)} robot moves labelled {move.action} here (§4): its node "
                      f"has robot agenda {child.robot_agenda} and human agendas "
                      f"{sorted(child.human_agendas)}; the moves lead to (robot agenda, human "
                      f"agendas) {ways}")
            self.end(node.id)
            return []
        if not self.check_move(node, 0, st, path):
            self.end(node.id)
            return []
        return [(0, st)]

    def recorded(self, child: PolicyNode, steps: list[Step]) -> Step | None:
        """The move of ``steps`` (several moves one label denotes) whose node is ``child``:
        the one the recorded edge names. Matched on the agendas (the robot's, and the human
        agendas A_H), then on every recorded fact; None when several moves share the label
        and none has the child's agendas (a lone move is checked by its child's facts)."""
        sem = self.sem
        if len(steps) == 1:
            return steps[0]
        want = sorted(list(h) for h in child.human_agendas)
        fits = [s for s in steps if s.after is not None
                and sem.shown(s.after.robot) == list(child.robot_agenda)
                and sorted(sem.shown(h) for h in s.after.humans) == want]
        if not fits:
            return None
        return next((s for s in fits if s.after is not None
                     and not self.facts(child, s.after, sem.is_goal(s.after))), fits[0])

    def hidden_choice(self, node: PolicyNode, path: list[str], where: str) -> bool:
        """§3: whether two human moves at ``node`` share a label (compared without spaces): the
        robot cannot tell them apart, so the policy would branch on a choice it cannot see."""
        first: dict[str, PolicyMove] = {}
        for move in node.moves:
            key = "".join(move.action.split())
            seen = first.setdefault(key, move)
            if seen is move:
                continue
            visible = self.problem.human.intentions == Intentions.VISIBLE
            self.fail(path, f"{where}: two human branches have the label {move.action} (to "
                      f"nodes {seen.to} and {move.to}): the robot sees the same move in both, "
                      "so the policy branches on a hidden choice (§3"
                      + (', under intentions = "visible" a repeated action label names the '
                         'intention: grab(c1) [rest]' if visible else "") + ")")
            self.end(node.id)
            return True
        return False

    def human_node(self, node: PolicyNode, es: EState, path: list[str],
                   where: str) -> list[tuple[int, Step]]:
        if self.hidden_choice(node, path, where):
            return []
        options = self.sem.human_options(es)
        used: list[Step] = []
        out: list[tuple[int, Step]] = []
        for j, move in enumerate(node.moves):
            child = self.policy.nodes[move.to]
            cpath = [*path, self.move_label(HUMAN, move.action)]
            matches = self.human_steps(es, move.action, options)
            if not matches:
                self.fail(cpath, f"node {child.id} (H {move.action}): extra human branch: "
                          f"not one of the human's options (section 4) "
                          f"{[o.label for o in options]}")
                self.end(node.id)
                continue
            st = next((m for m in matches if m not in used), matches[0])
            if st in used:
                self.fail(cpath, f"node {child.id} (H {move.action}): duplicate human "
                          "branch: this option is already covered")
                self.end(node.id)
                continue
            used.append(st)
            if st.after is None:
                self.fail(cpath, f"node {child.id} (H {move.action}): the human's action is "
                          "not applicable in T: the branch fails (acting on a false belief)")
                self.end(node.id)
                continue
            if not self.check_move(node, j, st, path):
                self.end(node.id)
                continue
            out.append((j, st))
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

    def values(self, order: list[int] | None
               ) -> tuple[dict[int, Fraction | None], dict[int, Fraction | None]]:
        """§7: the worst-case and the expected cost-to-go of every node, from the validator's
        own move costs and the problem's weights, children before parents; None under a
        violation (or everywhere on a cyclic policy)."""
        nodes = self.policy.nodes
        worst: dict[int, Fraction | None] = {}
        mean: dict[int, Fraction | None] = {}
        for n in order or []:
            node = nodes[n]
            worst[n] = mean[n] = None
            if not node.moves:
                if n in self.goals_reached:
                    worst[n] = mean[n] = Fraction(0)
                continue
            turn = self.turn.get(n)
            if turn is None or (turn == ROBOT and len(node.moves) != 1):
                continue
            parts: list[tuple[Fraction, Fraction, Fraction]] = []
            for j, m in enumerate(node.moves):
                w, v, cost = worst.get(m.to), mean.get(m.to), self.step_cost.get((n, j))
                if w is None or v is None or cost is None:
                    break
                parts.append((cost + w, cost + v, self.weight.get((n, j), Fraction(1))))
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
                      f"{[str(t) for t in want.ties]} (section 7)")

    def check_summary(self, order: list[int] | None) -> None:
        pol = self.policy
        nodes = pol.nodes
        worst, mean = self.values(order)
        expected = self.problem.objective.kind == ObjectiveKind.EXPECTED
        val, what = (mean, "expected") if expected else (worst, "worst-case")
        paths = self.paths()
        for n in sorted(val, key=lambda i: (len(paths.get(i, [])), i)):
            v = val[n]
            if v is not None and not _same(nodes[n].value, v):
                self.fail(paths.get(n, []), f"node {n} ({self.reached_by(n)}): value is "
                          f"{nodes[n].value}, but its {what} cost-to-go is {_num(v)} "
                          "(section 7)")
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
        if order is None:
            return
        # counted in the tree unfolding, by the number of root paths reaching each node
        reach = dict.fromkeys(order, 0)
        reach[0] = 1
        comms = leaves = 0
        for n in reversed(order):  # parents first
            for m in nodes[n].moves:
                reach[m.to] += reach[n]
                if m.kind in COMMUNICATIONS or m.told:
                    comms += reach[n]
            if not nodes[n].moves:
                leaves += reach[n]
        if pol.communications != comms:
            self.fail([], f"communications is {pol.communications}, but the policy has "
                      f"{comms} inform/ask/announce moves and moves said with an inform "
                      "(counted in its tree unfolding)")
        if pol.leaves != leaves:
            self.fail([], f"leaves is {pol.leaves}, but the policy has {leaves} leaves in its "
                      "tree unfolding (root-to-leaf branches)")

    def reached_by(self, n: int) -> str:
        """How node ``n`` was first reached: "start", or the move into it."""
        path = self.paths().get(n)
        return path[-1] if path else "start"

    def paths(self) -> dict[int, list[str]]:
        """The path to each node: the one it was first checked by, else the first found."""
        nodes = self.policy.nodes
        out: dict[int, list[str]] = {0: [], **self.path_of}
        stack = list(out)
        while stack:
            n = stack.pop()
            for m in nodes[n].moves:
                if 0 <= m.to < len(nodes) and m.to not in out:
                    out[m.to] = [*out[n], f"{m.agent} {m.action}"]
                    stack.append(m.to)
        return out

    def report(self, order: list[int] | None = None) -> Report:
        branches = self.branches_checked(order)
        if self.violations:
            return Report(False, self.violations[0], list(self.violations), self.nodes_checked,
                          branches)
        return Report(True, f"valid: {self.nodes_checked} nodes, {branches} branches checked",
                      [], self.nodes_checked, branches)


__all__ = ["Report", "validate"]
