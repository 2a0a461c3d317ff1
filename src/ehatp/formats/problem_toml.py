"""The problem file: TOML in, a checked :class:`~ehatp.model.problem.Problem` out
(``docs/problem-format.md``).

:func:`load` checks everything before anything is built: a mistake is one :class:`InputError`
line naming the file, the line and key, and the fix. The checks a problem built in Python passes
too live with the data, in :mod:`ehatp.model.problem`; what is the file's own (its tables and
keys, where each key belongs, the domain it names and how that is found) lives here.
"""

from __future__ import annotations

import copy
import hashlib
import importlib
import importlib.util
import inspect
import re
import sys
import sysconfig
import tomllib
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from ..errors import DomainError, InputError, control_char
from ..model.domain import AGENT_TYPE, Domain, is_domain_factory
from ..model.options import OPTION_KEYS, read_options, read_steps
from ..model.problem import (
    BeliefWorld,
    Checker,
    Costs,
    GroundAtom,
    Limits,
    Problem,
    TaskCall,
    call_str,
    check_atom,
    check_belief_values,
    check_task,
    check_values,
    fact_str,
    parse_call,
    parse_fact,
    parse_size,
    show_value,
)
from ..model.registry import BUILTIN, HOW_TO_DECLARE, declared, declared_modules

# ehatp's own domains by name ("module:attribute"; the model layer does not import the domain
# library); every declared domain, these included, is in ehatp.model.registry
REGISTRY: dict[str, str] = BUILTIN


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
               "options", "human", "communication", "objective", "steps"}
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


class TomlReader(Checker):
    """Holds the file text so errors can point at the line of the key they are about."""

    def __init__(self, path: str, text: str) -> None:
        super().__init__(path)
        self.text = text
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
    r = TomlReader(str(path), text)
    data = _toml(r, text, overrides)
    prob = r.table(data, "problem", _TABLE_KEYS["problem"], required=True)
    domain = _resolve_domain(r, r.table(data, "domain", None, required=True), Path(path).parent)
    name, starts, K, description = _header(r, prob, domain, Path(path).stem)
    objects, seen = _objects(r, data, domain)
    atom = _atom_reader(r, domain, seen)
    init_t = r.table(data, "init", _TABLE_KEYS["init"], required=True)
    init = frozenset(atom("[init] true", a) for a in r.strings("[init] true",
                                                                init_t.get("true", [])))
    check_values(r, "[init] true", init, domain, seen)
    agendas = _agendas(r, data, domain, seen)
    beliefs = _beliefs(r, data.get("beliefs"), atom, init, domain, seen)
    goal = _goal(r, data, atom)
    costs, limits = _costs(r, data, domain), _limits(r, data)
    human, communication, objective, notes = read_options(r, data, domain.metrics)
    steps = read_steps(r, data)
    after = tuple(r.strings("[problem] after", prob.get("after", [])))
    return Problem(name=name, domain=domain, objects=objects, init=init,
                   robot_agenda=agendas["robot"], human_agenda=agendas["human"], beliefs=beliefs,
                   starts=starts, K=K, costs=costs, limits=limits, human=human,
                   communication=communication, objective=objective, steps=steps, notes=notes,
                   goal=goal, after=after, description=description,
                   source=str(path))


def _toml(r: TomlReader, text: str, overrides: Mapping[str, Any] | None) -> dict[str, Any]:
    """Return the file's tables, ``overrides`` applied, once every top-level key is known."""
    if not text.strip():
        raise InputError(r.path, "", "the file is empty",
                         "write a problem (see docs/problem-format.md)")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(r.path, "", f"not valid TOML: {e}", "fix the TOML syntax") from None
    except RecursionError:  # the parser recurses per nesting level
        raise InputError(r.path, "", "arrays or tables are nested too deeply",
                         "flatten the file (a problem needs two levels at most)") from None
    for dotted, value in (overrides or {}).items():
        _override(r.path, data, dotted, value)
    _printable(r, data)
    for k in data:
        if k not in _TOP_KEYS:
            wrong = r.misplaced("", k)
            if wrong is not None:
                raise r.err(k, f"unknown table or key {k!r}: {wrong[0]}", wrong[1])
            raise r.err(k, f"unknown table or key {k!r}", f"use {', '.join(sorted(_TOP_KEYS))}")
    return data


# where text of several lines is at home (newlines and tabs allowed, other controls not)
_PROSE = {("problem", "description")}


def _printable(r: TomlReader, data: Mapping[str, Any]) -> None:
    """Refuse a key or string value holding a control character (ESC included): no name of a
    problem, object or task has one, and printed to a terminal it could be an escape code.
    (A walk with a stack: any depth.)"""
    stack: list[tuple[tuple[str, ...], Any]] = [((), data)]
    while stack:
        path, value = stack.pop()
        if isinstance(value, dict):
            for k, v in value.items():
                stack += [(path, k), ((*path, k), v)]
        elif isinstance(value, list):
            stack += [(path, v) for v in value]
        elif isinstance(value, str):
            text = value.replace("\n", "").replace("\t", "") if path in _PROSE else value
            if (ch := control_char(text)) is not None:
                place = (f"[{path[0]}] {'.'.join(path[1:])}".strip() if len(path) > 1
                         else path[0] if path else "")
                raise r.err(place, f"{value!r} holds the control character {ch!r}",
                            "remove it: names and values are printable text")


def _header(r: TomlReader, prob: Mapping[str, Any], domain: Domain,
            stem: str) -> tuple[str, str, int, str]:
    """Return ``[problem]``'s name (the file's stem by default), who starts ("human" or
    "robot", also given by the agents' names), K and description."""
    name = r.string("[problem] name", prob.get("name", stem), 'name = "P1"')
    starts = r.string("[problem] starts", prob.get("starts", "human"), 'starts = "human"')
    starts = {domain.human_name: "human", domain.robot_name: "robot"}.get(starts, starts)
    if starts not in ("human", "robot"):
        raise r.err("[problem] starts", f"unknown agent {prob.get('starts')!r}",
                    f'write "human" or "robot" (or "{domain.human_name}"/"{domain.robot_name}")')
    K = prob.get("K", 2)
    if isinstance(K, bool) or not isinstance(K, int) or K < 0:
        raise r.err("[problem] K", f"K must be a whole number >= 0, got {show_value(K)}",
                    "write e.g. K = 2")
    description = r.string("[problem] description", prob.get("description", ""),
                           'description = "two cubes"')
    return name, starts, K, description


def _objects(r: TomlReader, data: Mapping[str, Any],
             domain: Domain) -> tuple[dict[str, list[str]], dict[str, str]]:
    """Return ``[objects]`` by type and the type of every object, the domain's constants
    included."""
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
    return objects, seen


AtomReader = Callable[[str, str], GroundAtom]


def _atom_reader(r: TomlReader, domain: Domain, seen: Mapping[str, str]) -> AtomReader:
    """Return the reader of one atom (or value) written at a place of the file, checked."""

    def atom(place: str, text: str) -> GroundAtom:
        c = parse_fact(text)
        if c is None:
            raise r.err(place, f"cannot read atom {text!r}", 'write it as "pred(obj, obj)", or '
                        '"var(obj) = value" for a state variable or a counter', text)
        check_atom(r, place, text, c[0], c[1], domain, seen)
        return c

    return atom


def _agendas(r: TomlReader, data: Mapping[str, Any], domain: Domain,
             seen: Mapping[str, str]) -> dict[str, tuple[TaskCall, ...]]:
    """Return ``[agenda]``'s task calls by agent ("robot", "human"; the file may use the
    agents' names)."""
    agents = {"robot", "human", domain.robot_name, domain.human_name}
    ag_t = r.table(data, "agenda", agents, required=True)
    agendas: dict[str, tuple[TaskCall, ...]] = {"robot": (), "human": ()}
    for key, v in ag_t.items():
        who = "robot" if key in ("robot", domain.robot_name) else "human"
        agendas[who] = tuple(_task(r, f"[agenda] {key}", s, domain, who, seen)
                             for s in r.strings(f"[agenda] {key}", v))
    return agendas


def _goal(r: TomlReader, data: Mapping[str, Any],
          atom: AtomReader) -> tuple[tuple[bool, GroundAtom], ...]:
    """Return the top-level ``goal`` as (holds, atom) pairs: ``"not a"`` is (False, a)."""
    goal: list[tuple[bool, GroundAtom]] = []
    if "goal" in data:
        for s in r.strings("goal", data["goal"]):
            neg = s.strip().startswith("not ")
            goal.append((not neg, atom("goal", s.strip()[4:] if neg else s)))
    return tuple(goal)


def _costs(r: TomlReader, data: Mapping[str, Any], domain: Domain) -> Costs:
    """Return ``[costs]``, ``[costs.actions]`` naming the domain's actions."""
    c_t = r.table(data, "costs", _TABLE_KEYS["costs"])
    acts = c_t.pop("actions", {})
    if not isinstance(acts, dict):
        raise r.err("[costs] actions", "actions must be a table", "write [costs.actions]")
    all_ops = {*domain.robot.operators, *domain.human.operators}
    for a in acts:
        if a not in all_ops:
            raise r.unknown_key("costs.actions", a, all_ops, what="action")
    return Costs(
        **{("pass_" if k == "pass" else k): r.number(f"[costs] {k}", v) for k, v in c_t.items()},
        actions={a: r.number(f"[costs.actions] {a}", v) for a, v in acts.items()},
    )


def _limits(r: TomlReader, data: Mapping[str, Any]) -> Limits:
    """Return ``[limits]``, each key not given at its default."""
    l_t = r.table(data, "limits", _TABLE_KEYS["limits"])
    return Limits(
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


def _size(r: TomlReader, place: str, v: Any) -> int:
    try:
        return parse_size(v)
    except ValueError:
        raise r.err(place, f"expected a memory size, got {show_value(v)}",
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


def _int(r: TomlReader, place: str, v: Any, least: int = 1) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < least:
        raise r.err(place, f"expected a whole number {'> 0' if least == 1 else f'>= {least}'}"
                    f", got {show_value(v)}", "write e.g. 1000")
    return v


def _flag(r: TomlReader, place: str, v: Any) -> bool:
    if not isinstance(v, bool):
        raise r.err(place, f"expected true or false, got {show_value(v)}", "write e.g. false")
    return v


def _task(r: TomlReader, place: str, text: str, domain: Domain, who: str,
          seen: Mapping[str, str]) -> TaskCall:
    c = parse_call(text)
    if c is None:
        raise r.err(place, f"cannot read task {text!r}", 'write it as "task(obj, ...)"', text)
    check_task(r, place, text, c[0], c[1], domain, who, seen)
    return c


def _beliefs(r: TomlReader, raw: Any, atom: Callable[[str, str], GroundAtom],
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
        check_belief_values(r, place, tr, fa, init, domain, seen)
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


# --- the domain a problem names --------------------------------------------------------------

_DOMAIN_FORMS = ('a declared domain ({known}), "file.py:attribute" (a Python file in the problem '
                 'file\'s folder) or "package.module:attribute" of a declared domain\'s module')
_IDENT = re.compile(r"[A-Za-z_]\w*")
_MODULE = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*")


def _resolve_domain(r: TomlReader, t: Mapping[str, Any], base: Path) -> Domain:
    """The domain ``[domain] name`` names. Problem files are data: a module is imported only
    when it declared itself a domain (:mod:`ehatp.model.registry`) or is a ``.py`` file in the
    problem's folder, and nothing is called except a declared target or a function marked with
    :func:`~ehatp.model.domain.domain_factory`."""
    ref = t.get("name")
    if ref is None:
        forms = _DOMAIN_FORMS.format(known=", ".join(sorted(declared())))
        raise r.err("[domain] name", "missing domain name", f"write name = one of {forms}")
    ref = r.string("[domain] name", ref, 'name = "cubes"')
    options = {k: v for k, v in t.items() if k != "name"}
    mod_name, _, attr = ref.rpartition(":")
    files: set[str] = set()
    if mod_name.endswith(".py") and _IDENT.fullmatch(attr):  # the user's file: their code
        f = _domain_file(r, ref, mod_name, base)
        files.add(str(f))
        obj, trusted = getattr(_run_file(r, ref, f), attr, None), False
    else:
        obj, trusted = _declared(r, ref)
    if obj is None:
        raise r.err("[domain] name", f"{mod_name} has no attribute {attr!r}",
                    "name a Domain, or a function marked @domain_factory that returns one", ref)
    if isinstance(obj, Domain):
        if options:
            raise r.err("[domain]", f"domain {ref!r} takes no options",
                        f"remove {', '.join(sorted(options))}")
        return obj
    if not trusted and not is_domain_factory(obj):
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
        # the call itself refused the options (no frame of the factory ran): the file's fault;
        # anything the factory raised, whatever its type, is the domain's own error
        refused = isinstance(e, TypeError) and (e.__traceback__ is None
                                                or e.__traceback__.tb_next is None)
        what = "bad domain options" if options and refused else ""
        raise _failure(r, ref, e, files, what, options) from None
    if not isinstance(dom, Domain):
        raise r.err("[domain] name", f"{ref!r} gave {type(dom).__name__}, not a Domain",
                    "return a Domain from the factory")
    return dom


def _declared(r: TomlReader, ref: str) -> tuple[Any, bool]:
    """Return what the declared domain ``ref`` stands for, and whether it is trusted (a
    declared target, called even unmarked): ``ref`` is a declared name, or
    ``"module:attribute"`` of a module that a declared domain names. Anything else is refused
    before any import, with the declared names and how to declare one."""
    known = BUILTIN if ref in BUILTIN else declared()  # ehatp's own: no metadata to read
    target, trusted = known.get(ref), True
    if target is None:
        mod_name, _, attr = ref.rpartition(":")
        if not mod_name or not _IDENT.fullmatch(attr) or mod_name not in declared_modules(known):
            what = (f"{ref!r} names a module that declared no domain, so it is not imported"
                    if mod_name else f"unknown domain {ref!r}")
            raise r.err("[domain] name", f"{what}; the declared domains are "
                        f"{', '.join(sorted(known))}",
                        'name one of them, a "file.py:attribute" in the problem\'s folder, or '
                        f"a module:attribute of a declared domain's module; {HOW_TO_DECLARE}",
                        ref)
        target, trusted = ref, ref in known.values()
    if not isinstance(target, str):  # registered from Python as an object
        return target, True
    mod_name, _, attr = target.rpartition(":")
    obj = getattr(_import(r, ref, mod_name), attr, None)
    if obj is None:
        raise r.err("[domain] name", f"{mod_name} has no attribute {attr!r}",
                    "name a Domain, or a function marked @domain_factory that returns one", ref)
    return obj, trusted


def _domain_file(r: TomlReader, ref: str, rel: str, base: Path) -> Path:
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


def _run_file(r: TomlReader, ref: str, f: Path) -> ModuleType:
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


def _import(r: TomlReader, ref: str, mod_name: str) -> ModuleType:
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


def _check_options(r: TomlReader, ref: str, factory: Any, options: Mapping[str, Any]) -> None:
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


def _failure(r: TomlReader, ref: str, e: BaseException, files: set[str],
             what: str = "", options: Mapping[str, Any] | None = None) -> InputError:
    """Anything a domain module raises, as one line: where in its code, and what. ``what``
    (``"bad domain options"``) says the call itself refused ``options``, before any of the
    domain's code ran; otherwise the error is the domain's, at the last line of its code the
    traceback passes through, and the options it was called with are named, since one of them
    may be what it refuses."""
    at = _code_place(e, files)
    at = f" at {at}" if at else ""
    if isinstance(e, SyntaxError):
        detail = f"SyntaxError: {e.msg}"
    elif isinstance(e, DomainError):
        detail = str(e)
    else:
        detail = f"{type(e).__name__}: {e}" if str(e) else type(e).__name__
    if what:  # the call refused the options: there is no line of the domain's to show
        return r.err("[domain]", f"{what} for {ref!r}: {detail}", "fix the option")
    verb = "is malformed" if isinstance(e, DomainError) else "failed"
    if options:
        given = ", ".join(f"{k} = {v!r:.40}" for k, v in options.items())
        return r.err("[domain] name", f"domain {ref!r} {verb}{at}, called with {given}: "
                     f"{detail}", "that is the domain's own error: fix its code there, or the "
                     "[domain] option it refuses", ref)
    return r.err("[domain] name", f"domain {ref!r} {verb}{at}: {detail}",
                 "fix the domain module (it is Python code, run as such)", ref)


__all__ = ["REGISTRY", "TomlReader", "load", "loads"]
