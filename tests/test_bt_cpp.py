"""The BehaviorTree.CPP v4 trees ehatp writes, loaded and ticked in the real BehaviorTree.CPP
by the small program tests/bt_cpp/tick.cpp (its custom nodes registered as
docs/behaviour-trees.md says): every example's export, an IPC domain's, a 300-move chain and
150 nested choices. Each run follows the same human choices as the py_trees tree of the same
policy and must do the same, line for line; an example's run is also replayed through an
``ehatp.Executor``. Built by ``make bt-cpp`` (benchmarks/bt_cpp.py) into a cache folder; without
it these tests are skipped, saying so."""

from __future__ import annotations

import importlib.util
import random
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

import ehatp
from ehatp import Policy
from ehatp.formats import bt
from ehatp.run.executor import Executor

from .bt_cpp.policies import chain_policy, comb_policy
from .bt_cpp.schema import problems
from .conftest import DATA, EXAMPLES, Example, solved_v2

pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parent.parent
RUNS = 10  # human choice scripts per example
HDDL = Path(__file__).parent / "data" / "hddl"


def tick_program() -> Path:
    spec = importlib.util.spec_from_file_location("bt_cpp_build", ROOT / "benchmarks" /
                                                  "bt_cpp.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    path: Path = module.program()
    return path


@pytest.fixture(scope="module")
def tick() -> Path:
    path = tick_program()
    if not path.exists():
        pytest.skip(f"BehaviorTree.CPP not built: run make bt-cpp (no {path})")
    return path


def run_cpp(tick: Path, tmp_path: Path, text: str, choices: list[int]) -> tuple[str, list[str]]:
    """Return the status and the event lines of the tree ``text`` ticked in BehaviorTree.CPP."""
    f = tmp_path / "tree.xml"
    f.write_text(text, encoding="utf-8")
    r = subprocess.run([str(tick), str(f), "--choices", ",".join(map(str, choices))],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode in (0, 1), r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("loaded\t") and lines[-1].startswith("status\t"), r.stdout[-500:]
    return lines[-1].split("\t")[1], lines[1:-1]


def run_py(policy: Policy, choices: list[int], problem: ehatp.Problem | None = None
           ) -> tuple[str, list[str]]:
    """Return the status and the event lines of the policy's py_trees tree, the human
    choosing as the tick program does."""
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    from py_trees.common import Status

    lines: list[str] = []
    turn = [0]

    def robot(cmd: Any) -> bool:
        kind = "say" if cmd.kind == "say" else cmd.kind
        lines.append(f"robot\t{kind}\t{cmd.action}\t{cmd.completes or ''}\t{cmd.answer or ''}")
        return True

    def human(t: Any) -> str:
        c = choices[turn[0] % len(choices)]
        turn[0] += 1
        chosen = "dance" if c < 0 else t.expected[c % len(t.expected)]
        lines.append(f"human\t{t.node}\t{chosen}")
        return str(chosen)

    root = bt.build_py_tree(policy, robot=robot, human=human, problem=problem,
                            on_goal=lambda n: lines.append(f"goal\t{n}"),
                            on_uncovered=lambda o, e: lines.append(f"uncovered\t{o}\t"
                                                                    f"{';'.join(e)}"))
    for _ in range(1_000_000):
        root.tick_once()
        if root.status != Status.RUNNING:
            break
    return ("SUCCESS" if root.status == Status.SUCCESS else "FAILURE"), lines


def replay(problem: ehatp.Problem, policy: Policy, lines: list[str]) -> Executor:
    """Return an executor that followed the events ``lines``: each robot move finished where
    the tree says (``completes``), each human action observed."""
    ex = Executor(problem, policy)
    ex.replay_opening()
    for line in lines:
        kind, *f = line.split("\t")
        if kind == "robot" and f[2]:
            want = ex.next_robot_action()
            assert want is not None and want.label == f[2], (want, line)
            ex.robot_action_done(f[2])
        elif kind == "human":
            assert ex.node is not None and int(f[0]) == ex.node.id
            ex.observe_human_action(f[1])
    return ex


def scripts(runs: int) -> list[list[int]]:
    return [[0], *([random.Random(s).randrange(8) for _ in range(64)] for s in range(runs - 1))]


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_example_loads_and_ticks_in_behaviortree_cpp_as_in_py_trees(
        tick: Path, tmp_path: Path, example: Example) -> None:
    problem, policy = solved_v2(example)
    text = bt.to_btcpp(bt.from_policy(policy, bt.answers_of(problem, policy)))
    for choices in scripts(RUNS):
        status, lines = run_cpp(tick, tmp_path, text, choices)
        assert status == "SUCCESS"
        assert (status, lines) == run_py(policy, choices, problem)
        ex = replay(problem, policy, lines)
        assert ex.done and ex.goal_reached
        assert lines[-1] == f"goal\t{ex.node.id if ex.node else None}"
    # the human does something the policy does not cover: reported once, the tree fails
    status, lines = run_cpp(tick, tmp_path, text, [-1])
    assert status == "FAILURE" and [x for x in lines if x.startswith("uncovered")] == \
        [x for x in run_py(policy, [-1], problem)[1] if x.startswith("uncovered")] != []
    # without the problem the answers are left to the robot: the tree still loads and runs
    status, _ = run_cpp(tick, tmp_path, bt.to_btcpp(bt.from_policy(policy)), [1, 0])
    assert status == "SUCCESS"


def test_a_policy_with_many_shared_states_loads_unfolded_and_ticks(tick: Path, tmp_path: Path
                                                                   ) -> None:
    """BehaviorTree.CPP builds each SubTree anew at every use: the 8-cube policy's 73 trees
    (about 3,900 lines) load as some 177,000 nodes, and still run as the policy says."""
    problem, policy = solved_v2(DATA / "cubes-8.toml")
    text = bt.to_btcpp(bt.from_policy(policy, bt.answers_of(problem, policy)))
    f = tmp_path / "cubes8.xml"
    f.write_text(text, encoding="utf-8")
    first = subprocess.run([str(tick), str(f)], capture_output=True, text=True, timeout=300)
    loaded = int(first.stdout.splitlines()[0].split("\t")[1])
    assert loaded > 10 * text.count("\n")  # the unfolding, far larger than the file
    for choices in scripts(3):
        status, lines = run_cpp(tick, tmp_path, text, choices)
        assert status == "SUCCESS" and (status, lines) == run_py(policy, choices, problem)
        assert replay(problem, policy, lines).goal_reached


def test_the_program_registers_the_nodes_the_tree_nodes_model_declares(tick: Path) -> None:
    def ports(model: ET.Element) -> dict[tuple[str, str], set[tuple[str, Any, Any]]]:
        return {(e.tag, str(e.get("ID"))): {(p.tag, p.get("name"), p.get("default"))
                                             for p in e if p.tag.endswith("_port")}
                for e in model}

    out = subprocess.run([str(tick), "--model"], capture_output=True, text=True, check=True)
    registered = ET.fromstring(out.stdout).find("TreeNodesModel")
    _, policy = solved_v2("cubes/p2")
    exported = ET.fromstring(bt.to_btcpp(bt.from_policy(policy))).find("TreeNodesModel")
    # a joint-step policy's model also declares WaitHumanStart (docs/behaviour-trees.md)
    _, joint = solved_v2("concurrent/stack4")
    exported_joint = ET.fromstring(bt.to_btcpp(bt.from_policy(joint))).find("TreeNodesModel")
    assert registered is not None and exported is not None and exported_joint is not None
    assert ports(registered) == ports(exported_joint)
    assert ports(exported_joint) == {**ports(exported), ("Action", "WaitHumanStart"): ports(
        registered)[("Action", "WaitHumanStart")]}


def test_a_300_move_chain_and_150_nested_choices_load_and_tick(tick: Path, tmp_path: Path,
                                                               monkeypatch: pytest.MonkeyPatch
                                                               ) -> None:
    chain = chain_policy(300)
    status, lines = run_cpp(tick, tmp_path, bt.to_btcpp(bt.from_policy(chain)), [0])
    assert status == "SUCCESS" and lines[-1] == "goal\t300"
    assert sum(x.startswith("robot") for x in lines) == 150
    assert (status, lines) == run_py(chain, [0])
    comb = comb_policy(150)
    text = bt.to_btcpp(bt.from_policy(comb))
    for choices in ([1], [1] * 100 + [0], *scripts(5)):
        status, lines = run_cpp(tick, tmp_path, text, choices)
        assert status == "SUCCESS" and (status, lines) == run_py(comb, choices)
    assert lines[-1].startswith("goal")
    # the same policy in one tree: refused by BehaviorTree.CPP and by the schema check
    monkeypatch.setattr(bt, "MAX_NESTED_CHOICES", 10_000)
    deep = bt.to_btcpp(bt.from_policy(comb))
    f = tmp_path / "deep.xml"
    f.write_text(deep, encoding="utf-8")
    r = subprocess.run([str(tick), str(f)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "Maximum XML nesting depth exceeded" in r.stderr
    assert problems(deep) != []


def test_an_ipc_domain_loads_and_ticks(tick: Path, tmp_path: Path) -> None:
    pytest.importorskip("unified_planning", reason="unified-planning is not installed "
                                                   "(pip install 'ehatp[hddl]')")
    from ehatp.formats import hddl

    problem = hddl.import_hddl(HDDL / "transport-domain.hddl",
                               HDDL / "transport-p1.hddl").problem()
    result = ehatp.solve(problem, expand=True)
    assert result.policy is not None
    policy = result.policy
    status, lines = run_cpp(tick, tmp_path, bt.to_btcpp(bt.from_policy(
        policy, bt.answers_of(problem, policy))), [0])
    assert status == "SUCCESS" and (status, lines) == run_py(policy, [0], problem)
    assert replay(problem, policy, lines).goal_reached
