"""A lifted policy (format version 3) as the version 2 graph over the real objects, for the
tools that need every real state (``ehatp expand``; docs/policy-format.md, "Version 3").

The expansion follows the policy through an :class:`~ehatp.run.executor.Executor` from the
real root, each move played by the problem's own semantics: a real node is a canonical node
read through the renaming of the path that reached it, memoised by the real epistemic state (as
the planner's own mapping back, ``ehatp solve --expand``), and each move carries the real
semantics' label. So the graph written is the one a search without symmetry's extraction would
describe for this policy, and the validator replays it on the real problem.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from ..epistemic.state import EState
from ..errors import PolicyTooLarge
from ..formats.policy import Policy, PolicyNode
from ..model.problem import Problem
from .executor import Executor


def expand_policy(problem: Problem, policy: Policy,
                  check: Callable[[], None] | None = None,
                  max_nodes: int | None = None) -> Policy:
    """Return the version 2 graph of ``policy`` for ``problem`` (``policy`` itself when it is
    not lifted): ids in the depth-first preorder of first visits, moves in order, values and
    counts those of the lifted graph (a renaming keeps them). ``check`` is called once per
    real node and may raise to stop the work; past ``max_nodes`` real nodes it raises
    :class:`~ehatp.errors.PolicyTooLarge`. Raises the executor's errors
    (:class:`~ehatp.errors.PolicyMismatch`) when the policy does not fit the problem."""
    if policy.symmetry is None:
        return policy
    start = Executor(problem, policy)
    start.replay_opening()
    index: dict[EState, int] = {}
    views: list[PolicyNode] = []
    kids: list[list[EState]] = []
    stack = [start]
    while stack:
        ex = stack.pop()
        if ex.state in index:
            continue
        if check is not None:
            check()
        if max_nodes is not None and len(views) >= max_nodes:
            raise PolicyTooLarge(max_nodes, len(policy.nodes))
        node = ex.node
        assert node is not None
        index[ex.state] = len(views)
        views.append(node)
        children = []
        for pm in node.moves:
            child = ex.copy()
            if pm.agent == ex.robot_name:
                child.robot_action_done()
            else:
                child.observe_human_action(pm.action)
            children.append(child)
        kids.append([c.state for c in children])
        stack.extend(reversed([c for c in children if c.state not in index]))
    nodes = [dataclasses.replace(
        view, id=i, moves=[dataclasses.replace(pm, to=index[s], renaming=0)
                           for pm, s in zip(view.moves, kids[i], strict=True)])
        for i, view in enumerate(views)]
    out = dataclasses.replace(policy, nodes=nodes, symmetry=None)
    out.leaves = out.count_branches()
    out.communications = out.count_communications()
    return out


__all__ = ["expand_policy"]
