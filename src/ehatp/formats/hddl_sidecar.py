"""The sidecar of an HDDL import (docs/hddl.md, "The sidecar"): what HDDL does not say -- the
agents' names, what the human perceives, when the two are together, the other agent -- read from
TOML or from a Python module, and the literals it writes (``"at(?x, depot)"``, ``"not busy"``).
"""

from __future__ import annotations

import importlib.util
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import HddlUnsupported, control_char
from .schema import mismatch

AGENTS = ("robot", "human")
CLASSES = ("observable", "inferable", "hidden")


# --- the sidecar -----------------------------------------------------------------------------


@dataclass
class SidecarMetric:
    """A ``[metrics.NAME]`` table: the steps in which ``agent`` does one of ``actions`` while
    the literals ``when`` hold at the step's start (docs/hddl.md, docs/concurrent.md C11)."""

    agent: str
    actions: list[str]
    when: list[str] = field(default_factory=list)
    doc: str = ""


METRIC_AGENTS = ("robot", "human", "either")


@dataclass
class Sidecar:
    """What HDDL does not say (docs/hddl.md, "The sidecar"). Literals are written
    ``"at(?x, depot)"`` or ``"not busy"``: ``?name`` is a parameter of the predicate being
    described (in ``when``), anything else an object."""

    robot: str = "R"
    human: str = "H"
    default: str = "observable"  # the class of a predicate not listed in ``classes``
    classes: dict[str, str] = field(default_factory=dict)  # predicate -> class
    when: dict[str, list[str]] = field(default_factory=dict)  # observable while these hold
    copresence: list[str] = field(default_factory=list)  # ground literals; [] = always
    other: str = "none"  # the other agent's model: "none" or "same" (the HDDL model too)
    other_agenda: list[str] = field(default_factory=list)
    # what the human expects of the robot, when the HDDL model is the robot's: "plan" (it
    # knows the robot's model, M_R^H = M_R, and follows which methods it may be using) or
    # "nothing" (M_R^H empty: it sees the robot's actions, and expects none)
    expects: str = "plan"
    # action -> what it holds while it runs ("?x": its parameter x, else a name): joint steps
    # never do two actions holding a common one together (docs/concurrent.md, C3 c)
    resources: dict[str, list[str]] = field(default_factory=dict)
    # metric name -> its declaration (docs/concurrent.md C11, "Metrics a domain declares"):
    # agent ("robot" | "human" | "either"), actions (names), when (literals over the actions'
    # parameters, "?x"; all must hold), doc
    metrics: dict[str, SidecarMetric] = field(default_factory=dict)
    problem: dict[str, Any] = field(default_factory=dict)  # [problem] K, starts, name
    limits: dict[str, Any] = field(default_factory=dict)  # [limits] of the problem
    customize: Path | None = None  # a Python sidecar with customize(d), run last
    source: str = "<defaults>"

    def check(self) -> None:
        where = self.source
        if self.default not in CLASSES:
            raise HddlUnsupported(f"{where}: [observability] default = {self.default!r}; "
                                  f"use one of {', '.join(CLASSES)}")
        for p, c in self.classes.items():
            if c not in CLASSES:
                raise HddlUnsupported(f"{where}: [observability] {p} = {c!r}; use one of "
                                      f"{', '.join(CLASSES)} (or [observability.when])")
        if self.other not in ("none", "same"):
            raise HddlUnsupported(f"{where}: [other] model = {self.other!r}; use \"none\" or "
                                  "\"same\"")
        if self.expects not in ("plan", "nothing"):
            raise HddlUnsupported(f"{where}: [other] expects = {self.expects!r}; use \"plan\" "
                                  "or \"nothing\"")
        for name, m in self.metrics.items():
            if not re.fullmatch(r"[a-z][a-z0-9_]*", name):
                raise HddlUnsupported(f"{where}: [metrics.{name}]: a metric's name is lower "
                                      "case letters, digits and _, starting with a letter")
            if m.agent not in METRIC_AGENTS:
                raise HddlUnsupported(f"{where}: [metrics.{name}] agent = {m.agent!r}; use "
                                      + ", ".join(f'"{a}"' for a in METRIC_AGENTS))
            if not m.actions:
                raise HddlUnsupported(f"{where}: [metrics.{name}] actions is empty; name the "
                                      "actions it counts")
        if self.other_agenda and self.other == "none" and self.customize is None:
            raise HddlUnsupported(f"{where}: [other] agenda needs model = \"same\" (or a "
                                  "Python sidecar whose customize(d) gives the other agent "
                                  "its tasks)")


_SIDECAR_KEYS = {
    "agents": {"robot", "human"},
    "observability": {"default", "when", "observable", "inferable", "hidden"},
    "copresence": {"when"},
    "other": {"model", "agenda", "expects"},
    "resources": set(),  # any action name
    "metrics": set(),  # any metric name, each a table of _METRIC_KEYS
    "problem": {"name", "K", "starts", "description"},
    "limits": {"timeout", "max_states", "max_depth", "max_memory", "max_decomposition",
               "symmetry"},
}


def read_sidecar(path: str | Path | None) -> Sidecar:
    """Read a TOML sidecar, or a Python one (a module with a ``SIDECAR`` dict of the same
    tables and, optionally, ``customize(d)`` run on the built domain); None: the defaults (a
    robot-only problem, every predicate observable, always together)."""
    if path is None:
        return Sidecar()
    p = Path(path)
    if p.suffix == ".py":
        spec = importlib.util.spec_from_file_location(f"_ehatp_sidecar_{abs(hash(p))}", p)
        if spec is None or spec.loader is None:
            raise HddlUnsupported(f"{p}: cannot load this Python sidecar")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        data = getattr(mod, "SIDECAR", {})
        side = _sidecar_from(data, str(p), check=False)
        if callable(getattr(mod, "customize", None)):
            side.customize = p.resolve()
        side.check()
        return side
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except OSError as e:
        raise HddlUnsupported(f"{p}: cannot read the sidecar ({e.strerror or e})") from None
    except UnicodeDecodeError:
        raise HddlUnsupported(f"{p}: not a text file; give a TOML sidecar") from None
    except tomllib.TOMLDecodeError as e:
        raise HddlUnsupported(f"{p}: not TOML ({e})") from None
    except RecursionError:
        raise HddlUnsupported(f"{p}: nested too deeply for a sidecar; see docs/hddl.md, "
                              "\"The sidecar\"") from None
    return _sidecar_from(data, str(p))


SCHEMA = "sidecar.schema.json"
"""The JSON Schema of a sidecar's tables, shipped beside this module."""


def check_schema(data: Any, where: str) -> None:
    """Raise :class:`HddlUnsupported` unless ``data`` (a sidecar's tables) has the shape the
    sidecar's schema gives: every table and key known, lists where lists go, strings and
    numbers where they go. The error names the first place that does not match, e.g.
    ``side.toml: copresence.when: must be a list``."""
    found = mismatch(SCHEMA, data)
    if found is not None:
        place, what = found
        raise HddlUnsupported(f"{where}: {place or 'the sidecar'}: "
                              f"{what.replace('an object', 'a table')}; see docs/hddl.md, "
                              "\"The sidecar\"")


def _printable(data: Mapping[str, Any], where: str) -> None:
    """Refuse a key or string of the sidecar that holds a control character (ESC included):
    they become names, printed to terminals and written to files (``[problem] description``
    may hold newlines and tabs, as in a problem file). (A walk with a stack: any depth.)"""
    stack: list[tuple[str, Any]] = [("", data)]
    while stack:
        place, value = stack.pop()
        if isinstance(value, Mapping):
            for k, v in value.items():
                stack += [(place or "a key", k), (f"{place}.{k}" if place else str(k), v)]
        elif isinstance(value, list | tuple):
            stack += [(place, v) for v in value]
        elif isinstance(value, str) and (ch := control_char(
                value.replace("\n", "").replace("\t", "") if place == "problem.description"
                else value)) is not None:
            raise HddlUnsupported(f"{where}: {place}: {value!r} holds the control character "
                                  f"{ch!r}; remove it")


def _sidecar_from(data: Mapping[str, Any], where: str, check: bool = True) -> Sidecar:
    if not isinstance(data, Mapping):
        raise HddlUnsupported(f"{where}: SIDECAR must be a dict of tables; see docs/hddl.md, "
                              "\"The sidecar\"")
    _printable(data, where)
    check_schema(dict(data), where)
    for table, value in data.items():
        keys = _SIDECAR_KEYS.get(table)
        if keys is None:
            raise HddlUnsupported(f"{where}: unknown table [{table}]; use "
                                  f"{', '.join(f'[{t}]' for t in _SIDECAR_KEYS)}")
        bad = (sorted(set(value) - keys)
               if table not in ("observability", "resources", "metrics") else [])
        if bad:
            raise HddlUnsupported(f"{where}: [{table}] has no key {bad[0]!r}; use "
                                  f"{', '.join(sorted(keys))}")
    s = Sidecar(source=where)
    agents = data.get("agents", {})
    s.robot, s.human = str(agents.get("robot", "R")), str(agents.get("human", "H"))
    obs = dict(data.get("observability", {}))
    s.default = str(obs.pop("default", "observable"))
    s.when = {str(k): [str(x) for x in v] for k, v in obs.pop("when", {}).items()}
    for cls in CLASSES:
        for pred in obs.pop(cls, []) if isinstance(obs.get(cls), list) else []:
            s.classes[str(pred)] = cls
    for pred, cls in obs.items():  # predicate = "hidden"
        s.classes[str(pred)] = str(cls)
    s.copresence = [str(x) for x in data.get("copresence", {}).get("when", [])]
    other = data.get("other", {})
    s.other = str(other.get("model", "none"))
    s.other_agenda = [str(x) for x in other.get("agenda", [])]
    s.expects = str(other.get("expects", "plan"))
    s.resources = {str(a): [str(x) for x in held]
                   for a, held in data.get("resources", {}).items()}
    s.metrics = {str(name): SidecarMetric(str(m.get("agent", "")),
                                          [str(a) for a in m.get("actions", [])],
                                          [str(x) for x in m.get("when", [])],
                                          str(m.get("doc", "")))
                 for name, m in data.get("metrics", {}).items()}
    s.problem = dict(data.get("problem", {}))
    s.limits = dict(data.get("limits", {}))
    if check:
        s.check()
    return s


def check_metrics(side: Sidecar, agent: str, params: Mapping[str, Mapping[str, str]]) -> None:
    """Raise :class:`HddlUnsupported`, naming the sidecar, unless every ``[metrics.NAME]``
    names actions of the domain (``params``: each action's parameters, by name, as the
    written module names them), counts an agent that has a model (``agent`` has the HDDL
    one; the other needs ``[other] model = "same"`` or a Python sidecar), and reads in
    ``when`` only parameters every one of its actions has (docs/concurrent.md C11)."""
    for name, m in sorted(side.metrics.items()):
        where = f"{side.source}: [metrics.{name}]"
        unknown = [a for a in m.actions if a not in params]
        if unknown:
            raise HddlUnsupported(f"{where} names {unknown[0]!r}, which is not an action of "
                                  "the domain")
        if m.agent not in (agent, "either") and side.other != "same" and side.customize is None:
            raise HddlUnsupported(f"{where}: agent = {m.agent!r}, but only the {agent} has the "
                                  f'HDDL model; add [other] model = "same", or count the '
                                  f"{agent}'s actions")
        for text in m.when:
            for x in literal(text, where)[2]:
                if x.startswith("?") and any(params[a].get(x[1:]) != params[m.actions[0]]
                                             .get(x[1:]) for a in m.actions):
                    raise HddlUnsupported(f"{where}: when reads {x}, which is not a parameter "
                                          "(of one type) of every action it counts "
                                          f"({', '.join(m.actions)})")


_LIT = re.compile(r"^\s*(not\s+)?([A-Za-z_][\w\-]*)\s*(?:\((.*)\))?\s*$")
_EQ = re.compile(r"^\s*(\??[\w\-]+)\s*(=|!=)\s*(\??[\w\-]+)\s*$")


def literal(text: str, where: str) -> tuple[bool, str, list[str]]:
    """``"at(?x, l1)"`` -> (True, "at", ["?x", "l1"]); ``"?p = a"`` -> (True, "=", [...])."""
    e = _EQ.match(text)
    if e:
        return e.group(2) == "=", "=", [e.group(1), e.group(3)]
    m = _LIT.match(text)
    if not m:
        raise HddlUnsupported(f"{where}: cannot read {text!r} as a literal (e.g. \"at(?x, l1)\", "
                              "\"not busy\" or \"?p = l1\")")
    args = [a.strip() for a in m.group(3).split(",")] if m.group(3) else []
    return m.group(1) is None, m.group(2), args


__all__ = ["AGENTS", "CLASSES", "METRIC_AGENTS", "SCHEMA", "Sidecar", "SidecarMetric",
           "check_metrics", "check_schema", "literal", "read_sidecar"]
