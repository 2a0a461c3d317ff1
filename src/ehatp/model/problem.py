"""Problem instances: objects, truth, the human's beliefs, agendas, K, costs, limits.

Problems are usually written in TOML (see ``docs/problem-format.md``) and read by :func:`load`,
which checks everything before anything is built: a mistake is one :class:`InputError` line
naming the file, the place and the fix.
"""

from __future__ import annotations

import importlib
import importlib.util
import re
import sys
import tomllib
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from ..errors import InputError
from .domain import AGENT_TYPE, Domain, DomainError

Cost = int | Fraction
GroundAtom = tuple[str, tuple[str, ...]]
TaskCall = tuple[str, tuple[str, ...]]

# Domain names usable in a problem's [domain] table; values are "module:attribute" so the model
# layer does not import the domain library.
REGISTRY: dict[str, str] = {
    "cubes": "ehatp.domains.cubes:make_domain",
    "cooking": "ehatp.domains.cooking:make_domain",
}


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


@dataclass(frozen=True)
class Options:
    # Whether the human, blocked by uncertainty, may silently pass after a robot wait (the
    # paper's trace b). See docs/semantics.md: with it, waiting for a question can never beat
    # a proactive inform in the worst case.
    human_passes_when_blocked: bool = True
    # Largest informing set the planner tries (subsets by increasing size).
    inform_max_atoms: int = 3


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
    options: Options = field(default_factory=Options)
    goal: tuple[tuple[bool, GroundAtom], ...] = ()
    # a fixed opening line of play (move labels); the policy starts where it ends
    after: tuple[str, ...] = ()
    description: str = ""
    source: str = "<python>"

    def all_objects(self) -> dict[str, list[str]]:
        """Objects by type, domain constants included, each list sorted by name."""
        out: dict[str, list[str]] = {t: [] for t in self.domain.types}
        for name, t in self.domain.constants.items():
            out[t].append(name)
        for t, names in self.objects.items():
            out.setdefault(t, []).extend(names)
        return {t: sorted(v) for t, v in out.items()}


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


def call_str(name: str, args: Sequence[str]) -> str:
    """``on(r, mt)``; a call without arguments is its bare name (``washed``)."""
    return f"{name}({', '.join(args)})" if args else name


# --- the loader ------------------------------------------------------------------------------

_TOP_KEYS = {"problem", "domain", "objects", "init", "beliefs", "agenda", "goal", "costs",
             "limits", "options"}


class _Reader:
    """Holds the file text so errors can point at a line."""

    def __init__(self, path: str, text: str) -> None:
        self.path, self.text = path, text

    def err(self, place: str, problem: str, fix: str = "", needle: str | None = None) -> InputError:
        line = self._line_of(needle) if needle else None
        where = f"{line}: {place}" if line else place
        return InputError(self.path, where, problem, fix)

    def _line_of(self, needle: str) -> int | None:
        for i, line in enumerate(self.text.splitlines(), 1):
            if needle in line.split("#", 1)[0]:
                return i
        return None

    def table(self, data: Mapping[str, Any], key: str, allowed: set[str],
              required: bool = False) -> dict[str, Any]:
        if key not in data:
            if required:
                raise self.err(f"[{key}]", f"missing table [{key}]",
                               f"add a [{key}] table (see docs/problem-format.md)")
            return {}
        t = data[key]
        if not isinstance(t, dict):
            raise self.err(key, f"{key} must be a table", f"write it as [{key}]", key)
        for k in t:
            if k not in allowed:
                raise self.err(f"[{key}] {k}", f"unknown key {k!r}",
                               f"use one of {', '.join(sorted(allowed))}", k)
        return dict(t)

    def strings(self, place: str, value: Any) -> list[str]:
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.err(place, "expected a list of strings", 'write e.g. ["on(r, mt)"]')
        return list(value)

    def number(self, place: str, value: Any, *, positive: bool = True) -> Cost:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.err(place, f"expected a number, got {value!r}", "write e.g. 1 or 2.5")
        if positive and value <= 0:
            raise self.err(place, f"must be positive, got {value}",
                           "give a number greater than 0 (costs must be positive)")
        return value if isinstance(value, int) else Fraction(str(value))


def load(path: str | Path) -> Problem:
    """Read a problem TOML file; raise :class:`InputError` on the first mistake."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as e:
        raise InputError(str(path), "", f"cannot read the file ({e.strerror})",
                         "check the path") from None
    r = _Reader(str(path), text)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(str(path), "", f"not valid TOML: {e}", "fix the TOML syntax") from None
    for k in data:
        if k not in _TOP_KEYS:
            raise r.err(k, f"unknown table or key {k!r}",
                        f"use {', '.join(sorted(_TOP_KEYS))}", k)

    prob = r.table(data, "problem", {"name", "description", "starts", "K", "after"},
                   required=True)
    dom_t = r.table(data, "domain", _any_key, required=True)
    domain = _resolve_domain(r, dom_t, p.parent)

    name = prob.get("name", p.stem)
    if not isinstance(name, str):
        raise r.err("[problem] name", "name must be a string", 'write name = "P1"', "name")
    starts = prob.get("starts", "human")
    starts = {domain.human_name: "human", domain.robot_name: "robot"}.get(starts, starts)
    if starts not in ("human", "robot"):
        raise r.err("[problem] starts", f"unknown agent {prob.get('starts')!r}",
                    f'write "human" or "robot" (or "{domain.human_name}"/"{domain.robot_name}")',
                    "starts")
    K = prob.get("K", 2)
    if isinstance(K, bool) or not isinstance(K, int) or K < 0:
        raise r.err("[problem] K", f"K must be a whole number >= 0, got {K!r}", "write e.g. K = 2",
                    "K")

    # objects
    objs_t = r.table(data, "objects", _any_key)
    objects: dict[str, list[str]] = {}
    seen: dict[str, str] = dict(domain.constants)
    for t, names in objs_t.items():
        if t not in domain.types or t == AGENT_TYPE:
            kinds = ", ".join(x for x in domain.types if x != AGENT_TYPE)
            raise r.err(f"[objects] {t}", f"unknown type {t!r} in domain {domain.name}",
                        f"use one of: {kinds}", t)
        for o in r.strings(f"[objects] {t}", names):
            if not re.fullmatch(r"[A-Za-z_][\w\-]*", o):
                raise r.err(f"[objects] {t}", f"bad object name {o!r}",
                            "use letters, digits, _ or -", o)
            if o in seen:
                raise r.err(f"[objects] {t}", f"object {o!r} is declared twice",
                            "give each object one type", o)
            seen[o] = t
            objects.setdefault(t, []).append(o)

    def atom(place: str, text: str) -> GroundAtom:
        c = parse_call(text)
        if c is None:
            raise r.err(place, f"cannot read atom {text!r}", 'write it as "pred(obj, obj)"', text)
        pname, args = c
        pred = domain.predicates.get(pname)
        if pred is None:
            hint = ("derived predicates cannot be stated, only their atoms"
                    if pname in domain.derived_predicates else
                    f"use one of: {', '.join(sorted(domain.predicates))}")
            raise r.err(place, f"unknown predicate {pname!r}", hint, text)
        _check_objects(r, place, text, pname, [v.type for v in pred.params], args, seen)
        return pname, args

    init_t = r.table(data, "init", {"true"}, required=True)
    init = frozenset(atom("[init] true", a) for a in r.strings("[init] true",
                                                                init_t.get("true", [])))

    # agendas
    ag_t = r.table(data, "agenda", {"robot", "human", domain.robot_name, domain.human_name},
                   required=True)
    agendas: dict[str, tuple[TaskCall, ...]] = {"robot": (), "human": ()}
    for key, v in ag_t.items():
        who = "robot" if key in ("robot", domain.robot_name) else "human"
        agendas[who] = tuple(_task(r, f"[agenda] {key}", s, domain, who, seen)
                             for s in r.strings(f"[agenda] {key}", v))

    beliefs = _beliefs(r, data.get("beliefs"), atom, init, domain, seen)

    goal: list[tuple[bool, GroundAtom]] = []
    if "goal" in data:
        for s in r.strings("goal", data["goal"]):
            neg = s.strip().startswith("not ")
            goal.append((not neg, atom("goal", s.strip()[4:] if neg else s)))

    c_t = r.table(data, "costs", {"inform", "ask", "wait", "pass", "actions"})
    acts = c_t.pop("actions", {})
    if not isinstance(acts, dict):
        raise r.err("[costs] actions", "actions must be a table", "write [costs.actions]")
    all_ops = {*domain.robot.operators, *domain.human.operators}
    for a in acts:
        if a not in all_ops:
            raise r.err(f"[costs.actions] {a}", f"unknown action {a!r}",
                        f"use one of: {', '.join(sorted(all_ops))}", a)
    costs = Costs(
        **{("pass_" if k == "pass" else k): r.number(f"[costs] {k}", v) for k, v in c_t.items()},
        actions={a: r.number(f"[costs.actions] {a}", v) for a, v in acts.items()},
    )
    l_t = r.table(data, "limits", {"timeout", "max_states", "max_depth"})
    limits = Limits(
        timeout=float(r.number("[limits] timeout", l_t["timeout"])) if "timeout" in l_t else None,
        max_states=_int(r, "[limits] max_states", l_t.get("max_states", Limits.max_states)),
        max_depth=_int(r, "[limits] max_depth", l_t.get("max_depth", Limits.max_depth)),
    )
    o_t = r.table(data, "options", {"human_passes_when_blocked", "inform_max_atoms"})
    hp = o_t.get("human_passes_when_blocked", True)
    if not isinstance(hp, bool):
        raise r.err("[options] human_passes_when_blocked", "expected true or false",
                    "write true or false", "human_passes_when_blocked")
    options = Options(hp, _int(r, "[options] inform_max_atoms", o_t.get("inform_max_atoms", 3)))
    description = prob.get("description", "")
    after = tuple(r.strings("[problem] after", prob.get("after", [])))
    return Problem(name=name, domain=domain, objects=objects, init=init,
                   robot_agenda=agendas["robot"], human_agenda=agendas["human"], beliefs=beliefs,
                   starts=starts, K=K, costs=costs, limits=limits, options=options,
                   goal=tuple(goal), after=after, description=str(description),
                   source=str(path))


class _AnyKey(set[str]):
    def __contains__(self, _: object) -> bool:
        return True


_any_key = _AnyKey()


def _int(r: _Reader, place: str, v: Any) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v <= 0:
        raise r.err(place, f"expected a whole number > 0, got {v!r}", "write e.g. 1000",
                    place.split()[-1])
    return v


def _check_objects(r: _Reader, place: str, text: str, name: str, types: Sequence[str],
                   args: Sequence[str], seen: Mapping[str, str]) -> None:
    if len(args) != len(types):
        raise r.err(place, f"{name} takes {len(types)} argument(s), got {len(args)} in {text!r}",
                    f"write {name}({', '.join(types)})", text)
    for a, t in zip(args, types, strict=True):
        if a not in seen:
            raise r.err(place, f"unknown object {a!r} in {text!r}",
                        "declare it under [objects]", text)
        if seen[a] != t:
            raise r.err(place, f"{a!r} is a {seen[a]}, but {name} expects a {t} there",
                        f"use an object of type {t}", text)


def _task(r: _Reader, place: str, text: str, domain: Domain, who: str,
          seen: Mapping[str, str]) -> TaskCall:
    c = parse_call(text)
    if c is None:
        raise r.err(place, f"cannot read task {text!r}", 'write it as "task(obj, ...)"', text)
    name, args = c
    models = [domain.robot] if who == "robot" else [domain.human]
    for m in models:
        decl = m.operators.get(name) or m.tasks.get(name)
        if decl is None:
            known = sorted({*m.operators, *m.tasks})
            raise r.err(place, f"{m.agent} has no task or action {name!r}",
                        f"use one of: {', '.join(known)}", text)
        _check_objects(r, place, text, name, [v.type for v in decl.params], args, seen)
    return name, args


def _beliefs(r: _Reader, raw: Any, atom: Callable[[str, str], GroundAtom],
             init: frozenset[GroundAtom], domain: Domain,
             seen: Mapping[str, str]) -> tuple[BeliefWorld, ...]:
    if raw is None:
        return (BeliefWorld(),)
    if not isinstance(raw, dict):
        raise r.err("beliefs", "beliefs must be a table", "write [beliefs] or [[beliefs.world]]")
    keys = set(raw)
    if keys - {"true", "false", "world"} or ("world" in keys and keys & {"true", "false"}):
        raise r.err("[beliefs]", "use either true/false (one world) or [[beliefs.world]] entries",
                    "see docs/problem-format.md", "beliefs")
    entries = raw.get("world", [raw])
    if not isinstance(entries, list) or not entries:
        raise r.err("[beliefs] world", "expected one or more [[beliefs.world]] tables",
                    "write [[beliefs.world]]")
    out = []
    for i, w in enumerate(entries):
        place = f"[[beliefs.world]] #{i + 1}" if "world" in raw else "[beliefs]"
        if not isinstance(w, dict) or set(w) - {"true", "false", "robot_agenda"}:
            raise r.err(place, "a world takes the keys true, false and robot_agenda",
                        "remove the other keys")
        tr = frozenset(atom(f"{place} true", s) for s in r.strings(f"{place} true",
                                                                     w.get("true", [])))
        fa = frozenset(atom(f"{place} false", s) for s in r.strings(f"{place} false",
                                                                      w.get("false", [])))
        for a in tr & init:
            raise r.err(f"{place} true", f"{call_str(*a)} is already true",
                        "list only atoms the human wrongly believes true", a[0])
        for a in fa - init:
            raise r.err(f"{place} false", f"{call_str(*a)} is already false",
                        "list only atoms the human wrongly believes false", a[0])
        agenda = None
        if "robot_agenda" in w:
            agenda = tuple(_task(r, f"{place} robot_agenda", s, domain, "robot", seen)
                           for s in r.strings(f"{place} robot_agenda", w["robot_agenda"]))
        out.append(BeliefWorld(tr, fa, agenda))
    return tuple(out)


def _resolve_domain(r: _Reader, t: Mapping[str, Any], base: Path) -> Domain:
    ref = t.get("name")
    if not isinstance(ref, str):
        raise r.err("[domain] name", "missing domain name",
                    f'write name = "cubes" (known: {", ".join(sorted(REGISTRY))}) or '
                    '"module:attribute" or "file.py:attribute"')
    options = {k: v for k, v in t.items() if k != "name"}
    target = REGISTRY.get(ref, ref)
    if ":" not in target:
        raise r.err("[domain] name", f"unknown domain {ref!r}",
                    f'use one of {", ".join(sorted(REGISTRY))}, "module:attribute" or '
                    '"file.py:attribute"', ref)
    mod_name, attr = target.rsplit(":", 1)
    try:
        if mod_name.endswith(".py"):
            f = (base / mod_name).resolve()
            spec = importlib.util.spec_from_file_location(f"ehatp_user_domain_{f.stem}", f)
            if spec is None or spec.loader is None or not f.exists():
                raise r.err("[domain] name", f"no domain file {f}",
                            "give a path relative to the problem file", ref)
            module = importlib.util.module_from_spec(spec)
            sys.modules[spec.name] = module
            spec.loader.exec_module(module)
        else:
            module = importlib.import_module(mod_name)
    except ImportError as e:
        raise r.err("[domain] name", f"cannot import {mod_name!r} ({e})",
                    "check the module name and that it is installed", ref) from None
    except DomainError as e:
        raise r.err("[domain] name", f"domain {ref!r} is malformed: {e}",
                    "fix the domain module", ref) from None
    obj = getattr(module, attr, None)
    if obj is None:
        raise r.err("[domain] name", f"{mod_name} has no attribute {attr!r}",
                    "name a Domain or a function returning one", ref)
    if isinstance(obj, Domain):
        if options:
            raise r.err("[domain]", f"domain {ref!r} takes no options",
                        f"remove {', '.join(sorted(options))}")
        return obj
    try:
        dom = obj(**options)
    except TypeError as e:
        raise r.err("[domain]", f"bad domain options for {ref!r}: {e}",
                    "see the domain's documentation for its options") from None
    except DomainError as e:
        raise r.err("[domain]", f"domain {ref!r} is malformed: {e}",
                    "fix the domain module") from None
    except ValueError as e:
        raise r.err("[domain]", f"bad domain option for {ref!r}: {e}", "fix the option") from None
    if not isinstance(dom, Domain):
        raise r.err("[domain] name", f"{ref!r} did not give a Domain", "return a Domain")
    return dom


def atoms_to_strs(atoms: Iterable[GroundAtom]) -> list[str]:
    return sorted(call_str(n, a) for n, a in atoms)
