"""The robot policy: a tree that branches on every human choice, and its JSON form.

A node is one step: the agent that acted, the action (in the domain's vocabulary), its cost, and
what holds after it (co-presence, K-counter, the human's worlds and how they differ from the
truth). The root is the initial state. See ``docs/policy-format.md``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from ..epistemic.semantics import ASK, INFORM, Move, bits_of
from ..epistemic.state import ROBOT, EState
from ..errors import InputError
from ..model.grounding import FINISH
from ..model.problem import Cost, call_str
from .andor import GOAL, Graph
from .values import Values

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
    value: Cost  # worst-case cost from here to the end
    goal: bool
    children: list[int] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        d = {k: v for k, v in self.__dict__.items()}
        d["cost"] = _num(self.cost)
        d["value"] = _num(self.value)
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
            "agents": self.agents, "K": self.K, "costs": self.costs, "cost": _num(self.cost),
            "communications": self.communications, "leaves": self.leaves,
            "optimal": self.optimal, "stats": self.stats, "after": self.after,
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
                   d.get("after", []))

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


def _num(c: Cost | float) -> int | float:
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


def extract(gr: Graph, root: int, values: Values, *, problem_name: str,
            optimal: bool = True, stats: dict[str, Any] | None = None) -> Policy:
    sem = gr.sem
    g = sem.g
    p = g.problem
    r_name, h_name = p.domain.robot_name, p.domain.human_name
    nodes: list[PolicyNode] = []

    def agenda(ag: tuple[int, ...]) -> list[str]:
        return [g.task_names[t] for t in ag if t != FINISH]

    def make(n: int, move: Move | None) -> PolicyNode:
        es: EState = gr.states[n]
        t = es.true
        div = 0
        diffs = []
        for s in sorted({s for s, _ in es.worlds}):
            div |= s ^ t
            diffs.append({"true": g.mask_atoms(s & ~t), "false": g.mask_atoms(t & ~s)})
        cost: Cost = 0
        if move is None:
            agent, kind, label, name, args = None, "start", "start", "start", []
        else:
            agent = r_name if move.agent == ROBOT else h_name
            kind, label, cost = move.kind, move.label, move.cost
            if move.op >= 0:
                op = (g.robot.ops if move.agent == ROBOT else g.human.ops)[move.op]
                name, args = op.schema, list(op.args)
            elif kind == INFORM:
                name, args = "inform", label[len("inform("):-1].split(", ")
            elif kind == ASK:
                name, args = "ask", [label[len("ask("):-1]]
            else:
                name, args = kind, []
        node = PolicyNode(
            id=len(nodes), agent=agent, kind=kind, action=label, name=name, args=args,
            cost=cost, copresent=sem.copresent(t), k=es.k, worlds=len(es.worlds),
            divergence=[(a if t >> i & 1 else f"not {a}")
                        for i, a in ((i, g.atoms[i]) for i in bits_of(div))],
            world_diffs=diffs, state=g.state_atoms(t), robot_agenda=agenda(es.robot_agenda),
            human_agenda=agenda(es.human_agenda),
            to_move=None if gr.status[n] == GOAL else (r_name if es.turn == ROBOT else h_name),
            value=values.value[n],  # type: ignore[arg-type]
            goal=gr.status[n] == GOAL)
        nodes.append(node)
        return node

    # iterative DFS in canonical child order; ids are preorder positions
    root_node = make(root, None)
    stack: list[tuple[int, PolicyNode]] = [(root, root_node)]
    while stack:
        n, pn = stack.pop()
        if gr.status[n] == GOAL:
            continue
        edges = gr.edges[n]
        chosen = [edges[values.choice[n]]] if gr.is_robot(n) else edges
        kids = []
        for e in chosen:
            kids.append((e.child, make(e.child, e.move)))
        pn.children = [k.id for _, k in kids]
        stack.extend(reversed(kids))
    # renumber to preorder so ids read top-down
    order: list[PolicyNode] = []
    st = [nodes[0]]
    while st:
        x = st.pop()
        order.append(x)
        st.extend(reversed([nodes[i] for i in x.children]))
    remap = {x.id: i for i, x in enumerate(order)}
    for x in order:
        x.id = remap[x.id]
        x.children = [remap[c] for c in x.children]
    leaves = sum(1 for x in order if not x.children)
    comms = sum(1 for x in order if x.kind in (INFORM, ASK))
    costs = {"inform": _num(p.costs.inform), "ask": _num(p.costs.ask),
             "wait": _num(p.costs.wait), "pass": _num(p.costs.pass_),
             "actions": {k: _num(v) for k, v in sorted(p.costs.actions.items())}}
    return Policy(problem_name, p.domain.name, {"robot": r_name, "human": h_name}, p.K, costs,
                  order, values.value[root], comms, leaves,  # type: ignore[arg-type]
                  optimal, stats or {}, list(p.after))


def explain_failure(gr: Graph, root: int) -> str:
    """Follow one failing line of play from the root and say where it dies."""
    from .andor import DEAD, OPEN

    sem = gr.sem
    names = (sem.names[0], sem.names[1])
    path: list[str] = []
    seen = {root}
    n = root
    while True:
        if gr.status[n] == DEAD:
            return _why(path, gr.dead_why.get(n, "dead end"))
        if gr.status[n] == OPEN:
            return _why(path, "the search stopped before this state was explored")
        edges = gr.edges[n]
        if gr.is_robot(n):
            nxt = next((e for e in edges if e.child not in seen), None)
            if nxt is None:
                return _why(path, f"every option of {names[0]} leads back to an earlier state")
        else:
            bad = [e for e in edges if e.child < 0 or not gr.solved[e.child]]
            fail = next((e for e in bad if e.child < 0), None)
            if fail is not None:
                path.append(f"{names[1]} {fail.move.label}")
                return _why(path, fail.move.failure)
            nxt = next((e for e in bad if e.child not in seen), None)
            if nxt is None:
                return _why(path, "every human choice here loops back to an earlier state")
        agent = names[0] if nxt.move.agent == ROBOT else names[1]
        path.append(f"{agent} {nxt.move.label}")
        n = nxt.child
        seen.add(n)


def _why(path: list[str], reason: str) -> str:
    steps = ", ".join(path[-12:])
    more = "…, " if len(path) > 12 else ""
    return (f"after {more}{steps}: {reason}" if path else reason)


__all__ = ["FORMAT", "VERSION", "Policy", "PolicyNode", "call_str", "explain_failure",
           "extract", "timeline"]
