"""Synthetic policies for the behaviour-tree tests: shapes no shipped example has.

- :func:`chain_policy`: ``moves`` moves in a row, robot actions and the human's passes in turn
  (as a long transport plan is), one goal;
- :func:`comb_policy`: ``choices`` human choices nested in one another: at each the human
  either stops (a goal) or lets the robot go on to the next choice.
"""

from __future__ import annotations

from typing import Any

from ehatp import Policy


def _node(i: int, to_move: str | None, value: int, moves: list[dict[str, Any]]) -> dict[str, Any]:
    return {"id": i, "copresent": True, "k": 0, "worlds": 1, "divergence": [],
            "world_diffs": [{"true": [], "false": []}], "state": [], "robot_agenda": [],
            "human_agenda": [], "to_move": to_move, "value": value, "goal": not moves,
            "moves": moves}


def _move(agent: str, name: str, args: list[str], to: int) -> dict[str, Any]:
    kind = "pass" if name == "pass" else "action"
    action = name if kind == "pass" else f"{name}({', '.join(args)})"
    return {"agent": agent, "kind": kind, "action": action, "name": name, "args": args,
            "cost": 1, "to": to, "told": []}


def _policy(problem: str, nodes: list[dict[str, Any]], leaves: int) -> Policy:
    return Policy.from_dict({
        "format": "ehatp-policy", "version": 2, "problem": problem, "domain": "synthetic",
        "agents": {"robot": "R", "human": "H"}, "K": 2,
        "costs": {"inform": 1, "ask": 1, "wait": 1, "pass": 1, "actions": {}},
        "cost": nodes[0]["value"], "communications": 0, "leaves": leaves, "optimal": True,
        "stats": {}, "after": [], "objective": {"kind": "worst-case", "weights": {},
                                                "ties": ["communications", "waits", "length"]},
        "worst_case": nodes[0]["value"], "nodes": nodes})


def chain_policy(moves: int) -> Policy:
    """Return a policy of ``moves`` moves in a row: the robot drives from place to place, the
    human passes in between."""
    nodes = []
    for i in range(moves):
        if i % 2 == 0:
            m = _move("R", "drive", ["truck", f"l{i}", f"l{i + 2}"], i + 1)
        else:
            m = _move("H", "pass", [], i + 1)
        nodes.append(_node(i, m["agent"], moves - i, [m]))
    nodes.append(_node(moves, None, 0, []))
    return _policy(f"chain-{moves}", nodes, 1)


def comb_policy(choices: int) -> Policy:
    """Return a policy of ``choices`` nested human choices: at choice i the human stops
    (``stop(i)``, a goal) or waits (``pass``) and the robot does ``step(i)`` before the next
    choice; after the last one the human stops."""
    nodes: list[dict[str, Any]] = []
    # ids: choice i is 3i, the robot's step after it 3i + 1, the goal of stopping 3i + 2
    for i in range(choices):
        c, r, g = 3 * i, 3 * i + 1, 3 * i + 2
        value = 2 * (choices - i) + 1
        nodes.append(_node(c, "H", value, [_move("H", "stop", [str(i)], g),
                                           _move("H", "pass", [], r)]))
        nodes.append(_node(r, "R", value - 1, [_move("R", "step", [str(i)], c + 3)]))
        nodes.append(_node(g, None, 0, []))
    last = 3 * choices
    nodes.append(_node(last, "H", 1, [_move("H", "stop", ["last"], last + 1)]))
    nodes.append(_node(last + 1, None, 0, []))
    return _policy(f"comb-{choices}", nodes, choices + 1)
