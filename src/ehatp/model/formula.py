"""Formulas as data: a small immutable AST the planner can inspect, ground and compile.

Domains build formulas with ordinary Python operators (``&``, ``|``, ``~``) on atoms made by
calling predicates; nothing here is an opaque callback. Grounding substitutes parameters,
expands quantifiers over the typed objects and folds static atoms; what is left is compiled
once into a closure over an integer bitset state.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

from mypy_extensions import mypyc_attr

# --- terms -----------------------------------------------------------------------------------


def _reduce(x: Any) -> tuple[type, tuple[Any, ...]]:
    """How a frozen dataclass here pickles and copies: its class called with its fields. (The
    compiled core's default would assign each field after creating the object, which a
    frozen class refuses: docs/compiled.md.)"""
    return type(x), tuple(getattr(x, f.name) for f in fields(x))


@dataclass(frozen=True, slots=True)
class Var:
    """A typed variable (operator/method parameter or quantified variable)."""

    name: str
    type: str

    def __str__(self) -> str:
        return f"?{self.name}"

    def __reduce__(self) -> tuple[Any, ...]:
        return _reduce(self)


Term = Var | str  # a str is an object name (constant)


def term_str(t: Term) -> str:
    return str(t) if isinstance(t, Var) else t


# --- formulas --------------------------------------------------------------------------------


class Formula:
    """Base class; subclasses are frozen dataclasses."""

    __slots__ = ()

    def __reduce__(self) -> tuple[Any, ...]:
        return _reduce(self)

    def __and__(self, other: Formula) -> Formula:
        return conj(self, other)

    def __or__(self, other: Formula) -> Formula:
        return disj(self, other)

    def __invert__(self) -> Formula:
        return Not(self)

    def __rshift__(self, other: Formula) -> Formula:  # implication, a >> b
        return disj(Not(self), other)


@dataclass(frozen=True, slots=True)
class Atom(Formula):
    pred: str
    args: tuple[Term, ...]

    def __str__(self) -> str:
        if not self.args:
            return self.pred
        return f"{self.pred}({', '.join(term_str(a) for a in self.args)})"

    def __invert__(self) -> Not:  # narrower than Formula's, so ``~atom`` types as an effect
        return Not(self)


@dataclass(frozen=True, slots=True)
class Eq(Formula):
    left: Term
    right: Term

    def __str__(self) -> str:
        return f"{term_str(self.left)} = {term_str(self.right)}"


@dataclass(frozen=True, slots=True)
class Is(Atom):
    """``v(args) = value``: a finite-domain state variable has this value. It is the atom
    ``v(args, value)`` of the variable's *value view* (the value is the last argument), so
    everything that reads atoms reads it; it prints as the domain writes it."""

    def __str__(self) -> str:
        head = Atom(self.pred, self.args[:-1])
        return f"{head} = {term_str(self.args[-1])}"


CMP_OPS = ("==", "!=", "<", "<=", ">", ">=")


@dataclass(frozen=True, slots=True)
class Cmp(Formula):
    """``c(args) op k``: a bounded-integer counter compared with a whole number."""

    counter: str
    args: tuple[Term, ...]
    op: str
    k: int

    def __str__(self) -> str:
        head = Atom(self.counter, self.args)
        return f"{head} {'=' if self.op == '==' else self.op} {self.k}"

    def holds(self, value: int) -> bool:
        """Whether ``value op k``."""
        op, k = self.op, self.k
        return {"==": value == k, "!=": value != k, "<": value < k, "<=": value <= k,
                ">": value > k, ">=": value >= k}[op]


@dataclass(frozen=True, slots=True)
class Not(Formula):
    arg: Formula

    def __str__(self) -> str:
        if isinstance(self.arg, Eq):
            return f"{term_str(self.arg.left)} != {term_str(self.arg.right)}"
        if isinstance(self.arg, Is):
            return str(self.arg).replace(" = ", " != ", 1)
        return f"not {_paren(self.arg)}"


@dataclass(frozen=True, slots=True)
class And(Formula):
    args: tuple[Formula, ...]

    def __str__(self) -> str:
        return " and ".join(_paren(a) for a in self.args) if self.args else "true"


@dataclass(frozen=True, slots=True)
class Or(Formula):
    args: tuple[Formula, ...]

    def __str__(self) -> str:
        return " or ".join(_paren(a) for a in self.args) if self.args else "false"


@dataclass(frozen=True, slots=True)
class Exists(Formula):
    vars: tuple[Var, ...]
    body: Formula

    def __str__(self) -> str:
        vs = ", ".join(f"{v.name}: {v.type}" for v in self.vars)
        return f"exists {vs}: {_paren(self.body)}"


@dataclass(frozen=True, slots=True)
class Forall(Formula):
    vars: tuple[Var, ...]
    body: Formula

    def __str__(self) -> str:
        vs = ", ".join(f"{v.name}: {v.type}" for v in self.vars)
        return f"forall {vs}: {_paren(self.body)}"


TRUE: Formula = And(())
FALSE: Formula = Or(())


def _paren(f: Formula) -> str:
    return f"({f})" if isinstance(f, And | Or | Exists | Forall) and str(f) not in (
        "true",
        "false",
    ) else str(f)


def conj(*fs: Formula) -> Formula:
    out: list[Formula] = []
    for f in fs:
        if isinstance(f, And):
            out.extend(f.args)
        else:
            out.append(f)
    return out[0] if len(out) == 1 else And(tuple(out))


def disj(*fs: Formula) -> Formula:
    out: list[Formula] = []
    for f in fs:
        if isinstance(f, Or):
            out.extend(f.args)
        else:
            out.append(f)
    return out[0] if len(out) == 1 else Or(tuple(out))


def exists(vars: Var | Sequence[Var], body: Formula) -> Formula:
    return Exists(tuple([vars] if isinstance(vars, Var) else vars), body)


def forall(vars: Var | Sequence[Var], body: Formula) -> Formula:
    return Forall(tuple([vars] if isinstance(vars, Var) else vars), body)


@mypyc_attr(allow_interpreted_subclasses=True)  # the DSL's VarTerm, CounterTerm (compiled core)
class ValueTerm:
    """A state-variable or counter term (``loc(c)``, ``balls(b)``): what ``eq`` compares
    with a value (see :mod:`ehatp.model.domain`)."""

    __slots__ = ()

    def eq(self, value: Term | int) -> Formula:
        raise NotImplementedError


def eq(a: Term | ValueTerm, b: Term | int) -> Formula:
    """``a = b``: two objects (a parameter and an object, or two parameters), or a state
    variable and a value (``eq(loc(c), mt)``), or a counter and a number (``eq(balls(b), 2)``)."""
    if isinstance(a, ValueTerm):
        return a.eq(b)
    if isinstance(b, int):
        raise TypeError(f"eq({term_str(a)}, {b}): a number compares only with a counter")
    return Eq(a, b)


# --- traversal -------------------------------------------------------------------------------


def free_vars(f: Formula) -> set[Var]:
    if isinstance(f, Atom | Cmp):
        return {a for a in f.args if isinstance(a, Var)}
    if isinstance(f, Eq):
        return {a for a in (f.left, f.right) if isinstance(a, Var)}
    if isinstance(f, Not):
        return free_vars(f.arg)
    if isinstance(f, And | Or):
        out: set[Var] = set()
        for a in f.args:
            out |= free_vars(a)
        return out
    if isinstance(f, Exists | Forall):
        return free_vars(f.body) - set(f.vars)
    raise TypeError(f"not a formula: {f!r}")


def atoms_of(f: Formula) -> Iterable[Atom]:
    if isinstance(f, Atom):
        yield f
    elif isinstance(f, Not):
        yield from atoms_of(f.arg)
    elif isinstance(f, And | Or):
        for a in f.args:
            yield from atoms_of(a)
    elif isinstance(f, Exists | Forall):
        yield from atoms_of(f.body)


# --- grounding -------------------------------------------------------------------------------

AtomFn = Callable[[str, tuple[str, ...]], "bool | int | Formula"]
"""Maps a ground atom to a static truth value, a fluent index (int) or a replacement formula."""


@dataclass(frozen=True, slots=True)
class GAtom(Formula):
    """A ground fluent atom, by index in the grounded problem's atom table."""

    index: int
    name: str

    def __str__(self) -> str:
        return self.name


@dataclass(frozen=True, slots=True)
class GTest(Formula):
    """A ground test over several fluent atoms that reads as one condition, e.g. a counter
    comparison ``balls(b1) >= 2`` over the counter's bits: ``body`` is what it compiles to,
    ``name`` how it prints. It is never split into its atoms (an ``ask`` asks it whole)."""

    body: Formula
    name: str

    def __str__(self) -> str:
        return self.name


def ground(
    f: Formula,
    binding: Mapping[Var, str],
    objects: Mapping[str, Sequence[str]],
    atom: Callable[[str, tuple[str, ...]], Formula],
    compare: Callable[[str, tuple[str, ...], str, int], Formula] | None = None,
) -> Formula:
    """Substitute ``binding``, expand quantifiers over ``objects`` (by type) and let ``atom``
    turn each ground atom into TRUE, FALSE, a GAtom or a (ground) formula, and ``compare``
    each ground counter comparison (counter, args, op, k); then simplify. (A plain recursive
    function: a nested one would be a reference cycle per call, left to the cycle collector.)"""
    return _ground(f, binding, objects, atom, compare)


def _term(t: Term, b: Mapping[Var, str]) -> str:
    if isinstance(t, Var):
        return b[t]
    return t


def _ground(f: Formula, b: Mapping[Var, str], objects: Mapping[str, Sequence[str]],
            atom: Callable[[str, tuple[str, ...]], Formula],
            compare: Callable[[str, tuple[str, ...], str, int], Formula] | None) -> Formula:
    if isinstance(f, Atom):
        return atom(f.pred, tuple(_term(a, b) for a in f.args))
    if isinstance(f, Eq):
        return TRUE if _term(f.left, b) == _term(f.right, b) else FALSE
    if isinstance(f, Not):
        return negate(_ground(f.arg, b, objects, atom, compare))
    if isinstance(f, And):
        return simplify_and([_ground(a, b, objects, atom, compare) for a in f.args])
    if isinstance(f, Or):
        return simplify_or([_ground(a, b, objects, atom, compare) for a in f.args])
    if isinstance(f, Exists | Forall):
        parts = [_ground(f.body, {**b, **dict(zip(f.vars, vals, strict=True))}, objects, atom,
                         compare)
                 for vals in product([objects[v.type] for v in f.vars])]
        return simplify_or(parts) if isinstance(f, Exists) else simplify_and(parts)
    if isinstance(f, Cmp):
        if compare is None:
            raise TypeError(f"no counters here: {f}")
        return compare(f.counter, tuple(_term(a, b) for a in f.args), f.op, f.k)
    if isinstance(f, GAtom | GTest):
        return f
    raise TypeError(f"not a formula: {f!r}")


def product(domains: Sequence[Sequence[str]]) -> Iterable[tuple[str, ...]]:
    """Every tuple with one value from each domain, in order."""
    if not domains:
        yield ()
        return
    for head in domains[0]:
        for tail in product(domains[1:]):
            yield (head, *tail)


def negate(f: Formula) -> Formula:
    if f == TRUE:
        return FALSE
    if f == FALSE:
        return TRUE
    if isinstance(f, Not):
        return f.arg
    return Not(f)


def simplify_and(parts: Iterable[Formula]) -> Formula:
    """The conjunction of ``parts``: FALSE if one is, TRUE ones left out, nested conjunctions
    flattened, each conjunct once (in the order first met; a dict, not a list, so that the
    forall over a few hundred objects stays linear)."""
    out: dict[Formula, None] = {}
    for p in parts:
        if p == FALSE:
            return FALSE
        if p == TRUE:
            continue
        for q in p.args if isinstance(p, And) else (p,):
            out[q] = None
    return next(iter(out)) if len(out) == 1 else And(tuple(out))


def simplify_or(parts: Iterable[Formula]) -> Formula:
    """The disjunction of ``parts``, as :func:`simplify_and` builds a conjunction."""
    out: dict[Formula, None] = {}
    for p in parts:
        if p == TRUE:
            return TRUE
        if p == FALSE:
            continue
        for q in p.args if isinstance(p, Or) else (p,):
            out[q] = None
    return next(iter(out)) if len(out) == 1 else Or(tuple(out))


def value_in(digits: Sequence[Formula], allowed: set[int], top: int) -> Formula:
    """Return a formula over a counter's ``digits`` (its atoms, lowest bit first) that holds
    when its value is in ``allowed``; values above ``top`` never occur, so they may go either
    way (Shannon expansion from the highest bit, whole halves decided at once)."""
    def go(j: int, base: int) -> Formula | None:  # values base .. base + 2**(j+1) - 1
        vals = [v for v in range(base, base + (2 << j if j >= 0 else 1)) if v <= top]
        if not vals:
            return None
        inside = [v in allowed for v in vals]
        if all(inside):
            return TRUE
        if not any(inside):
            return FALSE
        low, high = go(j - 1, base), go(j - 1, base + (1 << j))
        if high is None or high == low:
            return low
        assert low is not None
        b = digits[j]
        return simplify_or([simplify_and([b, high]), simplify_and([negate(b), low])])

    out = go(len(digits) - 1, 0)
    return FALSE if out is None else out


def ground_atoms(f: Formula) -> set[int]:
    """Indices of the fluent atoms a ground formula mentions."""
    if isinstance(f, GAtom):
        return {f.index}
    if isinstance(f, GTest):
        return ground_atoms(f.body)
    if isinstance(f, Not):
        return ground_atoms(f.arg)
    if isinstance(f, And | Or):
        out: set[int] = set()
        for a in f.args:
            out |= ground_atoms(a)
        return out
    return set()


# --- compilation -----------------------------------------------------------------------------

StateFn = Callable[[int], bool]


def compile_ground(f: Formula) -> StateFn:
    """Compile a ground formula into ``fn(state_bits) -> bool``.

    Conjunctions of literals (the common case) become two mask tests; the rest is generated
    Python source, compiled once, so evaluation in the search loop is a single call.
    """
    if f == TRUE:
        return _true
    if f == FALSE:
        return _false
    lits = _literals(f)
    if lits is not None:
        pos, neg = lits
        if not neg:
            return lambda s: s & pos == pos
        if not pos:
            return lambda s: not s & neg
        return lambda s: s & pos == pos and not s & neg
    src = f"lambda s: {_py(f)}"
    fn: StateFn = eval(compile(src, "<ehatp formula>", "eval"))  # noqa: S307 - generated code
    return fn


def _true(s: int) -> bool:
    return True


def _false(s: int) -> bool:
    return False


def _literals(f: Formula) -> tuple[int, int] | None:
    pos = neg = 0
    for p in f.args if isinstance(f, And) else (f,):
        if isinstance(p, GAtom):
            pos |= 1 << p.index
        elif isinstance(p, Not) and isinstance(p.arg, GAtom):
            neg |= 1 << p.arg.index
        else:
            return None
    return pos, neg


def _py(f: Formula) -> str:
    if isinstance(f, GAtom):
        return f"(s >> {f.index} & 1 == 1)"
    if isinstance(f, GTest):
        return _py(f.body)
    if isinstance(f, Not):
        return f"(not {_py(f.arg)})"
    if isinstance(f, And):
        return "(" + " and ".join(_py(a) for a in f.args) + ")" if f.args else "True"
    if isinstance(f, Or):
        return "(" + " or ".join(_py(a) for a in f.args) + ")" if f.args else "False"
    raise TypeError(f"formula is not ground: {f}")


def substitute(f: Formula, binding: Mapping[Var, str]) -> Formula:
    """Replace bound variables by object names, keeping the formula's shape (for display)."""

    def t(x: Term) -> Term:
        return binding.get(x, x) if isinstance(x, Var) else x

    if isinstance(f, Atom):  # an Is stays an Is
        return type(f)(f.pred, tuple(t(a) for a in f.args))
    if isinstance(f, Cmp):
        return Cmp(f.counter, tuple(t(a) for a in f.args), f.op, f.k)
    if isinstance(f, Eq):
        return Eq(t(f.left), t(f.right))
    if isinstance(f, Not):
        return Not(substitute(f.arg, binding))
    if isinstance(f, And):
        return And(tuple(substitute(a, binding) for a in f.args))
    if isinstance(f, Or):
        return Or(tuple(substitute(a, binding) for a in f.args))
    if isinstance(f, Exists | Forall):
        inner = {k: v for k, v in binding.items() if k not in f.vars}
        return type(f)(f.vars, substitute(f.body, inner))
    return f
