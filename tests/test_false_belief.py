"""Sally-Anne: while the human is away the robot moves the ball the human will need. The robot
must inform before the human acts, or defer the move until the human is back — whichever is
cheaper; with informing made expensive, deferral must win."""

from __future__ import annotations

import ehatp
from ehatp.formats.policy import PathStep, Policy

from .conftest import EXAMPLES_DIR, example, solved
from .scenarios import walk

SA = EXAMPLES_DIR / "sally-anne"


def leave_first(policy: Policy) -> list[PathStep]:
    return next(b for b in policy.branches() if b[1].action == "go(room, street)")


def test_cheap_inform_tidies_unseen_then_informs_before_the_human_reaches() -> None:
    p, policy = solved("sally-anne/inform")
    assert ehatp.validate(p, policy).ok
    branch = [n.action for n in leave_first(policy)]
    assert branch[2] == "move(basket, box)"  # unseen: the human keeps a false belief
    back = branch.index("go(street, room)")
    assert branch[back + 1] == "inform(not ball_in(basket), ball_in(box))"
    assert branch[back + 2] == "take(box)"
    # the irrelevant divergence (the ball is clean) is never told
    assert all("clean" not in n.action for b in policy.branches() for n in b)


def test_expensive_inform_defers_the_move_until_the_human_sees_it() -> None:
    p, policy = solved("sally-anne/defer")
    assert ehatp.validate(p, policy).ok
    assert policy.communications == 0 == example("sally-anne/defer").communications
    branch = leave_first(policy)
    move = next(n for n in branch if n.action == "move(basket, box)")
    assert move.copresent and move.worlds == 1  # done in front of the human


def test_without_either_the_human_fails_on_its_false_belief() -> None:
    # after an unseen move, skipping the inform lets the human reach into the basket
    p = ehatp.load(SA / "inform.toml")
    sem, es = walk(p, "go(room, street)", "move(basket, box)", "errand", "wait",
                   "go(street, room)", "wait")
    take = next(m for m in sem.moves(es) if m.label == "take(basket)")
    assert take.child is None and "false belief" in take.failure
