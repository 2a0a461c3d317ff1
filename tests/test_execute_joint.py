"""``ehatp execute`` in joint steps (docs/execution.md, "Joint steps"): every ``waiting`` line
carries the step's timing (decision timeout, recognition latency) the robot process keeps;
a timed-out decision is the robot process's ``pass``; turn-taking lines are unchanged and the
timing options are refused there in one line."""

from __future__ import annotations

import ehatp
from ehatp.run.executor import Executor

from .conftest import EXAMPLES_DIR
from .test_execute import ehatp_cli, lines, session

STACK4 = EXAMPLES_DIR / "concurrent" / "stack4.toml"
P2 = EXAMPLES_DIR / "cubes" / "p2.toml"


def test_every_waiting_line_of_a_joint_step_carries_its_timing() -> None:
    """Stack4 (the replies of tests/test_stacking.py): waiting at the root with pick(c1) and
    pass covered; the decision times out, so the robot process reports ``pass``; the robot's
    reply is ``pick(c1)``; once it is done the human decides again, the timing with it."""
    problem = ehatp.load(STACK4)
    code, out = session(Executor(problem), lines({"human": "pass"}, {"robot_done": True}),
                        decision_timeout=3.0, recognition_latency=0.25)
    waiting = [m["waiting"] for m in out if "waiting" in m]
    assert waiting[0] == {"human": "H", "expected": ["pick(c1)", "pass"],
                          "step": {"decision_timeout": 3.0, "recognition_latency": 0.25}}
    assert [m["robot"]["action"] for m in out if "robot" in m] == ["pick(c1)"]
    assert len(waiting) == 2 and waiting[1]["step"] == waiting[0]["step"]
    assert code == 1  # the input ended before the goal


def test_without_timing_a_joint_waiting_line_says_none_is_kept() -> None:
    _, out = session(Executor(ehatp.load(STACK4)), "")
    [waiting] = [m["waiting"] for m in out if "waiting" in m]
    assert waiting["step"] == {"decision_timeout": None, "recognition_latency": None}


def test_turn_taking_waiting_lines_are_unchanged_and_timing_is_refused() -> None:
    _, out = session(Executor(ehatp.load(P2)), "")
    [waiting] = [m["waiting"] for m in out if "waiting" in m]
    assert set(waiting) == {"human", "expected"}
    r = ehatp_cli("execute", P2, "--decision-timeout", "3", stdin="")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and "takes turns" in r.stderr
