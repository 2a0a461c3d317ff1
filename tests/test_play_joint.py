"""``ehatp play`` in joint steps (docs/play.md, "Joint steps"): the participant chooses the
human's move, then sees the robot's compliant reply; the robot's signal at each decision, read
from the policy's replies there; the decision timer whose end is a ``pass``; a scripted
participant over the socket (Starlette's TestClient) to the goal, with a replan. The browser
test is in tests/test_play_browser.py."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
from pathlib import Path
from typing import Any

import pytest

import ehatp
from ehatp import Passes
from ehatp.formats.policy import Policy
from ehatp.model.problem import Problem
from ehatp.play.session import MemoryLog, PlaySession, Source, policy_hash, replay

from .conftest import EXAMPLES_DIR, ROOT

STACK4 = EXAMPLES_DIR / "concurrent" / "stack4.toml"
STACK10 = EXAMPLES_DIR / "concurrent" / "stack10.toml"
HAVE_WEB = all(importlib.util.find_spec(m) for m in ("starlette", "uvicorn", "httpx"))
pytestmark = pytest.mark.filterwarnings("ignore:Using `httpx` with `starlette.testclient`")
needs_web = pytest.mark.skipif(not HAVE_WEB, reason="ehatp[play] is not installed "
                               "(pip install 'ehatp[play]' httpx)")


def stack4(diligent_policy: bool = False, path: Path = STACK4) -> tuple[Problem, Policy]:
    """Stack4 (or the stacking problem at ``path``) and its policy; ``diligent_policy``: the
    policy planned for a human who passes only with nothing it could do (``[human] passes =
    "idle"``), so a participant's ``pass`` where it could act is a move the policy does not
    cover."""
    problem = ehatp.load(path)
    planned = problem
    if diligent_policy:
        planned = dataclasses.replace(problem, human=dataclasses.replace(
            problem.human, passes=Passes.IDLE))
    policy = ehatp.solve(planned).policy
    assert policy is not None
    return problem, policy


def session(problem: Problem, policy: Policy, log: MemoryLog,
            timeout: float | None = 5.0, path: Path = STACK4) -> PlaySession:
    src = Source(str(path), "sha256:test", None, policy_hash(policy), "test")
    s = PlaySession(problem, policy, src, session_id="test", log=log, clock=lambda: "T",
                    decision_timeout=timeout)
    s.start()
    s.run_robot()
    return s


def test_the_robot_signals_what_its_replies_at_the_decision_are() -> None:
    """Stack4, by hand (the replies of tests/test_stacking.py). At the root the robot answers
    ``pick(c1)`` with ``wait`` and ``pass`` with ``pick(c1)``: it acts only if the human does
    not, "Act if you will". The participant passes and the robot picks ``c1``; now the human's
    ``pick(c2)`` is answered with ``place(c1, s1)``: "You can act in parallel" (so too while
    the human places ``c2``, the robot picking ``c3``, and picks ``c4``, the robot placing
    ``c3``). At the last decision the human holds ``c4`` and the robot has nothing left:
    ``place(c4, s4)`` is the human's only move (no pass, C5) and the reply ``wait``: "I will
    be passive this step". Five decisions, five steps."""
    problem, policy = stack4()
    s = session(problem, policy, MemoryLog())
    signals = []
    for move in ("pass", "pick(c2)", "place(c2, s2)", "pick(c4)", "place(c4, s4)"):
        view = s.participant_view()
        signals.append(view["signal"]["key"])
        assert s.choose(move) == "played", move
        s.run_robot()
    assert signals == ["act", "parallel", "parallel", "parallel", "passive"]
    assert s.outcome == "goal" and s.ex.cost == 5


def test_a_decision_that_times_out_is_a_pass_logged_and_replayed() -> None:
    """The root's timer ends: the human passes (the robot then picks ``c1``, its reply to a
    pass), the log says so (a ``timeout`` record, then the ``choice`` marked ``timeout``), a
    late timeout for the same decision changes nothing, and the replay writes the same
    records. Where the human may not pass (its last move: the robot has nothing to do, C5)
    there is no timer."""
    problem, policy = stack4()
    log = MemoryLog()
    s = session(problem, policy, log)
    assert s.participant_view()["timer"] == 5.0
    assert s.timeout(0) == "played"
    s.run_robot()
    assert [e.text for e in s.feed] == ["You wait.", "R: pick(c1)"]
    assert s.timeout(0) == "stale"
    assert [r["type"] for r in log.records if r["type"] in ("timeout", "choice")] == [
        "timeout", "choice"]
    assert [r for r in log.records if r["type"] == "choice"][0]["timeout"] is True
    for move in ("pick(c2)", "place(c2, s2)", "pick(c4)"):
        s.choose(move)
        s.run_robot()
    assert s.participant_view()["timer"] is None and s.timed_pass() is None
    s.choose("place(c4, s4)")
    s.run_robot()
    assert s.outcome == "goal"
    again = replay(log.records, problem, policy, s.source)
    assert again.ok, str(again)


def test_turn_taking_sessions_show_and_log_no_signal_and_no_timer() -> None:
    """Signals and timers are joint steps' only: a P2 session's view and log have neither,
    whatever timeout it is given (its records are those of before)."""
    problem = ehatp.load(ROOT / "examples" / "cubes" / "p2.toml")
    policy = ehatp.solve(problem).policy
    assert policy is not None
    log = MemoryLog()
    s = session(problem, policy, log, timeout=3.0)
    view = s.participant_view()
    assert "signal" not in view and "timer" not in view
    assert s.timeout(0) == "stale"
    assert all("signal" not in r and "decision_timeout" not in r for r in log.records)


def test_an_uncovered_pass_replans_and_the_session_reaches_the_goal() -> None:
    """The policy planned for a diligent human covers only ``pick(c1)`` at the root (its
    reply ``wait``: "I will be passive this step"); the participant passes: the robot plans
    again (one replan) and goes on, and the session ends at the goal."""
    problem, policy = stack4(diligent_policy=True)
    s = session(problem, policy, MemoryLog())
    assert s.participant_view()["signal"]["key"] == "passive"
    assert s.choose("pass") == "replanned"
    s.run_robot()
    while not s.over:
        moves = [m["label"] for m in s.moves()]
        s.choose(next((m for m in moves if m != "pass"), moves[0]))
        s.run_robot()
    assert s.outcome == "goal" and s.replans == 1


def _until_decision(ws: Any, step: int) -> dict[str, Any]:
    """Read the views the server pushes until the participant's next decision (or the end)
    after ``step`` moves."""
    while True:
        view: dict[str, Any] = ws.receive_json()["view"]
        if view["status"] in ("goal", "over") or (view["status"] == "your-turn"
                                                   and view["step"] > step):
            return view


@needs_web
def test_a_scripted_participant_plays_stack4_to_the_goal_over_the_socket(
        tmp_path: Path) -> None:
    """The server in-process, the diligent human's policy: the participant's first decision
    times out (a pass the policy does not cover: a replan), then it takes the first move that
    is not a pass at each decision, reading the robot's signal, until the tower stands. The
    session's log records the replan and the goal."""
    play_over_the_socket(STACK4, tmp_path)


def play_over_the_socket(path: Path, tmp_path: Path) -> None:
    """The scripted participant of the test above on the stacking problem at ``path``."""
    from starlette.testclient import TestClient

    from ehatp.play.files import session_log
    from ehatp.play.server import Hub, make_app
    from ehatp.play.session import read_log

    problem, policy = stack4(diligent_policy=True, path=path)
    src = Source(str(path), "sha256:test", None, policy_hash(policy), "test")

    def factory(sid: str) -> PlaySession:
        return PlaySession(problem, policy, src, session_id=sid,
                           log=session_log(tmp_path, sid), decision_timeout=2.0)

    with TestClient(make_app(Hub(factory))) as client:
        sid = client.get("/", follow_redirects=False).headers["location"].split("/")[-1]
        with client.websocket_connect(f"/ws/{sid}") as ws:
            view = ws.receive_json()["view"]
            assert view["status"] == "your-turn" and view["timer"] == 2.0
            assert view["signal"] == {"key": "passive", "text": "I will be passive this step"}
            ws.send_text(json.dumps({"timeout": 0}))
            view = _until_decision(ws, 0)
            signals = []
            while view["status"] == "your-turn":
                signals.append(view["signal"]["key"])
                move = next((m["label"] for m in view["moves"] if m["label"] != "pass"),
                            "pass")  # blocked (holding a cube whose turn has not come)
                ws.send_text(json.dumps({"move": move}))
                view = _until_decision(ws, view["step"])
            assert view["status"] == "goal"
            assert set(signals) <= {"act", "parallel", "passive"} and signals
    [log] = tmp_path.glob("*.jsonl")
    records = read_log(log)
    assert [r["type"] for r in records].count("replan") == 1
    [end] = [r for r in records if r["type"] == "end"]
    assert end["outcome"] == "goal"


def test_a_scripted_participant_builds_the_ten_cube_tower_after_a_replan() -> None:
    """Issue 20's "How we will know": ``examples/concurrent/stack10.toml`` played by a
    scripted participant to the goal, with a replan after an uncovered move (the session
    layer: what ``ehatp play`` runs behind its socket). By hand (docs/domains/stacking.md):
    at the root ``c1`` (shared) is the next cube, so the human may pick it or pass (C5: the
    robot can pick it); the policy planned for a diligent human (``passes = "idle"``) covers
    only ``pick(c1)``, its reply ``wait`` ("I will be passive this step"). The participant
    passes: the robot plans again for the problem's human (one replan; makespan 2n = 20, the
    human who passes whenever it may) and replies ``pick(c1)``, its only action ((pass, wait)
    is no step). Then the participant passes at every third decision where it may, and
    otherwise takes the first other move (a pass when it is the only one: the human holds a
    cube whose turn has not come). The tower stands within 20 steps (no branch is
    longer), no step pairs the human's ``pick(x)`` with the robot's ``pick(x)`` (C3), and the
    log replays."""
    problem, policy = stack4(diligent_policy=True, path=STACK10)
    log = MemoryLog()
    s = session(problem, policy, log, path=STACK10)
    [offer] = [r for r in log.records if r["type"] == "offer"]
    assert (offer["moves"], offer["covered"], offer["signal"]) == (
        ["pick(c1)", "pass"], ["pick(c1)"], "passive")
    assert s.choose("pass") == "replanned"
    s.run_robot()
    [replan] = [r for r in log.records if r["type"] == "replan"]
    assert replan["cost"] == 20
    assert [e.text for e in s.feed][-1] == "R: pick(c1)"
    decisions = 0
    while not s.over:
        moves = [m["label"] for m in s.moves()]
        passing = decisions % 3 == 1 and "pass" in moves
        other = next((m for m in moves if m != "pass"), "pass")  # "pass" alone: blocked
        assert s.choose("pass" if passing else other) == "played"
        s.run_robot()
        decisions += 1
    assert s.outcome == "goal" and s.replans == 1
    steps = [r for r in log.records if r["type"] == "step"]
    assert len(steps) % 2 == 0 and len(steps) // 2 <= 20
    pairs = [(h["move"], r["move"]) for h, r in zip(steps[::2], steps[1::2], strict=True)]
    assert all(h != r or not h.startswith("pick(") for h, r in pairs), pairs
    assert {f"c{i}" for i in range(1, 11)} <= {
        m.partition("(")[2].partition(",")[0] for pair in pairs for m in pair
        if m.startswith("place(")}
    again = replay(log.records, problem, policy, s.source)
    assert again.ok, str(again)


@needs_web
def test_a_scripted_participant_plays_stack10_to_the_goal_over_the_socket(
        tmp_path: Path) -> None:
    """As for stack4 above, over the socket: ``stack10.toml``, the diligent human's policy,
    the first decision timing out (an uncovered pass: a replan), then the first move that is
    not a pass at each decision (a pass when it is the only one) until the ten cubes
    stand."""
    play_over_the_socket(STACK10, tmp_path)
