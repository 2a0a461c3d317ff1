"""Every policy the planner returns also runs: it executes to the goal on every branch through the
executor a robot uses (ehatp.tools.walk, docs/simulation.md), and its behaviour tree ticks to the
goal in py_trees (docs/behaviour-trees.md). Planner and validator read the same rules, so they
can agree on a policy that a robot cannot follow; the executor is a third reader."""

from __future__ import annotations

import dataclasses
from functools import cache
from pathlib import Path

import pytest

import ehatp
from ehatp.model.problem import Problem
from ehatp.policy_format import Policy
from ehatp.tools.walk import tick_py_trees, walk_policy

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "examples").glob("**/*.toml"))


def _ids(p: Path) -> str:
    return str(p.relative_to(ROOT / "examples"))


@cache
def solved(path: Path) -> tuple[Problem, Policy]:
    problem = ehatp.load(path)
    result = ehatp.solve(problem)
    assert result.policy is not None, result.reason
    return problem, result.policy


@pytest.mark.parametrize("path", EXAMPLES, ids=_ids)
def test_every_shipped_example_walks_to_the_goal_on_every_branch(path: Path) -> None:
    problem, policy = solved(path)
    report = walk_policy(problem, policy)
    assert report.ok, report.message
    assert not report.capped and report.branches == policy.leaves


@pytest.mark.parametrize("path", EXAMPLES, ids=_ids)
def test_every_shipped_example_s_behaviour_tree_ticks_to_the_goal(path: Path) -> None:
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    problem, policy = solved(path)
    report = tick_py_trees(problem, policy)
    assert report.ok, report.message
    assert not report.capped and report.branches == policy.leaves


def test_the_walk_stops_at_the_cap_and_says_so() -> None:
    problem, policy = solved(ROOT / "examples" / "cubes" / "x1-4cubes-k2.toml")
    assert policy.leaves > 3
    report = walk_policy(problem, policy, cap=3)
    assert report.ok and report.capped and report.branches == 3
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    ticked = tick_py_trees(problem, policy, cap=3)
    assert ticked.ok and ticked.capped and ticked.branches == 3


def test_a_policy_whose_leaf_is_no_goal_fails_the_walk_on_that_branch() -> None:
    problem, policy = solved(ROOT / "examples" / "cubes" / "p2.toml")
    d = policy.to_dict()
    # cut the policy after its first move: the node it reaches becomes a leaf
    first = d["nodes"][0]["moves"][0]
    d["nodes"][first["to"]]["moves"] = []
    report = walk_policy(problem, Policy.from_dict(d))
    assert not report.ok and report.branches == 1
    assert report.message.startswith(f"branch 1 (H {first['action']}): ")
    assert report.message.endswith(f"policy leaf {first['to']} is reached but the goal does not "
                                   "hold there")


def test_a_policy_that_does_not_fit_fails_the_walk_with_the_executor_s_error() -> None:
    problem, policy = solved(ROOT / "examples" / "cubes" / "p2.toml")
    d = policy.to_dict()
    second = d["nodes"][0]["moves"][1]
    d["nodes"][second["to"]]["worlds"] = 7
    report = walk_policy(problem, Policy.from_dict(d))
    assert not report.ok and report.branches >= 1
    assert "differ on worlds" in report.message
    assert f"(H {second['action']})" in report.message


def test_a_problem_with_a_fixed_opening_walks_from_where_the_opening_ends() -> None:
    problem, policy = solved(ROOT / "examples" / "cubes" / "qualitative.toml")
    assert problem.after
    report = walk_policy(problem, policy)
    assert report.ok and report.branches == policy.leaves
    other = dataclasses.replace(problem, after=())
    assert not walk_policy(other, policy).ok  # planned after the opening: it does not fit
