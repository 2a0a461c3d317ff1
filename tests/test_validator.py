"""The independent validator: the planner's policies pass, every tampered policy is caught.

Tampering edits the policy as a tree (format version 1, :func:`tests.policy_v1.tree_dict`), node
by node, and reads it back: a node holds the move into it, as in the messages. Tampering with
the graph of version 2 itself (shared nodes) is in ``tests/test_policy_v2.py``."""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable
from fractions import Fraction
from typing import Any

import pytest

import ehatp
from ehatp import Costs, Policy, Problem
from ehatp.check.validator import Report, validate

from .conftest import EXAMPLES, Example, solved_v2
from .policy_v1 import tree_dict

Node = dict[str, Any]


def mutated(policy: Policy, edit: Callable[[dict[str, Any]], None]) -> Policy:
    """``policy`` unfolded into a version 1 tree, edited, and read back."""
    d = copy.deepcopy(tree_dict(policy))
    edit(d)
    return Policy.from_dict(d)


def node(d: dict[str, Any], **want: Any) -> Node:
    """The first node (in id order) whose fields have the given values."""
    for n in d["nodes"]:
        if all(n[k] == v for k, v in want.items()):
            return n  # type: ignore[no-any-return]
    raise LookupError(want)


def parent(d: dict[str, Any], child: Node) -> Node:
    return next(n for n in d["nodes"] if child["id"] in n["children"])


def caught(problem: Problem, policy: Policy, *needles: str) -> Report:
    r = validate(problem, policy)
    assert not r.ok
    assert r.violations and r.message == r.violations[0]
    for s in needles:
        assert s in r.message, (s, r.message)
    return r


# -- the planner's policies are valid -----------------------------------------------------------

@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_planned_policies_validate(example: Example) -> None:
    problem, policy = solved_v2(example)
    r = ehatp.validate(problem, policy)
    assert r.ok, "\n".join(r.violations)
    assert r.violations == []
    assert r.nodes_checked == len(policy.nodes)
    assert r.branches_checked == policy.leaves
    assert r.message == f"valid: {len(policy.nodes)} nodes, {policy.leaves} branches checked"


@pytest.mark.parametrize("name", ["cubes/p2", "cubes/qualitative"])
def test_json_round_trip_validates(name: str) -> None:
    problem, policy = solved_v2(name)
    assert validate(problem, Policy.from_dict(policy.to_dict())).ok


def test_fractional_costs_validate_after_json() -> None:
    problem, _ = solved_v2("cubes/qualitative")
    p = dataclasses.replace(problem, costs=Costs(inform=Fraction("2.5"), wait=Fraction("0.5"),
                                                  actions={"place": Fraction("1.5")}))
    policy = ehatp.solve(p).policy
    assert policy is not None
    assert validate(p, policy).ok
    assert validate(p, Policy.from_dict(policy.to_dict())).ok


# -- mutations, each caught with a precise message ------------------------------------------------

def test_robot_action_not_applicable_in_T() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        n = node(d, agent="R", kind="action", action="pick(r)")
        n.update(action="pick(w)", args=["w"])  # w lies on the other table

    caught(problem, mutated(policy, edit), "branch [H move(mt, ot), R pick(w)]",
           "not a legal robot option", "pick(w) is not applicable in T")


def test_robot_action_outside_the_agenda() -> None:
    problem, policy = solved_v2("sally-anne/inform")

    def edit(d: dict[str, Any]) -> None:
        # applicable in T, but the robot's agenda is already empty
        n = node(d, agent="R", kind="wait", copresent=False, k=2)
        n.update(kind="action", action="move(box, box)", name="move", args=["box", "box"],
                 cost=1)

    caught(problem, mutated(policy, edit), "R move(box, box)]", "not a legal robot option",
           "not the first action of any refinement of the robot agenda [] under T")


def test_human_branch_removed() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        d["nodes"][0]["children"].remove(node(d, agent="H", action="move(mt, ot)")["id"])

    caught(problem, mutated(policy, edit), "branch []", "missing human branch H move(mt, ot)")


def test_extra_human_branch() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        # the human stands at mt and w lies on ot: picking w is not one of its options
        extra = copy.deepcopy(node(d, goal=True))
        extra.update(id=len(d["nodes"]), action="pick(w)", name="pick", args=["w"])
        d["nodes"].append(extra)
        d["nodes"][0]["children"].append(extra["id"])

    caught(problem, mutated(policy, edit), "branch [H pick(w)]", "extra human branch")


def test_pass_right_after_a_robot_wait_is_not_a_human_option() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        # after the robot's wait the human can place w: it does not idle (section 4)
        leaf = node(d, goal=True)
        wait = parent(d, leaf)
        assert wait["kind"] == "wait"
        extra = copy.deepcopy(leaf)
        extra.update(id=len(d["nodes"]), kind="pass", action="pass", name="pass", args=[])
        d["nodes"].append(extra)
        wait["children"].append(extra["id"])

    caught(problem, mutated(policy, edit), "R wait, H pass]", "extra human branch")


def test_leaf_that_is_not_a_goal() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        node(d, agent="H", action="move(ot, mt)")["children"] = []

    r = caught(problem, mutated(policy, edit), "H move(ot, mt)]",
               "leaf that is not a goal", "the robot's agenda cannot finish under T")
    # what hung below it is cut off
    assert any("node(s) are not reachable from the root" in v for v in r.violations)


def test_goal_with_children() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        leaf = node(d, goal=True)
        leaf["children"] = [node(d, agent="R", kind="wait")["id"]]

    caught(problem, mutated(policy, edit), "a goal (§6) must be a leaf")


def test_wrong_cost_on_a_node() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        node(d, agent="H", action="pick(w)")["cost"] = 7

    r = caught(problem, mutated(policy, edit),
               "branch [H move(mt, ot), R pick(r), H pick(w)]",
               "cost is 7, but the move costs 1")
    assert len(r.violations) == 1


def test_wrong_inform_cost() -> None:
    problem, policy = solved_v2("cubes/qualitative-ask")
    assert validate(problem, policy).ok
    p2, pol2 = solved_v2("cubes/qualitative")

    def edit(d: dict[str, Any]) -> None:
        node(d, kind="inform")["cost"] = 10  # the problem's inform costs 1

    caught(p2, mutated(pol2, edit), "R inform(empty(box2))", "cost is 10, but the move costs 1")


def test_wrong_value_on_a_node() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        node(d, agent="H", action="pass")["value"] = 3

    r = caught(problem, mutated(policy, edit), "branch [H pass]",
               "value is 3, but its worst-case cost-to-go is 12")
    assert len(r.violations) == 1


def test_wrong_policy_cost() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        d["cost"] = d["cost"] + 1

    r = caught(problem, mutated(policy, edit),
               f"policy cost is {policy.cost + 1}, but the root's value is {policy.cost}")
    assert len(r.violations) == 1


def test_wrong_communications_and_leaves() -> None:
    problem, policy = solved_v2("cubes/qualitative")

    def edit(d: dict[str, Any]) -> None:
        d["communications"] = 0
        d["leaves"] = 3

    r = caught(problem, mutated(policy, edit), "communications is 0, but the policy has 1")
    assert any("leaves is 3, but the policy has 2 leaves" in v for v in r.violations)


def test_wrong_world_count() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        node(d, worlds=2)["worlds"] = 3

    r = caught(problem, mutated(policy, edit), "branch [H move(mt, ot), R pick(r)]",
               "recorded facts differ", "worlds is 3, expected 2")
    assert len(r.violations) == 1


@pytest.mark.parametrize(("field", "value", "needle"), [
    ("k", 0, "k is 0, expected 1"),
    ("copresent", True, "copresent is True, expected False"),
    ("human_agenda", ["organize"], "human_agenda is ['organize']"),
    ("state", ["at(R, mt)"], "state differs from the true state T"),
    ("to_move", "R", "to_move is 'R', expected 'H'"),
])
def test_wrong_recorded_fact(field: str, value: Any, needle: str) -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        node(d, agent="R", action="pick(r)", copresent=False)[field] = value

    caught(problem, mutated(policy, edit), "branch [H move(mt, ot), R pick(r)]", needle)


def test_inform_of_an_atom_the_human_already_believes() -> None:
    problem, policy = solved_v2("cubes/qualitative")

    def edit(d: dict[str, Any]) -> None:
        n = node(d, kind="inform")
        n.update(action="inform(at(H, mt))", args=["at(H, mt)"])

    caught(problem, mutated(policy, edit), "branch [R inform(at(H, mt))]",
           "every world already agrees with the truth on at(H, mt)")


def test_inform_of_more_atoms_than_needed() -> None:
    problem, policy = solved_v2("cubes/qualitative")

    def edit(d: dict[str, Any]) -> None:
        n = node(d, kind="inform")
        n.update(action="inform(empty(box2), in(r, box1))", args=["empty(box2)", "in(r, box1)"])

    caught(problem, mutated(policy, edit), "not a smallest fixing set: 2 atoms where 1 suffice")


def test_inform_while_apart() -> None:
    problem, policy = solved_v2("cubes/p2")

    def edit(d: dict[str, Any]) -> None:
        n = node(d, agent="R", action="wait", copresent=False)
        n.update(kind="inform", action="inform(empty(box1))", name="inform",
                 args=["empty(box1)"])

    caught(problem, mutated(policy, edit), "inform is offered only while co-present")


def test_human_acting_on_a_false_belief() -> None:
    problem, policy = solved_v2("sally-anne/inform")

    def edit(d: dict[str, Any]) -> None:
        # the robot waits instead of informing: the human, sure the ball is in the basket,
        # may reach for it there
        inform = node(d, kind="inform")
        before = parent(d, inform)
        inform.update({k: before[k] for k in ("state", "robot_agenda", "human_agenda",
                                              "copresent", "k", "worlds", "divergence",
                                              "world_diffs")})
        inform.update(kind="wait", action="wait", name="wait", args=[], cost=2, to_move="H")
        take = d["nodes"][inform["children"][0]]
        take.update(action="take(basket)", args=["basket"])

    r = caught(problem, mutated(policy, edit), "R wait, H take(basket)]",
               "not applicable in T: the branch fails")
    # and the human, sure of its next action, does not idle after the robot's wait
    assert any("R wait, H pass]" in v and "extra human branch" in v for v in r.violations)


def test_robot_node_with_two_children() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        n = node(d, agent="H", action="move(mt, ot)")
        n["children"].append(node(d, agent="R", action="wait")["id"])

    caught(problem, mutated(policy, edit), "branch [H move(mt, ot)]",
           "exactly one move")


def test_tampered_opening() -> None:
    problem, policy = solved_v2("cubes/qualitative")

    def edit(d: dict[str, Any]) -> None:
        d["after"][1] = "R wait"

    r = caught(problem, mutated(policy, edit), "opening: after[1] is 'R wait'",
               "the problem fixes 'R pick(r)'")
    # replayed as written, the robot never picked r, so it cannot place it
    assert any("opening: after[3] 'R place(r, box1)' is not a legal move" in v
               for v in r.violations[1:])


def test_opening_tampered_into_another_legal_line() -> None:
    problem, policy = solved_v2("cubes/qualitative")

    def edit(d: dict[str, Any]) -> None:
        d["after"][3] = "R place(r, box2)"

    r = caught(problem, mutated(policy, edit), "opening: after[3] is 'R place(r, box2)'")
    # legal, but it leads elsewhere than the recorded root
    assert any(v.startswith("branch []: node 0 (start): recorded facts differ")
               for v in r.violations[1:])


def test_illegal_opening_move() -> None:
    problem, policy = solved_v2("cubes/qualitative")

    def edit(d: dict[str, Any]) -> None:
        d["after"][2] = "H pick(r)"  # the human is at ot; r lies on mt

    r = caught(problem, mutated(policy, edit), "opening: after[2] is 'H pick(r)'")
    assert any("branch [H move(mt, ot), R pick(r)]: opening: after[2] 'H pick(r)' is not a "
               "legal move" in v for v in r.violations)


def test_opening_matching_a_tampered_problem_is_checked_too() -> None:
    problem, policy = solved_v2("cubes/qualitative")
    bad = [*problem.after]
    bad[1] = "R place(r, box1)"  # the robot does not hold r yet
    p = dataclasses.replace(problem, after=tuple(bad))
    pol = mutated(policy, lambda d: d.update(after=bad))
    caught(p, pol, "opening: after[1] 'R place(r, box1)' is not a legal move",
           "not applicable in T")


def test_other_branches_are_still_checked() -> None:
    problem, policy = solved_v2("cubes/p1")

    def edit(d: dict[str, Any]) -> None:
        node(d, agent="H", action="pick(w)")["cost"] = 7  # in the first branch
        # the last branch of the root's other child
        [n for n in d["nodes"] if n["action"] == "pass"][-1]["worlds"] = 5

    r = caught(problem, mutated(policy, edit), "cost is 7")
    assert len(r.violations) == 2
    assert "worlds is 5, expected 1" in r.violations[1]
    # each of the two faulty branches is checked up to its violation, the others to the end
    assert r.branches_checked == policy.leaves


def test_inform_label_with_the_wrong_value() -> None:
    problem, policy = solved_v2("cubes/qualitative")

    def edit(d: dict[str, Any]) -> None:
        node(d, kind="inform")["action"] = "inform(not empty(box2))"

    caught(problem, mutated(policy, edit), "the label tells empty(box2) is false, but it is "
           "true in T")
