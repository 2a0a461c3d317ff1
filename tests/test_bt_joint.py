"""Behaviour trees of joint-step policies (docs/behaviour-trees.md, "Joint steps"): with the
human first, each step is a ``WaitHumanStart`` (the human's action seen as it starts) and a
``Fallback`` over the human's move whose branch holds the robot's compliant reply; with the
robot first the export is refused in one line. Turn-taking exports are unchanged (their tests:
tests/test_bt.py, tests/test_bt_schema.py, tests/test_security_exporters.py)."""

from __future__ import annotations

import dataclasses
import random
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import ehatp
from ehatp import StepFirst
from ehatp.cli.app import app
from ehatp.formats import bt
from ehatp.formats.policy import Policy

from .conftest import EXAMPLES_DIR

STACK4 = EXAMPLES_DIR / "concurrent" / "stack4.toml"
P2 = EXAMPLES_DIR / "cubes" / "p2.toml"


def policy_of(path: Path, first: StepFirst | None = None) -> tuple[ehatp.Problem, Policy]:
    problem = ehatp.load(path)
    if first is not None:
        problem = dataclasses.replace(problem, steps=dataclasses.replace(problem.steps,
                                                                         first=first))
    policy = ehatp.solve(problem).policy
    assert policy is not None
    return problem, policy


def test_a_joint_step_is_a_wait_for_the_humans_start_then_the_reply_in_its_branch() -> None:
    """Stack4's root, by hand (tests/test_stacking.py): the human may ``pick(c1)`` (the reply
    ``wait``) or pass (the reply ``pick(c1)``). The tree's first step is ``WaitHumanStart``
    expecting both, then a ``Fallback`` whose branch for ``pick(c1)`` holds ``RobotWait`` and
    whose branch for ``pass`` holds ``RobotAction pick(c1)``, each after its ``HumanDid``. No
    ``WaitHumanAction`` anywhere, and the model declares ``WaitHumanStart``."""
    problem, policy = policy_of(STACK4)
    root = ET.fromstring(bt.to_btcpp(bt.from_policy(policy, bt.answers_of(problem, policy))))
    main = root.find("BehaviorTree[@ID='Policy']/Sequence")
    assert main is not None
    wait, fallback = list(main)[:2]
    assert wait.tag == "WaitHumanStart" and wait.get("expected") == "pick(c1);pass"
    first: dict[str, list[tuple[str, str | None]]] = {}
    for branch in fallback:
        name = branch.get("name", "")
        first[name] = [(e.tag, e.get("completes")) for e in list(branch)[:2]]
    assert first["H pick(c1)"] == [("HumanDid", None), ("RobotWait", "wait")]
    assert first["H pass"] == [("HumanDid", None), ("RobotAction", "pick(c1)")]
    assert root.find(".//WaitHumanAction") is None
    declared = {e.get("ID") for e in root.find("TreeNodesModel") or []}
    assert declared == bt.CUSTOM_IDS | bt.JOINT_IDS


def test_a_turn_taking_export_declares_no_joint_node() -> None:
    _, policy = policy_of(P2)
    text = bt.to_btcpp(bt.from_policy(policy))
    assert "WaitHumanStart" not in text
    assert "WaitHumanStart" not in bt.to_py_trees_source(bt.from_policy(policy))


def test_the_robot_first_is_refused_in_one_line(tmp_path: Path) -> None:
    """With ``first = "robot"`` the robot's action and the human's move run at once and the
    policy branches on the human's move while the robot acts: no tree; exit 2, one line
    saying why and what to do."""
    _, policy = policy_of(STACK4, StepFirst.ROBOT)
    with pytest.raises(bt.NotExpressible):
        bt.from_policy(policy)
    f = tmp_path / "robot-first.json"
    policy.write(f)
    for fmt in ("btcpp4", "py_trees"):
        r = CliRunner().invoke(app, ["export", "bt", str(f), "--format", fmt])
        assert r.exit_code == 2, r.output
        lines = r.output.strip().splitlines()
        assert len(lines) == 1 and "robot first" in lines[0] and "first = \"human\"" in lines[0]


def test_the_joint_py_tree_ticks_to_the_goal_on_every_run_against_the_executor() -> None:
    """The py_trees tree of stack4, ticked with a seeded random human choosing among the moves
    the policy covers at each step and the Executor checking every robot reply: 20 runs, each
    at the goal, nothing uncovered."""
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    from py_trees.common import Status

    from ehatp.formats.bt_py_trees import HumanTurn, RobotCommand

    problem, policy = policy_of(STACK4)
    state: dict[str, Any] = {}

    def robot(cmd: RobotCommand) -> bool:
        ex = state["ex"]
        if cmd.completes is not None:
            want = ex.next_robot_action()
            assert want is not None and want.label == cmd.completes
            ex.robot_action_done(cmd.completes)
        return True

    def human(turn: HumanTurn) -> str:
        ex = state["ex"]
        covered = [a.label for a in ex.expected_human_actions()]
        assert list(turn.expected) == covered
        choice = state["rng"].choice(covered)
        ex.observe_human_action(choice)
        return str(choice)

    root = bt.build_py_tree(policy, robot=robot, human=human, problem=problem)
    for seed in range(20):
        state.update(ex=ehatp.Executor(problem, policy), rng=random.Random(seed))
        for _ in range(1000):
            root.tick_once()
            if root.status != Status.RUNNING:
                break
        assert root.status == Status.SUCCESS
        assert state["ex"].done and state["ex"].goal_reached
