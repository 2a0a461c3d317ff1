"""A behaviour tree as data: :class:`BTNode` and the :class:`Forest` of trees that
:func:`ehatp.formats.bt.from_policy` builds from a policy, which the BehaviorTree.CPP and py_trees
writers (:mod:`ehatp.formats.bt`) and the py_trees behaviours (:mod:`ehatp.formats.bt_py_trees`)
read."""

from __future__ import annotations

from dataclasses import dataclass, field

from .policy import Policy

MAIN_TREE = "Policy"
SEP = ";"  # list separator in a port value (BehaviorTree.CPP splits vectors on it)


@dataclass
class BTNode:
    """One node of the tree: its BehaviorTree.CPP tag (node ID) and ports, in writing order.
    ``completes`` is the label of the robot's policy move that this node finishes (the last
    node of each robot move; the XML's ``completes`` port, written after the others); ``node``
    is the policy node of a human choice's ``Fallback`` (not written to XML)."""

    tag: str
    attrs: dict[str, str] = field(default_factory=dict)
    children: list[BTNode] = field(default_factory=list)
    completes: str | None = None
    node: int | None = None


@dataclass
class Forest:
    """The main tree and one tree per shared policy node, by ID (the main tree first, then by
    node id)."""

    main: str
    trees: dict[str, BTNode]
    policy: Policy


def tree_id(node: int) -> str:
    """The BehaviorTree ID of the shared policy node ``node``."""
    return f"Node_{node}"


def blackboard_key(node: int) -> str:
    """The blackboard entry where the human's action at policy node ``node`` is written."""
    return f"human_action_{node}"


__all__ = ["MAIN_TREE", "SEP", "BTNode", "Forest", "blackboard_key", "tree_id"]
