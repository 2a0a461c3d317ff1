"""``ehatp play`` in a real Chromium (slow): a scripted participant plays every branch of P2, P4
(where the human asks) and both Sally-Anne examples to the goal; at every step the facts and
events the page shows are checked against the human's worlds (tests/play_check.py: nothing
the human cannot perceive); an uncovered move makes the robot replan, which only the
experimenter's page says; every session's log replays to the same end state. In joint steps
(stack4) the page shows the robot's signal and the decision timer, whose end is a pass."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import pytest

from ehatp.play.session import read_log, replay

from .conftest import ROOT
from .play_check import PROBLEMS, branches, leaks, make_hub, serving
from .test_render import browser  # noqa: F401  (the fixture: a headless Chromium, or a skip)

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not all(importlib.util.find_spec(m) for m in ("starlette", "uvicorn")),
                       reason="ehatp[play] is not installed (pip install 'ehatp[play]')"),
]

READ_PAGE = """
const facts = [...document.querySelectorAll("[data-fact]")].map(
  e => ({fact: e.dataset.fact, status: e.dataset.status}));
const feed = [...document.querySelectorAll("#feed li")].map(
  e => ({kind: e.dataset.kind, text: e.textContent}));
const moves = [...document.querySelectorAll("#moves button")].map(e => e.dataset.move);
return {facts, feed, moves, text: document.body.innerText,
        step: document.body.dataset.step, status: document.body.dataset.status};
"""


def wait_turn(driver: Any, old_step: str | None = None) -> dict[str, Any]:
    """Wait until the page waits for the participant (or the session is over) after
    ``old_step``; return what the page shows."""
    from selenium.webdriver.support.ui import WebDriverWait

    def ready(d: Any) -> Any:
        page = d.execute_script(READ_PAGE)
        if page["status"] in ("your-turn", "goal", "over") and page["step"] != old_step \
                and d.execute_script("return document.body.dataset.ready") == "true":
            return page
        return False

    page: dict[str, Any] = WebDriverWait(driver, 20).until(ready)
    return page


def play_branch(driver: Any, address: str, hub: Any, moves: list[str]) -> Any:
    """Open a new session, play ``moves`` by clicking, check every page shown; return the
    session."""
    from selenium.webdriver.common.by import By

    driver.get(f"http://{address}/")
    sid = driver.current_url.rstrip("/").split("/")[-1]
    live = hub.sessions[sid].session
    page = wait_turn(driver)
    for move in [*moves, None]:
        assert int(page["step"]) == len(live.ex.history)
        found = leaks(live.ex, page["facts"], page["feed"])
        assert found == [], (moves, move, found)
        assert "replan" not in page["text"].lower()
        if move is None:
            break
        assert move in page["moves"], (move, page["moves"])
        driver.find_element(By.CSS_SELECTOR, f'button[data-move="{move}"]').click()
        page = wait_turn(driver, page["step"])
    return live, page


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_a_participant_plays_every_branch_to_the_goal_seeing_only_what_the_human_can(
        name: str, browser: Any, tmp_path: Path) -> None:  # noqa: F811
    hub = make_hub(ROOT / PROBLEMS[name], tmp_path)
    with serving(hub) as address:
        probe = hub.new()  # a session to read the policy's branches from
        paths = branches(probe.session.ex)
        assert paths
        for moves in paths:
            live, page = play_branch(browser, address, hub, moves)
            assert page["status"] == "goal" and live.outcome == "goal", moves
            log = next(tmp_path.glob(f"*-{live.id}.jsonl"))
            report = replay(read_log(log), live.problem, live.policy, live.source)
            assert report.ok, str(report)
            assert report.session.ex.state == live.ex.state


def test_an_uncovered_move_replans_and_only_the_experimenter_page_says_so(
        browser: Any, tmp_path: Path) -> None:  # noqa: F811
    from selenium.webdriver.support.ui import WebDriverWait

    hub = make_hub(ROOT / "examples/cubes/qualitative.toml", tmp_path,
                   policy_of=ROOT / "examples/cubes/qualitative-ask.toml")
    with serving(hub) as address:
        live, page = play_branch(browser, address, hub, ["pass", "place(w, box2)"])
        assert page["status"] == "goal" and live.replans == 1
        assert "R says: empty(box2)" in [e["text"] for e in page["feed"]]
        shot = tmp_path / "play.png"
        browser.save_screenshot(str(shot))
        assert shot.stat().st_size > 10_000
        browser.get(f"http://{address}/experimenter/{live.id}?key={hub.key}")
        WebDriverWait(browser, 20).until(
            lambda d: d.execute_script("return document.body.dataset.ready") == "true")
        assert browser.execute_script("return document.body.dataset.replans") == "1"
        assert "(REPLANNED)" in browser.execute_script("return document.body.innerText")
        log = next(tmp_path.glob(f"*-{live.id}.jsonl"))
        records = read_log(log)
        assert [r["move"] for r in records if r["type"] == "replan"] == ["pass"]
        assert replay(records, live.problem, live.policy, live.source).ok
        # no console errors on either page
        errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        assert errors == []


def test_joint_steps_a_timed_out_decision_replans_and_the_participant_stacks_to_the_goal(
        browser: Any, tmp_path: Path) -> None:  # noqa: F811
    """Stack4 in joint steps, the policy planned for a diligent human (tests/test_play_joint.py):
    the page shows the robot's signal ("I will be passive this step" at the root, where the
    policy expects ``pick(c1)`` only) and the decision timer; the participant lets the timer
    run out (1 s): a pass the policy does not cover, so the robot replans; then it clicks the
    first move that is not a pass at each decision, the page showing a signal at each, until
    the tower stands. The log replays."""
    from selenium.webdriver.common.by import By

    from ehatp.play.files import session_log
    from ehatp.play.server import Hub
    from ehatp.play.session import PlaySession, Source, policy_hash

    from .test_play_joint import STACK4, stack4

    problem, policy = stack4(diligent_policy=True)
    src = Source(str(STACK4), "sha256:test", None, policy_hash(policy), "test")

    def factory(sid: str) -> PlaySession:
        return PlaySession(problem, policy, src, session_id=sid,
                           log=session_log(tmp_path, sid), decision_timeout=1.0)

    hub = Hub(factory)
    signal = "return document.getElementById('signal').textContent"
    with serving(hub) as address:
        browser.get(f"http://{address}/")
        sid = browser.current_url.rstrip("/").split("/")[-1]
        live = hub.sessions[sid].session
        page = wait_turn(browser)
        assert browser.execute_script(signal) == "R signals: I will be passive this step"
        assert "Time to decide" in browser.execute_script(
            "return document.getElementById('timer').textContent")
        page = wait_turn(browser, page["step"])  # the timer ends: the human passes
        assert live.replans == 1 and page["feed"][0]["text"] == "You wait."
        shown = []
        while page["status"] == "your-turn":
            shown.append(browser.execute_script(signal))
            move = next(m for m in page["moves"] if m != "pass")
            browser.find_element(By.CSS_SELECTOR, f'button[data-move="{move}"]').click()
            page = wait_turn(browser, page["step"])
        assert page["status"] == "goal" and live.outcome == "goal"
        assert shown and all(s.startswith("R signals: ") for s in shown)
        records = read_log(next(tmp_path.glob(f"*-{sid}.jsonl")))
        assert [r["move"] for r in records if r["type"] == "replan"] == ["pass"]
        assert replay(records, live.problem, live.policy, live.source).ok
        errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        assert errors == []


def test_the_experimenter_page_switches_the_robot_s_profile_and_the_participant_sees_the_reply(
        browser: Any, tmp_path: Path) -> None:  # noqa: F811
    """stack-prefs (profiles ``builder`` and ``hurry``; derived by hand in
    tests/test_play_profile.py): the participant picks c1 (the robot waits); at step 2's start
    the experimenter's page switches the robot to ``hurry`` with its control; back on the
    participant's page the signal is now "You can act in parallel" (builder's was "Act if you
    will"), and to ``place(c1, s1)`` the robot picks c2 at once (builder would wait). The
    participant's page never names a profile; the log replays."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select, WebDriverWait

    from ehatp.play.files import load_setup, session_log
    from ehatp.play.server import Hub
    from ehatp.play.session import PlaySession

    setup = load_setup(ROOT / "examples/concurrent/stack-prefs.toml", None, "none")

    def factory(sid: str) -> PlaySession:
        return PlaySession(setup.problem, setup.policy, setup.source, session_id=sid,
                           log=session_log(tmp_path, sid), graph=setup.graph)

    hub = Hub(factory, key="k3y")
    signal = "return document.getElementById('signal').textContent"
    with serving(hub) as address:
        browser.get(f"http://{address}/")
        sid = browser.current_url.rstrip("/").split("/")[-1]
        live = hub.sessions[sid].session
        page = wait_turn(browser)
        browser.find_element(By.CSS_SELECTOR, 'button[data-move="pick(c1)"]').click()
        page = wait_turn(browser, page["step"])
        assert page["step"] == "2"
        assert browser.execute_script(signal) == "R signals: Act if you will"
        browser.get(f"http://{address}/experimenter/{sid}?key=k3y")
        WebDriverWait(browser, 20).until(
            lambda d: d.execute_script("return document.body.dataset.profile") == "builder")
        Select(browser.find_element(By.ID, "profile-choice")).select_by_value("hurry")
        browser.find_element(By.ID, "profile-switch").click()
        WebDriverWait(browser, 20).until(
            lambda d: d.execute_script("return document.body.dataset.switch") == "switched")
        assert browser.find_element(By.ID, "profile-result").text == (
            "Switched: the robot now follows hurry.")
        browser.get(f"http://{address}/s/{sid}")
        page = wait_turn(browser)
        assert browser.execute_script(signal) == "R signals: You can act in parallel"
        browser.find_element(By.CSS_SELECTOR, 'button[data-move="place(c1, s1)"]').click()
        page = wait_turn(browser, page["step"])
        assert [e["text"] for e in page["feed"]][-1] == "R: pick(c2)"
        assert not any(n in page["text"] for n in ("builder", "hurry", "profile"))
        errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        assert errors == []
    records = read_log(next(tmp_path.glob(f"*-{sid}.jsonl")))
    assert [r["profile"] for r in records if r["type"] == "profile"] == ["hurry"]
    assert live.profile() == "hurry"
    assert replay(records, live.problem, live.policy, live.source, None, setup.graph).ok
