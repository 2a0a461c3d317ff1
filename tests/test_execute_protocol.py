"""``ehatp execute``'s protocol, the additions of issue 18 (docs/execution.md): a failed robot
action replanned from what was observed, a number on every output line, a malformed label
answered ``bad-request``, and ``--save-replans`` creating its folder.

Inputs are written by hand; the expected lines are derived by hand from the cube domain
(docs/domains/): in P2 (two cubes, opaque boxes, the human starts) the human passes, the robot
picks r, the human passes again, and the policy tells the robot to place r in box1 (policy
node 17). Its physical alternatives there are place(r, box1) and place(r, box2).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

import ehatp
from ehatp.run.execute import label_syntax
from ehatp.run.executor import Executor

from .conftest import EXAMPLES, EXAMPLES_DIR, Example, solved
from .test_execute import QUAL, QUAL_ASK, ehatp_cli, kinds, lines, numbered, session

P2 = EXAMPLES_DIR / "cubes" / "p2.toml"
TO_PLACE = ({"human": "pass"}, {"robot_done": "pick(r)"}, {"human": "pass"})  # to node 17


def p2() -> Executor:
    problem, policy = solved(P2)
    return Executor(problem, policy)


def robot(action: str, name: str, *args: str) -> dict[str, Any]:
    return {"robot": {"action": action, "kind": "wait" if name == "wait" else "action",
                      "name": name, "args": list(args), "told": [], "cost": 1}}


def step(index: int, agent: str, action: str, node: int) -> dict[str, Any]:
    # every move of the cube domain costs 1, so the total is the index
    return {"step": {"index": index, "agent": agent, "action": action, "cost": 1,
                     "node": node, "total": index}}


def answer(msgs: list[dict[str, Any]], line: int) -> list[dict[str, Any]]:
    """The lines answering input line ``line`` (the session answers each in turn; errors
    name their line): those after the answer to the previous line."""
    ends = [i for i, m in enumerate(msgs) if {"robot", "waiting", "goal", "error"} & set(m)]
    return msgs[ends[line - 1] + 1:ends[line] + 1]


def without(msg: dict[str, Any], *keys: str) -> dict[str, Any]:
    return {k: v for k, v in msg.items() if k not in keys}


STATS = ("cost", "nodes", "distinct", "generated", "time_ms")


# --- a robot action that failed ----------------------------------------------------------------


@pytest.mark.parametrize("failed", [{"robot_failed": "pick(r)"}, {"robot_failed": True},
                                    {"robot_failed": "R pick(r)"}])
def test_a_robot_action_that_did_not_happen_is_replanned_from_the_same_state(
        failed: dict[str, Any]) -> None:
    code, msgs = session(p2(), lines({"human": "pass"}, failed, {"robot_done": "pick(r)"}))
    assert code == 1  # the input ends before the goal
    replanned, again = answer(msgs, 2)
    # nothing changed, so the new policy starts where the old one was, at policy node 10 after
    # the human's pass (cost 1): P2's worst case, 13, goes through that pass (the other branch
    # costs 7), so from here the optimal worst case is 13 - 1 = 12, and the robot is told to
    # pick r again
    assert without(replanned["replanned"], *STATS[1:]) == {
        "action": "pick(r)", "agent": "R", "failed": True, "outcome": None, "after": 1,
        "status": "solved", "cost": 12}
    assert again == robot("pick(r)", "pick", "r")
    assert answer(msgs, 3)[0] == step(2, "R", "pick(r)", 1)  # node 1 of the new policy


def test_a_robot_action_with_another_outcome_is_replanned_after_that_outcome() -> None:
    code, msgs = session(p2(), lines(
        *TO_PLACE,
        {"robot_failed": {"action": "place(r, box1)", "observed": ["in(r, box2)",
                                                                   "not empty(box2)"]}},
        # r is in box2, so w goes to box1: the human fetches it from the other table while
        # the robot, with nothing left to do, waits
        {"human": "move(mt, ot)"}, {"robot_done": "wait"}, {"human": "pick(w)"},
        {"robot_done": "wait"}, {"human": "move(ot, mt)"}, {"robot_done": "wait"},
        {"human": "place(w, box1)"}))
    assert code == 0
    assert answer(msgs, 3)[-1] == robot("place(r, box1)", "place", "r", "box1")
    replanned, played, beliefs, waiting = answer(msgs, 4)
    assert without(replanned["replanned"], *STATS) == {
        "action": "place(r, box1)", "agent": "R", "failed": True, "outcome": "place(r, box2)",
        "observed": ["in(r, box2)", "not empty(box2)"], "after": 4, "status": "solved"}
    assert replanned["replanned"]["cost"] >= 7  # at least the seven moves played below
    assert played == step(4, "R", "place(r, box2)", 0)  # the new policy's root
    # the human saw it (both at the main table): one world, no false belief
    assert len(beliefs["beliefs"]["worlds"]) == 1 and beliefs["beliefs"]["false"] == []
    assert waiting == {"waiting": {"human": "H", "expected": ["move(mt, ot)", "pass"]}}
    assert [m["step"]["action"] for m in msgs[msgs.index(played) + 1:] if "step" in m] == [
        "move(mt, ot)", "wait", "pick(w)", "wait", "move(ot, mt)", "wait", "place(w, box1)"]
    assert msgs[-1] == {"goal": True, "steps": 11, "cost": 11}


def test_observed_facts_name_the_outcome_or_are_one_error_line() -> None:
    facts = [["handempty(R)"],     # both placements leave the hand empty
             ["in(w, box1)"],      # no action of the robot puts w anywhere
             ["flying(r)"],        # no such atom
             ["not handempty(R)"]]  # r still in the hand: the action did not happen
    code, msgs = session(p2(), lines(*TO_PLACE, *({"robot_failed": {
        "action": "place(r, box1)", "observed": f}} for f in facts)))
    assert code == 1
    (several,) = answer(msgs, 4)
    assert several == {
        "error": "unexplained", "line": 4, "action": "place(r, box1)",
        "observed": ["handempty(R)"], "outcomes": ["place(r, box1)", "place(r, box2)"],
        "message": "the observed facts fit more than one outcome of R's actions here "
                   "(place(r, box1), place(r, box2)); observe more facts"}
    (none,) = answer(msgs, 5)
    assert none == {
        "error": "unexplained", "line": 5, "action": "place(r, box1)",
        "observed": ["in(w, box1)"], "outcomes": [],
        "message": "the observed facts fit no outcome of R's actions here; replanning needs "
                   "a state the problem's model can reach"}
    (unknown,) = answer(msgs, 6)
    assert unknown == {
        "error": "bad-request", "line": 6,
        "message": "'flying(r)' is not a fact that can change in this problem; observed facts "
                   "are atoms as the beliefs lines write them, or 'not ATOM'"}
    replanned, again = answer(msgs, 7)
    assert replanned["replanned"]["outcome"] is None and replanned["replanned"]["after"] == 3
    assert again == robot("place(r, box1)", "place", "r", "box1")


@pytest.mark.parametrize(("value", "outcome"), [
    ("balls(b1) = 1", "drop(b1)"),  # the drop happened after all
    ("balls(b1) = 0", None),        # it did not
])
def test_observed_facts_may_give_a_counters_value(value: str, outcome: str | None) -> None:
    from .test_counters import balls_problem

    # the robot fills box b1 with balls while the human is out: after "leave", it is told to
    # drop one; a counter is written by its value, as the beliefs lines write it
    problem = balls_problem()
    result = ehatp.solve(problem)
    assert result.policy is not None
    code, msgs = session(Executor(problem, result.policy), lines(
        {"human": "leave"},
        {"robot_failed": {"action": "drop(b1)", "observed": [value]}},
        {"robot_failed": {"action": "drop(b1)", "observed": ["balls(b1) = 3"]}}))
    assert answer(msgs, 1)[-1] == robot("drop(b1)", "drop", "b1")
    replanned = answer(msgs, 2)[0]["replanned"]
    assert (replanned["outcome"], replanned["observed"]) == (outcome, [value])
    if outcome is None:
        assert answer(msgs, 2)[1:] == [robot("drop(b1)", "drop", "b1")]
        (error,) = answer(msgs, 3)  # three balls: no outcome of one drop
        assert (error["error"], error["outcomes"]) == ("unexplained", [])
    else:
        assert answer(msgs, 2)[1] == step(2, "R", "drop(b1)", 0)
        assert answer(msgs, 2)[-1] == {"waiting": {"human": "H", "expected": ["scoop"]}}


@pytest.mark.parametrize(("sent", "error", "message"), [
    ({"robot_failed": "pick(w)"}, "wrong-action",
     "R reports 'pick(w)' but the policy says place(r, box1)"),
    ({"robot_failed": 3}, "bad-request",
     'robot_failed takes the action\'s label or true, or {"action": ..., "observed": [...]}'),
    ({"robot_failed": {"action": "place(r, box1)", "observed": []}}, "bad-request",
     'robot_failed with facts is {"action": "ACTION", "observed": ["FACT", "not FACT", ...]}: '
     "at least one observed fact, as strings"),
    ({"robot_failed": {"action": "place(r, box1)", "seen": ["in(r, box2)"]}}, "bad-request",
     'robot_failed with facts is {"action": "ACTION", "observed": ["FACT", "not FACT", ...]}: '
     "at least one observed fact, as strings"),
])
def test_a_bad_robot_failed_line_is_one_error_and_changes_nothing(
        sent: dict[str, Any], error: str, message: str) -> None:
    code, msgs = session(p2(), lines(*TO_PLACE, sent, {"robot_done": "place(r, box1)"}))
    assert answer(msgs, 4) == [{"error": error, "message": message, "line": 4}]
    assert answer(msgs, 5)[0] == step(4, "R", "place(r, box1)", 17)  # the old policy goes on


def test_robot_failed_while_the_human_is_to_move_is_the_wrong_turn() -> None:
    code, msgs = session(p2(), lines({"robot_failed": "pick(r)"}))
    assert answer(msgs, 1) == [{"error": "wrong-turn", "line": 1,
                                "message": "it is not R's turn: H is to move"}]


def test_a_replanned_human_move_says_who_moved_and_that_nothing_failed() -> None:
    # the policy of a human who asks when blocked, run with one who may wait silently
    code, msgs = session(Executor(solved(QUAL).problem, solved(QUAL_ASK).policy),
                         lines({"robot_done": True}, {"human": "pass"}), replan=True)
    (replanned,) = [m["replanned"] for m in msgs if "replanned" in m]
    assert (replanned["action"], replanned["agent"], replanned["failed"]) == ("pass", "H", False)


# --- malformed labels ------------------------------------------------------------------------


def test_a_label_with_a_syntax_error_is_a_bad_request_not_uncovered() -> None:
    code, msgs = session(p2(), lines({"human": "pick(w"}, {"human": "dance"},
                                     {"human": "pass"}, {"robot_done": "pick(r"}))
    assert answer(msgs, 1) == [{
        "error": "bad-request", "line": 1, "action": "pick(w",
        "message": "'pick(w' is not a move label: a ( is not closed; write it as the policy "
                   "prints it, e.g. place(w, box2)"}]
    (dance,) = answer(msgs, 2)  # well formed, no move of the human: still uncovered
    assert (dance["error"], dance["action"]) == ("uncovered", "dance")
    assert answer(msgs, 3)[0] == step(1, "H", "pass", 10)  # nothing changed before
    assert answer(msgs, 4) == [{
        "error": "bad-request", "line": 4, "action": "pick(r",
        "message": "'pick(r' is not a move label: a ( is not closed; write it as the policy "
                   "prints it, e.g. place(w, box2)"}]


@pytest.mark.parametrize(("label", "why"), [
    ("pick(w", "a ( is not closed"),
    ("ask(can_put(w, box2)", "a ( is not closed"),
    ("pick(w))", "nothing more expected, found ')'"),
    ("pick(,w)", "a name expected, found ','"),
    ("pick(w,)", "a name expected, found ')'"),
    ("(w)", "a name expected, found '('"),
    ("pick(w) x", "nothing more expected, found 'x'"),
    ("inform(empty(box2)) +", "it ends early (a name expected)"),
    ("fetch [shelve", "it ends early (] expected)"),
    ("", "it is empty"),
    ("   ", "it is empty"),
    ("pick(w ", "a ( is not closed"),
])
def test_label_syntax_says_what_is_wrong(label: str, why: str) -> None:
    assert label_syntax(label) == why


@pytest.mark.parametrize("label", [
    "pass", "pick(w)", " pick(w) ", "H pick(w)", "place(w,box2)", "ask(can_put(w, box2))",
    "inform(not ball_in(basket), ball_in(box))", "inform(loc(r) = mt)",
    "inform(empty(box2)) + place(r, box1)", "fetch [shelve]", "fetch []",
])
def test_label_syntax_accepts_every_form_a_policy_prints(label: str) -> None:
    assert label_syntax(label) is None


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_label_of_every_example_policy_is_well_formed(example: Example) -> None:
    problem, policy = solved(example)
    labels = [*problem.after, *(m.action for n in policy.nodes for m in n.moves)]
    assert [(label, label_syntax(label)) for label in labels if label_syntax(label)] == []


# --- numbered lines, --save-replans ------------------------------------------------------------


def test_every_output_line_ends_with_its_number_errors_included() -> None:
    import io
    import json

    from ehatp.run.execute import json_lines, run

    out = io.StringIO()
    run(p2(), io.StringIO(lines("oops", {"human": "pass"})), json_lines(out))
    msgs = [json.loads(x) for x in out.getvalue().splitlines()]
    assert [(next(iter(m)), m["seq"]) for m in msgs] == [
        ("start", 1), ("beliefs", 2), ("waiting", 3), ("error", 4),   # bad-json
        ("step", 5), ("beliefs", 6), ("robot", 7), ("error", 8)]      # end-of-input
    assert [list(m)[-1] for m in msgs] == ["seq"] * 8


def test_save_replans_creates_the_folder_with_its_parents(tmp_path: Path) -> None:
    folder = tmp_path / "runs" / "today"
    ask = tmp_path / "ask.json"
    solved(QUAL_ASK).policy.write(ask)
    r = ehatp_cli("execute", QUAL, "--policy", ask, "--replan", "--save-replans", folder,
                  stdin=lines({"robot_done": True}, {"human": "pass"}))
    assert r.returncode == 1, r.stderr  # the input ends before the goal
    (replanned,) = [m["replanned"] for m in numbered(r.stdout) if "replanned" in m]
    assert replanned["policy"] == str(folder / "replan-1.json")
    assert (folder / "replan-1.json").is_file()


def test_save_replans_under_a_file_is_one_error_line(tmp_path: Path) -> None:
    (tmp_path / "f").write_text("", encoding="utf-8")
    r = ehatp_cli("execute", QUAL, "--save-replans", tmp_path / "f" / "x", stdin="")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == (f"error: {tmp_path / 'f' / 'x'}: cannot create the folder (Not a "
                        "directory); give --save-replans a folder ehatp may create and "
                        "write\n")


def test_the_no_policy_line_before_the_protocol_is_numbered_too(tmp_path: Path) -> None:
    tiny = tmp_path / "tiny.toml"
    tiny.write_text(QUAL.read_text(encoding="utf-8") + "\n[limits]\nmax_states = 2\n",
                    encoding="utf-8")
    r = ehatp_cli("execute", tiny, stdin="")
    assert r.returncode == 1
    assert kinds(numbered(r.stdout)) == ["error"]


# --- a line too long ---------------------------------------------------------------------------


def test_a_line_longer_than_the_cap_is_a_bad_request_never_echoed_and_the_next_line_is_read(
        ) -> None:
    import io

    from ehatp.run.execute import MAX_LINE, run

    out: list[dict[str, Any]] = []
    huge = '{"human": "' + "a" * (3 * MAX_LINE) + '"}\n'
    code = run(p2(), io.StringIO(huge + '{"human": "pass"}\n'), out.append)
    errors = [m for m in out if "error" in m]
    # by hand: start, beliefs and waiting (seq 1-3), then line 1 is refused whole (seq 4);
    # line 2 (pass, a move the policy covers at the root) is played; the input then ends
    assert errors[0] == {"error": "bad-request", "message": f"the line is longer than "
                         f"{MAX_LINE:,} characters; send one JSON object per line, as the "
                         "protocol says", "line": 1, "seq": 4}
    assert any(m.get("step", {}).get("action") == "pass" for m in out)
    assert errors[-1]["error"] == "end-of-input" and code == 1
    assert all(len(str(m)) < 1000 for m in out)


def test_each_replan_gets_the_limits_execute_was_given(monkeypatch: pytest.MonkeyPatch) -> None:
    import io

    from ehatp.errors import ExecutionError
    from ehatp.run.execute import run

    ex = p2()
    asked: list[dict[str, Any]] = []

    def replan(*args: Any, **options: Any) -> Any:
        asked.append(options)
        raise ExecutionError("no policy: time limit of 0.5 s reached")

    monkeypatch.setattr(ex, "replan", replan)
    out: list[dict[str, Any]] = []
    lines = "".join(json.dumps(m) + "\n" for m in TO_PLACE)
    code = run(ex, io.StringIO(lines + '{"robot_failed": "place(r, box1)"}\n'), out.append,
               timeout=0.5, max_memory=1 << 30)
    assert asked == [{"timeout": 0.5, "max_memory": 1 << 30}]
    assert out[-1]["error"] == "no-policy" and "time limit of 0.5 s" in out[-1]["message"]
    assert code == 1
