"""``ehatp play``: the experimenter switches the robot's preference profile mid-session
(docs/play.md, "Switching the robot's profile"; docs/concurrent.md C11, "Relabelling"): in the
session (:meth:`PlaySession.switch_profile`), over the experimenter's socket and its
endpoint, in the log and its replay. The robot's replies after a switch were derived by hand
from docs/domains/stacking.md before the planner was run (each test's docstring)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from ehatp.cli.app import app
from ehatp.model.options import StepFirst
from ehatp.play.files import Setup, load_setup, session_log
from ehatp.play.session import MemoryLog, PlaySession, policy_hash, read_log, replay
from ehatp.run.walk import walk_from

from .conftest import ROOT
from .play_check import PROBLEMS, leaks, view_facts
from .test_play import needs_web

PREFS = ROOT / "examples" / "concurrent" / "stack-prefs.toml"
# Starlette 1.x warns that its TestClient will leave httpx; it works with it all the same
pytestmark = pytest.mark.filterwarnings("ignore:Using `httpx` with `starlette.testclient`")
NAMES = ("builder", "hurry", "shared_taken", "makespan", "profile")  # never the participant's


@pytest.fixture(scope="module")
def setup() -> Setup:
    """stack-prefs as ``ehatp play`` loads it: solved once, its graph kept (profile
    ``builder``, optimistic)."""
    s = load_setup(PREFS, None, "none")
    assert s.graph is not None and s.problem.objective.profile == "builder"
    return s


def start(setup: Setup, log: Any = None, first: StepFirst | None = None) -> PlaySession:
    problem, policy, graph = setup.problem, setup.policy, setup.graph
    if first is not None:  # the same table, the robot deciding first in every step
        from ehatp import solve

        problem = dataclasses.replace(problem, steps=dataclasses.replace(problem.steps,
                                                                         first=first))
        r = solve(problem, keep_graph=True)
        assert r.policy is not None and r.graph is not None
        policy, graph = r.policy, r.graph
    s = PlaySession(problem, policy, setup.source, session_id="t", log=log or MemoryLog(),
                    clock=lambda: "T", graph=graph)
    s.start()
    s.run_robot()
    return s


def move(s: PlaySession, label: str) -> list[str]:
    """Play the participant's ``label`` and the robot's moves after it; return the moves
    played since (``H x``, ``R y``)."""
    n = len(s.ex.history)
    assert s.choose(label) in ("played", "replanned"), (label, s.moves())
    s.run_robot()
    return [h.played for h in s.ex.history[n:]]


def to_goal(s: PlaySession) -> None:
    """Play the policy's first covered move at every decision until the session ends."""
    while not s.over:
        move(s, s.ex.expected_human_actions()[0].label)


def hidden(view: dict[str, Any]) -> bool:
    """Whether the participant's view names no profile nor metric (only the robot's moves and
    signals may show a switch)."""
    text = json.dumps(view)
    return not any(n in text for n in NAMES)


def test_after_the_switch_to_hurry_the_robot_takes_the_shared_cube_at_once(
        setup: Setup, tmp_path: Path) -> None:
    """By hand, from docs/domains/stacking.md (c1 in the human's zone, c2 and c3 shared, c4
    the robot's; the tower c1..c4; the human decides first, C4).

    Step 1: the only cube wanted is c1, which only the human reaches; the robot has nothing
    to do, so the human may not pass (C5): ``pick(c1)``, and the robot's only reply is
    ``wait``, under either profile. The participant's signal is ``passive``.

    Step 2 starts with c1 in the human's hand: the robot may pick the cube above it, c2
    (shared). ``builder`` (shared_taken first) replies ``wait`` to ``place(c1, s1)`` and
    ``pick(c2)`` only to a pass (a (pass, wait) is no step): the signal is ``act``.
    ``hurry`` (makespan first) replies ``pick(c2)`` to ``place(c1, s1)`` (the two work side
    by side): the signal is ``parallel``. This is the only place the two profiles part
    (docs/domains/stacking.md, "Where the profiles part").

    So switched to ``hurry`` at step 2's start (moves played: 2), the robot's next reply is
    ``pick(c2)`` where ``builder``'s would have been ``wait``; ``hurry``'s root vector there
    (makespan, shared_taken) is (4, 1): step 2 (place c1, pick c2), step 3 (the human picks c3,
    the robot places c2), step 4 (the human places c3, the robot picks c4), step 5 (pass,
    place c4); one shared cube taken. The session reaches the goal, the relabelled policy is
    walked on every branch from the switch, the log replays, and the participant is never
    shown a profile's name."""
    log = session_log(tmp_path, "t")
    s = start(setup, log)
    assert s.participant_view()["signal"]["key"] == "passive"
    assert move(s, "pick(c1)") == ["H pick(c1)", "R wait"]
    assert s.participant_view()["signal"]["key"] == "act"
    assert s.experimenter_view()["profiles"] == {
        "current": "builder", "names": ["builder", "hurry"], "queued": None, "switches": 0,
        "can_switch": True}
    assert s.switch_profile("hurry") == "switched"
    rec = s.log.records[-1] if isinstance(s.log, MemoryLog) else read_log(log.path)[-1]
    assert (rec["type"], rec["profile"], rec["step"], rec["metrics"], rec["value"]) == (
        "profile", "hurry", 2, ["makespan", "shared_taken"], [4, 1])
    assert rec["policy_hash"].startswith("sha256:")
    assert s.profile() == "hurry" and s.experimenter_view()["profiles"]["switches"] == 1
    assert s.participant_view()["signal"]["key"] == "parallel"
    walked = walk_from(s.ex.copy())
    assert walked.ok, str(walked)
    assert move(s, "place(c1, s1)") == ["H place(c1, s1)", "R pick(c2)"]
    to_goal(s)
    assert s.outcome == "goal"
    assert [h.played for h in s.ex.history][4:] == [
        "H pick(c3)", "R place(c2, s2)", "H place(c3, s3)", "R pick(c4)", "H pass",
        "R place(c4, s4)"]
    assert hidden(s.participant_view())
    assert not leaks(s.ex, view_facts(v := s.participant_view()), v["feed"])
    log.close()
    records = read_log(log.path)
    report = replay(records, setup.problem, setup.policy, setup.source, None, setup.graph)
    assert report.ok, str(report)
    assert report.session.profile() == "hurry"
    assert report.session.ex.state == s.ex.state
    # a log whose switch names the other profile does not replay
    edited = [{**r, "profile": "builder"} if r["type"] == "switch" else r for r in records]
    assert not replay(edited, setup.problem, setup.policy, setup.source, None,
                      setup.graph).ok
    # nor does a log replayed without the kept graph: the switch is refused there
    assert not replay(records, setup.problem, setup.policy, setup.source).ok
    # and `ehatp play --replay` searches the graph again and replays it
    r = CliRunner().invoke(app, ["play", "--replay", str(log.path)])
    assert r.exit_code == 0, r.output
    assert "the robot switched to profile hurry at step 2: ['makespan', 'shared_taken'] " \
           "[4, 1]" in r.output
    assert r.output.rstrip().endswith("goal after 10 steps, cost 5")


def test_without_the_switch_the_builder_leaves_the_shared_cube_to_the_human(
        setup: Setup) -> None:
    """The same moves, no switch (derived by hand above): ``builder`` replies ``wait`` to
    ``place(c1, s1)`` -- the switch, not the moves, made the robot pick c2."""
    s = start(setup)
    move(s, "pick(c1)")
    assert move(s, "place(c1, s1)") == ["H place(c1, s1)", "R wait"]
    to_goal(s)
    assert s.outcome == "goal" and s.profile() == "builder" and s.switches == 0


def test_a_switch_refused_is_one_record_with_the_reason_and_changes_nothing(
        setup: Setup) -> None:
    """Unknown profile, no graph kept, a problem without profiles, a finished session: each
    request is logged, refused with one reason, and the robot's policy is unchanged."""
    s = start(setup)
    before = s.ex.policy
    assert s.switch_profile("lazy") == "refused"
    assert s.log.records[-1]["reason"] == "no profile 'lazy': the problem names builder, hurry"
    assert s.ex.policy is before and s.profile() == "builder"
    bare = PlaySession(setup.problem, setup.policy, setup.source, session_id="b",
                       log=MemoryLog())
    bare.start()
    assert bare.switch_profile("hurry") == "refused" and bare.profile() == "builder"
    assert bare.log.records[-1]["reason"].startswith(  # type: ignore[attr-defined]
        "no explored graph is kept")
    cubes = load_setup(ROOT / PROBLEMS["p2"], None)
    assert cubes.graph is None
    c = PlaySession(cubes.problem, cubes.policy, cubes.source, session_id="c", log=MemoryLog())
    c.start()
    assert c.switch_profile("hurry") == "refused"
    assert c.log.records[-1]["reason"].startswith(  # type: ignore[attr-defined]
        "cannot switch to profile 'hurry': the problem's [objective] kind is")
    assert c.experimenter_view()["profiles"] is None
    to_goal(s)
    assert s.switch_profile("hurry") == "refused"
    assert s.log.records[-1]["reason"] == "the session is over (goal)"  # type: ignore[attr-defined]
    assert [r["type"] for r in s.log.records[-2:]] == [  # type: ignore[attr-defined]
        "switch", "switch-refused"]


def test_no_keep_graph_searches_nothing_with_a_policy_and_switches_nothing(
        setup: Setup, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``ehatp play --no-keep-graph --policy P``: the setup reads the policy and searches
    nothing (the planner, patched to fail, is never called); its sessions refuse a switch,
    saying no graph is kept. Without the flag the same setup searches once, for the graph."""
    import ehatp.search.planner as planner

    pol = tmp_path / "p.json"
    setup.policy.write(pol)
    calls: list[bool] = []

    def counting(*args: Any, **kw: Any) -> Any:
        calls.append(kw.get("keep_graph", False))
        raise AssertionError("searched")

    monkeypatch.setattr(planner, "solve", counting)
    bare = load_setup(PREFS, pol, "none", keep_graph=False)
    assert calls == [] and bare.graph is None and bare.policy == setup.policy
    s = PlaySession(bare.problem, bare.policy, bare.source, session_id="n", log=MemoryLog(),
                    graph=bare.graph)
    s.start()
    assert s.switch_profile("hurry") == "refused"
    assert s.log.records[-1]["reason"].startswith(  # type: ignore[attr-defined]
        "no explored graph is kept")
    with pytest.raises(AssertionError, match="searched"):
        load_setup(PREFS, pol, "none")
    assert calls == [True]


def test_a_switch_asked_mid_step_is_made_when_the_step_ends(setup: Setup) -> None:
    """The robot deciding first (the same table): at the participant's decision the robot's
    move of this step is made and the human's reply is due (mid-step, C1), so the switch is
    queued and made once the participant's move ends the step, before the robot's next move
    -- which is the new profile's: the policy then followed is the one the executor relabels
    at that state (checked on a copy switched there by hand), and it walks on every branch."""
    s = start(setup, first=StepFirst.ROBOT)
    assert s.human_to_move and s.ex.state.pending
    assert s.switch_profile("hurry") == "queued"
    assert s.experimenter_view()["profiles"]["queued"] == "hurry"
    label = s.ex.expected_human_actions()[0].label
    by_hand = s.ex.copy()
    by_hand.observe_human_action(label)
    assert not by_hand.state.pending and s.graph is not None
    hurry = by_hand.switch_profile(s.graph, "hurry")
    walked = walk_from(by_hand.copy())
    assert walked.ok, str(walked)
    assert s.choose(label) == "played"
    types = [r["type"] for r in s.log.records]  # type: ignore[attr-defined]
    assert types[types.index("switch-queued"):].count("profile") == 1
    rec = next(r for r in s.log.records if r["type"] == "profile")  # type: ignore[attr-defined]
    assert rec["step"] == len(by_hand.history) and s.profile() == "hurry"
    assert rec["policy_hash"] == policy_hash(hurry)
    reply = by_hand.next_robot_action()
    assert reply is not None
    n = len(s.ex.history)
    s.run_robot()
    assert s.ex.history[n].played == "R " + reply.label
    to_goal(s)
    assert s.outcome == "goal"
    report = replay(s.log.records, s.problem, s.policy, s.source,  # type: ignore[attr-defined]
                    None, s.graph)
    assert report.ok, str(report)


@needs_web
def test_the_experimenter_switches_over_the_socket_and_the_endpoint_with_the_key(
        setup: Setup, tmp_path: Path) -> None:
    """Over the server: the experimenter's socket switches (``{"profile": NAME}``), the
    endpoint refuses a wrong key and an unknown profile with one message each, and the
    participant's views never name a profile."""
    from starlette.testclient import TestClient

    from ehatp.play.server import Hub, make_app

    def factory(sid: str) -> PlaySession:
        return PlaySession(setup.problem, setup.policy, setup.source, session_id=sid,
                           log=session_log(tmp_path, sid), graph=setup.graph)

    hub = Hub(factory, key="k3y")
    with TestClient(make_app(hub)) as client:
        sid = client.get("/", follow_redirects=False).headers["location"].split("/")[-1]
        url = f"/api/s/{sid}/profile"
        bad = client.post(url + "?key=wrong", content=json.dumps({"profile": "hurry"}))
        assert bad.status_code == 403 and bad.json()["reason"].startswith(
            "forbidden: the experimenter's key is missing or wrong")
        unknown = client.post(url + "?key=k3y", content=json.dumps({"profile": "lazy"}))
        assert unknown.status_code == 409 and unknown.json() == {
            "result": "refused", "profile": "builder",
            "reason": "no profile 'lazy': the problem names builder, hurry"}
        with client.websocket_connect(f"/ws/{sid}") as ws:
            views = [ws.receive_json()["view"]]
            ws.send_text(json.dumps({"move": "pick(c1)"}))
            while views[-1]["step"] < 2 or views[-1]["status"] != "your-turn":
                views.append(ws.receive_json()["view"])
            assert views[-1]["signal"]["key"] == "act"
            with client.websocket_connect(f"/ws/{sid}/experimenter?key=k3y") as ex:
                assert ex.receive_json()["view"]["profiles"]["current"] == "builder"
                ex.send_text(json.dumps({"profile": "hurry"}))
                while (msg := ex.receive_json())["type"] != "switch":
                    pass
                assert msg == {"type": "switch", "result": "switched", "profile": "hurry"}
            views.append(ws.receive_json()["view"])
            assert views[-1]["signal"]["key"] == "parallel"
            ws.send_text(json.dumps({"move": "place(c1, s1)"}))
            while views[-1]["step"] < 4:
                views.append(ws.receive_json()["view"])
            assert [f["text"] for f in views[-1]["feed"]][-2:] == ["You: place(c1, s1)",
                                                                    "R: pick(c2)"]
            assert all(hidden(v) for v in views)
    log = next(tmp_path.glob("*.jsonl"))
    records = read_log(log)
    assert [r["profile"] for r in records if r["type"] == "switch"] == ["lazy", "hurry"]
    report = replay(records, setup.problem, setup.policy, setup.source, None, setup.graph)
    assert report.ok, str(report)


def test_a_replan_keeps_its_own_graph_and_the_switch_after_it_relabels_that_one(
        setup: Setup) -> None:
    """stack-prefs played against the policy planned for a human who passes only when it has
    nothing to do (``[human] passes = "idle"``, tests/test_play_joint.py): by hand, at step 2
    (the human holds c1, the robot could pick c2) a ``pass`` is legal (C5) but not covered, so
    the robot replans, with the replan's graph kept (C11); its reply to the pass is ``pick(c2)``,
    its only action ((pass, wait) is no step). Then the human must place c1 (the robot, holding
    c2 whose turn has not come, has nothing to do: no pass) and the robot waits. The switch to
    ``hurry`` there relabels the replan's graph; the session reaches the goal and the log
    (a replan and a switch) replays."""
    from .test_play_joint import stack4

    problem, policy = stack4(diligent_policy=True, path=PREFS)
    s = PlaySession(problem, policy, setup.source, session_id="r", log=MemoryLog(),
                    clock=lambda: "T", graph=setup.graph)
    s.start()
    s.run_robot()
    assert move(s, "pick(c1)") == ["H pick(c1)", "R wait"]
    assert move(s, "pass") == ["H pass", "R pick(c2)"]
    assert s.replans == 1 and s.graph is not None and s.graph is not setup.graph
    assert move(s, "place(c1, s1)") == ["H place(c1, s1)", "R wait"]
    assert s.switch_profile("hurry") == "switched" and s.profile() == "hurry"
    walked = walk_from(s.ex.copy())
    assert walked.ok, str(walked)
    to_goal(s)
    assert s.outcome == "goal"
    records = s.log.records  # type: ignore[attr-defined]
    assert [r["type"] for r in records if r["type"] in ("replan", "profile")] == [
        "replan", "profile"]
    assert replay(records, problem, policy, setup.source, None, setup.graph).ok
