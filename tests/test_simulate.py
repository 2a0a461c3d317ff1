"""`ehatp simulate` and the execution API (docs/simulation.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

import ehatp
from ehatp.cli.app import app as ehatp_app
from ehatp.formats.policy import PathStep, Policy
from ehatp.run.executor import ExecutionError, Executor, PolicyMismatch, UncoveredHumanAction

from .conftest import EXAMPLES_DIR, Example, every_example_by_branch, solved_v2

CUBES = EXAMPLES_DIR / "cubes"
P2, QUAL, QUAL_ASK = CUBES / "p2.toml", CUBES / "qualitative.toml", CUBES / "qualitative-ask.toml"

STEP = re.compile(r"^(\d+)\. (\S+) (.+?)  \(cost [^;]+; (.*)\)$")
WORLDS = re.compile(r"^  \S+ knows the truth; \S+ now entertains (\d+) worlds?")


def app() -> typer.Typer:
    return ehatp_app  # the real command line: `simulate` is one of its commands


def invoke(*args: str, input: str | None = None) -> tuple[int, str]:
    r = CliRunner().invoke(app(), ["simulate", *args], input=input)
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    return r.exit_code, r.output


def steps(output: str) -> list[tuple[str, str, str, int]]:
    """(agent, label, where, worlds after) for every printed step."""
    out: list[tuple[str, str, str, int]] = []
    lines = output.splitlines()
    for i, line in enumerate(lines):
        m = STEP.match(line)
        if m:
            worlds = next(int(w.group(1)) for x in lines[i + 1:] if (w := WORLDS.match(x)))
            out.append((m.group(2), m.group(3), m.group(4), worlds))
    return out


def write_policy(tmp_path: Path, problem: Path) -> Path:
    path = tmp_path / f"{problem.stem}.json"
    solved_v2(problem).policy.write(path)
    return path


def script_for(branch: list[PathStep], robot: str) -> str:
    """The human's moves of a branch, with the robot's as checked expectations."""
    lines = ["# derived from the policy"]
    for n in branch[1:]:
        lines.append(f"{n.agent} {n.action}" if n.agent == robot else n.action)
    return "\n".join(lines) + "\n"


# -- every branch of P2 ------------------------------------------------------------------------

def test_every_p2_branch_reaches_the_goal_with_the_policy_world_counts(tmp_path: Path) -> None:
    policy = solved_v2(P2).policy
    pfile = write_policy(tmp_path, P2)
    robot = policy.agents["robot"]
    branches = policy.branches()
    assert len(branches) == policy.leaves > 1
    for i, branch in enumerate(branches):
        script = tmp_path / f"branch{i}.txt"
        script.write_text(script_for(branch, robot), encoding="utf-8")
        code, out = invoke(str(P2), "--policy", str(pfile), "--human", "script",
                           "--script", str(script))
        assert code == 0, out
        assert "outcome: goal reached" in out
        got = steps(out)
        assert [(a, lab) for a, lab, _, _ in got] == [(n.agent, n.action) for n in branch[1:]]
        assert [w for *_, w in got] == [n.worlds for n in branch[1:]]
        assert [where for _, _, where, _ in got] == [f"policy node {n.id}" for n in branch[1:]]
        cost = sum(n.cost for n in branch[1:])
        assert f"total cost {cost};" in out


def test_solves_when_no_policy_is_given() -> None:
    code, out = invoke(str(P2))
    assert code == 0
    assert "policy solved now" in out and "outcome: goal reached" in out


# -- the paper's two traces --------------------------------------------------------------------

def test_qualitative_trace_informs_that_box2_is_empty(tmp_path: Path) -> None:
    script = tmp_path / "s.txt"
    script.write_text("R inform(empty(box2))\nH place(w, box2)\n", encoding="utf-8")
    code, out = invoke(str(QUAL), "--script", str(script))
    assert code == 0, out
    got = steps(out)
    opening = [tuple(s.split(" ", 1)) for s in ehatp.load(QUAL).after]
    assert [(a, lab) for a, lab, _, _ in got[:5]] == opening
    assert [where for _, _, where, _ in got[:4]] == ["opening"] * 4
    assert got[4][2] == "end of the opening, policy node 0" and got[4][3] == 2
    assert got[5][:2] == ("R", "inform(empty(box2))") and got[5][3] == 1
    assert got[6][:2] == ("H", "place(w, box2)") and got[6][3] == 1
    assert len(got) == 7 and "outcome: goal reached after 7 steps" in out
    assert "situation assessment: H sees" in out and "rules out 2 worlds (4 -> 2)" in out
    assert "R tells H: empty(box2) (2 -> 1 world)" in out


def test_qualitative_executor_worlds_after_the_opening() -> None:
    ex = Executor(ehatp.load(QUAL), solved_v2(QUAL).policy)
    while ex.in_opening:
        if ex.next_robot_action() is not None:
            ex.robot_action_done()
        else:
            ex.observe_human_action(ex.expected_human_actions()[0])
    assert ex.node is ex.policy.root and ex.to_move == "R"
    worlds = ex.human_worlds()
    assert len(worlds) == 2
    assert {("in(r, box1)" in w.atoms, "in(r, box2)" in w.atoms) for w in worlds} == {
        (True, False), (False, True)}
    assert sum(w.is_truth for w in worlds) == 1
    assert {"in(r, box1)", "in(r, box2)", "empty(box1)", "empty(box2)"} == set(
        ex.uncertain_atoms())
    action = ex.next_robot_action()
    assert action is not None
    assert (action.kind, action.name, action.args) == ("inform", "inform", ("empty(box2)",))
    ex.robot_action_done()
    assert len(ex.human_worlds()) == 1 and ex.next_robot_action() is None
    assert {a.label for a in ex.expected_human_actions()} == {"place(w, box2)", "pass"}
    step = ex.observe_human_action("H place(w, box2)")
    assert ex.done and ex.goal_reached and ex.to_move is None
    assert step.node is not None and step.node.goal
    assert ex.cost == 7


def test_qualitative_ask_trace_waits_for_the_question(tmp_path: Path) -> None:
    script = tmp_path / "s.txt"
    script.write_text("# the paper's trace (a)\nR wait\nH ask(can_put(w, box2))  # H asks\n"
                      "R wait\nH place(w, box2)\n", encoding="utf-8")
    code, out = invoke(str(QUAL_ASK), "--human", "script", "--script", str(script))
    assert code == 0, out
    got = steps(out)
    assert got[4][3] == 2
    assert [(a, lab, w) for a, lab, _, w in got[5:]] == [
        ("R", "wait", 2), ("H", "ask(can_put(w, box2))", 1), ("R", "wait", 1),
        ("H", "place(w, box2)", 1)]
    assert "H asks whether can_put(w, box2); R answers yes (2 -> 1 world)" in out
    assert "outcome: goal reached after 9 steps; total cost 9 (opening 5, then 4)" in out


# -- leaving the policy ------------------------------------------------------------------------

def test_uncovered_human_action_raises_with_the_expected_actions() -> None:
    # planned for a human who asks when blocked; this problem's human may also wait silently
    ex = Executor(ehatp.load(QUAL), solved_v2(QUAL_ASK).policy)
    while ex.in_opening:
        if ex.next_robot_action() is not None:
            ex.robot_action_done()
        else:
            ex.observe_human_action(ex.expected_human_actions()[0])
    ex.robot_action_done("R wait")
    before = ex.state
    with pytest.raises(UncoveredHumanAction) as e:
        ex.observe_human_action("pass")
    err = e.value
    assert err.action == "pass"
    assert err.expected == ["ask(can_put(w, box1))", "ask(can_put(w, box2))"]
    assert "pass" in err.possible
    assert str(err) == ("H did pass, which policy node 1 does not cover; the policy expects "
                        "ask(can_put(w, box1)) or ask(can_put(w, box2))")
    assert ex.state == before  # nothing changed: the controller may still report another move
    ex.observe_human_action("ask(can_put(w, box2))")


def test_human_leaving_the_opening_or_the_model() -> None:
    ex = Executor(ehatp.load(QUAL), solved_v2(QUAL).policy)
    with pytest.raises(UncoveredHumanAction, match=r"H did pass, which the problem's "
                       r"fixed opening does not cover; the policy expects move\(mt, ot\)"):
        ex.observe_human_action("pass")
    with pytest.raises(UncoveredHumanAction, match=r"dance, which is not a move of H here "
                       r"\(the model allows move\(mt, ot\), pass\)"):
        ex.observe_human_action("dance")
    with pytest.raises(ExecutionError, match="it is not R's turn: H is to move"):
        ex.robot_action_done()


def test_policy_with_a_missing_branch(tmp_path: Path) -> None:
    d = solved_v2(P2).policy.to_dict()
    root = d["nodes"][0]
    dropped = root["moves"][0]["action"]
    root["moves"] = root["moves"][1:]
    ex = Executor(ehatp.load(P2), Policy.from_dict(d))
    with pytest.raises(UncoveredHumanAction, match="policy node 0 does not cover"):
        ex.observe_human_action(dropped)


def test_cli_stops_with_exit_1_when_the_policy_does_not_cover(tmp_path: Path) -> None:
    pfile = write_policy(tmp_path, QUAL_ASK)
    script = tmp_path / "s.txt"
    script.write_text("R wait\npass\n", encoding="utf-8")
    code, out = invoke(str(QUAL), "--policy", str(pfile), "--script", str(script))
    assert code == 1
    assert out.splitlines()[-1] == (
        "stopped: H did pass, which policy node 1 does not cover; the policy expects "
        "ask(can_put(w, box1)) or ask(can_put(w, box2))")


def test_a_scripted_pass_after_a_forced_wait_leaves_the_policy_and_is_no_bad_input(
        tmp_path: Path) -> None:
    # the human who asks when blocked: after the robot's forced wait the fairness rule lets
    # the policy leave out the human's pass (docs/semantics.md §4), but the human can pass
    pfile = write_policy(tmp_path, QUAL_ASK)
    script = tmp_path / "s.txt"
    script.write_text("R wait\npass\n", encoding="utf-8")
    code, out = invoke(str(QUAL_ASK), "--policy", str(pfile), "--script", str(script))
    assert code == 1
    assert out.splitlines()[-1] == (
        "stopped: H did pass, which policy node 1 does not cover (a policy need not: after a "
        "forced robot wait, docs/semantics.md §4); the policy expects ask(can_put(w, box1)) or "
        "ask(can_put(w, box2))")


def test_script_expecting_another_robot_move_stops(tmp_path: Path) -> None:
    script = tmp_path / "s.txt"
    script.write_text("R wait\n", encoding="utf-8")
    code, out = invoke(str(QUAL), "--script", str(script))
    assert code == 1
    assert f"stopped: {script}:1: the script expects R wait, the policy does " \
           "inform(empty(box2))" in out


def test_policy_that_does_not_fit_the_problem(tmp_path: Path) -> None:
    with pytest.raises(PolicyMismatch, match="opening"):
        Executor(ehatp.load(QUAL), solved_v2(P2).policy)
    d = solved_v2(P2).policy.to_dict()
    first = d["nodes"][0]["moves"][0]
    d["nodes"][first["to"]]["worlds"] = 7
    ex = Executor(ehatp.load(P2), Policy.from_dict(d))
    # the edge is followed to the node it records, whose state is not the move's child
    with pytest.raises(PolicyMismatch, match=rf"policy node 0 says H {re.escape(first['action'])}"
                       rf" to node {first['to']}, but no move .* \(they differ on worlds\)"):
        ex.observe_human_action(first["action"])


# -- human modes -------------------------------------------------------------------------------

def test_random_human_is_deterministic() -> None:
    runs = {seed: invoke(str(P2), "--human", "random", "--seed", str(seed)) for seed in range(6)}
    for seed, (code, out) in runs.items():
        assert code == 0
        assert invoke(str(P2), "--human", "random", "--seed", str(seed)) == (code, out)
    assert len({out for _, out in runs.values()}) > 1


def test_first_human_is_the_default() -> None:
    code, out = invoke(str(P2))
    assert code == 0 and "human moves: first option" in out
    assert steps(out)[0][:2] == ("H", "move(mt, ot)")  # the semantics' first option at the root


def test_ask_reads_numbers_and_labels_from_piped_stdin() -> None:
    # a number, a label, two bad answers, a label with the agent's name, then numbers
    code, out = invoke(str(P2), "--human", "ask",
                       input="2\nmove(mt, ot)\nnonsense\n7\nH pick(w)\n1\n1\n")
    assert code == 0, out
    assert "  H to move; options:\n    1) move(mt, ot)\n    2) pass\n" in out
    assert "not an option: 'nonsense'; type 1 or a label" in out
    assert "not an option: '7'" in out
    humans = [lab for a, lab, _, _ in steps(out) if a == "H"]
    assert humans == ["pass", "move(mt, ot)", "pick(w)", "move(ot, mt)", "place(w, box2)"]
    assert "outcome: goal reached" in out


def test_ask_with_input_running_out_is_bad_input() -> None:
    code, out = invoke(str(P2), "--human", "ask", input="")
    assert code == 2
    assert "<stdin>: input ended while H had to move; give one choice per line" in out
    assert "Traceback" not in out


# -- bad input ---------------------------------------------------------------------------------

@pytest.mark.parametrize(("args", "message"), [
    (["missing.toml"], "missing.toml: cannot read the file"),
    ([str(P2), "--human", "bogus"], "--human: 'bogus' is not a mode; use one of ask, random"),
    ([str(P2), "--human", "script"], "--human script: no script given; add --script FILE"),
    ([str(P2), "--policy", "nowhere.json"], "nowhere.json: no such file"),
])
def test_bad_input_is_one_line_and_exit_2(args: list[str], message: str) -> None:
    code, out = invoke(*args)
    assert code == 2
    assert message in out and "Traceback" not in out


def test_bad_script_lines(tmp_path: Path) -> None:
    script = tmp_path / "s.txt"
    script.write_text("# comment\n\ndance\n", encoding="utf-8")
    code, out = invoke(str(P2), "--script", str(script))
    assert code == 2
    assert f"{script}:3: 'dance' is not a move of H here; give one of: " in out
    script.write_text("move(mt, ot)\n", encoding="utf-8")
    code, out = invoke(str(P2), "--script", str(script))
    assert code == 2 and f"{script}:end: the script ended but H must move" in out
    script.write_text("R inform(empty(box2))\nplace(w, box2)\npass\n", encoding="utf-8")
    code, out = invoke(str(QUAL), "--script", str(script))
    assert code == 2 and f"{script}:3: the run is over but the script goes on" in out


def test_policy_for_another_problem_is_bad_input(tmp_path: Path) -> None:
    pfile = write_policy(tmp_path, P2)
    code, out = invoke(str(QUAL), "--policy", str(pfile))
    assert code == 2
    assert f"{pfile}: the policy was planned after the opening []" in out
    bad = tmp_path / "bad.json"
    bad.write_text("{not json", encoding="utf-8")
    code, out = invoke(str(P2), "--policy", str(bad))
    assert code == 2 and f"{bad}:1:2: not valid JSON" in out


# -- the API over every example --------------------------------------------------------------

@pytest.mark.parametrize("example", every_example_by_branch())
def test_executor_follows_every_branch_of_every_example(example: Example) -> None:
    problem, policy = solved_v2(example)  # every example has a policy
    for branch in policy.branches():
        ex = Executor(problem, policy)
        while ex.in_opening:
            if ex.next_robot_action() is not None:
                ex.robot_action_done()
            else:
                ex.observe_human_action(ex.expected_human_actions()[0])
        for n in branch[1:]:
            if n.agent == policy.agents["robot"]:
                action = ex.next_robot_action()
                assert action is not None and action.label == n.action
                step = ex.robot_action_done(n.action)
            else:
                assert n.action in {a.label for a in ex.expected_human_actions()}
                step = ex.observe_human_action(n.action)
            assert step.node is n.node and len(ex.human_worlds()) == n.worlds
            assert ex.explain(step)
        assert ex.done and ex.goal_reached and ex.next_robot_action() is None
