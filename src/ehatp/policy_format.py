"""The policy file format: the robot policy as data, its JSON form, and nothing else.

A policy is a tree that branches on every human choice. A node is one step: the agent that
acted, the move (label, name and arguments in the domain's vocabulary), its cost, and what holds
after it (co-presence, K-counter, the human's worlds and how they differ from the truth). The root
is the initial state. See ``docs/policy-format.md``.

This module imports neither the planner nor the validator: both use it, and so can any tool that
only reads policy files.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from .errors import InputError

Cost = int | Fraction

POLICY_FIX = "give a policy JSON written by `ehatp solve --out FILE`"
FORMAT = "ehatp-policy"
VERSION = 1


@dataclass
class PolicyNode:
    id: int
    agent: str | None  # who acted to reach this node (None at the root)
    kind: str  # start | action | wait | pass | inform | ask
    action: str
    name: str
    args: list[str]
    cost: Cost
    copresent: bool
    k: int
    worlds: int
    divergence: list[str]  # truth's literals on which some world disagrees
    world_diffs: list[dict[str, list[str]]]  # per world: atoms true / false unlike the truth
    state: list[str]  # true fluent atoms
    robot_agenda: list[str]
    human_agenda: list[str]
    to_move: str | None  # who moves next (None at a goal leaf)
    value: Cost  # cost from here to the end, under the policy's objective
    goal: bool
    children: list[int] = field(default_factory=list)
    told: list[str] = field(default_factory=list)  # literals said with an action (speech)

    def to_dict(self) -> dict[str, Any]:
        d = {k: v for k, v in self.__dict__.items()}
        d["cost"] = num(self.cost)
        d["value"] = num(self.value)
        return d


@dataclass
class Policy:
    problem: str
    domain: str
    agents: dict[str, str]
    K: int
    costs: dict[str, Any]
    nodes: list[PolicyNode]
    cost: Cost
    communications: int
    leaves: int
    optimal: bool = True
    stats: dict[str, Any] = field(default_factory=dict)
    after: list[str] = field(default_factory=list)  # the fixed opening the root follows
    # {"kind": "worst-case" | "expected", "weights": {...}, "ties": [...]}
    objective: dict[str, Any] = field(default_factory=lambda: {"kind": "worst-case"})
    worst_case: Cost | None = None  # the policy's worst-case cost (None: not recorded)
    expected: Cost | None = None  # its expected cost over human choices

    @property
    def root(self) -> PolicyNode:
        return self.nodes[0]

    def children(self, n: PolicyNode) -> list[PolicyNode]:
        return [self.nodes[i] for i in n.children]

    def branches(self) -> list[list[PolicyNode]]:
        """Every root-to-leaf path."""
        out: list[list[PolicyNode]] = []
        stack: list[list[PolicyNode]] = [[self.root]]
        while stack:
            path = stack.pop()
            kids = self.children(path[-1])
            if not kids:
                out.append(path)
            for c in reversed(kids):
                stack.append([*path, c])
        return out

    def timelines(self) -> list[dict[str, Any]]:
        return [timeline(self, b) for b in self.branches()]

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": FORMAT, "version": VERSION, "problem": self.problem, "domain": self.domain,
            "agents": self.agents, "K": self.K, "costs": self.costs, "cost": num(self.cost),
            "communications": self.communications, "leaves": self.leaves,
            "optimal": self.optimal, "stats": self.stats, "after": self.after,
            "objective": self.objective,
            "worst_case": None if self.worst_case is None else num(self.worst_case),
            "expected": None if self.expected is None else num(self.expected),
            "nodes": [n.to_dict() for n in self.nodes], "timelines": self.timelines(),
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1, sort_keys=True) + "\n"

    def write(self, path: str | Path) -> None:
        Path(path).write_text(self.to_json(), encoding="utf-8")

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Policy:
        if d.get("format") != FORMAT:
            raise ValueError(f"not an ehatp policy (format is {d.get('format')!r})")
        if d.get("version") != VERSION:
            raise ValueError(f"policy format version {d.get('version')} is not {VERSION}")
        nodes = [PolicyNode(**{k: v for k, v in n.items()}) for n in d["nodes"]]
        return cls(d["problem"], d["domain"], d["agents"], d["K"], d["costs"], nodes, d["cost"],
                   d["communications"], d["leaves"], d.get("optimal", True), d.get("stats", {}),
                   d.get("after", []), d.get("objective", {"kind": "worst-case"}),
                   d.get("worst_case"), d.get("expected"))

    @classmethod
    def read(cls, path: str | Path) -> Policy:
        return cls.from_dict(json.loads(Path(path).read_text(encoding="utf-8")))

    @classmethod
    def load(cls, path: str | Path) -> Policy:
        """Read a policy file written by ``ehatp solve``, checking its tree; anything else is
        one :class:`~ehatp.errors.InputError` line naming the file."""
        name = str(path)
        try:
            text = Path(path).read_text(encoding="utf-8")
        except FileNotFoundError:
            raise InputError(name, "", "no such file", POLICY_FIX) from None
        except OSError as e:
            raise InputError(name, "", f"cannot read the file ({e.strerror or e})",
                             "check the path") from None
        except UnicodeDecodeError:
            raise InputError(name, "", "not a text file", POLICY_FIX) from None
        try:
            raw = json.loads(text)
        except json.JSONDecodeError as e:
            raise InputError(name, f"{e.lineno}:{e.colno}", f"not valid JSON ({e.msg})",
                             POLICY_FIX) from None
        if not isinstance(raw, dict):
            raise InputError(name, "", "not an ehatp policy (expected a JSON object)",
                             POLICY_FIX)
        try:
            policy = cls.from_dict(raw)
        except ValueError as e:
            raise InputError(name, "", str(e), POLICY_FIX) from None
        except KeyError as e:
            raise InputError(name, "", f"not an ehatp policy (missing field {e})",
                             POLICY_FIX) from None
        except TypeError as e:
            raise InputError(name, "", f"malformed policy node ({e})", POLICY_FIX) from None
        policy._check_tree(name)
        return policy

    def _check_tree(self, name: str) -> None:
        # readers walk children blindly; a hand-edited file must not send them into a loop
        n = len(self.nodes)
        if n == 0:
            raise InputError(name, "nodes", "the policy has no nodes", POLICY_FIX)
        if not isinstance(self.agents, dict) or not {"robot", "human"} <= self.agents.keys():
            raise InputError(name, "agents", "agents must name the robot and the human",
                             POLICY_FIX)
        has_parent = [False] * n
        for i, node in enumerate(self.nodes):
            if node.id != i:
                raise InputError(name, f"nodes[{i}]", f"node id {node.id} is not its position",
                                 POLICY_FIX)
            for c in node.children:
                if not isinstance(c, int) or not 0 < c < n or has_parent[c]:
                    raise InputError(name, f"nodes[{i}].children",
                                     f"child {c!r} is out of range or has two parents",
                                     POLICY_FIX)
                has_parent[c] = True
            if not isinstance(node.world_diffs, list) or not isinstance(node.state, list):
                raise InputError(name, f"nodes[{i}]", "world_diffs and state must be lists",
                                 POLICY_FIX)
        orphans = n - sum(has_parent) - 1
        if orphans:
            raise InputError(name, "nodes", f"{orphans} node(s) are not below the root",
                             POLICY_FIX)


def num(c: Cost | float) -> int | float:
    if isinstance(c, Fraction):
        return int(c) if c.denominator == 1 else float(c)
    return c


def timeline(policy: Policy, branch: list[PolicyNode]) -> dict[str, Any]:
    """Turn-taking steps while together; parallel lanes between separation and reunion."""
    r_name, h_name = policy.agents["robot"], policy.agents["human"]
    steps: list[dict[str, Any]] = []
    lanes: dict[str, list[str]] | None = None
    prev = branch[0]
    for n in branch[1:]:
        assert n.agent is not None
        if prev.copresent:
            steps.append({"agent": n.agent, "action": n.action})
        else:
            if lanes is None:
                lanes = {r_name: [], h_name: []}
                steps.append({"parallel": lanes})
            lanes[n.agent].append(n.action)
        if n.copresent:
            lanes = None
        prev = n
    return {"leaf": branch[-1].id, "steps": steps}


__all__ = ["FORMAT", "POLICY_FIX", "VERSION", "Cost", "Policy", "PolicyNode", "num", "timeline"]
