"""Grounding: a problem becomes integer bitset states, compiled formulas and ground HTNs, once.

Objects are sorted by name and predicates by name, so atom indices, task ids and every later
order are canonical: the planner's output does not depend on declaration order.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction

from .domain import AgentModel, Domain, DomainError, Effect, ForEach, Method, TaskRef, When
from .formula import (
    FALSE,
    TRUE,
    And,
    Atom,
    Formula,
    GAtom,
    Not,
    StateFn,
    Var,
    compile_ground,
    ground,
    product,
    simplify_and,
    substitute,
)
from .problem import Cost, Problem, call_str

FINISH = -1
"""Pseudo task id: the agenda can be completed (nothing left to do)."""


@dataclass(frozen=True, slots=True, eq=False)
class GOp:
    """A ground primitive action of one agent model."""

    id: int
    name: str
    schema: str
    args: tuple[str, ...]
    pre_f: Formula
    pre: StateFn
    add: int
    dele: int
    cond: tuple[tuple[StateFn, int, int], ...]
    cost: Cost
    done_f: Formula | None
    done: StateFn | None

    def apply(self, s: int) -> int:
        add, dele = self.add, self.dele
        for fn, a, d in self.cond:
            if fn(s):
                add |= a
                dele |= d
        return (s & ~dele) | add


@dataclass(frozen=True, slots=True, eq=False)
class GMethod:
    name: str
    pre_f: Formula
    pre: StateFn
    subtasks: tuple[int, ...]
    # partial order: each subtask's predecessors (bitmask over subtasks, transitively closed);
    # None: the subtasks in the order listed (docs/semantics.md §1)
    order: tuple[int, ...] | None = None


@dataclass(eq=False)
class GModel:
    """A ground agent model: task id -> primitive action or (done condition, methods)."""

    agent: str
    ops: dict[int, GOp] = field(default_factory=dict)
    methods: dict[int, tuple[GMethod, ...]] = field(default_factory=dict)
    done: dict[int, tuple[Formula, StateFn]] = field(default_factory=dict)


@dataclass(eq=False)
class Grounded:
    """Everything the planner needs, in compact form."""

    problem: Problem
    atoms: list[str]
    atom_index: dict[str, int]
    task_names: list[str]
    task_index: dict[str, int]
    robot: GModel
    human: GModel
    robot_seen_by_human: GModel
    init: int
    beliefs: list[tuple[int, tuple[int, ...]]]
    robot_agenda: tuple[int, ...]
    human_agenda: tuple[int, ...]
    visible: list[tuple[StateFn, int]]
    observable_mask: int
    inferable_mask: int
    hidden_mask: int
    copresent_f: Formula
    copresent: StateFn
    goal_f: Formula
    goal: StateFn
    fns: dict[Formula, StateFn]
    display: dict[Formula, str]

    def compile(self, f: Formula) -> StateFn:
        fn = self.fns.get(f)
        if fn is None:
            fn = self.fns[f] = compile_ground(f)
        return fn

    def state_atoms(self, s: int) -> list[str]:
        return [self.atoms[i] for i in _bits(s)]

    def mask_atoms(self, m: int) -> list[str]:
        return [self.atoms[i] for i in _bits(m)]

    def visible_mask(self, t: int) -> int:
        m = 0
        for fn, mask in self.visible:
            if fn(t):
                m |= mask
        return m


def _bits(m: int) -> Iterable[int]:
    i = 0
    while m:
        if m & 1:
            yield i
        m >>= 1
        i += 1


def ground_problem(problem: Problem, check: Callable[[], None] | None = None) -> Grounded:
    """Ground ``problem`` after checking it (a Problem built in Python is checked as a problem
    file is: unknown predicates, objects or tasks raise InputError, not a KeyError later).
    ``check`` is called once per ground task (a time or memory limit may raise from it)."""
    problem.check()
    return _Grounder(problem, check).run()


def _no_check() -> None:
    pass


class _Grounder:
    def __init__(self, problem: Problem, check: Callable[[], None] | None = None) -> None:
        self.p = problem
        self.check = check or _no_check
        self.d: Domain = problem.domain
        self.objects = problem.all_objects()
        self.obj_type = {o: t for t, os in self.objects.items() for o in os}
        self.fns: dict[Formula, StateFn] = {}
        # ground formula -> how the domain wrote it (derived predicates kept by name)
        self.display: dict[Formula, str] = {}
        self.task_names: list[str] = []
        self.task_index: dict[str, int] = {}
        self._derived: dict[tuple[str, tuple[str, ...]], Formula] = {}

    # -- atoms --
    def run(self) -> Grounded:
        d, p = self.d, self.p
        fluent = set()
        for model in d.models().values():
            for op in model.operators.values():
                fluent |= _effect_preds(op.effects)
        for w in p.beliefs:
            fluent |= {a[0] for a in w.true | w.false}
        self.static = {n for n in d.predicates if n not in fluent}
        atoms: list[str] = []
        for name in sorted(d.predicates):
            if name in self.static:
                continue
            pred = d.predicates[name]
            for args in product([self.objects[v.type] for v in pred.params]):
                atoms.append(call_str(name, args))
        self.atoms = atoms
        self.atom_index = {a: i for i, a in enumerate(atoms)}
        init_strs = {call_str(n, a) for n, a in p.init}
        self.init_static = {s for s in init_strs if s.split("(")[0] in self.static}
        init = self.bits(s for s in init_strs if s in self.atom_index)

        # observability: group ground atoms by their ground visibility formula
        groups: dict[Formula, int] = {}
        obs = inf = hid = 0
        for name in sorted(d.predicates):
            if name in self.static:
                continue
            pred = d.predicates[name]
            for args in product([self.objects[v.type] for v in pred.params]):
                bit = 1 << self.atom_index[call_str(name, args)]
                kind = pred.observability.kind
                if kind == "observable":
                    obs |= bit
                    f = self.ground_f(pred.observability.when, dict(zip(pred.params, args,
                                                                          strict=True)))
                    if f != FALSE:
                        groups[f] = groups.get(f, 0) | bit
                elif kind == "inferable":
                    inf |= bit
                else:
                    hid |= bit
        visible = [(self.compile(f), m) for f, m in groups.items()]

        # tasks and models
        self.models: dict[int, GModel] = {}
        r_ag = self.agenda(p.robot_agenda)
        h_ag = self.agenda(p.human_agenda)
        robot = self.ground_model(d.robot, [r_ag])
        human = self.ground_model(d.human, [h_ag])
        beliefs = []
        belief_agendas = [r_ag]
        for w in p.beliefs:
            s = init | self.bits(call_str(*a) for a in w.true)
            s &= ~self.bits(call_str(*a) for a in w.false)
            ag = self.agenda(w.robot_agenda) if w.robot_agenda is not None else r_ag
            belief_agendas.append(ag)
            beliefs.append((s, ag))
        rh = (robot if d.robot_seen_by_human is d.robot
              else self.ground_model(d.robot_seen_by_human, belief_agendas, estimate=True))
        if rh is robot and any(ag != r_ag for ag in belief_agendas):
            robot = rh = self.ground_model(d.robot, belief_agendas)

        cop_f = self.ground_f(d.copresence, {})
        goal_parts = [self.ground_f(d.goal, {})] if d.goal is not None else []
        for positive, (n, a) in p.goal:
            g = self.ground_f(Atom(n, a), {})
            goal_parts.append(g if positive else Not(g))
        goal_f = simplify_and(goal_parts)
        return Grounded(
            problem=p, atoms=atoms, atom_index=self.atom_index, task_names=self.task_names,
            task_index=self.task_index, robot=robot, human=human, robot_seen_by_human=rh,
            init=init, beliefs=beliefs, robot_agenda=r_ag, human_agenda=h_ag, visible=visible,
            observable_mask=obs, inferable_mask=inf, hidden_mask=hid, copresent_f=cop_f,
            copresent=self.compile(cop_f), goal_f=goal_f, goal=self.compile(goal_f), fns=self.fns,
            display=self.display,
        )

    def bits(self, names: Iterable[str]) -> int:
        b = 0
        for n in names:
            b |= 1 << self.atom_index[n]
        return b

    def compile(self, f: Formula) -> StateFn:
        fn = self.fns.get(f)
        if fn is None:
            fn = self.fns[f] = compile_ground(f)
        return fn

    def atom(self, pred: str, args: tuple[str, ...]) -> Formula:
        for a in args:
            if a not in self.obj_type:
                raise DomainError(f"{pred}({', '.join(args)}): unknown object {a!r}")
        dv = self.d.derived_predicates.get(pred)
        if dv is not None:  # grounded once per arguments (can_put(c, b) is in many formulas)
            key = (pred, args)
            g = self._derived.get(key)
            if g is None:
                g = self._derived[key] = self.ground_f(dv.body,
                                                       dict(zip(dv.params, args, strict=True)))
            return g
        if pred not in self.d.predicates:
            raise DomainError(f"unknown predicate {pred!r}")
        name = call_str(pred, args)
        if pred in self.static:
            return TRUE if name in self.init_static else FALSE
        idx = self.atom_index.get(name)
        if idx is None:
            raise DomainError(f"{name}: an argument has the wrong type")
        return GAtom(idx, name)

    def ground_f(self, f: Formula, binding: Mapping[Var, str]) -> Formula:
        return ground(f, binding, self.objects, self.atom)

    def shown(self, f: Formula, binding: Mapping[Var, str]) -> Formula:
        """Ground ``f`` and remember how each conjunct reads in the domain's vocabulary."""
        display = self.display
        if not isinstance(f, And):
            g = self.ground_f(f, binding)
            if g not in display:
                display[g] = str(substitute(f, binding))
            return g
        # each conjunct grounded once: the conjunction is their simplified And (as ground()
        # makes it), and each keeps its own reading too
        parts = [(part, self.ground_f(part, binding)) for part in f.args]
        g = simplify_and([gp for _, gp in parts])
        if g not in display:
            display[g] = str(substitute(f, binding))
        for part, gp in parts:
            if gp not in display:
                display[gp] = str(substitute(part, binding))
        return g

    # -- tasks --
    def task_id(self, name: str) -> int:
        i = self.task_index.get(name)
        if i is None:
            i = self.task_index[name] = len(self.task_names)
            self.task_names.append(name)
        return i

    def agenda(self, calls: Iterable[tuple[str, tuple[str, ...]]]) -> tuple[int, ...]:
        return tuple(self.task_id(call_str(n, a)) for n, a in calls)

    def ground_model(self, model: AgentModel, agendas: Sequence[tuple[int, ...]],
                     estimate: bool = False) -> GModel:
        """Ground the tasks reachable from ``agendas``. In the human's ``estimate`` of the robot
        model a task it does not know has no way to be done (the human cannot expect it)."""
        g = GModel(model.agent)
        calls: dict[int, tuple[str, tuple[str, ...]]] = {}
        todo = [t for ag in agendas for t in ag]
        for t in todo:
            calls[t] = _split(self.task_names[t])
        seen: set[int] = set()
        methods_of: dict[str, list[Method]] = {}
        for m in model.methods:
            methods_of.setdefault(m.task.name, []).append(m)
        while todo:
            t = todo.pop()
            if t in seen:
                continue
            seen.add(t)
            self.check()
            name, args = calls[t]
            op = model.operators.get(name)
            if op is not None:
                b = dict(zip(op.params, args, strict=True))
                pre_f = self.shown(op.pre, b)
                add, dele, cond = self.effects(op.effects, b, TRUE)
                cost = self.p.costs.actions.get(name, _exact(op.cost))
                done_f = self.ground_f(op.done, b) if op.done is not None else None
                g.ops[t] = GOp(t, self.task_names[t], name, args, pre_f, self.compile(pre_f),
                               add, dele, tuple(cond), cost, done_f,
                               self.compile(done_f) if done_f is not None else None)
                continue
            task = model.tasks.get(name)
            if task is None and estimate:
                g.methods[t] = ()
                continue
            if task is None:
                raise DomainError(f"{model.agent} has no task or action {name!r}")
            tb = dict(zip(task.params, args, strict=True))
            if task.done is not None:
                df = self.ground_f(task.done, tb)
                g.done[t] = (df, self.compile(df))
            gms = []
            for m in sorted(methods_of.get(name, []), key=lambda m: m.name):
                for vals in product([self.objects[v.type] for v in m.params]):
                    b = {**tb, **dict(zip(m.params, vals, strict=True))}
                    pre_f = self.shown(m.pre, b)
                    if pre_f == FALSE:
                        continue
                    subs = []
                    for st in m.subtasks:
                        sargs = tuple(b[a] if isinstance(a, Var) else a for a in st.args)
                        self._check_subtask(model, st, sargs)
                        sid = self.task_id(call_str(st.name, sargs))
                        calls[sid] = (st.name, sargs)
                        subs.append(sid)
                        todo.append(sid)
                    label = f"{m.name}({', '.join(vals)})" if vals else m.name
                    gms.append(GMethod(f"{name}.{label}", pre_f, self.compile(pre_f),
                                       tuple(subs), m.predecessors()))
            g.methods[t] = tuple(gms)
        return g

    def _check_subtask(self, model: AgentModel, st: TaskRef, args: tuple[str, ...]) -> None:
        decl = model.operators.get(st.name) or model.tasks.get(st.name)
        if decl is None:
            raise DomainError(f"{model.agent}: subtask {st.name!r} is neither a task nor an action")
        for a, v in zip(args, decl.params, strict=True):
            if self.obj_type.get(a) != v.type:
                raise DomainError(f"{model.agent}: subtask {st}: {a!r} is not a {v.type}")

    def effects(self, effs: Sequence[Effect], b: Mapping[Var, str],
                cond: Formula) -> tuple[int, int, list[tuple[StateFn, int, int]]]:
        add = dele = 0
        conds: list[tuple[StateFn, int, int]] = []
        for e in effs:
            if isinstance(e, Atom | Not):
                atom = e if isinstance(e, Atom) else e.arg
                if not isinstance(atom, Atom):
                    raise DomainError(f"effect {e} is not an atom or its negation")
                g = self.ground_f(atom, b)
                if not isinstance(g, GAtom):
                    raise DomainError(f"effect {e}: {atom.pred} is not a fluent predicate")
                bit = 1 << g.index
                if cond == TRUE:
                    if isinstance(e, Atom):
                        add |= bit
                    else:
                        dele |= bit
                else:
                    conds.append((self.compile(cond), bit if isinstance(e, Atom) else 0,
                                  0 if isinstance(e, Atom) else bit))
            elif isinstance(e, When):
                c = simplify_and([cond, self.ground_f(e.cond, b)])
                if c != FALSE:
                    a2, d2, c2 = self.effects(e.effects, b, c)
                    conds.extend(c2)
                    if a2 or d2:
                        conds.append((self.compile(c), a2, d2))
            elif isinstance(e, ForEach):
                for vals in product([self.objects[v.type] for v in e.vars]):
                    a2, d2, c2 = self.effects(e.effects,
                                              {**b, **dict(zip(e.vars, vals, strict=True))}, cond)
                    add |= a2
                    dele |= d2
                    conds.extend(c2)
            else:
                raise DomainError(f"not an effect: {e!r}")
        return add, dele & ~add, conds


def _exact(c: int | float) -> Cost:
    """Costs are summed and compared exactly: a float becomes the Fraction it reads as."""
    return c if isinstance(c, int) else Fraction(str(c))


def _effect_preds(effs: Iterable[Effect]) -> set[str]:
    out: set[str] = set()
    for e in effs:
        if isinstance(e, Atom):
            out.add(e.pred)
        elif isinstance(e, Not) and isinstance(e.arg, Atom):
            out.add(e.arg.pred)
        elif isinstance(e, When | ForEach):
            out |= _effect_preds(e.effects)
    return out


def _split(name: str) -> tuple[str, tuple[str, ...]]:
    head, _, rest = name.partition("(")
    args = tuple(a.strip() for a in rest.rstrip(")").split(",")) if rest.strip(")") else ()
    return head, args


__all__ = ["FINISH", "GMethod", "GModel", "GOp", "Grounded", "ground_problem"]
