"""A policy file as the tools read it: :func:`read_policy` loads it
(:meth:`~ehatp.formats.policy.Policy.load`) and checks the type of every field the tools read and
whether its counts match its graph, so that a hand-edited or truncated file is one
:class:`~ehatp.errors.InputError` line instead of a wrong display or a crash;
:func:`check_consistent` checks that what the file says agrees with itself (values, turns,
goals, worlds, the moves' text), as ``show`` and ``render`` do before they display it;
:func:`check_policy_problem` checks it was planned for a given problem."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..model.problem import Problem
from .policy import POLICY_FIX, Policy, malformed
from .schema import mismatch


def read_policy(path: Path | str, *, counts: bool = True,
                check: Callable[[], None] | None = None) -> Policy:
    """Read and check a policy file (version 3 or 2; 1 turned into a graph): parsed once by
    :meth:`Policy.load`, the JSON is checked against the format's schema before anything reads
    it (:func:`check_schema`: no field is read before its shape is known), then the type of
    every field the tools read and
    (``counts``) whether the header's counts and the moves' agents match the graph, so a
    hand-edited or truncated file is one :class:`InputError` line instead of a wrong display
    or a crash. (``validate`` leaves the counts to the validator.) ``check``, e.g. a time
    limit's, is called between the steps and every few hundred nodes, and may raise."""
    if check is not None:
        check()
    try:
        policy = Policy.load(path, check, inspect=lambda raw: check_schema(str(path), raw))
    except (AttributeError, TypeError, KeyError, ValueError, IndexError, RecursionError) as e:
        # the format reader trusts the JSON's shapes; anything it trips on is the file's fault
        place, what = _shape(path) or ("", f"malformed policy ({type(e).__name__}: {e})")
        raise InputError(str(path), place, what, POLICY_FIX) from None
    check_policy(policy, str(path), counts=counts)
    return policy


SCHEMA = "policy.schema.json"
"""The JSON Schema of policy format versions 2 and 3, shipped beside this module."""


def check_schema(name: str, raw: Any) -> None:
    """Raise :class:`InputError` unless ``raw``, a policy file's parsed JSON, matches the
    policy format's schema (versions 2 and 3; a version 1 file, which the schema does not
    describe, is left to :meth:`Policy.load`). The error names the first field that does not
    match, e.g. ``p.json:objective: must be an object``."""
    if not isinstance(raw, dict) or raw.get("version") not in (2, 3) or isinstance(
            raw.get("version"), bool):
        return
    found = mismatch(SCHEMA, raw)
    if found is not None:
        place, what = found
        raise InputError(name, place, what, POLICY_FIX + " (the file does not match the "
                         "format's schema: see docs/policy-format.md)")


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


EDITED_FIX = ("give the policy `ehatp solve` wrote, unedited (`ehatp validate PROBLEM POLICY` "
              "checks every rule)")
MOVE_KINDS = ("action", "wait", "pass", "inform", "ask", "silence", "answer", "announce")
_NAMED_AS_KIND = ("wait", "pass", "inform", "ask")  # kinds whose move is named as the kind


def _close(a: Any, b: Any) -> bool:
    """Return whether two costs are equal, up to the rounding of a number JSON wrote as a
    decimal (an expected cost such as 1/3)."""
    x, y = Fraction(a), Fraction(b)
    return x == y or abs(x - y) <= Fraction(1, 10**9) * max(Fraction(1), abs(y))


def check_consistent(policy: Policy, name: str) -> None:
    """Raise :class:`InputError` at the first thing ``policy`` says that its own graph
    contradicts -- what a hand edit leaves behind that :func:`check_policy` does not see,
    since each field still has the right type. Checked from the file alone, linear in its
    size: who moves at each node (its moves are that agent's; the robot has one move); goals
    (a node without moves is a goal, of value 0, and a goal has no moves); every node's value
    from its moves' costs and the next nodes' values (the worst of them under the worst-case
    objective, between the cheapest and the worst under the expected one), the header's cost,
    worst case and expected cost from the root's; the K-counter (within K, 0 while the agents
    are together); the worlds (as many as ``world_diffs`` lists, none contradicting the
    node's state, ``divergence`` the literals they differ on); each move's kind, and its text
    (``action``) beginning with its ``name``. Whether each move is legal in the problem is the
    validator's (``ehatp validate``)."""
    def fail(place: str, what: str) -> InputError:
        return InputError(name, place, what + " (the file contradicts itself)", EDITED_FIX)

    agents = policy.agents
    robot = agents["robot"]
    expected = isinstance(policy.objective, dict) and policy.objective.get("kind") == "expected"
    uniform = not (isinstance(policy.objective, dict) and policy.objective.get("weights"))
    worst: dict[int, Fraction] = {}
    mean: dict[int, Fraction] = {}
    for i in reversed(policy.topological_order()):  # children first
        node = policy.nodes[i]
        at = f"nodes[{i}]"
        _check_worlds(node, at, policy.K, fail)
        for j, m in enumerate(node.moves):
            if m.kind not in MOVE_KINDS:
                raise fail(f"{at}.moves[{j}].kind", f"{m.kind!r:.40} is not a kind of move "
                           f"({', '.join(MOVE_KINDS)})")
            if m.kind in _NAMED_AS_KIND and m.name != m.kind:
                raise fail(f"{at}.moves[{j}].name", f"a {m.kind} move is named {m.kind}, not "
                           f"{m.name!r:.40}")
            if not m.action.startswith(m.name):
                raise fail(f"{at}.moves[{j}].action", f"{m.action!r:.60} is not a move named "
                           f"{m.name!r:.40}, as its name says")
        if not node.moves:
            if not node.goal:
                raise fail(f"{at}.goal", "a node without moves ends a branch, so it is a "
                           "goal, but goal is false")
            if node.to_move is not None:
                raise fail(f"{at}.to_move", f"a goal has no one to move, not "
                           f"{node.to_move!r:.40}")
            if not _close(node.value, 0):
                raise fail(f"{at}.value", f"a goal's cost to go is 0, not {node.value}")
            worst[i] = mean[i] = Fraction(0)
            continue
        if node.goal:
            raise fail(f"{at}.goal", f"a goal ends its branch, but the node has "
                       f"{len(node.moves)} move(s)")
        movers = {m.agent for m in node.moves}
        if movers != {node.to_move}:
            raise fail(f"{at}.to_move", f"says {node.to_move!r:.40} moves, but the moves are "
                       f"{' and '.join(sorted(movers))}'s")
        if node.to_move == robot and len(node.moves) != 1:
            raise fail(f"{at}.moves", f"the robot ({robot}) moves here and a policy chooses "
                       f"one move for it, not {len(node.moves)}")
        costs = [Fraction(m.cost) + worst[m.to] for m in node.moves]
        means = [Fraction(m.cost) + mean[m.to] for m in node.moves]
        worst[i] = max(costs)
        mean[i] = sum(means, Fraction(0)) / len(means)
        low = min(Fraction(m.cost) + Fraction(policy.nodes[m.to].value) for m in node.moves)
        high = max(Fraction(m.cost) + Fraction(policy.nodes[m.to].value) for m in node.moves)
        if not expected and not _close(node.value, high):
            raise fail(f"{at}.value", f"is {node.value}, but its worst move costs {_n(high)} "
                       "to the goal (move cost plus the next node's value)")
        if expected and uniform and not _close(node.value, mean[i]):
            raise fail(f"{at}.value", f"is {node.value}, but its moves' mean cost to the goal "
                       f"is {_n(mean[i])} (move cost plus the next node's value)")
        if expected and not (low <= Fraction(node.value) <= high or _close(node.value, low)
                             or _close(node.value, high)):
            raise fail(f"{at}.value", f"is {node.value}, outside what its moves cost to the "
                       f"goal ({_n(low)} to {_n(high)})")
    if not _close(policy.cost, policy.root.value):
        raise fail("cost", f"says {policy.cost}, but the root's value is {policy.root.value}")
    if policy.worst_case is not None and not _close(policy.worst_case, worst[0]):
        raise fail("worst_case", f"says {policy.worst_case}, but the policy's worst branch "
                   f"costs {_n(worst[0])}")
    if policy.expected is not None and uniform and not _close(policy.expected, mean[0]):
        raise fail("expected", f"says {policy.expected}, but the policy's expected cost is "
                   f"{_n(mean[0])}")


def _n(x: Fraction) -> str:
    """Return a cost as the file writes it: a whole number, or a decimal."""
    return str(x.numerator) if x.denominator == 1 else f"{float(x):g}"


def _check_worlds(node: Any, at: str, K: int,
                  fail: Callable[[str, str], InputError]) -> None:
    """What a node says of the K-counter and the worlds agrees with itself (see
    :func:`check_consistent`)."""
    if node.k > K:
        raise fail(f"{at}.k", f"{node.k} robot turns unseen is over the bound K = {K}")
    if node.copresent and node.k != 0:
        raise fail(f"{at}.k", f"is {node.k}, but the agents are together, where the counter "
                   "is 0")
    if node.worlds != len(node.world_diffs):
        raise fail(f"{at}.worlds", f"says {node.worlds}, but world_diffs lists "
                   f"{len(node.world_diffs)}")
    state = set(node.state)
    differ: set[str] = set()
    for j, d in enumerate(node.world_diffs):
        if not isinstance(d, dict) or not all(
                isinstance(d.get(k), list) and all(isinstance(a, str) for a in d[k])
                for k in ("true", "false")):
            raise fail(f"{at}.world_diffs[{j}]", "must be an object with lists true and false")
        for a in d["true"]:
            if a in state:
                raise fail(f"{at}.world_diffs[{j}].true", f"{a!r:.60} is listed as true unlike "
                           "the truth, but the node's state holds it")
            differ.add(f"not {a}")
        for a in d["false"]:
            if a not in state:
                raise fail(f"{at}.world_diffs[{j}].false", f"{a!r:.60} is listed as false "
                           "unlike the truth, but the node's state does not hold it")
            differ.add(a)
    if differ != set(node.divergence):
        raise fail(f"{at}.divergence", "is not the literals on which the worlds differ from "
                   f"the truth ({', '.join(sorted(differ)) or 'none'})")


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


__all__ = ["EDITED_FIX", "MOVE_KINDS", "SCHEMA", "check_consistent", "check_policy",
           "check_policy_problem", "check_schema", "read_policy"]
