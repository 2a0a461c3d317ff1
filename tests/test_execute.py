"""`ehatp execute` (the JSON-lines protocol), replanning with Executor.as_problem/replan, and
Policy._repr_html_ (docs/execution.md, docs/notebook.md)."""

from __future__ import annotations

import dataclasses
import io
import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

import ehatp
from ehatp.formats.policy import Policy
from ehatp.run.execute import json_lines, run
from ehatp.run.executor import ExecutionError, Executor, UncoveredHumanAction

from .conftest import EXAMPLES, EXAMPLES_DIR, ROOT, Example, solved

CUBES = EXAMPLES_DIR / "cubes"
QUAL, QUAL_ASK = CUBES / "qualitative.toml", CUBES / "qualitative-ask.toml"


def ehatp_cli(*args: str | Path, stdin: str) -> subprocess.CompletedProcess[str]:
    script = Path(sys.executable).with_name("ehatp")
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "ehatp.cli"]
    return subprocess.run([*cmd, *map(str, args)], input=stdin, capture_output=True,
                          text=True, timeout=120)


def lines(*msgs: Any) -> str:
    return "".join((m if isinstance(m, str) else json.dumps(m)) + "\n" for m in msgs)


def session(ex: Executor, stdin: str, **kw: Any) -> tuple[int, list[dict[str, Any]]]:
    """Run the protocol in-process; every output line must be one JSON object."""
    out = io.StringIO()
    code = run(ex, io.StringIO(stdin), json_lines(out), **kw)
    return code, numbered(out.getvalue())


def numbered(stdout: str) -> list[dict[str, Any]]:
    """The output lines as objects, once each is checked to end with its number ("seq": 1,
    2, ...), which is then dropped."""
    msgs = [json.loads(x) for x in stdout.splitlines()]
    assert [list(m)[-1] for m in msgs] == ["seq"] * len(msgs)
    assert [m.pop("seq") for m in msgs] == list(range(1, len(msgs) + 1))
    return msgs


def kinds(msgs: list[dict[str, Any]]) -> list[str]:
    return [next(iter(m)) for m in msgs]


# --- a live session in a subprocess: the human leaves the policy, the robot replans -----------


def test_scripted_session_replans_and_reaches_the_goal(tmp_path: Path) -> None:
    # planned for a human who asks when blocked; here the human may also wait silently
    pfile = tmp_path / "ask.json"
    solved(QUAL_ASK).policy.write(pfile)
    script = lines({"robot_done": "wait"},      # the policy's first move
                   {"human": "pass"},           # not covered: the human waits silently
                   {"robot_done": True},        # whatever the new policy said
                   {"human": "place(w, box2)"})
    r = ehatp_cli("execute", QUAL, "--policy", pfile, "--replan", "--save-replans", tmp_path,
                  stdin=script)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    msgs = numbered(r.stdout)
    assert kinds(msgs) == ["start", "beliefs", "robot",
                           "step", "beliefs", "waiting",
                           "replanned", "step", "beliefs", "robot",
                           "step", "beliefs", "waiting",
                           "step", "beliefs", "goal"]
    start = msgs[0]["start"]
    assert start["opening"] == ["H move(mt, ot)", "R pick(r)", "H pick(w)", "R place(r, box1)",
                                "H move(ot, mt)"]
    assert msgs[2]["robot"] == {"action": "wait", "kind": "wait", "name": "wait", "args": [],
                                "told": [], "cost": 1}
    assert msgs[5]["waiting"]["expected"] == ["ask(can_put(w, box1))", "ask(can_put(w, box2))"]
    replanned = msgs[6]["replanned"]
    assert replanned["action"] == "pass" and replanned["status"] == "solved"
    assert msgs[9]["robot"]["action"] == "inform(empty(box2))"
    assert msgs[11]["beliefs"] == {"worlds": [{"true": [], "false": [],
                                               "robot_agenda": ["organize"]}],
                                   "uncertain": [], "false": []}
    assert msgs[-1] == {"goal": True, "steps": 9, "cost": 9}
    # the replanned policy, checked by the validator against the execution as a problem
    new = Policy.load(replanned["policy"])
    assert new.after == [*start["opening"], "R wait", "H pass"]
    as_problem = dataclasses.replace(ehatp.load(QUAL), after=tuple(new.after))
    report = ehatp.validate(as_problem, new)
    assert report.ok, report
    assert new.cost == replanned["cost"]


def test_without_replan_an_uncovered_action_is_one_error_line_and_the_run_goes_on() -> None:
    ex = Executor(ehatp.load(QUAL), solved(QUAL_ASK).policy)
    code, msgs = session(ex, lines({"robot_done": True}, {"human": "pass"},
                                   {"human": "ask(can_put(w, box2))"}, {"robot_done": True},
                                   {"human": "place(w, box2)"}))
    assert code == 0
    errors = [m for m in msgs if "error" in m]
    assert errors == [{
        "error": "uncovered", "line": 2, "action": "pass",
        "expected": ["ask(can_put(w, box1))", "ask(can_put(w, box2))"],
        "possible": ["ask(can_put(w, box1))", "ask(can_put(w, box2))", "pass"],
        "message": "H did pass, which policy node 1 does not cover; the policy expects "
                   "ask(can_put(w, box1)) or ask(can_put(w, box2))"}]
    assert kinds(msgs)[-1] == "goal"


def test_protocol_errors_are_one_json_line_each() -> None:
    bad = ["not json", "[1, 2]", '{"human": "pass", "robot_done": true}', '{"dance": 1}',
           '{"human": 3}', '{"robot_done": 1}', '{"human": "pass"}',   # the robot is to move
           '{"robot_done": "pick(w)"}',                                # not the policy's move
           "", "   "]                                                  # blank: ignored
    ex = Executor(ehatp.load(QUAL), solved(QUAL).policy)
    code, msgs = session(ex, lines(*bad, {"robot_done": "inform(empty(box2))"},
                                   {"human": "dance"},                  # not a move of H
                                   {"robot_done": True},                # H is to move
                                   {"human": "place(w, box2)"}))
    assert code == 0
    errors = [m for m in msgs if "error" in m]
    assert [(e["error"], e["line"]) for e in errors] == [
        ("bad-json", 1), ("bad-request", 2), ("bad-request", 3), ("bad-request", 4),
        ("bad-request", 5), ("bad-request", 6), ("wrong-turn", 7), ("wrong-action", 8),
        ("uncovered", 12), ("wrong-turn", 13)]
    assert all(isinstance(e["message"], str) and e["message"] for e in errors)
    assert errors[-2]["action"] == "dance" and "dance" not in errors[-2]["possible"]
    # an error changes nothing: the answer after each one is the next good line's
    assert kinds(msgs)[-1] == "goal"


def test_input_ending_before_the_goal_exits_1() -> None:
    ex = Executor(ehatp.load(QUAL), solved(QUAL).policy)
    code, msgs = session(ex, lines({"robot_done": True}))
    assert code == 1
    assert msgs[-1]["error"] == "end-of-input"


def test_cli_exit_codes() -> None:
    r = ehatp_cli("execute", ROOT / "missing.toml", stdin="")
    assert r.returncode == 2 and r.stdout == ""
    assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("error: ")
    r = ehatp_cli("execute", QUAL, stdin=lines({"robot_done": True}))  # solved now; input ends
    assert r.returncode == 1
    assert json.loads(r.stdout.splitlines()[-1])["error"] == "end-of-input"


# --- Executor.as_problem and replan -------------------------------------------------------------


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_as_problem_of_a_fresh_executor_solves_to_the_same_cost(example: Example) -> None:
    problem, policy = solved(example)
    again = ehatp.solve(Executor(problem, policy).as_problem())
    assert again.policy is not None
    assert again.policy.cost == policy.cost
    assert again.policy.after == policy.after


def test_replan_mid_execution_is_valid_and_continues() -> None:
    problem = ehatp.load(CUBES / "p4.toml")
    ex = Executor(problem, solved(CUBES / "p4.toml").policy)
    for _ in range(3):  # a few steps into the policy
        if ex.next_robot_action() is not None:
            ex.robot_action_done()
        else:
            ex.observe_human_action(ex.expected_human_actions()[-1])
    before = ex.state
    result = ex.replan()  # no human move: plan again from here
    assert result.policy is not None and ex.policy is result.policy
    assert ex.state == before and ex.node is result.policy.root
    assert ehatp.validate(ex.as_problem(), ex.policy).ok
    assert result.policy.after == list(ex.as_problem().after)
    while not ex.done:
        if ex.next_robot_action() is not None:
            ex.robot_action_done()
        else:
            ex.observe_human_action(ex.expected_human_actions()[0])
    assert ex.goal_reached


def test_replan_refuses_what_the_human_model_does_not_allow() -> None:
    ex = Executor(ehatp.load(QUAL), solved(QUAL_ASK).policy)
    ex.replay_opening()
    ex.robot_action_done()
    state, policy, n = ex.state, ex.policy, len(ex.history)
    with pytest.raises(UncoveredHumanAction, match="not a move of H here"):
        ex.replan("dance")
    assert (ex.state, ex.policy, len(ex.history)) == (state, policy, n)
    new = ex.replan("H pass").policy  # allowed by the model, not covered: applied, replanned
    assert new is ex.policy and ex.history[-1].replanned
    assert ex.history[-1].action.label == "pass" and ex.history[-1].node is ex.policy.root
    assert ex.next_robot_action() is not None
    with pytest.raises(ExecutionError, match="it is not H's turn: R is to move"):
        ex.replan("pass")


def forced_wait() -> Executor:
    """The cube problem whose human asks when blocked, after its opening and the robot's wait:
    the robot had nothing to do (a forced wait), so the fairness rule (docs/semantics.md §4)
    lets the policy leave out the human's pass: it covers the human's two questions only."""
    ex = Executor(ehatp.load(QUAL_ASK), solved(QUAL_ASK).policy)
    ex.replay_opening()
    ex.robot_action_done("wait")
    assert ex.state.forced
    return ex


ASKS = ["ask(can_put(w, box1))", "ask(can_put(w, box2))"]


def test_a_pass_after_a_forced_wait_is_legal_but_not_covered_and_not_an_impossible_move() -> None:
    ex = forced_wait()
    assert [m.label for m in ex.possible_human_moves()] == ASKS
    assert [m.label for m in ex.legal_human_moves()] == [*ASKS, "pass"]
    assert ex.node is not None
    with pytest.raises(UncoveredHumanAction) as e:
        ex.observe_human_action("pass")
    assert str(e.value).startswith(f"H did pass, which policy node {ex.node.id} does not cover "
                                   "(a policy need not: after a forced robot wait")
    assert e.value.possible == [*ASKS, "pass"]
    with pytest.raises(UncoveredHumanAction, match="not a move of H here"):
        ex.observe_human_action("dance")  # impossible: an error of its own
    code, msgs = session(forced_wait(), lines({"human": "pass"}, {"human": ASKS[1]},
                                              {"robot_done": True}, {"human": "place(w, box2)"}))
    assert code == 0 and kinds(msgs)[-1] == "goal"
    (error,) = [m for m in msgs if "error" in m]
    assert error["error"] == "uncovered" and error["possible"] == [*ASKS, "pass"]


def test_with_replan_a_pass_after_a_forced_wait_is_replanned_from() -> None:
    code, msgs = session(forced_wait(), lines({"human": "pass"}, {"robot_done": True},
                                              {"human": "place(w, box2)"}), replan=True)
    assert [m for m in msgs if "error" in m] == []
    assert kinds(msgs).count("replanned") == 1 and code == 0 and kinds(msgs)[-1] == "goal"
    assert [m["robot"]["action"] for m in msgs if "robot" in m][-1] == "inform(empty(box2))"


def test_replanning_after_a_robot_move_that_shares_its_label_replays_the_move_taken() -> None:
    from .test_every_policy_runs import fetching

    problem = fetching()  # two robot methods start with fetch; the first is a dead end
    result = ehatp.solve(problem)
    assert result.policy is not None
    ex = Executor(problem, result.policy)
    step = ex.robot_action_done("fetch")  # the policy's, toward shelve
    assert step.action.label == "fetch" and step.played == "R fetch [shelve]"
    before = ex.state
    new = ex.replan().policy
    assert new is not None and new.after == ["R fetch [shelve]"]
    assert ex.state == before and ex.node is not None and ex.node.robot_agenda == ["shelve"]
    assert ehatp.validate(ex.as_problem(), new).ok


def test_replan_within_the_opening_keeps_it() -> None:
    problem = ehatp.load(QUAL)
    ex = Executor(problem, solved(QUAL).policy)
    ex.observe_human_action("move(mt, ot)")
    ex.replan()
    assert ex.in_opening and ex.policy.after == list(problem.after)
    ex.replay_opening()
    assert ex.node is ex.policy.root


# --- the explorer in a notebook -----------------------------------------------------------------


def test_the_notebook_html_of_a_policy_is_the_explorer_in_an_iframe() -> None:
    policy = solved(CUBES / "p2.toml").policy
    html = ehatp.explore(policy)._repr_html_()
    assert html.startswith("<iframe") and html.rstrip().endswith("</iframe>")
    assert 'sandbox="allow-scripts"' in html
    assert "&lt;script" in html  # the page is escaped inside srcdoc, not live in the notebook
    assert "<script" not in html
    assert html == ehatp.explore(policy)._repr_html_()  # deterministic


def test_inside_ipython_a_policy_shows_itself_as_the_explorer(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """`import ehatp` in a Jupyter kernel registers an HTML formatter for Policy by name
    (docs/notebook.md); outside IPython it does nothing."""
    registered: dict[tuple[str, str], Any] = {}

    class Formatter:
        def for_type_by_name(self, module: str, name: str, show: Any) -> None:
            registered[module, name] = show

    shell = SimpleNamespace(display_formatter=SimpleNamespace(
        formatters={"text/html": Formatter()}))
    monkeypatch.setitem(sys.modules, "IPython", SimpleNamespace(get_ipython=lambda: shell))
    ehatp._show_policies_in_notebooks()
    show = registered[ehatp.Policy.__module__, "Policy"]
    policy = solved(CUBES / "p2.toml").policy
    assert show(policy) == ehatp.explore(policy)._repr_html_()
    registered.clear()
    monkeypatch.setitem(sys.modules, "IPython", SimpleNamespace(get_ipython=lambda: None))
    ehatp._show_policies_in_notebooks()
    assert registered == {}
