"""Every BehaviorTree.CPP v4 tree ehatp writes passes a structural check written from that
format (tests/bt_cpp/schema.py: what BehaviorTree.CPP's parser checks and its generated schema
requires), however long the policy: every example's export, an IPC domain's and synthetic
policies longer and deeper than the parser's nesting limit. The real BehaviorTree.CPP loads and
ticks them in tests/test_bt_cpp.py when it is built."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import ehatp
from ehatp import Policy
from ehatp.formats import bt

from .bt_cpp.policies import chain_policy, comb_policy
from .bt_cpp.schema import MAX_DEPTH, depth, problems
from .conftest import EXAMPLES, Example, solved_v2
from .test_bt import inlined, policy_shape, shared, xml_shape

HDDL = Path(__file__).parent / "data" / "hddl"


def export(policy: Policy, problem: ehatp.Problem | None = None) -> str:
    answers = None if problem is None else bt.answers_of(problem, policy)
    return bt.to_btcpp(bt.from_policy(policy, answers))


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_example_export_passes_the_schema_check_with_and_without_its_problem(
        example: Example) -> None:
    problem, policy = solved_v2(example)
    for text in (export(policy, problem), export(policy)):
        assert problems(text) == []
        assert depth(text) <= bt.MAX_DEPTH


def test_an_ipc_domain_export_passes_the_schema_check() -> None:
    pytest.importorskip("unified_planning", reason="unified-planning is not installed "
                                                   "(pip install 'ehatp[hddl]')")
    from ehatp.formats import hddl

    imported = hddl.import_hddl(HDDL / "transport-domain.hddl", HDDL / "transport-p1.hddl")
    problem = imported.problem()
    result = ehatp.solve(problem, expand=True)
    assert result.policy is not None
    text = export(result.policy, problem)
    assert problems(text) == []
    assert xml_shape(text) == policy_shape(result.policy)


def test_a_300_move_chain_is_one_flat_tree_that_passes_the_schema_check() -> None:
    policy = chain_policy(300)
    text = export(policy)
    assert problems(text) == []
    root = ET.fromstring(text)
    assert [t.get("ID") for t in root.findall("BehaviorTree")] == ["Policy"]
    assert depth(text) == 4  # the human's pass: Fallback, its branch, HumanDid
    assert xml_shape(text) == policy_shape(policy)


def test_choices_nested_past_the_limit_go_on_in_subtrees_within_the_depth() -> None:
    policy = comb_policy(150)  # 150 nested choices: 300 levels in one tree
    text = export(policy)
    assert problems(text) == []
    assert depth(text) == bt.MAX_DEPTH < MAX_DEPTH == bt.BTCPP_MAX_DEPTH
    trees = xml_shape(text)
    assert len(trees) == 3  # cut twice, once every MAX_NESTED_CHOICES + 1 choices
    assert not shared(policy) and inlined(trees, shared(policy)) == policy_shape(policy)


def test_the_check_refuses_what_behaviortree_cpp_refuses(monkeypatch: pytest.MonkeyPatch
                                                          ) -> None:
    """The check is not vacuous: the faults of earlier exports fail it."""
    problem, policy = solved_v2("cubes/qualitative-ask")
    bare = export(policy)  # no problem: the answers' Say leaves its answer out
    # Say's optional ports without a default: required in BehaviorTree.CPP's schema
    no_defaults = re.sub(r' default="[^"]*"', "", bare)
    assert any("'answer' has no default" in p for p in problems(no_defaults))
    # the nesting limit, as before the long branches went on in subtrees
    monkeypatch.setattr(bt, "MAX_NESTED_CHOICES", 10_000)
    deep = export(comb_policy(150))
    assert depth(deep) > MAX_DEPTH
    assert any("nested deeper than 256" in p for p in problems(deep))
    # a port the model does not declare, a SubTree to no tree, a model after the trees' end
    text = export(policy, problem)
    assert any("'colour' is not a port" in p
               for p in problems(text.replace("<RobotWait", '<RobotWait colour="red"', 1)))
    assert any("names no tree" in p
               for p in problems(text.replace('SubTree ID="Node_2"', 'SubTree ID="Node_9"', 1)))
    assert any("not the last child" in p for p in problems(
        text.replace("</root>", '<BehaviorTree ID="Late"><AlwaysFailure/></BehaviorTree></root>')))


def test_the_model_declares_every_custom_node_with_a_default_for_every_optional_port() -> None:
    problem, policy = solved_v2("cubes/p4")
    root = ET.fromstring(export(policy, problem))
    (model,) = root.findall("TreeNodesModel")
    declared = {e.get("ID"): {p.get("name"): p.get("default") for p in e
                              if p.tag.endswith("_port")} for e in model}
    assert set(declared) == bt.CUSTOM_IDS
    assert declared["Say"] == {"kind": None, "literals": "", "question": "", "answer": "",
                               "intention": "", "completes": ""}
    for robot in ("RobotAction", "RobotWait", "Silence", "Say"):
        assert declared[robot]["completes"] == ""
    assert all(p.get("type") == "std::string" for e in model for p in e
               if p.tag.endswith("_port"))


def test_the_node_finishing_each_robot_move_says_so_in_the_xml() -> None:
    _, policy = solved_v2("cubes/qualitative")  # inform(empty(box2)), then waits
    root = ET.fromstring(export(policy))
    robot = [(e.tag, e.get("completes")) for e in root.iter()
             if e.tag in ("RobotAction", "RobotWait", "Say", "Silence")]
    assert ("Say", "inform(empty(box2))") in robot
    assert all(c is not None for _, c in robot)
    # an action said with an inform (speech = "with-action"): the Say finishes nothing, the
    # action finishes the move
    d = solved_v2("cubes/p2").policy.to_dict()
    m = next(m for n in d["nodes"] for m in n["moves"] if m["agent"] == "R"
             and m["kind"] == "action")
    m["told"], m["action"] = ["empty(box2)"], f"inform(empty(box2)) + {m['action']}"
    root = ET.fromstring(export(Policy.from_dict(d)))
    seq = [(e.tag, e.get("completes")) for e in root.iter() if e.tag in ("Say", "RobotAction")]
    at = seq.index(("RobotAction", m["action"]))
    assert seq[at - 1] == ("Say", None)
