"""Problem instances: objects, truth, the human's beliefs, agendas, K, costs, limits.

Problems are usually written in TOML (see ``docs/problem-format.md``) and read by :func:`load`,
which checks everything before anything is built: a mistake is one :class:`InputError` line
naming the file, the place and the fix.
"""

from __future__ import annotations

import copy
import hashlib
import importlib
import importlib.util
import inspect
import math
import re
import sys
import sysconfig
import tomllib
import traceback
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from types import ModuleType
from typing import Any

from ..errors import InputError
from .domain import AGENT_TYPE, Domain, DomainError, article, is_domain_factory, signature
from .formula import Var
from .options import OPTION_KEYS, Communication, HumanModel, Objective, read_options

Cost = int | Fraction
GroundAtom = tuple[str, tuple[str, ...]]
TaskCall = tuple[str, tuple[str, ...]]

# Domain names usable in a problem's [domain] table; values are "module:attribute" so the model
# layer does not import the domain library. These are trusted: their factories are called even
# unmarked.
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
    goal: tuple[tuple[bool, GroundAtom], ...] = ()
    # a fixed opening line of play (move labels); the policy starts where it ends
    after: tuple[str, ...] = ()
    description: str = ""
    source: str = "<python>"
    # one-line notes for the user, e.g. a deprecated spelling in the file
    notes: tuple[str, ...] = ()

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
        """Check predicates, objects, types, tasks and settings as :func:`load` checks a
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


# --- the loader ------------------------------------------------------------------------------

# The keys each table takes ("beliefs.world" is the array of tables [[beliefs.world]]); [objects]
# and [domain] take any key. A key found in the wrong table is reported with where it belongs.
_TABLE_KEYS: dict[str, frozenset[str]] = {
    "problem": frozenset({"name", "description", "starts", "K", "after"}),
    "domain": frozenset({"name"}),
    "init": frozenset({"true"}),
    "beliefs": frozenset({"true", "false", "world"}),
    "beliefs.world": frozenset({"true", "false", "robot_agenda"}),
    "agenda": frozenset({"robot", "human"}),
    "costs": frozenset({"inform", "ask", "wait", "pass", "actions"}),
    "limits": frozenset({"timeout", "max_states", "max_depth", "max_memory",
                         "max_decomposition", "symmetry", "ground_ahead"}),
    **OPTION_KEYS,
}
_TOP_TABLES = {"problem", "domain", "objects", "init", "beliefs", "agenda", "costs", "limits",
               "options", "human", "communication", "objective"}
_TOP_VALUES = {"goal"}  # top-level keys that are not tables
_TOP_KEYS = _TOP_TABLES | _TOP_VALUES

_HEADER = re.compile(r"^\s*\[(\[)?\s*([^\[\]]+?)\s*\]\]?\s*(?:#.*)?$")
_BARE_OR_QUOTED = r"""(?:[A-Za-z0-9_\-]+|"[^"]*"|'[^']*')"""
_KEY_LINE = re.compile(rf"^\s*({_BARE_OR_QUOTED}(?:\s*\.\s*{_BARE_OR_QUOTED})*)\s*=")
_PLACE = re.compile(r"^\[\[?([^\]]+)\]\]?(?:\s+#(\d+))?(?:\s+(\S+))?")


def _key_path(dotted: str) -> tuple[str, ...]:
    """``costs . "actions"`` -> ``("costs", "actions")``."""
    return tuple(a or b or c for a, b, c in
                 re.findall(r'"([^"]*)"|\'([^\']*)\'|([A-Za-z0-9_\-]+)', dotted))


def _code(line: str) -> str:
    """The line without its comment (a ``#`` inside a string is not a comment)."""
    quote = ""
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = ""
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            return line[:i]
    return line


@dataclass(frozen=True)
class _Entry:
    """A table header or a ``key =`` line: its full dotted path and where it is."""

    path: tuple[str, ...]
    occurrence: int  # 1-based, counts [[array]] tables of the same name
    line: int
    header: bool


class _Reader:
    """Holds the file text so errors can point at the line of the key they are about."""

    def __init__(self, path: str, text: str) -> None:
        self.path, self.text = path, text
        self.lines = text.splitlines()
        self.entries: list[_Entry] = []
        table: tuple[str, ...] = ()
        occurrence, seen = 1, dict[tuple[str, ...], int]()
        for i, line in enumerate(self.lines, 1):
            if h := _HEADER.match(line):
                table = _key_path(h.group(2))
                seen[table] = occurrence = seen.get(table, 0) + 1
                self.entries.append(_Entry(table, occurrence, i, True))
            elif k := _KEY_LINE.match(line):
                self.entries.append(_Entry(table + _key_path(k.group(1)), occurrence, i, False))
        self.first_table = next((".".join(e.path) for e in self.entries if e.header), "")

    def err(self, place: str, problem: str, fix: str = "", needle: str | None = None) -> InputError:
        """An error at ``place`` (``[table] key``, ``[[table]] #n key`` or a top-level key);
        ``needle`` is text of the value to point at when the value spans lines."""
        line = self._line_of(place, needle)
        where = f"{line}: {place}" if line else place
        return InputError(self.path, where, problem, fix)

    def _line_of(self, place: str, needle: str | None) -> int | None:
        m = _PLACE.match(place)
        if m:
            table, nth, key = _key_path(m.group(1)), int(m.group(2) or 0), m.group(3)
        else:
            table, nth, key = (), 0, place.split()[0] if place.strip() else None
        want = [table + (key,)] if key else []
        want.append(table)  # else the table itself (a header, or an inline table's key)
        for path in want:
            for j, e in enumerate(self.entries):
                if e.path == path and (nth == 0 or e.occurrence == nth):
                    return self._find(needle, j) or e.line
        if needle:  # not where expected (e.g. an inline table): the first mention will do
            return next((i for i, ln in enumerate(self.lines, 1) if needle in _code(ln)), None)
        return None

    def _find(self, needle: str | None, j: int) -> int | None:
        # a value runs until the next key line (a header's table until the next header)
        e = self.entries[j]
        end = len(self.lines)
        for nxt in self.entries[j + 1:]:
            if nxt.header or not e.header:
                end = nxt.line - 1
                break
        if needle:
            for i in range(e.line, end + 1):
                if needle in _code(self.lines[i - 1]):
                    return i
        return None

    def misplaced(self, table: str, key: str) -> tuple[str, str] | None:
        """Why ``key`` does not belong in ``table`` and where to move it, if it belongs
        elsewhere: TOML reads every key after a ``[table]`` header as part of that table."""
        if key in _TOP_VALUES:
            first = self.first_table or table
            return (f"{key} is a top-level key, but it comes after the [{table}] header, so "
                    f"TOML reads it as part of [{table}]",
                    f"move it above the first table ([{first}])")
        homes = sorted(t for t, keys in _TABLE_KEYS.items() if key in keys and t != table)
        if homes:
            return (f"{key} belongs in {' or '.join(f'[{t}]' for t in homes)}",
                    "move it under that header")
        if key in _TOP_TABLES and key != table:
            return f"{key} is a table of its own", f"write it under its own [{key}] header"
        return None

    def unknown_key(self, table: str, key: str, allowed: Iterable[str], place: str = "",
                    what: str = "key") -> InputError:
        """An unknown key of ``table``: where it belongs if elsewhere, else what is allowed."""
        place = place or f"[{table}] {key}"
        wrong = self.misplaced(table, key)
        if wrong is not None:
            return self.err(place, f"unknown {what} {key!r} in [{table}]: {wrong[0]}", wrong[1])
        return self.err(place, f"unknown {what} {key!r}",
                        f"use one of: {', '.join(sorted(allowed))}")

    def table(self, data: Mapping[str, Any], key: str, allowed: Iterable[str] | None,
              required: bool = False) -> dict[str, Any]:
        """Table ``key`` of ``data``; ``allowed`` None takes any key."""
        if key not in data:
            if required:
                raise self.err(f"[{key}]", f"missing table [{key}]",
                               f"add a [{key}] table (see docs/problem-format.md)")
            return {}
        t = data[key]
        if not isinstance(t, dict):
            raise self.err(key, f"{key} must be a table", f"write it as [{key}]")
        if allowed is not None:
            for k in t:
                if k not in allowed:
                    raise self.unknown_key(key, k, allowed)
        return dict(t)

    def string(self, place: str, value: Any, example: str) -> str:
        if not isinstance(value, str):
            raise self.err(place, f"expected a string, got {_show(value)}",
                           f"write e.g. {example}")
        return value

    def strings(self, place: str, value: Any) -> list[str]:
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.err(place, f"expected a list of strings, got {_show(value)}",
                           'write e.g. ["on(r, mt)"]')
        return list(value)

    def number(self, place: str, value: Any, *, positive: bool = True) -> Cost:
        if isinstance(value, bool) or not isinstance(value, int | float | Fraction):
            raise self.err(place, f"expected a number, got {_show(value)}",
                           "write e.g. 1 or 2.5")
        if isinstance(value, float) and not math.isfinite(value):
            raise self.err(place, f"expected a finite number, got {value}",
                           "write e.g. 1 or 2.5")
        if positive and value <= 0:
            raise self.err(place, f"must be positive, got {value}",
                           "give a number greater than 0 (costs must be positive)")
        return value if isinstance(value, int | Fraction) else Fraction(str(value))


def _show(value: Any) -> str:
    """A value as the user wrote it, briefly (a whole table would not fit on one line)."""
    text = repr(value)
    if len(text) > 40 and isinstance(value, dict | list):
        return "a table" if isinstance(value, dict) else "a list"
    return text


def load(path: str | Path, overrides: Mapping[str, Any] | None = None) -> Problem:
    """Read a problem TOML file; raise :class:`InputError` on the first mistake.

    ``overrides`` (see :func:`loads`) replace values of the file before it is checked."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as e:
        raise InputError(str(path), "", f"cannot read the file ({e.strerror or e})",
                         "check the path") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line = raw[:e.start].count(b"\n") + 1
        raise InputError(str(path), str(line), f"not a UTF-8 text file (byte "
                         f"0x{raw[e.start]:02x} at offset {e.start})",
                         "give a problem file in TOML, saved as UTF-8") from None
    return loads(text, path, overrides)


def loads(text: str, path: str | Path, overrides: Mapping[str, Any] | None = None) -> Problem:
    """Read a problem from TOML ``text`` as if it were the file ``path``: errors name that file
    and a domain ``"file.py:attribute"`` is looked for beside it. ``overrides`` maps dotted keys
    to values that replace (or add) the file's before anything is checked, so they are checked
    as if written there: ``{"problem.K": 3, "communication.inform": "anywhere",
    "domain.turn_before_move": True}``. Raise :class:`InputError` on the first mistake."""
    p = Path(path)
    if not text.strip():
        raise InputError(str(path), "", "the file is empty",
                         "write a problem (see docs/problem-format.md)")
    r = _Reader(str(path), text)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(str(path), "", f"not valid TOML: {e}", "fix the TOML syntax") from None
    except RecursionError:  # the parser recurses per nesting level
        raise InputError(str(path), "", "arrays or tables are nested too deeply",
                         "flatten the file (a problem needs two levels at most)") from None
    for dotted, value in (overrides or {}).items():
        _override(str(path), data, dotted, value)
    for k in data:
        if k not in _TOP_KEYS:
            wrong = r.misplaced("", k)
            if wrong is not None:
                raise r.err(k, f"unknown table or key {k!r}: {wrong[0]}", wrong[1])
            raise r.err(k, f"unknown table or key {k!r}", f"use {', '.join(sorted(_TOP_KEYS))}")

    prob = r.table(data, "problem", _TABLE_KEYS["problem"], required=True)
    dom_t = r.table(data, "domain", None, required=True)
    domain = _resolve_domain(r, dom_t, p.parent)

    name = r.string("[problem] name", prob.get("name", p.stem), 'name = "P1"')
    starts = r.string("[problem] starts", prob.get("starts", "human"), 'starts = "human"')
    starts = {domain.human_name: "human", domain.robot_name: "robot"}.get(starts, starts)
    if starts not in ("human", "robot"):
        raise r.err("[problem] starts", f"unknown agent {prob.get('starts')!r}",
                    f'write "human" or "robot" (or "{domain.human_name}"/"{domain.robot_name}")')
    K = prob.get("K", 2)
    if isinstance(K, bool) or not isinstance(K, int) or K < 0:
        raise r.err("[problem] K", f"K must be a whole number >= 0, got {_show(K)}",
                    "write e.g. K = 2")
    description = r.string("[problem] description", prob.get("description", ""),
                           'description = "two cubes"')

    # objects
    objs_t = r.table(data, "objects", None)
    objects: dict[str, list[str]] = {}
    seen: dict[str, str] = dict(domain.constants)
    kinds = [x for x in domain.types if x != AGENT_TYPE]
    for t, names in objs_t.items():
        if t not in kinds:
            wrong = r.misplaced("objects", t)
            if wrong is not None:
                raise r.err(f"[objects] {t}", f"unknown type {t!r} in [objects]: {wrong[0]}",
                            wrong[1])
            raise r.err(f"[objects] {t}", f"unknown type {t!r} in domain {domain.name}",
                        f"use one of: {', '.join(kinds)}")
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
        c = parse_fact(text)
        if c is None:
            raise r.err(place, f"cannot read atom {text!r}", 'write it as "pred(obj, obj)", or '
                        '"var(obj) = value" for a state variable or a counter', text)
        _check_atom(r, place, text, c[0], c[1], domain, seen)
        return c

    init_t = r.table(data, "init", _TABLE_KEYS["init"], required=True)
    init = frozenset(atom("[init] true", a) for a in r.strings("[init] true",
                                                                init_t.get("true", [])))
    _check_values(r, "[init] true", init, domain, seen)

    # agendas
    agents = {"robot", "human", domain.robot_name, domain.human_name}
    ag_t = r.table(data, "agenda", agents, required=True)
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

    c_t = r.table(data, "costs", _TABLE_KEYS["costs"])
    acts = c_t.pop("actions", {})
    if not isinstance(acts, dict):
        raise r.err("[costs] actions", "actions must be a table", "write [costs.actions]")
    all_ops = {*domain.robot.operators, *domain.human.operators}
    for a in acts:
        if a not in all_ops:
            raise r.unknown_key("costs.actions", a, all_ops, what="action")
    costs = Costs(
        **{("pass_" if k == "pass" else k): r.number(f"[costs] {k}", v) for k, v in c_t.items()},
        actions={a: r.number(f"[costs.actions] {a}", v) for a, v in acts.items()},
    )
    l_t = r.table(data, "limits", _TABLE_KEYS["limits"])
    limits = Limits(
        timeout=float(r.number("[limits] timeout", l_t["timeout"])) if "timeout" in l_t else None,
        max_states=_int(r, "[limits] max_states", l_t.get("max_states", Limits.max_states)),
        max_depth=_int(r, "[limits] max_depth", l_t.get("max_depth", Limits.max_depth)),
        max_memory=_size(r, "[limits] max_memory", l_t["max_memory"])
        if "max_memory" in l_t else None,
        max_decomposition=_int(r, "[limits] max_decomposition",
                               l_t.get("max_decomposition", Limits.max_decomposition)),
        symmetry=_flag(r, "[limits] symmetry", l_t.get("symmetry", Limits.symmetry)),
        ground_ahead=_int(r, "[limits] ground_ahead",
                          l_t.get("ground_ahead", Limits.ground_ahead), least=0),
    )
    human, communication, objective, notes = read_options(r, data)
    after = tuple(r.strings("[problem] after", prob.get("after", [])))
    return Problem(name=name, domain=domain, objects=objects, init=init,
                   robot_agenda=agendas["robot"], human_agenda=agendas["human"], beliefs=beliefs,
                   starts=starts, K=K, costs=costs, limits=limits, human=human,
                   communication=communication, objective=objective, notes=notes,
                   goal=tuple(goal), after=after, description=description,
                   source=str(path))


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


def _size(r: _Reader, place: str, v: Any) -> int:
    try:
        return parse_size(v)
    except ValueError:
        raise r.err(place, f"expected a memory size, got {_show(v)}",
                    'write e.g. "2G", "512M" or a number of bytes') from None


def _override(file: str, data: dict[str, Any], dotted: str, value: Any) -> None:
    """Set ``data[a][b][c] = value`` for ``dotted = "a.b.c"``, making missing tables."""
    keys = dotted.split(".")
    if not all(keys):
        raise InputError(file, f"override {dotted!r}", "an empty key",
                         "write table.key, e.g. problem.K")
    table = data
    for i, k in enumerate(keys[:-1]):
        table = table.setdefault(k, {})
        if not isinstance(table, dict):
            raise InputError(file, f"override {dotted}", f"{'.'.join(keys[:i + 1])} is not a "
                             "table", "override a key inside a table, e.g. problem.K")
    table[keys[-1]] = copy.deepcopy(value)  # the loader may consume what it reads


def _int(r: _Reader, place: str, v: Any, least: int = 1) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < least:
        raise r.err(place, f"expected a whole number {'> 0' if least == 1 else f'>= {least}'}"
                    f", got {_show(v)}", "write e.g. 1000")
    return v


def _flag(r: _Reader, place: str, v: Any) -> bool:
    if not isinstance(v, bool):
        raise r.err(place, f"expected true or false, got {_show(v)}", "write e.g. false")
    return v


def _check_atom(r: _Reader, place: str, text: str, pname: str, args: Sequence[str],
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


def _check_objects(r: _Reader, place: str, text: str, name: str, params: Sequence[Var],
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


def _check_values(r: _Reader, place: str, facts: Iterable[GroundAtom], domain: Domain,
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


def _task(r: _Reader, place: str, text: str, domain: Domain, who: str,
          seen: Mapping[str, str]) -> TaskCall:
    c = parse_call(text)
    if c is None:
        raise r.err(place, f"cannot read task {text!r}", 'write it as "task(obj, ...)"', text)
    _check_task(r, place, text, c[0], c[1], domain, who, seen)
    return c


def _check_task(r: _Reader, place: str, text: str, name: str, args: Sequence[str],
                domain: Domain, who: str, seen: Mapping[str, str]) -> None:
    m = domain.robot if who == "robot" else domain.human
    decl = m.operators.get(name) or m.tasks.get(name)
    if decl is None:
        known = sorted({*m.operators, *m.tasks})
        raise r.err(place, f"{m.agent} has no task or action {name!r}",
                    f"use one of: {', '.join(known)}", text)
    _check_objects(r, place, text, name, decl.params, args, seen, domain)


def _beliefs(r: _Reader, raw: Any, atom: Callable[[str, str], GroundAtom],
             init: frozenset[GroundAtom], domain: Domain,
             seen: Mapping[str, str]) -> tuple[BeliefWorld, ...]:
    if raw is None:
        return (BeliefWorld(),)
    if not isinstance(raw, dict):
        raise r.err("beliefs", "beliefs must be a table", "write [beliefs] or [[beliefs.world]]")
    for k in raw:
        if k not in _TABLE_KEYS["beliefs"]:
            raise r.unknown_key("beliefs", k, _TABLE_KEYS["beliefs"])
    if "world" in raw and raw.keys() & {"true", "false"}:
        raise r.err("[beliefs]", "use either true/false (one world) or [[beliefs.world]] entries",
                    "see docs/problem-format.md")
    entries = raw.get("world", [raw])
    if not isinstance(entries, list) or not entries:
        raise r.err("[beliefs] world", "expected one or more [[beliefs.world]] tables",
                    "write [[beliefs.world]]")
    out = []
    for i, w in enumerate(entries):
        place = f"[[beliefs.world]] #{i + 1}" if "world" in raw else "[beliefs]"
        if not isinstance(w, dict):
            raise r.err(place, "a world must be a table", "write [[beliefs.world]]")
        if "world" in raw:
            for k in w:
                if k not in _TABLE_KEYS["beliefs.world"]:
                    raise r.unknown_key("beliefs.world", k, _TABLE_KEYS["beliefs.world"],
                                        f"{place} {k}")
        tr = frozenset(atom(f"{place} true", s) for s in r.strings(f"{place} true",
                                                                     w.get("true", [])))
        fa = frozenset(atom(f"{place} false", s) for s in r.strings(f"{place} false",
                                                                      w.get("false", [])))
        _check_belief_values(r, place, tr, fa, init, domain, seen)
        for a in sorted(tr & init):
            raise r.err(f"{place} true", f"{fact_str(domain, *a)} is already true",
                        "list only atoms the human wrongly believes true",
                        fact_str(domain, *a))
        for a in sorted(fa - init):
            raise r.err(f"{place} false", f"{call_str(*a)} is already false",
                        "list only atoms the human wrongly believes false", call_str(*a))
        agenda = None
        if "robot_agenda" in w:
            agenda = tuple(_task(r, f"{place} robot_agenda", s, domain, "robot", seen)
                           for s in r.strings(f"{place} robot_agenda", w["robot_agenda"]))
        out.append(BeliefWorld(tr, fa, agenda))
    return tuple(out)


def _check_belief_values(r: _Reader, place: str, true: Iterable[GroundAtom],
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
    _check_values(r, f"{place} true", true, domain, seen, complete=False)
    now = _values_of(domain, init)
    for n, a in sorted(true):
        if n in domain.counters and now.get((n, a[:-1]), "0") == str(int(a[-1])):
            raise r.err(f"{place} true", f"{fact_str(domain, n, a)} is already true",
                        "list only values the human wrongly believes", fact_str(domain, n, a))


# --- the domain a problem names --------------------------------------------------------------

_DOMAIN_FORMS = ('a registered name ({known}), "file.py:attribute" (a Python file in the problem '
                 'file\'s folder) or "package.module:attribute"')
_IDENT = re.compile(r"[A-Za-z_]\w*")
_MODULE = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*")


def _resolve_domain(r: _Reader, t: Mapping[str, Any], base: Path) -> Domain:
    """The domain ``[domain] name`` names. Problem files are data: this imports a domain
    module (which runs it, as Python does), but calls nothing except a function marked with
    :func:`~ehatp.model.domain.domain_factory`."""
    forms = _DOMAIN_FORMS.format(known=", ".join(sorted(REGISTRY)))
    ref = t.get("name")
    if ref is None:
        raise r.err("[domain] name", "missing domain name", f"write name = one of {forms}")
    ref = r.string("[domain] name", ref, 'name = "cubes"')
    options = {k: v for k, v in t.items() if k != "name"}
    registered = ref in REGISTRY
    target = REGISTRY.get(ref, ref)
    mod_name, _, attr = target.rpartition(":")
    if not mod_name or not _IDENT.fullmatch(attr):
        raise r.err("[domain] name", f"unknown domain {ref!r}", f"use {forms}", ref)
    files: set[str] = set()
    if mod_name.endswith(".py"):
        f = _domain_file(r, ref, mod_name, base)
        files.add(str(f))
        module = _run_file(r, ref, f)
    else:
        module = _import(r, ref, mod_name)
    obj = getattr(module, attr, None)
    if obj is None:
        raise r.err("[domain] name", f"{mod_name} has no attribute {attr!r}",
                    "name a Domain, or a function marked @domain_factory that returns one", ref)
    if isinstance(obj, Domain):
        if options:
            raise r.err("[domain]", f"domain {ref!r} takes no options",
                        f"remove {', '.join(sorted(options))}")
        return obj
    if not registered and not is_domain_factory(obj):
        raise r.err("[domain] name", f"{ref!r} is neither a Domain nor a function marked as a "
                    "domain factory, and a problem file may not call anything else",
                    "name a Domain, or mark the function that builds it with "
                    "@ehatp.domain_factory", ref)
    _check_options(r, ref, obj, options)
    code = getattr(obj, "__code__", None)
    if code is not None:
        files.add(code.co_filename)
    try:
        dom = obj(**options)
    except (Exception, SystemExit) as e:
        what = "bad domain option" if options and isinstance(e, ValueError | TypeError) else ""
        raise _failure(r, ref, e, files, what) from None
    if not isinstance(dom, Domain):
        raise r.err("[domain] name", f"{ref!r} gave {type(dom).__name__}, not a Domain",
                    "return a Domain from the factory")
    return dom


def _domain_file(r: _Reader, ref: str, rel: str, base: Path) -> Path:
    """``rel`` as a file in ``base`` or below it; nothing outside the problem's folder."""
    given = Path(rel)
    if given.is_absolute() or given.drive or ".." in given.parts:
        raise r.err("[domain] name", f"{rel!r} is not inside the problem file's folder",
                    "give the domain file's path relative to the problem file, without '..' "
                    "(or install it as a module and name it \"module:attribute\")", ref)
    root = base.resolve()
    f = (root / given).resolve()
    if not f.is_relative_to(root):  # e.g. through a symbolic link
        raise r.err("[domain] name", f"{rel!r} leads outside the problem file's folder (to "
                    f"{f})", "put the domain file in the problem's folder", ref)
    if not f.is_file():
        raise r.err("[domain] name", f"no domain file {f}",
                    "give a path relative to the problem file", ref)
    return f


def _run_file(r: _Reader, ref: str, f: Path) -> ModuleType:
    # one module name per file, so two problems' domain.py do not replace each other
    digest = hashlib.sha256(str(f).encode()).hexdigest()[:10]
    stem = re.sub(r"\W", "_", f.stem)
    name = f"ehatp_user_domain_{stem}_{digest}"
    spec = importlib.util.spec_from_file_location(name, f)
    if spec is None or spec.loader is None:
        raise r.err("[domain] name", f"{f} cannot be loaded as Python",
                    "name a .py file", ref)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look modules up by name
    try:
        spec.loader.exec_module(module)
    except (Exception, SystemExit) as e:
        del sys.modules[name]
        raise _failure(r, ref, e, {str(f)}) from None
    return module


def _import(r: _Reader, ref: str, mod_name: str) -> ModuleType:
    if not _MODULE.fullmatch(mod_name):
        raise r.err("[domain] name", f"{mod_name!r} is not a module name",
                    "write package.module:attribute", ref)
    top = mod_name.split(".")[0]
    if top in sys.stdlib_module_names:
        raise r.err("[domain] name", f"{mod_name!r} is part of Python's standard library, "
                    "which holds no ehatp domain", "name a domain module", ref)
    try:
        return importlib.import_module(mod_name)
    except ModuleNotFoundError as e:
        if e.name is not None and (mod_name + ".").startswith(e.name + "."):
            raise r.err("[domain] name", f"cannot import {mod_name!r} ({e})",
                        "check the module name and that it is installed", ref) from None
        raise _failure(r, ref, e, set()) from None
    except (Exception, SystemExit) as e:
        raise _failure(r, ref, e, set()) from None


def _check_options(r: _Reader, ref: str, factory: Any, options: Mapping[str, Any]) -> None:
    """Options the factory does not take are a mistake in the problem file, not the domain."""
    try:
        sig = inspect.signature(factory)
    except (TypeError, ValueError):
        return  # no signature to check against: the call will tell
    try:
        sig.bind(**options)
    except TypeError as e:
        params = [p.name for p in sig.parameters.values()
                  if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
        extra = sorted(k for k in options if k not in params)
        if extra and (wrong := r.misplaced("domain", extra[0])) is not None:
            raise r.err(f"[domain] {extra[0]}", f"unknown key {extra[0]!r} in [domain]: "
                        f"{wrong[0]}", wrong[1]) from None
        takes = f"its options are {', '.join(params)}" if params else "it takes no options"
        raise r.err(f"[domain] {extra[0]}" if extra else "[domain]",
                    f"bad domain options for {ref!r}: {e}", takes) from None


_OWN = Path(__file__).resolve().parents[1]  # the ehatp package: never the user's line
_STDLIB = Path(sysconfig.get_paths()["stdlib"]).resolve()


def _code_place(e: BaseException, files: set[str]) -> str:
    """``file:line`` of the domain code that raised ``e``: the deepest frame in ``files``,
    else the deepest outside ehatp and the standard library."""
    if isinstance(e, SyntaxError) and e.filename:
        return f"{e.filename}:{e.lineno}"
    frames = traceback.extract_tb(e.__traceback__)
    mine = [f for f in frames if f.filename in files]
    if not mine:
        mine = [f for f in frames if not f.filename.startswith("<")
                and not Path(f.filename).resolve().is_relative_to(_OWN)
                and not Path(f.filename).resolve().is_relative_to(_STDLIB)]
    return f"{mine[-1].filename}:{mine[-1].lineno}" if mine else ""


def _failure(r: _Reader, ref: str, e: BaseException, files: set[str],
             what: str = "") -> InputError:
    """Anything a domain module raises, as one line: where in its code, and what."""
    at = _code_place(e, files)
    at = f" at {at}" if at else ""
    if isinstance(e, SyntaxError):
        detail = f"SyntaxError: {e.msg}"
    elif isinstance(e, DomainError):
        detail = str(e)
    else:
        detail = f"{type(e).__name__}: {e}" if str(e) else type(e).__name__
    if what:  # the factory refused an option: where in its code does not help
        return r.err("[domain]", f"{what} for {ref!r}: {detail}", "fix the option")
    verb = "is malformed" if isinstance(e, DomainError) else "failed"
    return r.err("[domain] name", f"domain {ref!r} {verb}{at}: {detail}",
                 "fix the domain module (it is Python code, run as such)", ref)


# --- problems built in Python ----------------------------------------------------------------


def check_problem(problem: Problem) -> None:
    """Check a :class:`Problem` as :func:`load` checks a file: predicates, objects, types,
    tasks, costs and settings. Raise :class:`InputError` (file ``problem.source``) on the
    first mistake. The planner calls it, so a Problem built in Python is checked too."""
    r = _Reader(problem.source, "")
    d = problem.domain
    if not isinstance(d, Domain):
        raise r.err("domain", f"expected a Domain, got {type(d).__name__}", "pass a Domain")
    d.check()
    if not isinstance(problem.name, str):
        raise r.err("name", f"expected a string, got {_show(problem.name)}", 'name="P1"')
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
            _check_atom(r, place, call_str(name, args), name, args, d, seen)

    def tasks(place: str, value: Iterable[Any], who: str) -> None:
        for c in value:
            name, args = _pair(r, place, c, "task", '("organize", ())')
            _check_task(r, place, call_str(name, args), name, args, d, who, seen)

    atoms("init", problem.init)
    _check_values(r, "init", problem.init, d, seen)
    tasks("robot_agenda", problem.robot_agenda, "robot")
    tasks("human_agenda", problem.human_agenda, "human")
    for i, w in enumerate(problem.beliefs, 1):
        if not isinstance(w, BeliefWorld):
            raise r.err(f"beliefs #{i}", f"expected a BeliefWorld, got {type(w).__name__}",
                        "write BeliefWorld(true=..., false=...)")
        atoms(f"beliefs #{i} true", w.true)
        atoms(f"beliefs #{i} false", w.false)
        _check_belief_values(r, f"beliefs #{i}", w.true, w.false, problem.init, d, seen)
        if w.robot_agenda is not None:
            tasks(f"beliefs #{i} robot_agenda", w.robot_agenda, "robot")
    for g in problem.goal:
        if not (isinstance(g, tuple) and len(g) == 2 and isinstance(g[0], bool)):
            raise r.err("goal", f"expected (True or False, atom) pairs, got {_show(g)}",
                        'write goal=((True, ("in", ("r", "box1"))),)')
        atoms("goal", [g[1]])
    if problem.starts not in ("human", "robot"):
        raise r.err("starts", f"unknown agent {problem.starts!r}", 'write "human" or "robot"')
    if isinstance(problem.K, bool) or not isinstance(problem.K, int) or problem.K < 0:
        raise r.err("K", f"K must be a whole number >= 0, got {_show(problem.K)}", "write K=2")
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


def _pair(r: _Reader, place: str, value: Any, what: str,
          example: str) -> tuple[str, tuple[str, ...]]:
    """A ``(name, (arg, ...))`` pair, as atoms and task calls are written in Python."""
    if (isinstance(value, tuple) and len(value) == 2 and isinstance(value[0], str)
            and isinstance(value[1], tuple) and all(isinstance(a, str) for a in value[1])):
        return value[0], value[1]
    raise r.err(place, f"expected a {what} as (name, (arg, ...)), got {_show(value)}",
                f"write e.g. {example}")


def atoms_to_strs(atoms: Iterable[GroundAtom]) -> list[str]:
    return sorted(call_str(n, a) for n, a in atoms)
