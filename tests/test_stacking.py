"""The shared stacking domain (src/ehatp/domains/stacking.py, docs/domains/stacking.md): both
agents build one tower in joint, compliant steps. Every figure below is derived by hand in the
test's docstring before the planner was run."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

import ehatp
from ehatp.formats.policy import Policy

from .conftest import EXAMPLES_DIR
from .test_concurrent import solved as solved_checked

STACK4 = EXAMPLES_DIR / "concurrent" / "stack4.toml"
STACK10 = EXAMPLES_DIR / "concurrent" / "stack10.toml"


def solved(path: Path) -> Policy:
    """The problem's policy, checked by the validator and walked through the Executor."""
    return solved_checked(ehatp.load(path))


def steps(policy: Policy) -> Iterator[tuple[tuple[str, ...], str, str]]:
    """Every step of every branch: the human's moves before it, its human move, the reply."""
    for branch in policy.iter_branches():
        humans: list[str] = []
        for step in branch[1:]:
            assert step.move is not None
            if step.move.step == "reply":
                yield tuple(humans[:-1]), humans[-1], step.move.action
            elif step.move.step in ("human", "ask"):
                humans.append(step.move.action)


def replies(policy: Policy) -> dict[tuple[str, ...], str]:
    """The robot's reply after each line of human moves (the step's own move last)."""
    return {(*before, h): r for before, h, r in steps(policy)}


@pytest.mark.parametrize(("path", "cubes"), [(STACK4, 4), (STACK10, 10)], ids=["4", "10"])
def test_the_worst_case_is_two_steps_per_cube(path: Path, cubes: int) -> None:
    """By hand. Every cube needs two actions (pick, place), and no step is (pass, wait) (C3),
    so a branch takes at most 2n steps. The human who passes whenever it may (C5: the robot
    has a real action) forces exactly that: while it passes the robot acts alone; it may not
    pass only when the robot has nothing to do, and then the robot's one reply is ``wait``.
    One action per step: 2n steps, whatever the robot does. Stack4: 8; stack10: 20; no
    communication (one table, everything in sight)."""
    policy = solved(path)
    assert (policy.cost, policy.communications) == (2 * cubes, 0)


def test_the_robot_never_takes_the_cube_the_human_reaches_for() -> None:
    """Stack4's root: the tower is empty, ``c1`` (shared) is the one cube anyone may pick
    (``c2`` is wanted only once ``c1`` is in a hand). The human reaches for ``c1``: the robot's
    one action, ``pick(c1)``, is no reply (C3 a and c: the cube is gone and held), so it waits;
    the human places ``c1`` while the robot, with nothing in reach (``c2`` is the human's),
    waits again. Over every step of stack4 and stack10, a human ``pick(x)`` is never answered by
    ``pick(x)``."""
    p4 = solved(STACK4)
    assert replies(p4)[("pick(c1)",)] == "wait"
    assert replies(p4)[("pick(c1)", "place(c1, s1)")] == "wait"
    for policy in (p4, solved(STACK10)):
        clashes = [(h, r) for _, h, r in steps(policy)
                   if h.startswith("pick(") and r == h]
        assert clashes == []


def test_the_robot_works_beside_the_human() -> None:
    """Parallel steps in stack4, by hand. The human passes, the robot picks ``c1``; now
    ``c2`` is wanted (the cube below it is in a hand) and the human picks it while the robot
    places ``c1``: one step, both acting (no common resource, same state either order). Later,
    the human places ``c2`` while the robot picks ``c3`` (its own zone, wanted once ``c2`` is in
    a hand): again both act."""
    r = replies(solved(STACK4))
    assert r[("pass", "pick(c2)")] == "place(c1, s1)"
    assert r[("pick(c1)", "place(c1, s1)", "pick(c2)", "place(c2, s2)")] == "pick(c3)"
    both = [(h, rep) for _, h, rep in steps(solved(STACK4)) if h != "pass" and rep != "wait"]
    assert both


def test_the_domain_is_declared_by_name() -> None:
    """``[domain] name = "stacking"`` needs no file beside the problem: a built-in, declared as
    an entry point too (pyproject.toml)."""
    from ehatp.model.registry import BUILTIN

    assert BUILTIN["stacking"] == "ehatp.domains.stacking:make_domain"
    assert ehatp.load(STACK4).domain.name == "stacking"
