"""The declarative domain API: types, predicates with observability, per-agent HTN models.

A domain is a short Python module::

    d = Domain("kitchen")
    Place = d.type("place")
    a, p = Var("a", "agent"), Var("p", Place)
    at = d.predicate("at", a, p)                       # observable by default
    washed = d.predicate("washed", observability=HIDDEN)
    d.copresence = at("R", "kitchen") & at("H", "kitchen")
    wash = d.robot.action("wash", pre=~washed(), effects=[washed()])
    prepare = d.robot.task("prepare", done=washed())
    d.robot.method(prepare, "by_washing", subtasks=[wash()])

Everything a domain says is data (formulas, effect lists, task references), so the planner can
analyse it: which atoms a precondition reads, what the human can see, how to print a policy.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, TypeVar

from ..errors import EhatpError
from .formula import TRUE, And, Atom, Eq, Exists, Forall, Formula, Not, Or, Term, Var, free_vars

AGENT_TYPE = "agent"


class DomainError(EhatpError):
    """A mistake in a domain definition (raised while the domain module is built)."""


# --- domain factories ------------------------------------------------------------------------

_FACTORY_MARK = "__ehatp_domain_factory__"
F = TypeVar("F", bound=Callable[..., Any])


def domain_factory(fn: F) -> F:
    """Mark ``fn`` as a function that builds a :class:`Domain` from keyword options.

    A problem file's ``[domain] name = "module:attribute"`` may only name a ``Domain`` or a
    function marked so: problem files are data, and this keeps them from calling anything else.
    Its other ``[domain]`` keys become ``fn``'s keyword arguments::

        @domain_factory
        def make_domain(variant: int = 1) -> Domain: ...
    """
    setattr(fn, _FACTORY_MARK, True)
    return fn


def is_domain_factory(obj: object) -> bool:
    """Whether ``obj`` was marked with :func:`domain_factory`."""
    return callable(obj) and getattr(obj, _FACTORY_MARK, False) is True


# --- observability ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Observability:
    kind: Literal["observable", "inferable", "hidden"]
    when: Formula = TRUE

    def __str__(self) -> str:
        return f"observable when {self.when}" if self.kind == "observable" else self.kind


def observable(when: Formula = TRUE) -> Observability:
    """The human perceives the atom's value whenever ``when`` holds in the true state."""
    return Observability("observable", when)


INFERABLE = Observability("inferable")
"""Learned only by witnessing the action that changed it."""
HIDDEN = Observability("hidden")
"""Learned only through communication."""


# --- predicates ------------------------------------------------------------------------------


def _check_args(kind: str, name: str, params: Sequence[Var], args: Sequence[Term]) -> None:
    if len(args) != len(params):
        raise DomainError(f"{kind} {name} takes {len(params)} argument(s), got {len(args)}")
    for p, a in zip(params, args, strict=True):
        if isinstance(a, Var) and a.type != p.type:
            raise DomainError(
                f"{kind} {name}: argument {a.name} has type {a.type}, expected {p.type}"
            )
        if not isinstance(a, Var | str):
            raise DomainError(f"{kind} {name}: argument {a!r} is neither a Var nor an object name")


@dataclass(frozen=True, eq=False)
class Predicate:
    name: str
    params: tuple[Var, ...]
    observability: Observability

    def __call__(self, *args: Term) -> Atom:
        _check_args("predicate", self.name, self.params, args)
        return Atom(self.name, tuple(args))


@dataclass(frozen=True, eq=False)
class Derived:
    """A named formula (non-recursive macro), e.g. ``can_put(c, b)``: printed by name, expanded
    when grounded."""

    name: str
    params: tuple[Var, ...]
    body: Formula

    def __call__(self, *args: Term) -> Atom:
        _check_args("derived predicate", self.name, self.params, args)
        return Atom(self.name, tuple(args))


# --- effects ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class When:
    """Conditional effect: ``effects`` apply if ``cond`` holds before the action."""

    cond: Formula
    effects: tuple[Effect, ...]


@dataclass(frozen=True)
class ForEach:
    """Universal effect over typed variables."""

    vars: tuple[Var, ...]
    effects: tuple[Effect, ...]


Effect = Atom | Not | When | ForEach
"""An atom is added, ``~atom`` is deleted."""


def when(cond: Formula, *effects: Effect) -> When:
    return When(cond, tuple(effects))


def for_each(vars: Var | Sequence[Var], *effects: Effect) -> ForEach:
    return ForEach(tuple([vars] if isinstance(vars, Var) else vars), tuple(effects))


# --- tasks -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class TaskRef:
    """A (possibly non-ground) reference to a task in a method body or an agenda."""

    name: str
    args: tuple[Term, ...]

    def __str__(self) -> str:
        if not self.args:
            return self.name
        return f"{self.name}({', '.join(str(a) if isinstance(a, Var) else a for a in self.args)})"


@dataclass(frozen=True, eq=False)
class Operator:
    name: str
    params: tuple[Var, ...]
    pre: Formula
    effects: tuple[Effect, ...]
    cost: int | float
    done: Formula | None

    def __call__(self, *args: Term) -> TaskRef:
        _check_args("action", self.name, self.params, args)
        return TaskRef(self.name, tuple(args))


@dataclass(frozen=True, eq=False)
class AbstractTask:
    name: str
    params: tuple[Var, ...]
    done: Formula | None

    def __call__(self, *args: Term) -> TaskRef:
        _check_args("task", self.name, self.params, args)
        return TaskRef(self.name, tuple(args))


@dataclass(frozen=True, eq=False)
class Method:
    task: AbstractTask
    name: str
    params: tuple[Var, ...]
    pre: Formula
    subtasks: tuple[TaskRef, ...]
    # pairs (i, j): subtask i comes before subtask j; None: the subtasks in the order listed
    order: tuple[tuple[int, int], ...] | None = None

    def predecessors(self) -> tuple[int, ...] | None:
        """For a partially ordered method, each subtask's predecessors as a bitmask over the
        subtasks, transitively closed (docs/semantics.md §1); None when totally ordered."""
        if self.order is None:
            return None
        preds = [0] * len(self.subtasks)
        for i, j in self.order:
            preds[j] |= 1 << i
        changed = True
        while changed:
            changed = False
            for j, m in enumerate(preds):
                closed = m
                for i in range(len(preds)):
                    if m >> i & 1:
                        closed |= preds[i]
                if closed != m:
                    preds[j], changed = closed, True
        return tuple(preds)


@dataclass(eq=False)
class AgentModel:
    """One agent's HTN model: its operators, abstract tasks and methods."""

    agent: str
    operators: dict[str, Operator] = field(default_factory=dict)
    tasks: dict[str, AbstractTask] = field(default_factory=dict)
    methods: list[Method] = field(default_factory=list)

    def _fresh(self, name: str) -> None:
        if name in self.operators or name in self.tasks:
            raise DomainError(f"{self.agent}: task or action {name!r} is defined twice")

    def action(
        self,
        name: str,
        *params: Var,
        pre: Formula = TRUE,
        effects: Iterable[Effect] = (),
        cost: int | float = 1,
        done: Formula | None = None,
    ) -> Operator:
        """Declare a primitive action of this agent."""
        self._fresh(name)
        if cost <= 0:
            raise DomainError(f"{self.agent}.{name}: cost must be positive, got {cost}")
        op = Operator(name, tuple(params), pre, tuple(effects), cost, done)
        _check_scope(f"action {name}", set(params), [pre, *([done] if done else [])])
        # an effect with a variable the action does not bind could only fail when grounded
        loose = _effect_vars(f"action {name}", op.effects) - set(params)
        if loose:
            raise DomainError(f"action {name}: an effect uses unbound "
                              f"{', '.join(sorted(v.name for v in loose))}; add it to the "
                              "action's parameters or bind it with for_each")
        self.operators[name] = op
        return op

    def task(self, name: str, *params: Var, done: Formula | None = None) -> AbstractTask:
        """Declare an abstract task; ``done`` lets the agent skip it when it already holds."""
        self._fresh(name)
        t = AbstractTask(name, tuple(params), done)
        if done is not None:
            _check_scope(f"task {name}", set(params), [done])
        self.tasks[name] = t
        return t

    def method(
        self,
        task: AbstractTask,
        name: str,
        *,
        params: Sequence[Var] = (),
        pre: Formula = TRUE,
        subtasks: Sequence[TaskRef] = (),
        order: Iterable[tuple[int, int]] | None = None,
    ) -> Method:
        """A way to decompose ``task``; ``params`` beyond the task's are chosen freely (one
        alternative per binding satisfying ``pre``). The subtasks are done in the order listed,
        unless ``order`` gives the order between them as pairs of indices ``(before,
        after)``: ``order=[(0, 2), (1, 2)]`` does the first two in either order, then the third;
        ``order=[]`` leaves them unordered (docs/semantics.md §1, "Partial order")."""
        if self.tasks.get(task.name) is not task:
            raise DomainError(f"{self.agent}: method {name} refines {task.name}, not a task here")
        scope = set(task.params) | set(params)
        _check_scope(f"method {task.name}.{name}", scope, [pre])
        for st in subtasks:
            loose = {a for a in st.args if isinstance(a, Var)} - scope
            if loose:
                raise DomainError(f"method {task.name}.{name}: subtask {st} uses unbound "
                                  f"{', '.join(sorted(v.name for v in loose))}")
        pairs = None if order is None else _order_pairs(f"method {task.name}.{name}", order,
                                                         len(subtasks))
        m = Method(task, name, tuple(params), pre, tuple(subtasks), pairs)
        self.methods.append(m)
        return m

    def copy(self, agent: str | None = None) -> AgentModel:
        """A shallow copy, e.g. to start the human's estimate of the robot's model."""
        return AgentModel(agent or self.agent, dict(self.operators), dict(self.tasks),
                          list(self.methods))


def _order_pairs(where: str, order: Iterable[tuple[int, int]],
                 n: int) -> tuple[tuple[int, int], ...]:
    """A method's ``order``, checked (indices of its subtasks, no cycle) and sorted."""
    pairs: set[tuple[int, int]] = set()
    for p in order:
        if (not isinstance(p, tuple | list) or len(p) != 2
                or not all(isinstance(x, int) and not isinstance(x, bool) for x in p)):
            raise DomainError(f"{where}: order {p!r} is not a pair of subtask indices "
                              "(before, after)")
        i, j = p
        if not (0 <= i < n and 0 <= j < n):
            raise DomainError(f"{where}: order ({i}, {j}) names a subtask it does not have "
                              f"(indices 0..{n - 1})")
        if i == j:
            raise DomainError(f"{where}: order ({i}, {j}) puts a subtask before itself")
        pairs.add((i, j))
    after: dict[int, set[int]] = {}
    for i, j in pairs:
        after.setdefault(i, set()).add(j)
    for start in range(n):  # a cycle would leave no subtask able to come first
        seen, todo = set(), list(after.get(start, ()))
        while todo:
            k = todo.pop()
            if k == start:
                raise DomainError(f"{where}: order has a cycle through subtask {start}")
            if k not in seen:
                seen.add(k)
                todo.extend(after.get(k, ()))
    return tuple(sorted(pairs))


def _check_scope(where: str, scope: set[Var], formulas: Iterable[Formula]) -> None:
    for f in formulas:
        loose = free_vars(f) - scope
        if loose:
            raise DomainError(f"{where}: formula {f} uses unbound "
                              f"{', '.join(sorted(v.name for v in loose))}")


def _effect_vars(where: str, effects: Iterable[object]) -> set[Var]:
    """The variables ``effects`` leave free; anything that is not an effect is a DomainError."""
    out: set[Var] = set()
    for e in effects:
        if isinstance(e, Atom):
            out |= free_vars(e)
        elif isinstance(e, Not) and isinstance(e.arg, Atom):
            out |= free_vars(e.arg)
        elif isinstance(e, When):
            out |= free_vars(e.cond) | _effect_vars(where, e.effects)
        elif isinstance(e, ForEach):
            out |= _effect_vars(where, e.effects) - set(e.vars)
        else:
            raise DomainError(f"{where}: {e!r} is not an effect (write an atom, ~atom, "
                              "when(...) or for_each(...))")
    return out


# --- the domain ------------------------------------------------------------------------------


class Domain:
    """Types, constants, predicates, co-presence and the three task models M_R, M_H, M_R^H."""

    def __init__(self, name: str, *, robot: str = "R", human: str = "H", doc: str = "") -> None:
        self.name = name
        self.doc = doc
        self.robot_name = robot
        self.human_name = human
        self.types: list[str] = [AGENT_TYPE]
        self.constants: dict[str, str] = {robot: AGENT_TYPE, human: AGENT_TYPE}
        self.predicates: dict[str, Predicate] = {}
        self.derived_predicates: dict[str, Derived] = {}
        self.robot = AgentModel(robot)
        self.human = AgentModel(human)
        self._robot_seen_by_human: AgentModel | None = None
        self.copresence: Formula = TRUE
        self.goal: Formula | None = None

    @property
    def robot_seen_by_human(self) -> AgentModel:
        """M_R^H, the human's estimate of the robot's model (defaults to M_R itself)."""
        return self._robot_seen_by_human or self.robot

    @robot_seen_by_human.setter
    def robot_seen_by_human(self, model: AgentModel) -> None:
        self._robot_seen_by_human = model

    def type(self, name: str) -> str:
        if name in self.types:
            raise DomainError(f"type {name!r} is declared twice")
        self.types.append(name)
        return name

    def constant(self, name: str, type: str) -> str:
        """An object every problem of this domain has (e.g. a named table)."""
        if type not in self.types:
            raise DomainError(f"constant {name}: unknown type {type!r}")
        if name in self.constants:
            raise DomainError(f"constant {name!r} is declared twice")
        self.constants[name] = type
        return name

    def predicate(
        self, name: str, *params: Var, observability: Observability | None = None
    ) -> Predicate:
        """Declare a predicate. Observable (always visible) unless told otherwise; the
        visibility condition may use the predicate's own parameters."""
        self._fresh_pred(name)
        for p in params:
            if p.type not in self.types:
                raise DomainError(f"predicate {name}: unknown type {p.type!r}")
        obs = observability or observable()
        _check_scope(f"visibility of {name}", set(params), [obs.when])
        pred = Predicate(name, tuple(params), obs)
        self.predicates[name] = pred
        return pred

    def derived(self, name: str, params: Sequence[Var], body: Formula) -> Derived:
        self._fresh_pred(name)
        _check_scope(f"derived predicate {name}", set(params), [body])
        d = Derived(name, tuple(params), body)
        self.derived_predicates[name] = d
        return d

    def _fresh_pred(self, name: str) -> None:
        if name in self.predicates or name in self.derived_predicates:
            raise DomainError(f"predicate {name!r} is declared twice")

    def check(self) -> None:
        """What declaring cannot check, because it may be set later: the goal and co-presence
        are closed formulas, and every variable has a declared type. Raise DomainError."""
        for what, f in (("copresence", self.copresence), ("goal", self.goal)):
            if f is None:
                continue
            if not isinstance(f, Formula):
                raise DomainError(f"domain {self.name}: {what} is {f!r}, not a formula")
            _check_scope(f"domain {self.name}: {what}", set(), [f])
        for where, v in self._variables():
            if v.type not in self.types:
                raise DomainError(f"{where}: variable {v.name} has the undeclared type "
                                  f"{v.type!r}; declare it with d.type({v.type!r})")

    def _variables(self) -> Iterable[tuple[str, Var]]:
        def of(where: str, f: object) -> Iterable[tuple[str, Var]]:
            if isinstance(f, Atom):
                yield from ((where, a) for a in f.args if isinstance(a, Var))
            elif isinstance(f, Eq):
                yield from ((where, a) for a in (f.left, f.right) if isinstance(a, Var))
            elif isinstance(f, Not):
                yield from of(where, f.arg)
            elif isinstance(f, And | Or):
                for a in f.args:
                    yield from of(where, a)
            elif isinstance(f, Exists | Forall):
                yield from ((where, v) for v in f.vars)
                yield from of(where, f.body)
            elif isinstance(f, When):
                yield from of(where, f.cond)
                for e in f.effects:
                    yield from of(where, e)
            elif isinstance(f, ForEach):
                yield from ((where, v) for v in f.vars)
                for e in f.effects:
                    yield from of(where, e)

        yield from of("copresence", self.copresence)
        yield from of("goal", self.goal)
        for d in self.derived_predicates.values():
            yield from ((f"derived predicate {d.name}", v) for v in d.params)
            yield from of(f"derived predicate {d.name}", d.body)
        for p in self.predicates.values():
            yield from of(f"visibility of {p.name}", p.observability.when)
        for m in (self.robot, self.human, self.robot_seen_by_human):
            for op in m.operators.values():
                where = f"{m.agent}: action {op.name}"
                yield from ((where, v) for v in op.params)
                for f in (op.pre, op.done, *op.effects):
                    yield from of(where, f)
            for t in m.tasks.values():
                yield from ((f"{m.agent}: task {t.name}", v) for v in t.params)
                yield from of(f"{m.agent}: task {t.name}", t.done)
            for me in m.methods:
                where = f"{m.agent}: method {me.task.name}.{me.name}"
                yield from ((where, v) for v in me.params)
                yield from of(where, me.pre)

    def models(self) -> dict[str, AgentModel]:
        return {"robot": self.robot, "human": self.human,
                "robot_seen_by_human": self.robot_seen_by_human}

    def __repr__(self) -> str:
        return f"Domain({self.name!r})"
