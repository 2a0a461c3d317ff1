"""Problem instances as data: objects, truth, the human's beliefs, agendas, K, costs, limits;
how atoms and task calls are written (``on(r, mt)``); and the checks a problem passes before it
is planned for (:func:`check_problem`), each mistake one :class:`InputError` line naming the
place and the fix.

Problems are usually written in TOML (``docs/problem-format.md``), read by
:mod:`ehatp.formats.problem_toml` (``ehatp.load``), which runs these same checks with the line
of the file in each message.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from .._deprecated import moved_names
from ..errors import InputError
from .domain import AGENT_TYPE, Domain, article, signature
from .formula import Var
from .options import Communication, HumanModel, Metric, Objective, Steps, known_metrics

Cost = int | Fraction
GroundAtom = tuple[str, tuple[str, ...]]
TaskCall = tuple[str, tuple[str, ...]]


@dataclass(frozen=True)
class Costs:
    inform: Cost = 1
    ask: Cost = 1
    wait: Cost = 1
    pass_: Cost = 1
    actions: Mapping[str, Cost] = field(default_factory=dict)


@dataclass(frozen=True)
class Limits:
    timeout: float | None = None
    max_states: int = 5_000_000
    max_depth: int = 400
    max_memory: int | None = None  # bytes of resident memory; [limits] max_memory = "2G"
    # nested methods allowed before a refinement's first action (docs/semantics.md §1)
    max_decomposition: int = 64
    # search over states up to interchangeable objects (docs/semantics.md §3, "Symmetry")
    symmetry: bool = True
    # ground tasks per agent model grounded before the search; the rest when the refinement
    # reaches them (docs/semantics.md §1, "Grounding")
    ground_ahead: int = 5_000


@dataclass(frozen=True)
class BeliefWorld:
    """One world the human entertains, as differences from the truth."""

    true: frozenset[GroundAtom] = frozenset()
    false: frozenset[GroundAtom] = frozenset()
    robot_agenda: tuple[TaskCall, ...] | None = None


@dataclass
class Problem:
    name: str
    domain: Domain
    objects: dict[str, list[str]]
    init: frozenset[GroundAtom]
    robot_agenda: tuple[TaskCall, ...]
    human_agenda: tuple[TaskCall, ...]
    beliefs: tuple[BeliefWorld, ...] = (BeliefWorld(),)
    starts: str = "human"
    K: int = 2
    costs: Costs = field(default_factory=Costs)
    limits: Limits = field(default_factory=Limits)
    human: HumanModel = field(default_factory=HumanModel)
    communication: Communication = field(default_factory=Communication)
    objective: Objective = field(default_factory=Objective)
    # turns (§4) or joint, compliant steps (docs/concurrent.md)
    steps: Steps = field(default_factory=Steps)
    goal: tuple[tuple[bool, GroundAtom], ...] = ()
    # a fixed opening line of play (move labels); the policy starts where it ends
    after: tuple[str, ...] = ()
    description: str = ""
    source: str = "<python>"
    # one-line notes for the user, e.g. a deprecated spelling in the file
    notes: tuple[str, ...] = ()

    def __repr__(self) -> str:
        """Return a one-line summary: name, domain, objects, K and the file it came from."""
        n = sum(len(v) for v in self.objects.values())
        return (f"Problem({self.name!r}, domain={self.domain.name!r}, objects={n}, "
                f"K={self.K}, source={self.source!r})")

    def all_objects(self) -> dict[str, list[str]]:
        """Objects by type, domain constants included, each list sorted by name; a type's
        list holds its subtypes' objects too."""
        own: dict[str, list[str]] = {t: [] for t in self.domain.types}
        for name, t in self.domain.constants.items():
            own[t].append(name)
        for t, names in self.objects.items():
            own.setdefault(t, []).extend(names)
        out: dict[str, list[str]] = {t: [] for t in own}
        for t, names in own.items():
            for up in (t, *self.domain.hierarchy.ancestors(t)):
                out.setdefault(up, []).extend(names)
        return {t: sorted(v) for t, v in out.items()}

    def check(self) -> None:
        """Check predicates, objects, types, tasks and settings as :func:`ehatp.load` checks a
        file; raise :class:`~ehatp.errors.InputError` on the first mistake."""
        check_problem(self)


# --- parsing helpers -------------------------------------------------------------------------

_CALL = re.compile(r"^\s*([A-Za-z_][\w\-]*)\s*(?:\((.*)\))?\s*$")


def parse_call(text: str) -> tuple[str, tuple[str, ...]] | None:
    """``"on(r, mt)"`` -> ``("on", ("r", "mt"))``; ``"organize"`` -> ``("organize", ())``."""
    m = _CALL.match(text)
    if not m:
        return None
    args = tuple(a.strip() for a in m.group(2).split(",")) if m.group(2) else ()
    if any(not re.fullmatch(r"[\w\-]+", a) for a in args):
        return None
    return m.group(1), args


def parse_fact(text: str) -> tuple[str, tuple[str, ...]] | None:
    """An atom, or a state variable's or counter's value in the *value view*:
    ``"loc(r) = mt"`` and ``"loc(r, mt)"`` are both ``("loc", ("r", "mt"))``,
    ``"balls(b1) = 2"`` is ``("balls", ("b1", "2"))``."""
    head, eq_, value = text.partition("=")
    if not eq_:
        return parse_call(text)
    c = parse_call(head)
    value = value.strip()
    if c is None or not re.fullmatch(r"[\w\-]+", value):
        return None
    return c[0], (*c[1], value)


def fact_str(domain: Domain, name: str, args: Sequence[str]) -> str:
    """A fact as a problem file writes it: ``loc(r) = mt`` for a variable or a counter."""
    if name in domain.variables or name in domain.counters:
        return f"{call_str(name, args[:-1])} = {args[-1]}"
    return call_str(name, args)


def call_str(name: str, args: Sequence[str]) -> str:
    """``on(r, mt)``; a call without arguments is its bare name (``washed``)."""
    return f"{name}({', '.join(args)})" if args else name


def parse_size(v: str | int) -> int:
    """A memory size in bytes: ``"2G"``, ``"512M"``, ``"1.5GB"``, ``"800k"`` (binary units) or
    a whole number of bytes; ValueError when it is none of these or not positive."""
    if isinstance(v, bool) or not isinstance(v, str | int):
        raise ValueError(f"not a memory size: {v!r}")
    if isinstance(v, int):
        n = v
    else:
        m = re.match(r"^\s*(\d+(?:\.\d+)?)\s*([kKmMgGtT]?)(?:i?[bB])?\s*$", v)
        if m is None:
            raise ValueError(f"not a memory size: {v!r}")
        n = int(float(m[1]) * 1024 ** " kmgt".index(m[2].lower() or " "))
    if n <= 0:
        raise ValueError(f"a memory size must be positive, got {v!r}")
    return n


# --- checks ----------------------------------------------------------------------------------


class Checker:
    """Builds the one-line errors of a problem's checks: the file, the place (``[table] key``
    in a file, ``objects cube`` for a problem built in Python), the problem and the fix. The
    TOML reader's subclass adds the line of the file."""

    def __init__(self, path: str) -> None:
        self.path = path

    def err(self, place: str, problem: str, fix: str = "", needle: str | None = None) -> InputError:
        """An error at ``place``; ``needle``, text of the value, lets a file reader find its
        line."""
        return InputError(self.path, place, problem, fix)

    def string(self, place: str, value: Any, example: str) -> str:
        if not isinstance(value, str):
            raise self.err(place, f"expected a string, got {show_value(value)}",
                           f"write e.g. {example}")
        return value

    def strings(self, place: str, value: Any) -> list[str]:
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.err(place, f"expected a list of strings, got {show_value(value)}",
                           'write e.g. ["on(r, mt)"]')
        return list(value)

    def number(self, place: str, value: Any, *, positive: bool = True) -> Cost:
        if isinstance(value, bool) or not isinstance(value, int | float | Fraction):
            raise self.err(place, f"expected a number, got {show_value(value)}",
                           "write e.g. 1 or 2.5")
        if isinstance(value, float) and not math.isfinite(value):
            raise self.err(place, f"expected a finite number, got {value}",
                           "write e.g. 1 or 2.5")
        if positive and value <= 0:
            raise self.err(place, f"must be positive, got {value}",
                           "give a number greater than 0 (costs must be positive)")
        return value if isinstance(value, int | Fraction) else Fraction(str(value))


def show_value(value: Any) -> str:
    """A value as the user wrote it, briefly (a whole table would not fit on one line)."""
    text = repr(value)
    if len(text) > 40 and isinstance(value, dict | list):
        return "a table" if isinstance(value, dict) else "a list"
    return text


def check_atom(r: Checker, place: str, text: str, pname: str, args: Sequence[str],
               domain: Domain, seen: Mapping[str, str]) -> None:
    pred = domain.predicates.get(pname)
    if pred is not None:
        _check_objects(r, place, text, pname, pred.params, args, seen, domain)
        return
    sv = domain.variables.get(pname)
    c = domain.counters.get(pname)
    if sv is not None or c is not None:
        params = sv.params if sv is not None else c.params  # type: ignore[union-attr]
        head = f"{pname}({', '.join(p.type for p in params)})" if params else pname
        kind = "state variable" if sv is not None else "counter"
        if len(args) != len(params) + 1:
            raise r.err(place, f"{pname} is a {kind}: {text!r} gives no value",
                        f'write "{head} = value"', text)
        if sv is not None:
            _check_objects(r, place, text, pname, (*sv.params, sv.value), args, seen, domain)
            return
        assert c is not None
        _check_objects(r, place, text, pname, c.params, args[:-1], seen, domain)
        if not args[-1].isdigit() or int(args[-1]) > c.max:
            raise r.err(place, f"{call_str(pname, args[:-1])} is a counter from 0 to {c.max}, "
                        f"not {args[-1]!r}", f"give a whole number from 0 to {c.max}", text)
        return
    named = sorted({*domain.predicates, *domain.variables, *domain.counters})
    hint = ("derived predicates cannot be stated, only their atoms"
            if pname in domain.derived_predicates else f"use one of: {', '.join(named)}")
    raise r.err(place, f"unknown predicate {pname!r}", hint, text)


def _check_objects(r: Checker, place: str, text: str, name: str, params: Sequence[Var],
                   args: Sequence[str], seen: Mapping[str, str], domain: Domain) -> None:
    types = [p.type for p in params]
    if len(args) != len(types):
        raise r.err(place, f"{name} takes {len(types)} argument(s), got {len(args)} in {text!r}",
                    f"write {name}({', '.join(types)})", text)
    h = domain.hierarchy
    for a, p in zip(args, params, strict=True):
        t = p.type
        if a not in seen:
            raise r.err(place, f"unknown object {a!r} in {text!r}",
                        "declare it under [objects]", text)
        if not h.is_sub(seen[a], t):
            if h.ancestors(seen[a]) or h.ancestors(t):  # name the hierarchy
                raise r.err(place, f"{a!r} is {h.a(seen[a])}; {signature(name, params)} wants "
                            f"{article(t)} {t} for {p.name}",
                            f"use an object of type {t} (or a subtype)", text)
            raise r.err(place, f"{a!r} is {article(seen[a])} {seen[a]}, but {name} expects "
                        f"{article(t)} {t} there", f"use an object of type {t}", text)


def _values_of(domain: Domain, facts: Iterable[GroundAtom]) -> dict[tuple[str, tuple[str, ...]],
                                                                      str]:
    """The value each state variable and counter has in ``facts`` (value view)."""
    return {(n, a[:-1]): a[-1] for n, a in facts if n in domain.variables or n in domain.counters}


def check_values(r: Checker, place: str, facts: Iterable[GroundAtom], domain: Domain,
                 seen: Mapping[str, str], complete: bool = True) -> None:
    """Each state variable and counter has at most one value in ``facts``; with ``complete``
    every state variable has one (a counter not given is 0)."""
    given: dict[tuple[str, tuple[str, ...]], str] = {}
    for n, a in sorted(facts):
        if n not in domain.variables and n not in domain.counters:
            continue
        key = (n, a[:-1])
        if key in given:
            raise r.err(place, f"{call_str(*key)} is given two values, {given[key]} and "
                        f"{a[-1]}", "give each state variable or counter one value",
                        fact_str(domain, n, a))
        given[key] = a[-1]
    if not complete:
        return
    h = domain.hierarchy
    for name in sorted(domain.variables):
        sv = domain.variables[name]
        objs = [sorted(o for o, t in seen.items() if h.is_sub(t, p.type)) for p in sv.params]
        for args in _product(objs):
            if (name, args) not in given:
                vals = sorted(o for o, t in seen.items() if h.is_sub(t, sv.values))
                example = f"{call_str(name, args)} = {vals[0] if vals else 'value'}"
                raise r.err(place, f"the state variable {call_str(name, args)} has no value",
                            f'give it one, e.g. "{example}"')


def _product(domains: Sequence[Sequence[str]]) -> list[tuple[str, ...]]:
    out: list[tuple[str, ...]] = [()]
    for d in domains:
        out = [(*t, x) for t in out for x in d]
    return out


def check_task(r: Checker, place: str, text: str, name: str, args: Sequence[str],
               domain: Domain, who: str, seen: Mapping[str, str]) -> None:
    m = domain.robot if who == "robot" else domain.human
    decl = m.operators.get(name) or m.tasks.get(name)
    if decl is None:
        known = sorted({*m.operators, *m.tasks})
        raise r.err(place, f"{m.agent} has no task or action {name!r}",
                    f"use one of: {', '.join(known)}", text)
    _check_objects(r, place, text, name, decl.params, args, seen, domain)


def check_belief_values(r: Checker, place: str, true: Iterable[GroundAtom],
                        false: Iterable[GroundAtom], init: Iterable[GroundAtom],
                        domain: Domain, seen: Mapping[str, str]) -> None:
    """A world gives a state variable or a counter the value the human believes, under
    ``true`` (once); ``false`` cannot say it, a value being more than "not this one"."""
    for n, a in sorted(false):
        if n in domain.variables or n in domain.counters:
            raise r.err(f"{place} false", f"{fact_str(domain, n, a)}: a state variable or "
                        "counter has one value, so the human believes another one",
                        f'list the value it believes under true, e.g. "{call_str(n, a[:-1])} '
                        '= ..."', fact_str(domain, n, a))
    check_values(r, f"{place} true", true, domain, seen, complete=False)
    now = _values_of(domain, init)
    for n, a in sorted(true):
        if n in domain.counters and now.get((n, a[:-1]), "0") == str(int(a[-1])):
            raise r.err(f"{place} true", f"{fact_str(domain, n, a)} is already true",
                        "list only values the human wrongly believes", fact_str(domain, n, a))


# --- problems built in Python ----------------------------------------------------------------


def check_problem(problem: Problem) -> None:
    """Check a :class:`Problem` as :func:`ehatp.load` checks a file: predicates, objects, types,
    tasks, costs and settings. Raise :class:`InputError` (file ``problem.source``) on the
    first mistake. The planner calls it, so a Problem built in Python is checked too."""
    r = Checker(problem.source)
    d = problem.domain
    if not isinstance(d, Domain):
        raise r.err("domain", f"expected a Domain, got {type(d).__name__}", "pass a Domain")
    d.check()
    if not isinstance(problem.name, str):
        raise r.err("name", f"expected a string, got {show_value(problem.name)}", 'name="P1"')
    seen: dict[str, str] = dict(d.constants)
    kinds = [x for x in d.types if x != AGENT_TYPE]
    if not isinstance(problem.objects, Mapping):
        raise r.err("objects", "expected a dict of type -> object names",
                    'write objects={"cube": ["r", "w"]}')
    for t, names in problem.objects.items():
        if t not in kinds:
            raise r.err(f"objects {t}", f"unknown type {t!r} in domain {d.name}",
                        f"use one of: {', '.join(kinds)}")
        for o in r.strings(f"objects {t}", list(names) if isinstance(names, tuple) else names):
            if not re.fullmatch(r"[A-Za-z_][\w\-]*", o):
                raise r.err(f"objects {t}", f"bad object name {o!r}",
                            "use letters, digits, _ or -")
            if o in seen:
                raise r.err(f"objects {t}", f"object {o!r} is declared twice",
                            "give each object one type")
            seen[o] = t

    def atoms(place: str, value: Iterable[Any]) -> None:
        for a in sorted(value, key=repr):
            name, args = _pair(r, place, a, "atom", '("on", ("r", "mt"))')
            check_atom(r, place, call_str(name, args), name, args, d, seen)

    def tasks(place: str, value: Iterable[Any], who: str) -> None:
        for c in value:
            name, args = _pair(r, place, c, "task", '("organize", ())')
            check_task(r, place, call_str(name, args), name, args, d, who, seen)

    atoms("init", problem.init)
    check_values(r, "init", problem.init, d, seen)
    tasks("robot_agenda", problem.robot_agenda, "robot")
    tasks("human_agenda", problem.human_agenda, "human")
    for i, w in enumerate(problem.beliefs, 1):
        if not isinstance(w, BeliefWorld):
            raise r.err(f"beliefs #{i}", f"expected a BeliefWorld, got {type(w).__name__}",
                        "write BeliefWorld(true=..., false=...)")
        atoms(f"beliefs #{i} true", w.true)
        atoms(f"beliefs #{i} false", w.false)
        check_belief_values(r, f"beliefs #{i}", w.true, w.false, problem.init, d, seen)
        if w.robot_agenda is not None:
            tasks(f"beliefs #{i} robot_agenda", w.robot_agenda, "robot")
    for g in problem.goal:
        if not (isinstance(g, tuple) and len(g) == 2 and isinstance(g[0], bool)):
            raise r.err("goal", f"expected (True or False, atom) pairs, got {show_value(g)}",
                        'write goal=((True, ("in", ("r", "box1"))),)')
        atoms("goal", [g[1]])
    if problem.starts not in ("human", "robot"):
        raise r.err("starts", f"unknown agent {problem.starts!r}", 'write "human" or "robot"')
    if isinstance(problem.K, bool) or not isinstance(problem.K, int) or problem.K < 0:
        raise r.err("K", f"K must be a whole number >= 0, got {show_value(problem.K)}", "write K=2")
    c = problem.costs
    for k in ("inform", "ask", "wait", "pass_"):
        r.number(f"costs {k}", getattr(c, k))
    all_ops = {*d.robot.operators, *d.human.operators}
    for a, v in c.actions.items():
        if a not in all_ops:
            raise r.err(f"costs actions {a}", f"unknown action {a!r}",
                        f"use one of: {', '.join(sorted(all_ops))}")
        r.number(f"costs actions {a}", v)
    r.strings("after", list(problem.after))
    for name, metrics in problem.objective.profiles.items():  # C11
        for m in metrics:
            if m not in _BUILT_IN_METRICS and m not in d.metrics:
                raise r.err(f"objective profiles {name}", f"unknown metric {m!r}",
                            "use one of " + known_metrics(d.metrics))


_BUILT_IN_METRICS = frozenset(m.value for m in Metric)


def _pair(r: Checker, place: str, value: Any, what: str,
          example: str) -> tuple[str, tuple[str, ...]]:
    """A ``(name, (arg, ...))`` pair, as atoms and task calls are written in Python."""
    if (isinstance(value, tuple) and len(value) == 2 and isinstance(value[0], str)
            and isinstance(value[1], tuple) and all(isinstance(a, str) for a in value[1])):
        return value[0], value[1]
    raise r.err(place, f"expected a {what} as (name, (arg, ...)), got {show_value(value)}",
                f"write e.g. {example}")


def atoms_to_strs(atoms: Iterable[GroundAtom]) -> list[str]:
    return sorted(call_str(n, a) for n, a in atoms)


if not TYPE_CHECKING:  # the TOML reader's old home, for one release (type checkers: use the new)
    __getattr__ = moved_names(__name__, "ehatp.formats.problem_toml", ("REGISTRY", "load", "loads"))
