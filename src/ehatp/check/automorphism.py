"""Renamings of interchangeable objects as the validator reads them (docs/semantics.md §3,
"Symmetry"): a permutation of the movable objects applied to atoms, tasks, states, agendas and
search nodes through integer tables, and the check that it is an automorphism of the ground
problem.

Part of the independent validator: written from the document, not from the planner's
:mod:`ehatp.search.symmetry`. A renaming is an automorphism when it moves no object the problem
names and maps onto themselves: ``[init]``, the belief worlds with their robot agendas, both
agendas, the observable / inferable / hidden atoms and each visibility condition with the atoms
it shows, co-presence, the goal, and the ground operators (precondition, effects, cost,
done-condition), methods (precondition, subtasks, order) and done-conditions of the three
models; formulas compare after renaming their atoms, conjunctions and disjunctions as sets.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import replace

from ..model.formula import And, Formula, GAtom, GTest, Not, Or
from ..model.grounded import GModel, Grounded
from ..model.problem import Problem
from .network import Agenda, Block
from .rules import EState

TOKEN = re.compile(r"[^\s(),=\[\]]+")


def named_objects(problem: Problem) -> dict[str, str]:
    """§3: the objects the problem names, never renamed, with where it names each: the
    domain's constants, the agendas, a belief world's robot agenda, a ``[goal]`` literal,
    ``after``, and a cost or an objective weight given by ground label."""
    out: dict[str, str] = {}

    def put(objs: Sequence[str], where: str) -> None:
        for o in objs:
            out.setdefault(o, where)

    put(list(problem.domain.constants), "the domain's constants")
    for what, agenda in (("the robot agenda", problem.robot_agenda),
                         ("the human agenda", problem.human_agenda)):
        for _, args in agenda:
            put(args, what)
    for w in problem.beliefs:
        for _, args in w.robot_agenda or ():
            put(args, "a belief world's robot agenda")
    for _, (_, args) in problem.goal:
        put(args, "[goal]")
    for label in problem.after:
        put(TOKEN.findall(label.partition(" ")[2]), "after")
    for key in problem.costs.actions:
        if "(" in key:
            put(TOKEN.findall(key), "a cost given by ground label")
    for key in problem.objective.weights:
        if "(" in key:
            put(TOKEN.findall(key), "an objective weight given by ground label")
    return out


def rename_name(name: str, ren: dict[str, str]) -> str:
    """A ground atom or task name with its objects renamed: ``on(c1, box1)``, ``loc(c1) =
    box1``, ``balls(b1)[2]``, ``take(c1)`` (every argument, and a variable's value)."""
    return TOKEN.sub(lambda m: ren.get(m.group(0), m.group(0)), name)


class Renaming:
    """One permutation of the movable objects (``image[i]`` is the index of object ``i``'s
    image in ``objects``) as integer tables over the ground problem's atoms and tasks; a name
    without an image in the ground problem is recorded in ``missing``."""

    def __init__(self, grounded: Grounded, objects: Sequence[str], image: Sequence[int],
                 net_canon: Callable[[Sequence[int], set[tuple[int, int]]], Agenda]) -> None:
        self.grounded = grounded
        self.ren = {objects[i]: objects[j] for i, j in enumerate(image) if i != j}
        self.missing: list[str] = []
        self.atom = self._table(grounded.atoms, grounded.atom_index)
        self.task = self._table(grounded.task_names, grounded.task_index)
        self.moved_atoms = 0
        for i, j in enumerate(self.atom):
            if i != j:
                self.moved_atoms |= 1 << i
        self._canon = net_canon

    def _table(self, names: Sequence[str], index: dict[str, int]) -> list[int]:
        out = list(range(len(names)))
        if not self.ren:
            return out
        for i, name in enumerate(names):
            new = rename_name(name, self.ren)
            if new != name:
                j = index.get(new)
                if j is None:
                    self.missing.append(f"{name} has no image ({new} is not in the ground "
                                        "problem)")
                else:
                    out[i] = j
        return out

    @property
    def identity(self) -> bool:
        return not self.ren

    def state(self, s: int) -> int:
        moved = s & self.moved_atoms
        if not moved:
            return s
        out = s & ~moved
        table = self.atom
        while moved:
            low = moved & -moved
            out |= 1 << table[low.bit_length() - 1]
            moved ^= low
        return out

    def agenda(self, ag: Agenda) -> Agenda:
        table = self.task
        out: list[int | Block] = []
        for t in ag:
            if isinstance(t, Block):  # renamed members, put back in canonical form (§1)
                out.extend(self._canon([table[x] for x in t.tasks], set(t.before)))
            else:
                out.append(table[t])
        return tuple(out)

    def estate(self, es: EState) -> EState:
        """A search node of §3 with its objects renamed."""
        if self.identity:
            return es
        return replace(es, true=self.state(es.true), robot=self.agenda(es.robot),
                       humans=frozenset(self.agenda(h) for h in es.humans),
                       worlds=frozenset((self.state(s), self.agenda(a)) for s, a in es.worlds))

    def shown(self) -> str:
        """The renaming as text: ``a→b, b→a``."""
        return ", ".join(f"{a}→{b}" for a, b in self.ren.items()) or "the identity"

    # -- the automorphism check ----------------------------------------------------------------

    def formula(self, f: Formula | None, renamed: bool = True) -> object:
        """A ground formula as a comparable value, atoms renamed (unless ``renamed`` is
        False), conjunctions and disjunctions as sets."""
        if f is None:
            return None
        if isinstance(f, GAtom):
            return self.atom[f.index] if renamed else f.index
        if isinstance(f, GTest):
            return ("test", self.formula(f.body, renamed))
        if isinstance(f, Not):
            return ("not", self.formula(f.arg, renamed))
        if isinstance(f, And | Or):
            return (type(f).__name__, frozenset(self.formula(a, renamed) for a in f.args))
        return ("other", str(f))

    def why_not(self, problem: Problem, named: dict[str, str]) -> str | None:
        """§3: why this renaming is not an automorphism of the ground problem (the first part
        it does not map onto itself), or None when it is one."""
        for o in self.ren:
            if o in named:
                return f"it renames {o}, which the problem names ({named[o]})"
        if self.missing:
            return self.missing[0]
        g = self.grounded
        for why in (self._problem_part(g), *(self._model(g, m) for m in _models(g))):
            if why is not None:
                return why
        return None

    def _problem_part(self, g: Grounded) -> str | None:
        """The initial state, the agendas, the belief worlds, the observability masks and
        visibility conditions, co-presence and the goal."""
        if self.state(g.init) != g.init:
            return "it maps the initial state onto another (" + self._atoms(g.init) + ")"
        if self.agenda(g.robot_agenda) != g.robot_agenda:
            return "it maps the robot agenda onto another"
        if self.agenda(g.human_agenda) != g.human_agenda:
            return "it maps the human agenda onto another"
        worlds = Counter(g.beliefs)
        if Counter((self.state(s), self.agenda(a)) for s, a in g.beliefs) != worlds:
            return "it maps the belief worlds (with their robot agendas) onto others"
        for what, mask in (("observable", g.observable_mask), ("inferable", g.inferable_mask),
                           ("hidden", g.hidden_mask)):
            if self.state(mask) != mask:
                return f"it maps the {what} atoms onto others (" + self._atoms(mask) + ")"
        formula_of = self._formulas(g)
        vis = [(formula_of.get(id(fn)), mask) for fn, mask in g.visible]
        if Counter((self.formula(f), self.state(m)) for f, m in vis) != Counter(
                (self.formula(f, False), m) for f, m in vis):
            return "it maps the visibility conditions (with the atoms they show) onto others"
        if self.formula(g.copresent_f) != self.formula(g.copresent_f, False):
            return "it maps co-presence onto another condition"
        if self.formula(g.goal_f) != self.formula(g.goal_f, False):
            return "it maps the goal onto another"
        return None

    def _atoms(self, mask: int) -> str:
        moved = [i for i in range(mask.bit_length()) if mask >> i & 1 and self.atom[i] != i
                 and not mask >> self.atom[i] & 1]
        g = self.grounded
        return ", ".join(f"{g.atoms[i]} becomes {g.atoms[self.atom[i]]}" for i in moved[:3])

    @staticmethod
    def _formulas(g: Grounded) -> dict[int, Formula]:
        return {id(fn): f for f, fn in g.fns.items()}

    def _model(self, g: Grounded, model: GModel) -> str | None:
        """A model's ground operators, methods and done-conditions."""
        names, who = g.task_names, f"{model.agent}'s model"
        formula_of = self._formulas(g)
        f = self.formula
        for t, op in model.ops.items():
            o2 = model.ops.get(self.task[t])
            what = f"in {who}, {names[t]} maps onto {names[self.task[t]]}, which"
            if o2 is None:
                return f"{what} is not an action"
            if (op.cost != o2.cost or self.state(op.add) != o2.add
                    or self.state(op.dele) != o2.dele or f(op.pre_f) != f(o2.pre_f, False)
                    or f(op.done_f) != f(o2.done_f, False)):
                return f"{what} has another precondition, effects, cost or done-condition"
            c1 = Counter((f(formula_of.get(id(c))), self.state(a), self.state(d))
                         for c, a, d in op.cond)
            c2 = Counter((f(formula_of.get(id(c)), False), a, d) for c, a, d in o2.cond)
            if c1 != c2:
                return f"{what} has other conditional effects"
        for t, methods in model.methods.items():
            m2 = model.methods.get(self.task[t], ())
            k1 = Counter((f(m.pre_f), self.agenda(m.subtasks), m.order) for m in methods)
            k2 = Counter((f(m.pre_f, False), m.subtasks, m.order) for m in m2)
            if k1 != k2:
                return (f"in {who}, the methods of {names[t]} map onto others than those of "
                        f"{names[self.task[t]]}")
        for t, (df, _) in model.done.items():
            d2 = model.done.get(self.task[t])
            if d2 is None or f(df) != f(d2[0], False):
                return (f"in {who}, the done-condition of {names[t]} maps onto another than "
                        f"that of {names[self.task[t]]}")
        for t in model.ops.keys() | model.methods.keys() | model.done.keys():
            u = self.task[t]
            if (t in model.ops, t in model.methods, t in model.done) != \
                    (u in model.ops, u in model.methods, u in model.done):
                return f"in {who}, {names[t]} and {names[u]} are not tasks of one kind"
        return None


def _models(g: Grounded) -> list[GModel]:
    out = [g.robot, g.human]
    if g.robot_seen_by_human is not g.robot:
        out.append(g.robot_seen_by_human)
    return out


def lazy(g: Grounded) -> bool:
    """Whether a model was grounded only in part (``[limits] ground_ahead``): its tables do
    not hold every task, so the whole model is not known."""
    return any(m.lazy for m in _models(g))


def ordered_methods(g: Grounded) -> bool:
    """Whether a model has a partially ordered method (§3: they turn the reduction off)."""
    return any(m.order is not None for model in _models(g) for ms in model.methods.values()
               for m in ms)


__all__ = ["TOKEN", "Renaming", "lazy", "named_objects", "ordered_methods", "rename_name"]
