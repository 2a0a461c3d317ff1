"""Policy files in the shape of format version 1 (the tree unfolding), for tests.

Version 1 wrote the policy as a tree in preorder: each node held the move into it (``agent``,
``kind``, ``action``, ``name``, ``args``, ``cost``, ``told``) and its ``children`` ids, and the
file ended with one timeline per branch. ``tests/data/p4-v1.json`` was written by that writer;
:func:`tree_dict` gives the same shape for any policy, so tests can edit a policy node by node
as a tree and read it back through :meth:`Policy.from_dict`'s version 1 path.
"""

from __future__ import annotations

from typing import Any

from ehatp.formats.policy import Policy, PolicyMove, timeline

START = {"agent": None, "kind": "start", "action": "start", "name": "start", "args": [],
         "cost": 0, "told": []}


def tree_dict(policy: Policy) -> dict[str, Any]:
    """``policy`` as a version 1 JSON object: its tree unfolding in preorder, moves in order."""
    d = policy.to_dict()
    d["version"] = 1
    nodes: list[dict[str, Any]] = []
    stack: list[tuple[PolicyMove | None, int, int]] = [(None, 0, -1)]
    while stack:
        move, nid, parent = stack.pop()
        node = policy.nodes[nid].to_dict()
        del node["moves"]
        own = START if move is None else {
            k: v for k, v in move.to_dict().items() if k != "to"}
        node.update(own, id=len(nodes), children=[])
        nodes.append(node)
        if parent >= 0:
            nodes[parent]["children"].append(node["id"])
        for m in reversed(policy.nodes[nid].moves):
            stack.append((m, m.to, node["id"]))
    d["nodes"] = nodes
    tree = Policy.from_dict(d)
    d["timelines"] = [{**timeline(tree, b), "leaf": b[-1].id} for b in tree.iter_branches()]
    return d

