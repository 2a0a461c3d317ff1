"""`ehatp export bt`: the policy as a BehaviorTree.CPP v4 XML tree and as a runnable py_trees
tree (docs/behaviour-trees.md)."""

from __future__ import annotations

import random
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import ehatp
from ehatp import Policy
from ehatp.cli.app import app
from ehatp.formats import bt
from ehatp.run.executor import Executor

from .conftest import DATA, EXAMPLES, EXAMPLES_DIR, Example, solved_v2

CUBES = EXAMPLES_DIR / "cubes"
RUNS = 100  # seeded random humans per example
BUILT_IN = {"Sequence", "Fallback", "SubTree", "AlwaysFailure"}


def py_trees_or_skip() -> Any:
    return pytest.importorskip(
        "py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]'; it is in the "
                           "test extra, so CI runs these tests)")


# --- the policy graph, as the tree should follow it -----------------------------------------


def shared(policy: Policy) -> set[int]:
    """Nodes with more than one move into them, counted here independently of bt.py."""
    into: dict[int, int] = {}
    for node in policy.nodes:
        for m in node.moves:
            into[m.to] = into.get(m.to, 0) + 1
    return {n for n, k in into.items() if k > 1}


def robot_items(m: Any) -> list[tuple[Any, ...]]:
    """A robot move as what the robot does, in order, each item ending with the label of the
    move it completes (the last one) or None."""
    said = [("say", tuple(m.told))] if m.told else []
    if m.kind == "inform":
        items = [("say", tuple(m.args))]
    elif m.kind == "silence":
        items = [("silence",)]
    elif m.kind == "wait":
        items = [*said, ("wait",)]
    else:
        assert m.kind == "action", m
        label = m.action.split(" + ")[-1]
        items = [*said, ("action", label, m.name, tuple(m.args))]
    return [(*x, m.action if i == len(items) - 1 else None) for i, x in enumerate(items)]


def policy_shape(policy: Policy) -> dict[str, list[tuple[Any, ...]]]:
    """Per tree (the main one, one per shared node): robot actions, human choices, goals."""
    share = shared(policy)
    robot = policy.agents["robot"]

    def walk(n: int, top: int) -> list[tuple[Any, ...]]:
        out: list[tuple[Any, ...]] = []
        while True:
            if n != top and n in share:
                return [*out, ("subtree", n)]
            node = policy.nodes[n]
            if not node.moves:
                assert node.goal
                return [*out, ("goal", n)]
            if node.moves[0].agent == robot:
                (m,) = node.moves
                out += robot_items(m)
                n = m.to
                continue
            branches = tuple((m.action, ("answer", m.args[0]) if m.kind == "ask" else None,
                              tuple(walk(m.to, top))) for m in node.moves)
            return [*out, ("human", n, branches)]

    out = {"Policy": walk(0, 0)}
    for s in sorted(share):
        out[f"Node_{s}"] = walk(s, s)
    return out


# --- the XML, read back independently --------------------------------------------------------


def xml_shape(text: str) -> dict[str, list[tuple[Any, ...]]]:
    root = ET.fromstring(text)

    def split(v: str | None) -> tuple[str, ...]:
        return tuple(x for x in (v or "").split(";") if x)

    def chain(elems: list[ET.Element]) -> list[tuple[Any, ...]]:
        out: list[tuple[Any, ...]] = []
        i = 0
        while i < len(elems):
            e = elems[i]
            a = e.attrib
            if e.tag == "Say":
                assert a["kind"] == "inform", a
                out.append(("say", split(a.get("literals")), a.get("completes")))
            elif e.tag == "RobotAction":
                out.append(("action", a["action"], a["action_name"], split(a["args"]),
                            a.get("completes")))
            elif e.tag == "RobotWait":
                out.append(("wait", a.get("completes")))
            elif e.tag == "Silence":
                out.append(("silence", a.get("completes")))
            elif e.tag == "SubTree":
                assert i == len(elems) - 1
                out.append(("subtree", int(a["ID"].removeprefix("Node_"))))
            elif e.tag == "GoalReached":
                assert i == len(elems) - 1
                out.append(("goal", int(a["node"])))
            elif e.tag in ("WaitHumanAction", "WaitHumanStart"):  # the latter: joint steps
                fallback = elems[i + 1]
                # a choice of one move: the policy goes on after the Fallback, not inside it
                flat = len(fallback) == 2
                assert fallback.tag == "Fallback" and (flat or i + 2 == len(elems))
                key = a["action"]
                assert key.startswith("{") and key.endswith("}")
                *covered, last = list(fallback)
                branches = []
                for b in covered:
                    assert b.tag == "Sequence"
                    did, *rest = list(b)
                    assert did.tag == "HumanDid" and did.attrib["observed"] == key
                    answer = None
                    if rest and rest[0].tag == "Say" and rest[0].attrib["kind"] == "answer":
                        answer = ("answer", rest[0].attrib["question"])
                        rest = rest[1:]
                    if flat:
                        assert rest == []
                        rest = elems[i + 2:]
                    branches.append((did.attrib["action"], answer, tuple(chain(rest))))
                assert split(a["expected"]) == tuple(x[0] for x in branches)
                report, fail = list(last)
                assert report.tag == "ReportUncovered" and fail.tag == "AlwaysFailure"
                assert report.attrib == {"observed": key, "expected": a["expected"]}
                node = int(key[1:-1].rsplit("_", 1)[1])
                out.append(("human", node, tuple(branches)))
                return out
            else:
                raise AssertionError(f"unexpected node {e.tag} in a chain")
            i += 1
        return out

    out = {}
    for tree in root.findall("BehaviorTree"):
        (seq,) = list(tree)
        assert seq.tag == "Sequence"
        out[tree.attrib["ID"]] = chain(list(seq))
    return out


def inlined(trees: dict[str, list[tuple[Any, ...]]], share: set[int]
            ) -> dict[str, list[tuple[Any, ...]]]:
    """Return ``trees`` (:func:`xml_shape`) with every tree of a node the policy does not share
    (a long branch cut to keep the XML shallow) put back where its one SubTree is."""
    cut = {int(t.removeprefix("Node_")) for t in trees if t != "Policy"} - share

    def put(items: list[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
        out: list[tuple[Any, ...]] = []
        for item in items:
            if item[0] == "subtree" and item[1] in cut:
                out += put(trees[f"Node_{item[1]}"])
            elif item[0] == "human":
                out.append(("human", item[1], tuple((action, answer, tuple(put(list(rest))))
                                                    for action, answer, rest in item[2])))
            else:
                out.append(item)
        return out

    return {t: put(items) for t, items in trees.items() if t == "Policy" or
            int(t.removeprefix("Node_")) not in cut}


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_xml_is_well_formed_complete_and_round_trips(example: Example) -> None:
    problem, policy = solved_v2(example)
    text = bt.to_btcpp(bt.from_policy(policy, bt.answers_of(problem, policy)))
    root = ET.fromstring(text)  # well-formed
    assert root.tag == "root" and root.attrib["BTCPP_format"] == "4"
    trees = [t.attrib["ID"] for t in root.findall("BehaviorTree")]
    assert root.attrib["main_tree_to_execute"] == "Policy"
    # exactly one tree per shared policy node, plus the main tree
    assert sorted(trees) == sorted(["Policy", *(f"Node_{s}" for s in shared(policy))])
    assert len(set(trees)) == len(trees)
    # every SubTree refers to a defined tree
    used = {e.attrib["ID"] for e in root.iter("SubTree")}
    assert used <= set(trees)
    # TreeNodesModel declares every custom node used
    (model,) = root.findall("TreeNodesModel")
    declared = {e.attrib["ID"] for e in model}
    tags = {e.tag for t in root.findall("BehaviorTree") for e in t.iter()} - {"BehaviorTree"}
    assert tags - BUILT_IN <= declared
    for e in (e for t in root.findall("BehaviorTree") for e in t.iter()):
        if e.tag in declared:  # and every port given is a declared port
            spec = model.find(f"*[@ID='{e.tag}']")
            assert spec is not None
            ports = {p.attrib["name"] for p in spec}
            assert set(e.attrib) - {"name"} <= ports, (e.tag, e.attrib)
    # the structure: robot actions, human choices and goals as in the policy graph
    assert xml_shape(text) == policy_shape(policy)


def test_answers_to_questions() -> None:
    problem, policy = solved_v2("cubes/qualitative-ask")
    text = bt.to_btcpp(bt.from_policy(policy, bt.answers_of(problem, policy)))
    says = {e.attrib["question"]: e.attrib["answer"] for e in ET.fromstring(text).iter("Say")
            if e.attrib["kind"] == "answer"}
    assert says == {"can_put(w, box1)": "no", "can_put(w, box2)": "yes"}
    bare = ET.fromstring(bt.to_btcpp(bt.from_policy(policy)))  # no problem: no answer port
    assert all("answer" not in e.attrib for e in bare.iter("Say"))


def test_xml_is_deterministic_and_the_cli_writes_it(tmp_path: Path) -> None:
    pfile = tmp_path / "p4.json"
    runner = CliRunner()
    assert runner.invoke(app, ["solve", str(CUBES / "p4.toml"), "--out", str(pfile)]
                         ).exit_code == 0
    outs = []
    for i in range(2):
        out = tmp_path / f"p4-{i}.xml"
        r = runner.invoke(app, ["export", "bt", str(pfile), "--format", "btcpp4", "--out",
                                str(out), "--problem", str(CUBES / "p4.toml")])
        assert r.exit_code == 0, r.output
        outs.append(out.read_bytes())
    assert outs[0] == outs[1]
    problem = ehatp.load(CUBES / "p4.toml")
    again = ehatp.solve(problem).policy
    assert again is not None
    assert outs[0].decode() == bt.to_btcpp(bt.from_policy(again, bt.answers_of(problem, again)))
    r = runner.invoke(app, ["export", "bt", str(pfile)])  # stdout, btcpp4 by default
    assert r.exit_code == 0 and r.stdout.startswith('<?xml version="1.0"')


def test_cli_bad_input_is_one_line(tmp_path: Path) -> None:
    runner = CliRunner()
    r = runner.invoke(app, ["export", "bt", str(tmp_path / "missing.json")])
    assert r.exit_code == 2
    r = runner.invoke(app, ["export", "bt", str(CUBES / "p2.toml"), "--format", "dot"])
    assert r.exit_code == 2


# --- py_trees ---------------------------------------------------------------------------------


class Run:
    """One execution: the tree's robot acts through the executor, a seeded random human picks
    among the moves the policy covers."""

    def __init__(self, ex: Executor, seed: int) -> None:
        self.ex, self.rng = ex, random.Random(seed)
        self.goals: list[int] = []
        self.uncovered: list[tuple[str, list[str]]] = []


def tick_to_end(root: Any, limit: int = 10_000) -> Any:
    from py_trees.common import Status

    for _ in range(limit):
        root.tick_once()
        if root.status != Status.RUNNING:
            return root.status
    raise AssertionError("the tree is still running")


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_py_tree_reaches_the_goal_against_the_executor(example: Example) -> None:
    py_trees_or_skip()
    from py_trees.common import Status

    from ehatp.formats.bt_py_trees import HumanTurn, RobotCommand

    problem, policy = solved_v2(example)
    start = Executor(problem, policy)
    start.replay_opening()  # the policy starts after the problem's fixed opening
    run = Run(start.copy(), 0)

    def robot(cmd: RobotCommand) -> bool:
        if cmd.completes is not None:  # the last part of the policy's robot move
            want = run.ex.next_robot_action()
            assert want is not None and want.label == cmd.completes
            if cmd.kind == "action":
                assert (cmd.name, cmd.args) == (want.name, want.args)
            run.ex.robot_action_done(cmd.completes)
        return True

    def human(turn: HumanTurn) -> str:
        covered = run.ex.expected_human_actions()
        assert list(turn.expected) == [a.label for a in covered]
        assert run.ex.node is not None and turn.node == run.ex.node.id
        choice = run.rng.choice(covered).label
        run.ex.observe_human_action(choice)
        return choice

    # one tree, ticked again for every run (a finished py_trees tree starts over)
    root = bt.build_py_tree(policy, robot=robot, human=human, on_goal=lambda n: run.goals
                            .append(n), on_uncovered=lambda o, e: run.uncovered.append((o, e)),
                            problem=problem)
    leaves = set()
    for seed in range(RUNS):
        run = Run(start.copy(), seed)
        assert tick_to_end(root) == Status.SUCCESS
        assert run.ex.done and run.ex.goal_reached
        assert run.ex.node is not None and run.goals == [run.ex.node.id]
        assert run.uncovered == []
        leaves.add(run.ex.node.id)
    if policy.leaves <= 4:  # the random human explores the policy
        assert len(leaves) == len({n.id for n in policy.nodes if n.goal})


def test_uncovered_human_action_is_reported_once_and_fails() -> None:
    py_trees_or_skip()
    from py_trees.common import Status

    _, policy = solved_v2("cubes/p2")
    choices = iter(["__first__", "dance"])  # covered at the first choice, then uncovered
    turns: list[Any] = []
    reported: list[tuple[str, list[str]]] = []

    def human(turn: Any) -> str:
        turns.append(turn)
        c = next(choices)
        return turn.expected[0] if c == "__first__" else c

    root = bt.build_py_tree(policy, robot=lambda cmd: True, human=human,
                            on_uncovered=lambda o, e: reported.append((o, e)))
    assert tick_to_end(root) == Status.FAILURE
    assert len(turns) == 2
    assert reported == [("dance", list(turns[1].expected))]


def test_robot_running_and_failing() -> None:
    py_trees_or_skip()
    from py_trees.common import Status

    _, policy = solved_v2("cubes/qualitative")
    calls: list[str] = []

    def slow(cmd: Any) -> bool | None:  # each command runs for two ticks
        calls.append(cmd.action)
        return None if calls.count(cmd.action) % 2 else True

    root = bt.build_py_tree(policy, robot=slow, human=lambda t: t.expected[0])
    root.tick_once()
    assert root.status == Status.RUNNING and calls == ["inform(empty(box2))"]
    assert tick_to_end(root) == Status.SUCCESS
    root = bt.build_py_tree(policy, robot=lambda cmd: False, human=lambda t: t.expected[0])
    assert tick_to_end(root) == Status.FAILURE


def test_py_trees_module_builds_the_same_tree(tmp_path: Path) -> None:
    py_trees = py_trees_or_skip()
    from py_trees.common import Status

    problem, policy = solved_v2("cubes/p4")
    pfile = tmp_path / "p4.json"
    policy.write(pfile)
    out = tmp_path / "p4_tree.py"
    r = CliRunner().invoke(app, ["export", "bt", str(pfile), "--format", "py_trees", "--out",
                                 str(out), "--problem", str(CUBES / "p4.toml")])
    assert r.exit_code == 0, r.output
    namespace: dict[str, Any] = {}
    exec(compile(out.read_text(encoding="utf-8"), str(out), "exec"), namespace)

    def trace(make: Any) -> list[str]:
        rng = random.Random(7)
        did: list[str] = []

        def robot(cmd: Any) -> bool:
            did.append(f"R {cmd.kind} {cmd.action} {cmd.completes}")
            return True

        def human(turn: Any) -> str:
            c = rng.choice(turn.expected)
            did.append(f"H {c}")
            return str(c)

        root = make(robot, human)
        shape = py_trees.display.ascii_tree(root)
        assert tick_to_end(root) == Status.SUCCESS
        return [shape, *did]

    generated = trace(namespace["make_tree"])
    built = trace(lambda r, h: bt.build_py_tree(policy, robot=r, human=h, problem=problem))
    assert generated == built
    assert len(generated) > 5


def test_a_large_policy_with_hidden_intentions_keeps_its_shape_and_a_shallow_module() -> None:
    # the 8-cube problem's human reaches move(mt, ot) by several methods (to fetch one cube or
    # another): the robot sees one move, and the node after it holds several human agendas
    problem, policy = solved_v2(DATA / "cubes-8.toml")
    assert any(len(n.human_agendas) > 1 for n in policy.nodes)
    assert all(len({m.action for m in n.moves}) == len(n.moves) for n in policy.nodes)
    bt.answers_of(problem, policy)  # walks every node along the policy's edges
    forest = bt.from_policy(policy, bt.answers_of(problem, policy))
    assert xml_shape(bt.to_btcpp(forest)) == policy_shape(policy)
    # the py_trees module: one function per human choice keeps the nesting shallow
    source = bt.to_py_trees_source(forest)
    compile(source, "cubes8_tree.py", "exec")
    assert max(len(x) - len(x.lstrip()) for x in source.splitlines()) <= 40
