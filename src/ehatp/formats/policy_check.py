"""A policy file as the tools read it: :func:`read_policy` loads it
(:meth:`~ehatp.formats.policy.Policy.load`) and checks the type of every field the tools read and
whether its counts match its graph, so that a hand-edited or truncated file is one
:class:`~ehatp.errors.InputError` line instead of a wrong display or a crash;
:func:`check_policy_problem` checks it was planned for a given problem."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from fractions import Fraction
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any, cast

from ..errors import InputError
from ..model.problem import Problem
from .policy import POLICY_FIX, Policy, malformed


def read_policy(path: Path | str, *, counts: bool = True,
                check: Callable[[], None] | None = None) -> Policy:
    """Read and check a policy file (version 3 or 2; 1 turned into a graph): the JSON against
    the format's schema first (:func:`check_schema`: nothing reads a field before its shape is
    known), then :meth:`Policy.load`, then the type of every field the tools read and
    (``counts``) whether the header's counts and the moves' agents match the graph, so a
    hand-edited or truncated file is one :class:`InputError` line instead of a wrong display
    or a crash. (``validate`` leaves the counts to the validator.) ``check``, e.g. a time
    limit's, is called between the steps and every few hundred nodes, and may raise."""
    check_schema(path)
    if check is not None:
        check()
    try:
        policy = Policy.load(path, check)
    except (AttributeError, TypeError, KeyError, ValueError, IndexError, RecursionError) as e:
        # the format reader trusts the JSON's shapes; anything it trips on is the file's fault
        place, what = _shape(path) or ("", f"malformed policy ({type(e).__name__}: {e})")
        raise InputError(str(path), place, what, POLICY_FIX) from None
    check_policy(policy, str(path), counts=counts)
    return policy


SCHEMA = "policy.schema.json"
"""The JSON Schema of policy format versions 2 and 3, shipped beside this module."""


@cache
def _schema_check() -> Callable[[Any], Any]:
    """Return the compiled check of :data:`SCHEMA` (compiled once per process)."""
    import fastjsonschema  # on first use: `ehatp --help` loads no schema checker

    schema = json.loads(resources.files(__package__).joinpath(SCHEMA).read_text("utf-8"))
    return cast(Callable[[Any], Any], fastjsonschema.compile(schema))


_SAY = {f"must be {kind}": f"must be {say}" for kind, say in [
    ("integer", "a whole number"), ("number", "a number"), ("string", "a string"),
    ("boolean", "true or false"), ("array", "a list"), ("object", "an object"),
    ("number or null", "a number or null"), ("string or null", "a string or null")]}
"""The schema checker's words for a type, in the words of the other policy errors."""


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


def check_schema(path: Path | str) -> None:
    """Raise :class:`InputError` unless the file at ``path`` is JSON (``NaN`` and
    ``Infinity`` refused) whose object matches the policy format's schema (versions 2 and 3;
    a version 1 file, which the schema does not describe, is left to :meth:`Policy.load`).
    The error names the first field that does not match, e.g. ``p.json:objective: must be
    object``. A file that cannot be read or parsed is left to :meth:`Policy.load` too, which
    says so in its own words."""
    name = str(path)
    try:
        raw = json.loads(Path(path).read_text(encoding="utf-8"), parse_constant=_no_constant)
    except ValueError as e:
        if "JSON allows" in str(e):
            raise InputError(name, "", str(e), POLICY_FIX) from None
        return
    except (OSError, RecursionError):
        return
    if not isinstance(raw, dict) or raw.get("version") not in (2, 3) or isinstance(
            raw.get("version"), bool):
        return
    check = _schema_check()
    import fastjsonschema

    try:
        check(raw)
    except fastjsonschema.JsonSchemaValueException as e:
        where = str(e.name or "data")
        place = where[len("data."):] if where.startswith("data.") else ""
        what = str(e.message)
        if what.startswith(where + " "):
            what = what[len(where) + 1:]
        what = _SAY.get(what, what)
        raise InputError(name, place, what[:200], POLICY_FIX + " (the file does not match "
                         "the format's schema: see docs/policy-format.md)") from None
    except RecursionError:
        raise InputError(name, "", "nested too deeply for a policy", POLICY_FIX) from None


def _shape(path: Path | str) -> tuple[str, str] | None:
    """Where a policy's JSON has the wrong shape for its reader, in the file's own terms."""
    try:
        raw = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    return malformed(raw)


_NODE_FIELDS: dict[str, tuple[str, str]] = {
    # field: (kind of value, how to say it)
    "copresent": ("bool", "true or false"), "k": ("int", "a whole number"),
    "worlds": ("int", "a whole number"), "divergence": ("strs", "a list of strings"),
    "state": ("strs", "a list of strings"), "robot_agenda": ("strs", "a list of strings"),
    "human_agenda": ("strs", "a list of strings"), "value": ("num", "a number"),
    "goal": ("bool", "true or false"), "to_move": ("str?", "a string or null"),
}
_MOVE_FIELDS: dict[str, tuple[str, str]] = {
    "agent": ("str", "a string"), "kind": ("str", "a string"), "action": ("str", "a string"),
    "name": ("str", "a string"), "args": ("strs", "a list of strings"),
    "cost": ("num", "a number"), "told": ("strs", "a list of strings"),
}
_TOP_FIELDS: dict[str, tuple[str, str]] = {
    "problem": ("str", "a string"), "domain": ("str", "a string"), "K": ("int", "a whole number"),
    "cost": ("num", "a number"), "communications": ("int", "a whole number"),
    "leaves": ("int", "a whole number"), "optimal": ("bool", "true or false"),
    "after": ("strs", "a list of strings"), "stats": ("dict", "an object"),
    "costs": ("dict", "an object"),
}


def _is(kind: str, v: Any) -> bool:
    if kind == "str":
        return isinstance(v, str)
    if kind == "str?":
        return v is None or isinstance(v, str)
    if kind == "strs":
        return isinstance(v, list) and all(isinstance(x, str) for x in v)
    if kind == "bool":
        return isinstance(v, bool)
    if kind == "int":
        return isinstance(v, int) and not isinstance(v, bool) and v >= 0
    if kind == "num":
        return (isinstance(v, int | Fraction) and not isinstance(v, bool)
                or isinstance(v, float) and math.isfinite(v))
    return isinstance(v, dict)


def check_policy(policy: Policy, name: str, *, counts: bool = True) -> None:
    """The structure :func:`read_policy` checks (see there); raise :class:`InputError`."""
    fix = POLICY_FIX + " (it looks edited by hand or cut short)"
    for f, (kind, say) in _TOP_FIELDS.items():
        if not _is(kind, getattr(policy, f)):
            raise InputError(name, f, f"{f} must be {say}, got {getattr(policy, f)!r:.40}", fix)
    agents = policy.agents
    if not all(isinstance(agents[a], str) and agents[a] for a in ("robot", "human")):
        raise InputError(name, "agents", "agents must name the robot and the human", fix)
    for i, node in enumerate(policy.nodes):
        for f, (kind, say) in _NODE_FIELDS.items():
            v = getattr(node, f)
            if not _is(kind, v):
                raise InputError(name, f"nodes[{i}].{f}", f"must be {say}, got {v!r:.40}", fix)
        for j, move in enumerate(node.moves):
            for f, (kind, say) in _MOVE_FIELDS.items():
                v = getattr(move, f)
                if not _is(kind, v):
                    raise InputError(name, f"nodes[{i}].moves[{j}].{f}",
                                     f"must be {say}, got {v!r:.40}", fix)
    if not counts:
        return
    for node in policy.nodes:
        for j, move in enumerate(node.moves):
            if move.agent not in agents.values():
                raise InputError(name, f"nodes[{node.id}].moves[{j}].agent",
                                 f"every move is the robot's or the human's "
                                 f"({agents['robot']}, {agents['human']}), not "
                                 f"{move.agent!r:.40}", fix)
    # counted over the graph: linear, however many branches share its nodes
    leaves = policy.count_branches()
    if leaves != policy.leaves:
        raise InputError(name, "leaves", f"says {policy.leaves}, but the policy has {leaves} "
                         "branches", fix)
    comms = policy.count_communications()
    if comms != policy.communications:
        raise InputError(name, "communications",
                         f"says {policy.communications}, but the policy has {comms}", fix)


def check_policy_problem(policy: Policy, policy_path: Path | str, problem: Problem) -> None:
    """Raise :class:`InputError` unless ``policy`` was planned for ``problem`` (same problem
    name, domain, agents and K)."""
    d = problem.domain
    pairs = [("problem", policy.problem, problem.name), ("domain", policy.domain, d.name),
             ("robot", policy.agents["robot"], d.robot_name),
             ("human", policy.agents["human"], d.human_name), ("K", policy.K, problem.K)]
    for what, have, want in pairs:
        if have != want:
            raise InputError(str(policy_path), what, f"planned for {what} {have!r}, but "
                             f"{problem.source} has {want!r}",
                             f"give the policy solved for that problem (ehatp solve "
                             f"{problem.source} --out {policy_path})")


__all__ = ["SCHEMA", "check_policy", "check_policy_problem", "check_schema", "read_policy"]
