"""A method's bindings (docs/semantics.md §1, "Grounding"): the values of its own parameters
for which no conjunct of its precondition folds to false before any action, enumerated in the
order of the product of their types' objects.

A conjunct is read as soon as its variables are bound. A positive literal of a static or
shrinking predicate (true only where the initial state says so) is not read but *offers*
values: an index of the initial facts gives, for the values of its other arguments, those its
variable takes there. The parameter it binds last takes only those; each parameter it names
before that takes only the values some fact has at its place with what is bound by then (the
facts' projection), since any other leaves the last one nothing to take. A fluent literal,
which never folds to false, is left to the whole precondition.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence

from .domain import Method
from .formula import FALSE, And, Atom, Formula, Term, Var, free_vars

Gen = tuple[str, tuple[int, ...], tuple[int, ...], tuple[Term, ...]]
"""A positive static or shrinking atom offering the values of one variable: (predicate, the
variable's positions, the positions whose values are known by then, the terms at those)."""

Plan = tuple[list[list[Formula]], list[list[Gen]]]
"""How to bind a method's parameters: per level (0: the task's arguments; ``i + 1``: the
method's ``i``-th parameter), the conjuncts read there and the atoms offering its values."""

_NONE: frozenset[str] = frozenset()


class Facts:
    """The initial state's facts as the bindings read them: per offering atom, its variable's
    values by the values of its known arguments; per type, each object's place in the type's
    list (both built once, when first asked)."""

    def __init__(self, init: Iterable[tuple[str, tuple[str, ...]]], arity: Mapping[str, int],
                 objects: Mapping[str, Sequence[str]]) -> None:
        self._init = tuple(init)
        self._arity = arity
        self._objects = objects
        self._offer: dict[Gen, dict[tuple[str, ...], frozenset[str]]] = {}
        self._positions: dict[str, dict[str, int]] = {}

    def offers(self, gen: Gen) -> dict[tuple[str, ...], frozenset[str]]:
        """§1: return, for the static or shrinking atom of ``gen``, the values its variable takes
        in the initial state's facts, by the values of its known arguments; an argument
        neither the variable nor known takes any value (it is projected out)."""
        index = self._offer.get(gen)
        if index is None:
            pred, at_v, fixed, _ = gen
            arity = self._arity[pred]
            found: dict[tuple[str, ...], set[str]] = {}
            for n, fact in self._init:
                if n == pred and len(fact) == arity and len({fact[k] for k in at_v}) == 1:
                    found.setdefault(tuple(fact[k] for k in fixed), set()).add(fact[at_v[0]])
            self._offer[gen] = index = {k: frozenset(x) for k, x in found.items()}
        return index

    def positions(self, type_: str) -> dict[str, int]:
        """Return each object of ``type_`` (its subtypes' included) by its place in the
        type's list, the order bindings follow."""
        r = self._positions.get(type_)
        if r is None:
            r = self._positions[type_] = {o: k for k, o in enumerate(self._objects[type_])}
        return r

    def objects(self, type_: str) -> Sequence[str]:
        """Return the objects of ``type_`` (its subtypes' included), in order."""
        return self._objects[type_]


def binding_plan(method: Method, bound: set[Var], factual: set[str],
                 never_false: Callable[[Formula], bool]) -> Plan:
    """§1: return how to bind ``method``'s own parameters (:data:`Plan`): each conjunct of
    its precondition at the level of the parameter that binds its last variable (a conjunct
    with a variable neither ``bound`` by the task nor a parameter is left to the whole
    precondition). A positive literal of a ``factual`` predicate (static or shrinking)
    offers values instead (the module's docstring), at each level that binds one of its
    variables; a conjunct that is ``never_false`` (a fluent literal) rules no binding out and
    is left to the whole precondition."""
    parts = list(method.pre.args) if isinstance(method.pre, And) else [method.pre]
    checks: list[list[Formula]] = [[] for _ in range(len(method.params) + 1)]
    gens: list[list[Gen]] = [[] for _ in range(len(method.params) + 1)]
    where = {v: i + 1 for i, v in enumerate(method.params)}
    for c in parts:
        try:
            vs = free_vars(c)
        except TypeError:  # a constant: the whole precondition reads it
            continue
        if any(v not in where and v not in bound for v in vs):
            continue
        at = max((where.get(v, 0) for v in vs), default=0)
        if at and type(c) is Atom and c.pred in factual:
            for lv in sorted({where[v] for v in vs if v in where}):
                v = method.params[lv - 1]
                at_v = tuple(k for k, a in enumerate(c.args) if a == v)
                fixed = tuple(k for k, a in enumerate(c.args)
                              if a != v and (not isinstance(a, Var) or where.get(a, 0) < lv))
                gens[lv].append((c.pred, at_v, fixed, tuple(c.args[k] for k in fixed)))
        elif not never_false(c):
            checks[at].append(c)
    return checks, gens


def bindings(method: Method, tb: Mapping[Var, str], plan: Plan, facts: Facts,
             ground_f: Callable[[Formula, Mapping[Var, str]], Formula],
             met: Callable[[], None]) -> list[tuple[str, ...]]:
    """§1: return the bindings of ``method``'s own parameters (the task's arguments ``tb``
    bound), in the order of the product of their types' objects, without those a conjunct
    read by ``plan`` grounds (``ground_f``) to false for; ``met`` is called once per value
    tried (a limit's check). Depth first, one iterator of values per parameter::

        level 0: the values offered for the first parameter
        take the current level's next value; if the conjuncts it binds hold:
            the last parameter: keep the binding; else go down a level, with the
                values offered for the next parameter given those bound above
        a level out of values: go back up one"""
    checks, gens = plan
    b = dict(tb)
    if any(ground_f(c, b) == FALSE for c in checks[0]):
        return []
    params = method.params
    n = len(params)
    if not n:
        return [()]
    domains = [facts.objects(v.type) for v in params]
    positions = [facts.positions(v.type) for v in params]

    def offered(i: int) -> Iterator[str]:
        gl = gens[i + 1]
        if not gl:
            return iter(domains[i])
        sets = [facts.offers(gen).get(tuple(b[a] if isinstance(a, Var) else a
                                            for a in gen[3]), _NONE) for gen in gl]
        least = min(sets, key=len)
        # the fewest values offered, in the order of the type's objects, kept where every
        # other atom offers them too
        at = positions[i]
        return iter([o for o in sorted((o for o in least if o in at), key=at.__getitem__)
                     if all(o in x for x in sets)])

    out: list[tuple[str, ...]] = []
    vals: list[str] = [""] * n
    levels = [offered(0)]
    while levels:
        i = len(levels) - 1
        v, cs = params[i], checks[i + 1]
        for o in levels[i]:
            met()
            b[v] = o
            if not cs or all(ground_f(c, b) != FALSE for c in cs):
                vals[i] = o
                if i + 1 == n:
                    out.append(tuple(vals))
                else:
                    levels.append(offered(i + 1))
                    break
        else:
            b.pop(v, None)
            levels.pop()
    return out


__all__ = ["Facts", "Gen", "Plan", "binding_plan", "bindings"]
