"""``ehatp show`` of a policy in joint steps (docs/concurrent.md): a step a line, the human's
move then the robot's reply, and for ``[objective] kind = "preferences"`` the profile, the
root's vector and the vector of each robot choice. Every expected line was derived by hand
from the rules (C3-C5, C11) before the planner was run; each test's docstring gives the
derivation. Every policy is validated and walked through the Executor on all its branches
(:func:`tests.test_concurrent.solved`)."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import ehatp
from ehatp.cli.app import app
from ehatp.formats.policy import Policy
from ehatp.formats.text import plain, policy_lines
from ehatp.model.options import Estimate
from ehatp.run.walk import walk_policy

from .conftest import EXAMPLES_DIR as EXAMPLES
from .test_concurrent import JOINT, chores, drawer, solved, two_hands
from .test_preferences import helper, prefer
from .test_render import browser, open_page  # noqa: F401  (browser is a fixture)


def shown(policy: Policy, **kw: bool) -> str:
    return plain(policy_lines(policy, **kw))


def tree(text: str) -> list[str]:
    """The lines of the ``Tree`` section."""
    lines = text.splitlines()
    start = lines.index("Tree") + 1
    return lines[start:lines.index("", start)]


def squeeze(lines: list[str]) -> list[str]:
    """``lines`` with runs of spaces as one (the columns' widths are not the point)."""
    return [re.sub(" +", " ", ln) for ln in lines]


def test_a_joint_step_reads_as_the_humans_move_then_the_robots_reply_on_one_line() -> None:
    """E2 (one cube, two hands) by hand, the human first (C4). Root: the human picks ``c`` or
    passes. ``pick(c)``: the robot can only wait (C3 a, c); then the robot is blocked and the
    human places ``c`` beside a wait: goal in 2 steps. ``pass``: the robot picks ((pass,
    wait) is no step), the human, blocked, passes while it places: goal in 2 steps. So the
    tree is the root, a fork of two, each branch two steps of one line each (nodes: the reply
    node after the human's move, the decision node after the reply), and each timeline two
    steps in two columns."""
    text = shown(solved(two_hands(JOINT)))
    assert ("joint steps: H moves first, R replies (the compliant robot); witness whole, "
            "commute state, a step costs 1") in text.splitlines()
    assert squeeze(tree(text)) == [
        "#0 start W=1",
        "H may do one of 2:",
        "+- #1 H pick(c) #2 R wait W=1",
        "| #3 H place(c) #4 R wait W=1 GOAL",
        "`- #5 H pass #6 R pick(c) W=1",
        " #7 H pass #8 R place(c) W=1 GOAL",
    ]
    timelines = text[text.index("Timelines"):].splitlines()
    assert squeeze(timelines) == [
        "Timelines (2 branches)",
        "branch 1 -> leaf #4 (goal), 2 steps, cost 2",
        " step H R", " 1 pick(c) wait", " 2 place(c) wait",
        "branch 2 -> leaf #8 (goal), 2 steps, cost 2",
        " step H R", " 1 pass pick(c)", " 2 pass place(c)",
    ]


def test_a_preferences_policy_shows_its_profile_the_root_vector_and_each_replys() -> None:
    """The helper problem (tests/test_preferences.py) by hand, profile ``lazy_human``
    (human_effort, makespan), worst case. When the human passes first the robot grabs ``b``
    (the human then passes twice): from that reply on, the human acts in no step and 3 steps
    remain: (0, 3); then ``put(a)`` (0, 2) and ``drop(b)`` (0, 1). When the human puts ``b``,
    the robot's reply ``put(a)`` ends it: (0, 1) (the human's action is its own move's, before
    the reply). The root takes the worst branch: ``hput(b)`` then ``put(a)`` is (1, 1), the
    pass branch (0, 3); (1, 1) is the greater."""
    text = shown(solved(prefer(helper(), "lazy_human")))
    assert ("preferences: profile lazy_human = (human_effort, makespan), worst-case "
            "estimate; root: human_effort = 1, makespan = 1") in text.splitlines()
    assert squeeze(tree(text)) == [
        "#0 start W=1",
        "H may do one of 2; worst (1, 1):",
        "+- #1 H hput(b) #2 R put(a) (0, 1) W=1 GOAL",
        "`- #3 H pass #4 R grab(b) (0, 3) W=1",
        " #5 H pass #6 R put(a) (0, 2) W=1",
        " #7 H pass #8 R drop(b) (0, 1) W=1 GOAL",
    ]


def test_another_profile_shows_the_other_reply_and_its_vector() -> None:
    """The helper problem by hand, profile ``hurry`` (makespan, human_effort): when the human
    passes the robot puts ``a`` (2 steps left, the human placing ``b`` in the second: (2, 1))
    rather than grabbing ``b`` (3 steps, (3, 0)); the human must then act ((pass, wait) is no
    step) and the robot waits: (1, 0), the node reached being the one after the first
    branch's step. Root: max{(1, 1), (2, 1)} = (2, 1). With ``estimate = "optimistic"`` and
    ``lazy_human`` the root is the best branch, min{(1, 1), (0, 3)} = (0, 3)."""
    text = shown(solved(prefer(helper(), "hurry")))
    assert "root: makespan = 2, human_effort = 1" in text
    assert squeeze(tree(text)) == [
        "#0 start W=1",
        "H may do one of 2; worst (2, 1):",
        "+- #1 H hput(b) #2 R put(a) (1, 0) W=1 GOAL",
        "`- #3 H pass #4 R put(a) (2, 1) W=1",
        " #5 H hput(b) R wait (1, 0) -> see node 2",
    ]
    best = shown(solved(prefer(helper(), "lazy_human", Estimate.OPTIMISTIC)))
    assert "optimistic estimate; root: human_effort = 0, makespan = 3" in best
    assert "H may do one of 2; best (0, 3):" in best


def test_with_the_robot_first_a_step_reads_the_robots_move_then_the_humans() -> None:
    """E2 with ``first = "robot"``, profile ``lazy_human`` (tests/test_preferences.py, by
    hand): the robot picks ``c`` and the human, who saw it start, passes; then the robot
    places it, the human passing: 2 steps in which the human never acts. The vector beside
    the robot's move is that of the node where it chose: (0, 2), then (0, 1)."""
    first = dataclasses.replace(JOINT, first=ehatp.StepFirst.ROBOT)
    text = shown(solved(prefer(two_hands(first), "lazy_human")))
    assert "joint steps: R moves first, H moves beside it" in text
    assert squeeze(tree(text)) == [
        "#0 start W=1",
        "#1 R pick(c) #2 H pass (0, 2) W=1",
        "#3 R place(c) #4 H pass (0, 1) W=1 GOAL",
    ]
    assert " step R H" in squeeze(text.splitlines())


def test_with_the_robot_first_the_humans_moves_beside_its_action_fork_below_it() -> None:
    """E1 (two chores) with ``first = "robot"``, by hand (C4, C5, C11). The robot decides
    first: ``put(a)``, or ``wait``. Beside ``put(a)`` the human, who sees it start, may
    ``put(b)`` (it commutes, no resource: goal in 1 step) or pass (beside an action it may);
    after a pass the robot is done, so it waits and beside a wait the human may not pass:
    ``put(b)``, 2 steps. Beside a ``wait`` first the human may not pass: ``put(b)``, then the
    robot's ``put(a)`` beside the human's pass: 2 steps, one branch. Both are worst case 2,
    no communication, the human acting once on every branch; the shorter average branch
    (1.5 against 2) puts ``a`` first. The robot's line stops mid-step (no W: the step is not
    over), the human's moves fork below it, and the pass branch's next step reaches the goal
    node printed above."""
    first = dataclasses.replace(JOINT, first=ehatp.StepFirst.ROBOT)
    text = shown(solved(chores(first)))
    assert squeeze(tree(text)) == [
        "#0 start W=1",
        "#1 R put(a)",
        "H may do one of 2 beside it:",
        "+- #2 H put(b) W=1 GOAL",
        "`- #3 H pass W=1",
        " #4 R wait H put(b) -> see node 2",
    ]


def test_a_question_is_a_step_of_its_own_whose_answer_is_implied() -> None:
    """E3 with the default human (tests/test_concurrent.py): when the human leaves, the robot
    moves the cube unseen; the human, back and unsure (two worlds), asks, which is a whole
    step (C3) that the robot answers, then takes ``c``: 4 steps and one question on that
    branch."""
    text = shown(solved(drawer(JOINT)))
    lines = squeeze(tree(text))
    ask = next(ln for ln in lines if "ask(in_box(c))" in ln)
    assert ask.endswith("H ask(in_box(c)) R (answers) W=1 COMM")
    first = text[text.index("branch 1 "):].splitlines()
    assert squeeze(first[:6]) == [
        "branch 1 -> leaf #7 (goal), 4 steps, cost 5",
        " step H R",
        " 1 leave move(c) apart",
        " 2 back wait",
        " 3 ask(in_box(c)) (answers)",
        " 4 take(c) wait",
    ]


def test_a_policy_planned_after_the_humans_move_starts_with_the_reply() -> None:
    """E2 planned again after the human picked ``c`` (``[problem] after``, how
    ``Executor.replan`` plans in the middle of a step): the root is the reply node, where the
    robot can only wait (C3); then the human places ``c``: 2 steps, the first begun before
    the root."""
    p = dataclasses.replace(two_hands(JOINT), after=("H pick(c)",))
    text = shown(solved(p))
    assert "after: H pick(c) (played before the root; [..] in the timelines)" in text
    assert squeeze(tree(text)) == [
        "#0 start W=1", "#1 R wait W=1", "#2 H place(c) #3 R wait W=1 GOAL"]
    assert squeeze(text.splitlines()[-2:]) == [" 1 [pick(c)] wait", " 2 place(c) wait"]


def test_ehatp_show_prints_every_step_of_stack4_once_per_branch(tmp_path: Path) -> None:
    """``examples/concurrent/stack4.toml`` from the command line: each step costs 1 and
    nobody speaks, so on every branch the number of steps is the branch's cost; a step's
    two moves are on one line, so no timeline line names the robot's ``wait`` alone."""
    out = tmp_path / "s4.json"
    runner = CliRunner()
    assert runner.invoke(app, ["solve", str(EXAMPLES / "concurrent" / "stack4.toml"),
                               "--out", str(out)]).exit_code == 0
    problem = ehatp.load(EXAMPLES / "concurrent" / "stack4.toml")
    assert ehatp.validate(problem, Policy.read(out)).ok
    assert walk_policy(problem, Policy.read(out)).ok
    r = runner.invoke(app, ["show", str(out)])
    assert r.exit_code == 0, r.output
    heads = re.findall(r"^branch \d+ -> leaf #\d+ \(goal\), (\d+) steps?, cost (\d+)$",
                       r.stdout, re.M)
    assert len(heads) == Policy.read(out).leaves == 18
    assert all(steps == cost for steps, cost in heads)
    assert max(int(c) for _, c in heads) == 8  # the worst case (docs/concurrent.md)


@pytest.mark.slow  # a real Chromium
def test_the_explorer_header_gives_the_steps_the_profile_and_the_root_vector(
        tmp_path: Path, browser: Any) -> None:  # noqa: F811
    """The helper problem with ``lazy_human`` (root (1, 1), derived above) in the HTML
    explorer: the header says who moves first, the profile and the root's vector, and marks
    neither cost optimised (the profile is what was optimised)."""
    from selenium.webdriver.common.by import By

    from ehatp.formats.render import to_html

    page = tmp_path / "helper.html"
    page.write_text(to_html(solved(prefer(helper(), "lazy_human"))), encoding="utf-8")
    open_page(browser, page)
    assert browser.find_element(By.ID, "policy-steps").text == \
        "joint steps: H moves first, R replies"
    assert browser.find_element(By.ID, "policy-profile").text == (
        "· profile lazy_human (human_effort, makespan), worst-case estimate; root: "
        "human_effort = 1, makespan = 1")
    assert browser.find_element(By.ID, "policy-worst-case").text == "worst-case cost 3"


def test_every_random_joint_policy_shows_each_branch_as_its_steps() -> None:
    """The agreement benchmark's random problems in joint steps (seeds 0-599; informs,
    questions, separations, the robot first, preferences): ``ehatp show`` prints each, and on
    every branch (the first 100 of each policy) the timeline has one line per step, i.e. per
    move that starts a step or is a question, and no more; each tree line holds at most one
    move of each agent."""
    from ehatp.experiments.randomgen import problem

    checked = 0
    for seed in range(600):
        p = problem(seed)
        if not p.steps.concurrent:
            continue
        policy = ehatp.solve(p, max_states=20000, timeout=4).policy
        if policy is None:
            continue
        text = shown(policy)
        steps = [int(n) for n in re.findall(r"^branch \d+ -> leaf #\d+ \((?:no )?goal\), "
                                            r"(\d+) steps?, cost", text, re.M)]
        want = [sum(1 for ps in branch[1:] if ps.move is not None and ps.move.step != "reply")
                + (1 if branch[1:] and branch[1].move is not None
                   and branch[1].move.step == "reply" else 0)
                for _, branch in zip(range(100), policy.iter_branches(), strict=False)]
        assert steps == want, seed
        for line in tree(text):
            for agent in ("H", "R"):
                assert len(re.findall(rf"(?:^|\s){agent}  \S", line)) <= 1, (seed, line)
        checked += 1
    assert checked >= 20, checked
