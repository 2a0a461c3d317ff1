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

import re
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, TypeVar

from ..errors import DomainError as DomainError  # defined in errors.py; its old home
from .formula import (
    TRUE,
    And,
    Atom,
    Cmp,
    Eq,
    Exists,
    Forall,
    Formula,
    Is,
    Not,
    Or,
    Term,
    ValueTerm,
    Var,
    free_vars,
    term_str,
)
from .options import Metric

AGENT_TYPE = "agent"


# --- domain factories ------------------------------------------------------------------------

_FACTORY_MARK = "__ehatp_domain_factory__"
F = TypeVar("F", bound=Callable[..., Any])


def domain_factory(fn: F) -> F:
    """Mark ``fn`` as a function that builds a :class:`Domain` from keyword options.

    A problem file's ``[domain] name = "module:attribute"`` (a ``.py`` file beside it, or a
    module that declared a domain: :mod:`ehatp.model.registry`) may only name a ``Domain``, a
    declared domain's own target, or a function marked so: problem files are data, and this
    keeps them from calling anything else. Its other ``[domain]`` keys become ``fn``'s keyword
    arguments::

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


# --- types -----------------------------------------------------------------------------------


class TypeHierarchy:
    """The domain's types and their parents: ``d.type("cube", parent="object")`` makes every
    cube an object, so a parameter, quantifier or variable of type ``object`` ranges over the
    cubes too."""

    def __init__(self) -> None:
        self.parent: dict[str, str] = {}

    def ancestors(self, t: str) -> list[str]:
        """``t``'s parent, its parent's parent, ... (nearest first)."""
        out: list[str] = []
        while t in self.parent:
            t = self.parent[t]
            out.append(t)
        return out

    def is_sub(self, t: str, of: str) -> bool:
        """Whether ``t`` is ``of`` or one of its subtypes."""
        return t == of or of in self.ancestors(t)

    def a(self, t: str) -> str:
        """``"a cube, a subtype of object"``: the type with its ancestors, for messages."""
        up = self.ancestors(t)
        return f"{article(t)} {t}" + (f", a subtype of {', of '.join(up)}" if up else "")


def article(t: str) -> str:
    """``"a"`` or ``"an"`` before the type name ``t``."""
    return "an" if t[:1].lower() in "aeiou" else "a"


def signature(name: str, params: Sequence[Var]) -> str:
    """``place(c: cube, b: box)``."""
    return f"{name}({', '.join(f'{p.name}: {p.type}' for p in params)})"


# --- predicates ------------------------------------------------------------------------------


def _check_args(kind: str, name: str, params: Sequence[Var], args: Sequence[Term],
                types: TypeHierarchy | None = None) -> None:
    if len(args) != len(params):
        raise DomainError(f"{kind} {name} takes {len(params)} argument(s), got {len(args)}")
    for p, a in zip(params, args, strict=True):
        if isinstance(a, Var) and not (a.type == p.type or types is not None
                                       and types.is_sub(a.type, p.type)):
            if types is not None and (types.ancestors(a.type) or types.ancestors(p.type)):
                raise DomainError(f"{kind} {name}: argument {a.name} is {types.a(a.type)}; "
                                  f"{signature(name, params)} wants {article(p.type)} "
                                  f"{p.type} for {p.name}")
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
    types: TypeHierarchy | None = field(default=None, repr=False)

    def __call__(self, *args: Term) -> Atom:
        _check_args("predicate", self.name, self.params, args, self.types)
        return Atom(self.name, tuple(args))


@dataclass(frozen=True, eq=False)
class Derived:
    """A named formula (non-recursive macro), e.g. ``can_put(c, b)``: printed by name, expanded
    when grounded."""

    name: str
    params: tuple[Var, ...]
    body: Formula
    types: TypeHierarchy | None = field(default=None, repr=False)

    def __call__(self, *args: Term) -> Atom:
        _check_args("derived predicate", self.name, self.params, args, self.types)
        return Atom(self.name, tuple(args))


# --- finite-domain state variables and bounded counters (docs/modelling.md) ------------------


@dataclass(frozen=True, eq=False)
class StateVariable:
    """``loc(c) ∈ Place``: one value among the objects of a type, in every state.

    ``value`` is the value parameter: its type is the value type, and the visibility condition
    may use it (``observable(at(H, p))`` with ``values=p``: the human sees whether the value is
    ``p`` while at ``p``). Calling it gives a term: ``loc(c).eq(mt)``, ``loc(c) == mt``,
    ``loc(c).set(box1)``."""

    name: str
    params: tuple[Var, ...]
    value: Var
    observability: Observability
    types: TypeHierarchy | None = field(default=None, repr=False)

    @property
    def values(self) -> str:
        """The value type."""
        return self.value.type

    def __call__(self, *args: Term) -> VarTerm:
        _check_args("variable", self.name, self.params, args, self.types)
        return VarTerm(self, tuple(args))


class VarTerm(ValueTerm):
    """``loc(c)``: compare it with a value (a formula) or assign it (an effect)."""

    __slots__ = ("args", "var")
    __hash__ = None  # type: ignore[assignment]  # == builds a formula

    def __init__(self, var: StateVariable, args: tuple[Term, ...]) -> None:
        self.var, self.args = var, args

    def _value(self, value: object) -> Term:
        v = self.var
        if isinstance(value, Var):
            ok = value.type == v.values or (v.types is not None
                                             and v.types.is_sub(value.type, v.values))
            if not ok:
                raise DomainError(f"variable {self}: {value.name} is {article(value.type)} "
                                  f"{value.type}, but its values are {v.values}s")
            return value
        if isinstance(value, str):
            return value
        raise DomainError(f"variable {self}: a value is an object name or a parameter of type "
                          f"{v.values}, not {value!r}")

    def eq(self, value: Term | int) -> Formula:
        """``loc(c) = value``."""
        return Is(self.var.name, (*self.args, self._value(value)))

    def ne(self, value: Term | int) -> Formula:
        """``loc(c) != value``."""
        return Not(self.eq(value))

    def __eq__(self, value: object) -> Formula:  # type: ignore[override]
        return self.eq(self._value(value))

    def __ne__(self, value: object) -> Formula:  # type: ignore[override]
        return self.ne(self._value(value))

    def set(self, value: Term) -> Assign:
        """The effect ``loc(c) := value``."""
        return Assign(self.var.name, self.args, self._value(value))

    def __str__(self) -> str:
        return str(Atom(self.var.name, self.args))


@dataclass(frozen=True, eq=False)
class Counter:
    """``balls(b) ∈ 0..max``: a bounded whole number, stored in binary (one atom per bit).
    Calling it gives a term: ``balls(b) >= 2``, ``balls(b).eq(0)``, ``balls(b).incr()``."""

    name: str
    params: tuple[Var, ...]
    max: int
    observability: Observability
    types: TypeHierarchy | None = field(default=None, repr=False)

    def __call__(self, *args: Term) -> CounterTerm:
        _check_args("counter", self.name, self.params, args, self.types)
        return CounterTerm(self, tuple(args))


class CounterTerm(ValueTerm):
    """``balls(b)``: compare it with a number (a formula) or change it (an effect)."""

    __slots__ = ("args", "counter")
    __hash__ = None  # type: ignore[assignment]  # == builds a formula

    def __init__(self, counter: Counter, args: tuple[Term, ...]) -> None:
        self.counter, self.args = counter, args

    def _k(self, k: object) -> int:
        if isinstance(k, bool) or not isinstance(k, int):
            raise DomainError(f"counter {self}: compare it with a whole number, not {k!r}")
        return k

    def _cmp(self, op: str, k: object) -> Formula:
        return Cmp(self.counter.name, self.args, op, self._k(k))

    def eq(self, value: Term | int) -> Formula:
        """``balls(b) = k``."""
        return self._cmp("==", value)

    def ne(self, value: Term | int) -> Formula:
        """``balls(b) != k``."""
        return self._cmp("!=", value)

    def __eq__(self, k: object) -> Formula:  # type: ignore[override]
        return self._cmp("==", k)

    def __ne__(self, k: object) -> Formula:  # type: ignore[override]
        return self._cmp("!=", k)

    def __lt__(self, k: object) -> Formula:
        return self._cmp("<", k)

    def __le__(self, k: object) -> Formula:
        return self._cmp("<=", k)

    def __gt__(self, k: object) -> Formula:
        return self._cmp(">", k)

    def __ge__(self, k: object) -> Formula:
        return self._cmp(">=", k)

    def set(self, k: int) -> Assign:
        """The effect ``balls(b) := k`` (0 <= k <= max)."""
        k = self._k(k)
        if not 0 <= k <= self.counter.max:
            raise DomainError(f"counter {self}: {k} is out of its range 0..{self.counter.max}")
        return Assign(self.counter.name, self.args, k)

    def incr(self, n: int = 1) -> Assign:
        """The effect ``balls(b) += n``, saturating at ``max``."""
        if self._k(n) <= 0:
            raise DomainError(f"counter {self}: incr takes a positive number, not {n}")
        return Assign(self.counter.name, self.args, None, n)

    def decr(self, n: int = 1) -> Assign:
        """The effect ``balls(b) -= n``, saturating at 0."""
        if self._k(n) <= 0:
            raise DomainError(f"counter {self}: decr takes a positive number, not {n}")
        return Assign(self.counter.name, self.args, None, -n)

    def __str__(self) -> str:
        return str(Atom(self.counter.name, self.args))


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


@dataclass(frozen=True)
class Assign:
    """``v(args) := value`` for a state variable, ``c(args) := k`` for a counter, or, with
    ``value`` None, ``c(args) += delta`` (saturating at 0 and the counter's max)."""

    name: str
    args: tuple[Term, ...]
    value: Term | int | None
    delta: int = 0

    def __str__(self) -> str:
        head = Atom(self.name, self.args)
        if self.value is None:
            return f"{head} {'+' if self.delta > 0 else '-'}= {abs(self.delta)}"
        return f"{head} := {self.value if isinstance(self.value, int) else term_str(self.value)}"


Effect = Atom | Not | When | ForEach | Assign
"""An atom is added, ``~atom`` is deleted, an :class:`Assign` sets a variable or a counter."""


def assign(term: VarTerm | CounterTerm, value: Term | int) -> Assign:
    """The effect ``term := value``: ``assign(loc(c), box1)``, ``assign(balls(b), 0)``."""
    if isinstance(term, VarTerm):
        if isinstance(value, int):
            raise DomainError(f"variable {term}: a value is an object, not {value!r}")
        return term.set(value)
    if isinstance(term, CounterTerm):
        if not isinstance(value, int):
            raise DomainError(f"counter {term}: a value is a whole number, not {value!r}")
        return term.set(value)
    raise DomainError(f"assign: {term!r} is neither a state variable nor a counter term")


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
    types: TypeHierarchy | None = field(default=None, repr=False)
    # what the action holds while it runs: parameters or constants (docs/concurrent.md, C3 c)
    resources: tuple[Term, ...] = ()

    def __call__(self, *args: Term) -> TaskRef:
        _check_args("action", self.name, self.params, args, self.types)
        return TaskRef(self.name, tuple(args))


@dataclass(frozen=True, eq=False)
class AbstractTask:
    name: str
    params: tuple[Var, ...]
    done: Formula | None
    types: TypeHierarchy | None = field(default=None, repr=False)

    def __call__(self, *args: Term) -> TaskRef:
        _check_args("task", self.name, self.params, args, self.types)
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
    types: TypeHierarchy | None = field(default=None, repr=False)  # the domain's, for checks

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
        resources: Iterable[Term] = (),
    ) -> Operator:
        """Declare a primitive action of this agent. ``resources`` (parameters, or names)
        are what it holds while it runs: in joint steps two actions that hold a common one
        are never done together (docs/concurrent.md, C3 c)."""
        self._fresh(name)
        if cost <= 0:
            raise DomainError(f"{self.agent}.{name}: cost must be positive, got {cost}")
        held = tuple(resources)
        for x in held:
            if isinstance(x, Var) and x not in params:
                raise DomainError(f"action {name}: resource {x} is not one of its parameters; "
                                  "name a parameter or a constant")
            if not isinstance(x, Var | str):
                raise DomainError(f"action {name}: resource {x!r} is neither a parameter nor "
                                  "a name")
        op = Operator(name, tuple(params), pre, tuple(effects), cost, done, self.types, held)
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
        t = AbstractTask(name, tuple(params), done, self.types)
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
                          list(self.methods), self.types)


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


def _named(params: Sequence[Var | str]) -> tuple[Var, ...]:
    """Parameters, a type name standing for a parameter named after it (``box``, ``box2``)."""
    out: list[Var] = []
    for p in params:
        if isinstance(p, str):
            n = sum(1 for q in params[:len(out)] if q == p)
            p = Var(p if n == 0 else f"{p}{n + 1}", p)
        if not isinstance(p, Var):
            raise DomainError(f"a parameter is a Var or a type name, not {p!r}")
        out.append(p)
    return tuple(out)


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
        cond = e.arg if isinstance(e, Not) else e
        if isinstance(cond, Is):
            raise DomainError(f"{where}: {e} is a condition, not an effect; to change the "
                              f"variable write {Atom(cond.pred, cond.args[:-1])}.set(value)")
        if isinstance(e, Assign):
            out |= {a for a in (*e.args, e.value) if isinstance(a, Var)}
        elif isinstance(e, Atom):
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


# --- metrics a preference profile may order (docs/concurrent.md, C11) ------------------------

MetricAgent = Literal["robot", "human", "either"]
METRIC_AGENTS: tuple[MetricAgent, ...] = ("robot", "human", "either")
_METRIC_NAME = re.compile(r"[a-z][a-z0-9_]*")


@dataclass(frozen=True, eq=False)
class DomainMetric:
    """A per-branch metric the domain declares (docs/concurrent.md C11, "Metrics a domain
    declares"): along a branch, the number of **steps** in which ``agent`` (``"robot"``,
    ``"human"``, or ``"either"`` of them: a step counts once even when both do) does an
    action of one of the operators ``actions`` while ``when`` holds. ``when`` is a formula
    over the operator's parameters (and constants, quantifiers), read in the true state at
    the step's start, before either action; ``TRUE`` counts every such action.

    A step adds 1 or 0 whatever comes after it, so the metric grows along a branch as the
    built-in ones do and a preference profile may order it with them
    (``[objective.profiles]``)."""

    name: str
    agent: MetricAgent
    actions: tuple[str, ...]
    when: Formula = TRUE
    doc: str = ""

    def agents(self) -> tuple[str, ...]:
        """The agents whose actions count: ``("robot",)``, ``("human",)`` or both."""
        return ("robot", "human") if self.agent == "either" else (self.agent,)

    def declaration(self) -> dict[str, object]:
        """The declaration as a policy file records it (docs/policy-format.md): ``agent``,
        ``actions``, ``when`` (the formula as printed, ``?c`` a parameter; ``"true"``) and
        ``doc``."""
        return {"agent": self.agent, "actions": list(self.actions), "when": str(self.when),
                "doc": self.doc}


# --- the domain ------------------------------------------------------------------------------


class Domain:
    """Types, constants, predicates, co-presence and the three task models M_R, M_H, M_R^H."""

    def __init__(self, name: str, *, robot: str = "R", human: str = "H", doc: str = "") -> None:
        self.name = name
        self.doc = doc
        self.robot_name = robot
        self.human_name = human
        self.types: list[str] = [AGENT_TYPE]
        self.hierarchy = TypeHierarchy()
        self.constants: dict[str, str] = {robot: AGENT_TYPE, human: AGENT_TYPE}
        self.predicates: dict[str, Predicate] = {}
        self.variables: dict[str, StateVariable] = {}
        self.counters: dict[str, Counter] = {}
        self.derived_predicates: dict[str, Derived] = {}
        self.robot = AgentModel(robot, types=self.hierarchy)
        self.human = AgentModel(human, types=self.hierarchy)
        self._robot_seen_by_human: AgentModel | None = None
        self.copresence: Formula = TRUE
        self.goal: Formula | None = None
        # metrics a preference profile may order beside the built-in ones (C11)
        self.metrics: dict[str, DomainMetric] = {}

    @property
    def robot_seen_by_human(self) -> AgentModel:
        """M_R^H, the human's estimate of the robot's model (defaults to M_R itself)."""
        return self._robot_seen_by_human or self.robot

    @robot_seen_by_human.setter
    def robot_seen_by_human(self, model: AgentModel) -> None:
        self._robot_seen_by_human = model

    def type(self, name: str, parent: str | None = None) -> str:
        """Declare a type; with ``parent`` (declared before), every object of this type is
        also one of the parent's: ``d.type("cube", parent="object")``. The built-in type
        ``agent`` may be given a parent once: ``d.type("agent", parent="place")``."""
        if parent is not None:
            if parent not in self.types:
                raise DomainError(f"type {name}: unknown parent type {parent!r}; declare it "
                                  f"first with d.type({parent!r})")
            if self.hierarchy.is_sub(parent, name):
                raise DomainError(f"type {name}: {parent} is {self.hierarchy.a(parent)}, so "
                                  f"{name} cannot be a subtype of it")
        if name in self.types:
            if name == AGENT_TYPE and parent is not None and name not in self.hierarchy.parent:
                self.hierarchy.parent[name] = parent
                return name
            raise DomainError(f"type {name!r} is declared twice")
        self.types.append(name)
        if parent is not None:
            self.hierarchy.parent[name] = parent
        return name

    def is_subtype(self, t: str, of: str) -> bool:
        """Whether type ``t`` is ``of`` or one of its subtypes."""
        return self.hierarchy.is_sub(t, of)

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
        pred = Predicate(name, tuple(params), obs, self.hierarchy)
        self.predicates[name] = pred
        return pred

    def variable(self, name: str, *params: Var | str, values: str | Var,
                 observability: Observability | None = None) -> StateVariable:
        """Declare a finite-domain state variable: ``loc(c)`` has exactly one value among the
        objects of type ``values`` (subtypes included) in every state. ``values`` may be a
        typed ``Var`` naming the value, for a visibility condition that depends on it:
        ``d.variable("pasta_at", values=p, observability=observable(at(H, p)))`` (the human
        sees whether the pasta is where it stands). Observable always unless told otherwise. A
        parameter may be given by its type alone (``d.variable("loc", Cube, values=Place)``):
        it is then named after the type."""
        self._fresh_pred(name)
        params = _named(params)
        value = values if isinstance(values, Var) else Var("value", values)
        if not isinstance(value.type, str) or value.type not in self.types:
            raise DomainError(f"variable {name}: unknown value type {value.type!r}")
        for p in params:
            if p.type not in self.types:
                raise DomainError(f"variable {name}: unknown type {p.type!r}")
        if value in params:
            raise DomainError(f"variable {name}: the value {value.name} is also a parameter")
        obs = observability or observable()
        _check_scope(f"visibility of {name}", {*params, value}, [obs.when])
        v = StateVariable(name, tuple(params), value, obs, self.hierarchy)
        self.variables[name] = v
        return v

    def counter(self, name: str, *params: Var | str, max: int,
                observability: Observability | None = None) -> Counter:
        """Declare a bounded counter ``balls(b) ∈ 0..max`` (stored in binary, one atom per
        bit); 0 unless the problem's ``[init]`` says otherwise. Observable always unless told
        otherwise; the visibility condition may use the counter's parameters. A parameter may be
        given by its type alone (``d.counter("balls", Box, max=3)``)."""
        self._fresh_pred(name)
        params = _named(params)
        if isinstance(max, bool) or not isinstance(max, int) or max < 1:
            raise DomainError(f"counter {name}: max must be a whole number >= 1, got {max!r}")
        for p in params:
            if p.type not in self.types:
                raise DomainError(f"counter {name}: unknown type {p.type!r}")
        obs = observability or observable()
        _check_scope(f"visibility of {name}", set(params), [obs.when])
        c = Counter(name, tuple(params), max, obs, self.hierarchy)
        self.counters[name] = c
        return c

    def derived(self, name: str, params: Sequence[Var], body: Formula) -> Derived:
        self._fresh_pred(name)
        _check_scope(f"derived predicate {name}", set(params), [body])
        d = Derived(name, tuple(params), body, self.hierarchy)
        self.derived_predicates[name] = d
        return d

    def metric(self, name: str, *, agent: MetricAgent, actions: Iterable[str | Operator],
               when: Formula = TRUE, doc: str = "") -> DomainMetric:
        """Declare a metric a preference profile may name (docs/concurrent.md C11, "Metrics
        a domain declares"): the steps in which ``agent`` (``"robot"``, ``"human"`` or
        ``"either"``) does an action of one of ``actions`` (operator names, or the operators
        themselves, declared before) while ``when`` holds in the state at the step's start.
        ``when`` may use the parameters every one of those operators has (the same ``Var``)::

            d.metric("shared_taken", agent="robot", actions=[pick], when=zone(c, "shared"),
                     doc="cubes the robot takes from the shared zone")

        The name is its one meaning: lower case letters, digits and ``_``, not a built-in
        metric's (``makespan``, ``human_end``, ``human_effort``, ``effort``,
        ``communications``), declared once."""
        where = f"metric {name!r}"
        if not isinstance(name, str) or not _METRIC_NAME.fullmatch(name):
            raise DomainError(f"{where}: a metric's name is lower case letters, digits and _, "
                              "starting with a letter")
        if name in {m.value for m in Metric}:
            raise DomainError(f"{where}: {name} is a built-in metric; give yours another name")
        if name in self.metrics:
            raise DomainError(f"{where} is declared twice")
        if agent not in METRIC_AGENTS:
            raise DomainError(f"{where}: agent {agent!r}; use one of "
                              + ", ".join(repr(a) for a in METRIC_AGENTS))
        if not isinstance(when, Formula):
            raise DomainError(f"{where}: when is {when!r}, not a formula")
        if not isinstance(doc, str):
            raise DomainError(f"{where}: doc is {doc!r}, not a string")
        names: list[str] = []
        for a in actions:
            n = a.name if isinstance(a, Operator) else a
            if not isinstance(n, str):
                raise DomainError(f"{where}: {a!r} is neither an operator nor its name")
            if n not in names:
                names.append(n)
        if not names:
            raise DomainError(f"{where}: name at least one action it counts")
        m = DomainMetric(name, agent, tuple(names), when, doc)
        models = [self.robot if who == "robot" else self.human for who in m.agents()]
        for n in names:
            ops = [model.operators[n] for model in models if n in model.operators]
            if not ops:
                raise DomainError(f"{where}: {n!r} is not an action of "
                                  f"{' or '.join(model.agent for model in models)}; declare "
                                  "the action first")
            for op in ops:
                _check_scope(f"{where} on {op.name}", set(op.params), [when])
        self.metrics[name] = m
        return m

    def metrics_of(self, agent: str, action: str) -> list[DomainMetric]:
        """C11: the declared metrics that count ``agent``'s (``"robot"`` or ``"human"``)
        actions of the operator ``action``."""
        return [m for m in self.metrics.values() if agent in m.agents() and action in m.actions]

    def _fresh_pred(self, name: str) -> None:
        if (name in self.predicates or name in self.derived_predicates
                or name in self.variables or name in self.counters):
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
            if isinstance(f, Atom | Cmp):
                yield from ((where, a) for a in f.args if isinstance(a, Var))
            elif isinstance(f, Assign):
                yield from ((where, a) for a in (*f.args, f.value) if isinstance(a, Var))
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
        valued: list[StateVariable | Counter] = [*self.variables.values(),
                                                  *self.counters.values()]
        for sv in valued:
            yield from of(f"visibility of {sv.name}", sv.observability.when)
        for dm in self.metrics.values():
            yield from of(f"metric {dm.name}", dm.when)
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
