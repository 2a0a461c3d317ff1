"""``ehatp play`` without a browser: sessions (what the participant is shown, its moves, live
replanning, the log and its replay), the server in-process (Starlette's TestClient), ten
sessions at once on a real server. The browser tests are in
tests/test_play_browser.py."""

from __future__ import annotations

import importlib.util
import json
import re
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from ehatp.play.session import (
    FileLog,
    MemoryLog,
    PlaySession,
    Source,
    comparable,
    perspective,
    policy_hash,
    read_log,
    replay,
)
from ehatp.play.views import check_scene, cooking_view, cubes_view, view_for

from .conftest import EXAMPLES, ROOT, Example, solved
from .play_check import PROBLEMS, branches, leaks, serving, view_facts

HAVE_WEB = all(importlib.util.find_spec(m) for m in ("starlette", "uvicorn", "httpx"))
# Starlette 1.x warns that its TestClient will leave httpx; it works with it all the same
pytestmark = pytest.mark.filterwarnings("ignore:Using `httpx` with `starlette.testclient`")
needs_web = pytest.mark.skipif(not HAVE_WEB, reason="ehatp[play] is not installed "
                               "(pip install 'ehatp[play]' httpx)")
STATIC = ROOT / "src" / "ehatp" / "play" / "static"


def session(name: str, log: Any = None, policy_of: str | None = None) -> PlaySession:
    s = solved(ROOT / PROBLEMS.get(name, name))
    policy = s.policy if policy_of is None else solved(ROOT / policy_of).policy
    src = Source(str(ROOT / PROBLEMS.get(name, name)), "sha256:test", None,
                 policy_hash(policy), "test")
    out = PlaySession(s.problem, policy, src, session_id="test", log=log or MemoryLog(),
                      view=view_for(s.problem.domain.name), clock=lambda: "T")
    out.start()
    out.run_robot()
    return out


def play(s: PlaySession, moves: list[str]) -> list[list[str]]:
    """Play ``moves``; return the leaks found at every step (empty lists when none)."""
    found = [leaks(s.ex, view_facts(v := s.participant_view()), v["feed"])]
    for m in moves:
        assert s.choose(m) in ("played", "replanned"), m
        s.run_robot()
        v = s.participant_view()
        found.append(leaks(s.ex, view_facts(v), v["feed"]))
    return found


# --- sessions ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_every_branch_reaches_the_goal_and_shows_only_what_the_human_perceives(
        name: str) -> None:
    paths = branches(session(name).ex)
    assert paths
    for path in paths:
        s = session(name)
        assert all(f == [] for f in play(s, path)), path
        assert s.outcome == "goal" and s.participant_view()["status"] == "goal"


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_example_plays_a_branch_to_the_goal_showing_only_what_the_human_perceives(
        example: Example) -> None:
    s = session(str(example.path))
    path = branches(s.ex, cap=1)[0]
    assert all(f == [] for f in play(s, path)), path
    assert s.outcome == "goal"
    report = replay(s.log.records, s.problem, s.policy, s.source)  # type: ignore[attr-defined]
    assert report.ok, str(report)


def test_a_participant_never_receives_the_truth_of_what_happened_out_of_sight() -> None:
    s = session("p2")
    s.choose("move(mt, ot)")
    s.run_robot()  # the robot picks r, unseen
    view = s.participant_view()
    text = json.dumps(view)
    assert "holding(R, r)" in s.ex.truth()
    assert not any("pick" in e["text"] for e in view["feed"])
    assert "R is out of sight." in [e["text"] for e in view["feed"]]
    assert {"name": "holding(R, r)", "predicate": "holding",
            "options": ["holding(R, r)", "not holding(R, r)"]} in view["unsure"]
    # nothing of the experimenter's side: no truth, no node, no worlds, no coverage
    for key in ("truth", "node", "worlds", "hypotheses", "covered", "replan"):
        assert f'"{key}"' not in text


def test_an_uncovered_move_replans_and_only_the_experimenter_hears_of_it() -> None:
    # the policy of a human who asks when blocked; this human waits silently instead
    s = session("examples/cubes/qualitative.toml",
                policy_of="examples/cubes/qualitative-ask.toml")
    assert s.participant_view()["moves"][-1]["label"] == "pass"
    assert s.choose("pass") == "replanned"
    s.run_robot()
    while s.human_to_move:
        assert s.choose(s.moves()[0]["label"]) in ("played", "replanned")
        s.run_robot()
    assert s.outcome == "goal"
    assert s.replans == 1
    log = s.log.records  # type: ignore[attr-defined]
    [rp] = [r for r in log if r["type"] == "replan"]
    assert rp["move"] == "pass" and rp["status"] == "solved"
    assert any(r["type"] == "step" and r["replanned"] for r in log)
    exp = s.experimenter_view()
    assert exp["policy"]["replans"] == 1 and any(h["replanned"] for h in exp["history"])
    assert "replan" not in json.dumps(s.participant_view()).lower()
    assert "R says: empty(box2)" in [e["text"] for e in s.participant_view()["feed"]]


def test_a_move_that_is_not_the_humans_is_rejected_and_changes_nothing() -> None:
    s = session("p2")
    before = s.participant_view()
    assert s.choose("fly(away)") == "rejected"
    assert s.choose("pick(r)") == "rejected"
    assert s.participant_view() == before
    assert [r["type"] for r in s.log.records[-2:]] == ["choice", "rejected"]  # type: ignore


def test_a_question_is_answered_and_the_answer_is_speech() -> None:
    s = session("examples/cubes/qualitative-ask.toml")
    asks = [m["label"] for m in s.moves() if m["kind"] == "ask"]
    assert asks, s.moves()
    s.choose(asks[0])
    feed = [e for e in s.participant_view()["feed"]]
    assert feed[-2]["kind"] == "you" and feed[-2]["text"].startswith("You ask R: ")
    assert feed[-1]["kind"] == "answer" and feed[-1]["text"] in ("R answers: yes",
                                                                 "R answers: no")


def test_the_log_replays_to_the_same_records_and_end(tmp_path: Path) -> None:
    path = tmp_path / "s.jsonl"
    log = FileLog(path)
    s = session("p4", log=log)
    for m in branches(s.ex)[-1]:
        s.choose(m)
        s.run_robot()
    log.close()
    records = read_log(path)
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1))
    assert {r["type"] for r in records} >= {"start", "step", "message", "beliefs", "offer",
                                            "choice", "end"}
    assert records[-1]["type"] == "end" and records[-1]["outcome"] == "goal"
    report = replay(records, s.problem, s.policy, s.source)
    assert report.ok, str(report)
    assert report.session.ex.state == s.ex.state
    # a record changed by hand is found
    records[5] = {**records[5], "text": "something else"}
    assert not replay(records, s.problem, s.policy, s.source).ok


def test_logs_are_deterministic_apart_from_times_and_session_ids() -> None:
    a, b = session("p2"), session("p2")
    for s in (a, b):
        for m in branches(s.ex)[0]:
            s.choose(m)
            s.run_robot()
    assert comparable(a.log.records) == comparable(b.log.records)  # type: ignore[attr-defined]


def test_a_cut_last_line_of_a_log_is_forgiven_and_a_bad_one_elsewhere_is_not(
        tmp_path: Path) -> None:
    path = tmp_path / "s.jsonl"
    path.write_text('{"type": "start"}\n{"type": "choice", "move": "pass"}\n{"type": "ste',
                    encoding="utf-8")
    assert [r["type"] for r in read_log(path)] == ["start", "choice"]
    path.write_text('{"type": "start"}\nnot json\n{"type": "end"}\n', encoding="utf-8")
    from ehatp.errors import InputError

    with pytest.raises(InputError, match="line 2"):
        read_log(path)


def test_the_cube_and_cooking_views_draw_only_the_perspective() -> None:
    s = session("p2")
    s.choose("move(mt, ot)")
    s.run_robot()
    p = perspective(s.ex)
    scene = check_scene(cubes_view(p))
    titles = [a["title"] for a in scene["areas"]]
    assert titles[:2] == ["table mt", "table ot"]
    items = {a["title"]: [i["text"] for i in a["items"]] for a in scene["areas"]}
    assert items["table ot"] == ["H", "w"]
    assert "r?" in items["R's hand"] and "r?" in items["table mt"]  # unsure where r is
    c = session("examples/cooking/cooking1.toml")
    assert view_for(c.ex.problem.domain.name) is cooking_view
    scene = check_scene(cooking_view(perspective(c.ex)))
    assert [a["title"] for a in scene["areas"]][:2] == ["kitchen", "pantry"]
    assert view_for("cooking-turn-way2") is cooking_view and view_for("sally-anne") is None


def test_the_pages_insert_data_as_text_only() -> None:
    for f in STATIC.iterdir():
        text = f.read_text(encoding="utf-8")
        for bad in ("innerHTML", "outerHTML", "insertAdjacentHTML", "document.write", "eval(",
                    "new Function"):
            assert bad not in text, (f.name, bad)
        if f.suffix == ".html":  # no inline script or style: the CSP allows none
            assert not re.search(r"<script(?![^>]*\bsrc=)", text), f.name
            assert "style=" not in text and "<style" not in text, f.name


# --- the server, in-process --------------------------------------------------------------------


@pytest.fixture
def hub(tmp_path: Path) -> Any:
    from ehatp.play.files import load_setup, session_log
    from ehatp.play.server import Hub

    setup = load_setup(ROOT / PROBLEMS["p2"], None)

    def factory(sid: str) -> PlaySession:
        return PlaySession(setup.problem, setup.policy, setup.source, session_id=sid,
                           log=session_log(tmp_path, sid), view=setup.view)

    return Hub(factory, key="k3y")


@needs_web
def test_each_visit_is_its_own_session_with_its_own_log(hub: Any, tmp_path: Path) -> None:
    from starlette.testclient import TestClient

    from ehatp.play.server import make_app

    with TestClient(make_app(hub)) as client:
        r1 = client.get("/", follow_redirects=False)
        r2 = client.get("/", follow_redirects=False)
        assert r1.status_code == r2.status_code == 303
        a, b = r1.headers["location"], r2.headers["location"]
        assert a != b and a.startswith("/s/")
        page = client.get(a)
        assert page.status_code == 200 and "script-src 'self'" in page.headers[
            "content-security-policy"]
        assert client.get("/s/nope").status_code == 404
        with client.websocket_connect("/ws/" + a.split("/")[-1]) as ws:
            view = ws.receive_json()["view"]
            assert view["status"] == "your-turn" and view["you"] == "H"
            ws.send_text(json.dumps({"move": "move(mt, ot)"}))
            seen = [ws.receive_json()["view"] for _ in range(2)]
            assert seen[-1]["feed"][-1]["text"] == "R is out of sight."
            ws.send_text("not json")
            assert ws.receive_json()["type"] == "error"
    logs = sorted(tmp_path.glob("*.jsonl"))
    assert len(logs) == 2
    for log in logs:
        records = read_log(log)
        assert {r["session"] for r in records} == {log.stem.split("-", 1)[1]}


@needs_web
def test_the_experimenter_pages_need_the_key(hub: Any) -> None:
    from starlette.testclient import TestClient
    from starlette.websockets import WebSocketDisconnect

    from ehatp.play.server import make_app

    with TestClient(make_app(hub)) as client:
        sid = client.get("/", follow_redirects=False).headers["location"].split("/")[-1]
        assert client.get("/experimenter").status_code == 403
        assert client.get(f"/experimenter/{sid}?key=wrong").status_code == 403
        assert client.get("/api/sessions?key=nope").status_code == 403
        assert client.get(f"/experimenter/{sid}?key=k3y").status_code == 200
        rows = client.get("/api/sessions?key=k3y").json()["sessions"]
        assert [r["session"] for r in rows] == [sid]
        with pytest.raises(WebSocketDisconnect), \
                client.websocket_connect(f"/ws/{sid}/experimenter?key=wrong") as ws:
            ws.receive_json()
        with client.websocket_connect(f"/ws/{sid}/experimenter?key=k3y") as ws:
            view = ws.receive_json()["view"]
            assert view["node"] == 0 and "at(H, mt)" in view["truth"]
            assert view["moves"] and all(m["covered"] for m in view["moves"])
        # another site's page cannot drive a session
        with pytest.raises(WebSocketDisconnect), client.websocket_connect(
                f"/ws/{sid}", headers={"origin": "http://evil.example"}) as ws:
            ws.receive_json()


@pytest.fixture
def live_server(hub: Any) -> Iterator[tuple[str, Any]]:
    """A real uvicorn server of ``hub`` on a free port, in a thread."""
    if not HAVE_WEB:
        pytest.skip("ehatp[play] is not installed (pip install 'ehatp[play]')")
    with serving(hub) as address:
        yield address, hub


def test_ten_sessions_at_once_lose_and_mix_no_log_line(live_server: tuple[str, Any],
                                                      tmp_path: Path) -> None:
    import httpx
    from websockets.sync.client import connect

    address, hub = live_server
    paths = branches(session("p2").ex)
    results: dict[int, str] = {}

    def participant(i: int) -> None:
        r = httpx.get(f"http://{address}/", follow_redirects=False)
        sid = r.headers["location"].split("/")[-1]
        with connect(f"ws://{address}/ws/{sid}") as ws:
            view = json.loads(ws.recv())["view"]
            for move in paths[i % len(paths)]:
                while view["status"] != "your-turn":
                    view = json.loads(ws.recv())["view"]
                ws.send(json.dumps({"move": move}))
                view = json.loads(ws.recv())["view"]
            while view["status"] not in ("goal", "over"):
                view = json.loads(ws.recv())["view"]
        results[i] = sid

    threads = [threading.Thread(target=participant, args=(i,)) for i in range(10)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert len(results) == 10
    logs = {p.stem.split("-", 1)[1]: p for p in tmp_path.glob("*.jsonl")}
    assert set(logs) == set(results.values())
    for i, sid in results.items():
        records = read_log(logs[sid])
        assert {r["session"] for r in records} == {sid}
        assert [r["seq"] for r in records] == list(range(1, len(records) + 1))
        choices = [r["move"] for r in records if r["type"] == "choice"]
        assert choices == paths[i % len(paths)]
        live = hub.sessions[sid].session
        report = replay(records, live.problem, live.policy, live.source)
        assert report.ok, str(report)
        assert report.session.ex.state == live.ex.state and live.outcome == "goal"


def test_a_move_on_a_false_belief_ends_the_session_as_failed(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A move the human can make but that fails (docs/semantics.md §4: it acts on a false
    belief) ends the session; no policy offers one, so the executor is made to."""
    import dataclasses

    from ehatp.errors import UncoveredHumanAction

    s = session("p2")
    real = s.ex.legal_human_moves()
    failing = dataclasses.replace(real[0], child=None, failure="on(w, ot) does not hold")

    def observe(label: str) -> Any:
        raise UncoveredHumanAction(label, [], [failing.label], "it fails")

    monkeypatch.setattr(s.ex, "legal_human_moves", lambda: [failing])
    monkeypatch.setattr(s.ex, "observe_human_action", observe)
    assert s.choose(failing.label) == "failed"
    assert s.outcome == "failed" and s.status() == "over"
    end = s.log.records[-1]  # type: ignore[attr-defined]
    assert end["type"] == "end" and end["outcome"] == "failed"
    assert end["reason"] == "on(w, ot) does not hold"
    view = s.participant_view()
    assert view["feed"][-1]["text"] == f"You try {failing.label}, but it cannot be done."
    assert "on(w, ot) does not hold" not in json.dumps(view) and view["moves"] == []


def test_a_step_record_names_the_robot_move_as_an_opening_would_where_labels_are_shared(
) -> None:
    """Two robot methods start with ``fetch`` (the first a dead end): the log's step record
    keeps the label as ``move`` and the move as ``[problem] after`` writes it,
    ``R fetch [shelve]``, as ``played`` (what ``ehatp relabel --after-from`` reads); a log
    without ``played`` (written before it was recorded) still replays."""
    from ehatp import solve

    from .test_every_policy_runs import fetching

    problem = fetching()
    policy = solve(problem).policy
    assert policy is not None
    src = Source("fetching.toml", "sha256:test", None, policy_hash(policy), "none")
    s = PlaySession(problem, policy, src, session_id="f", log=MemoryLog(), clock=lambda: "T")
    s.start()
    s.run_robot()
    steps = [r for r in s.log.records if r["type"] == "step"]  # type: ignore[attr-defined]
    assert steps[0]["move"] == "fetch" and steps[0]["played"] == "R fetch [shelve]"
    old = [{k: v for k, v in r.items() if k != "played"}
           for r in s.log.records]  # type: ignore[attr-defined]
    assert comparable(old) == comparable(s.log.records)  # type: ignore[attr-defined]
