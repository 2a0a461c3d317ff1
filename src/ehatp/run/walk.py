"""Walk a policy on every branch through :class:`~ehatp.run.executor.Executor`: the proof that a
policy the planner returned (and the validator accepted) also *runs*.

Planner and validator read the same rules (docs/semantics.md), so they can agree on a policy a
robot cannot execute; the executor is a third reader, the one a robot uses. :func:`walk_policy`
plays the policy as a robot would: at a robot node it does what the executor says (the move of
the policy's recorded edge, §4), at a human node it forks once per move the policy covers (every
AND branch, §4) and feeds it to the executor as an observed human action; each branch must end at
a leaf where the goal holds (§6). :func:`tick_py_trees` does the same with the policy's
behaviour tree for py_trees (``ehatp export bt``), checked against an executor on every branch.
See docs/simulation.md and docs/behaviour-trees.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..errors import ExecutionError
from ..formats.policy import Policy, label_key
from ..model.problem import Problem
from .executor import Executor
from .expand import expand_policy

if TYPE_CHECKING:
    from ..formats.bt_py_trees import HumanTurn, RobotCommand

DEFAULT_CAP = 2000


@dataclass(frozen=True)
class WalkReport:
    """What :func:`walk_policy` found: ``ok`` when every branch walked reached the goal,
    ``branches`` the branches walked to their end, ``capped`` when it stopped at the cap before
    the last branch, ``message`` the first failure (the branch's moves, then the error)."""

    ok: bool
    branches: int
    capped: bool
    message: str = ""

    def __str__(self) -> str:
        head = (f"{self.branches} branches walked" + (" (capped)" if self.capped else "")
                + (": every one reaches the goal" if self.ok else ""))
        return head if self.ok else f"{head}; {self.message}"


def walk_policy(problem: Problem, policy: Policy, *, cap: int = DEFAULT_CAP) -> WalkReport:
    """Return how executing ``policy`` for ``problem`` through an :class:`Executor` went on every
    root-to-leaf branch, depth first in the policy's order, up to ``cap`` branches.

    The problem's fixed opening is replayed first (moves already made). At a robot node the robot
    does what :meth:`Executor.next_robot_action` says; at a human node each move the policy covers
    (docs/semantics.md §4: every human option is an AND branch) is fed to its own copy of the
    executor (:meth:`Executor.copy`) with :meth:`Executor.observe_human_action`, by label, as a
    robot that only sees the human's actions would (§3, "What the robot observes"). A branch
    passes when the executor reaches a leaf of the policy where the goal holds (§6). The first
    failure stops the walk; its message names the branch's moves and the executor's error."""
    try:
        start = Executor(problem, policy)
        start.replay_opening()
    except ExecutionError as e:
        return WalkReport(False, 0, False, f"at the start: {e}")
    return walk_from(start, cap=cap)


def positions(start: Executor, *, cap: int = DEFAULT_CAP,
              step_starts: bool = False) -> list[Executor]:
    """Return an executor at each position of every branch of the policy ``start`` follows,
    from where ``start`` is (its opening replayed), depth first, the goal excluded: at most
    ``cap`` (a position two branches reach is listed once per branch). In joint steps a
    position is a step's start, or its middle (``state.pending``: the reply due), which
    ``step_starts`` leaves out. ``start`` itself does not move. For checks made wherever an
    execution may stand, e.g. a profile switch (C11)."""
    first = start.copy()
    first.replay_opening()
    out: list[Executor] = []
    stack = [first]
    while stack and len(out) < cap:
        ex = stack.pop()
        if ex.done:
            continue
        if not (step_starts and ex.state.pending):
            out.append(ex.copy())
        if ex.next_robot_action() is not None:
            ex.robot_action_done()
            stack.append(ex)
            continue
        assert ex.node is not None
        for label in [m.action for m in ex.node.moves]:
            nxt = ex.copy()
            nxt.observe_human_action(label)
            stack.append(nxt)
    return out


def walk_from(start: Executor, *, cap: int = DEFAULT_CAP) -> WalkReport:
    """Return how the policy ``start`` follows runs on every branch from where ``start`` is
    (e.g. after :meth:`Executor.switch_profile`, C11), as :func:`walk_policy` walks a policy
    from its root; ``start`` itself does not move (the walk plays copies). The branches' moves
    in a failure's message are those played from that point."""
    first = start.copy()
    try:
        first.replay_opening()
    except ExecutionError as e:
        return WalkReport(False, 0, False, f"at the start: {e}")
    # (executor, moves so far, the human move to feed first or None)
    stack: list[tuple[Executor, list[str], str | None]] = [(first, [], None)]
    branches = 0
    while stack:
        if branches >= cap:
            return WalkReport(True, branches, True)
        ex, path, pending = stack.pop()
        try:
            if pending is not None:
                path.append(f"{ex.human_name} {pending}")
                ex.observe_human_action(pending)
            while not ex.done:
                action = ex.next_robot_action()
                if action is not None:
                    path.append(f"{ex.robot_name} {action.label}")
                    ex.robot_action_done(action.label)
                    continue
                assert ex.node is not None
                labels = [m.action for m in ex.node.moves]
                norm = [label_key(x) for x in labels]
                if len(set(norm)) != len(norm):
                    dup = next(x for x, n in zip(labels, norm, strict=True) if norm.count(n) > 1)
                    raise ExecutionError(
                        f"policy node {ex.node.id} covers {ex.human_name} {dup} more than once: "
                        f"a robot that sees only the action cannot tell its branches apart")
                for label in reversed(labels[1:]):
                    stack.append((ex.copy(), list(path), label))
                path.append(f"{ex.human_name} {labels[0]}")
                ex.observe_human_action(labels[0])
        except ExecutionError as e:
            return WalkReport(False, branches, False, _failure(branches + 1, path, str(e)))
        branches += 1
        if not ex.goal_reached:
            assert ex.node is not None
            return WalkReport(False, branches, False, _failure(
                branches, path, f"policy leaf {ex.node.id} is reached but the goal does not "
                "hold there"))
    return WalkReport(True, branches, False)


class _Run:
    """One tick of the exported tree to its end, checked against its own executor: the choice
    made at each human turn (an index into the moves the policy covers) and how many there were,
    the moves so far, and the first error."""

    def __init__(self, ex: Executor, prefix: list[int]) -> None:
        self.ex, self.prefix = ex, prefix
        self.choices: list[tuple[int, int]] = []  # (index chosen, moves covered)
        self.path: list[str] = []
        self.error = ""
        self.goals: list[int] = []
        self.uncovered: list[str] = []


def tick_py_trees(problem: Problem, policy: Policy, *, cap: int = DEFAULT_CAP,
                  ticks: int = 100_000) -> WalkReport:
    """Return how the policy's behaviour tree for py_trees (:func:`ehatp.formats.bt.build_py_tree`,
    ``pip install 'ehatp[bt]'``) runs on every branch, up to ``cap`` branches: the tree is
    built once and ticked to its end once per branch, a scripted human choosing, turn after
    turn, each move the policy covers (docs/semantics.md §4: AND branches), depth first.

    Each run is checked against its own :class:`Executor`: every robot command that completes a
    policy move is the move the executor says (label, and name and arguments for an action),
    every answer to a question is the truthful one (§5), every human turn is at the executor's
    policy node with the moves it expects; the tree must end in SUCCESS at the goal leaf the
    executor reached, where the goal holds (§6), having reported nothing uncovered. At most
    ``ticks`` ticks a branch. Raises ImportError without py_trees."""
    from py_trees.common import Status

    from ..formats.bt import build_py_tree

    try:
        policy = expand_policy(problem, policy)  # lifted: the tree is the expanded graph's
        start = Executor(problem, policy)
        start.replay_opening()
    except ExecutionError as e:
        return WalkReport(False, 0, False, f"at the start: {e}")
    check = _TreeCheck(_Run(start.copy(), []))
    root = build_py_tree(policy, robot=check.robot, human=check.human,
                         on_goal=lambda node: check.run.goals.append(node),
                         on_uncovered=lambda seen, expected: check.run.uncovered.append(seen),
                         problem=problem)
    branches, prefix = 0, list[int]()
    while True:
        if branches >= cap:
            return WalkReport(True, branches, True)
        run = check.run = _Run(start.copy(), prefix)
        status = _tick(root, run, ticks)
        why = _tree_failure(run, status, ticks)
        if why:
            if status == Status.RUNNING:
                root.stop(Status.INVALID)
            return WalkReport(False, branches, False, _failure(branches + 1, run.path, why))
        branches += 1
        next_prefix = _next_branch(run.choices)
        if next_prefix is None:
            return WalkReport(True, branches, False)
        prefix = next_prefix


class _TreeCheck:
    """The robot's and the human's callbacks of the exported tree, each checked against the
    executor of the run under way (:attr:`run`, a new one for each branch)."""

    def __init__(self, run: _Run) -> None:
        self.run = run

    def fail(self, message: str) -> None:
        if not self.run.error:
            self.run.error = message

    def robot(self, cmd: RobotCommand) -> bool:
        """Return whether the robot's command is the policy's move (and any answer the
        truthful one), doing it on the executor."""
        ex = self.run.ex
        try:
            if cmd.question is not None:  # the answer to the question just asked
                last = ex.history[-1]
                yes = ex.answer(last.before, last.action.label)
                if cmd.answer is not None and yes is not None \
                        and cmd.answer != ("yes" if yes else "no"):
                    self.fail(f"the tree answers {cmd.answer} to {cmd.question}, the truth is "
                              f"{'yes' if yes else 'no'}")
                    return False
            if cmd.completes is None:
                return True
            want = ex.next_robot_action()
            if want is None or label_key(want.label) != label_key(cmd.completes):
                self.fail(f"the tree's robot does {cmd.completes}, the executor says "
                          f"{'nothing (not the robot turn)' if want is None else want.label}")
                return False
            if cmd.kind == "action" and (cmd.name, cmd.args) != (want.name, want.args):
                self.fail(f"the tree's robot does {cmd.name}{cmd.args}, the executor says "
                          f"{want.name}{want.args}")
                return False
            self.run.path.append(f"{ex.robot_name} {cmd.completes}")
            ex.robot_action_done(cmd.completes)
        except ExecutionError as e:
            self.fail(str(e))
            return False
        return True

    def human(self, turn: HumanTurn) -> str:
        """Return the human's move of this branch at ``turn`` (checked to be where the
        executor is, expecting what it expects), done on the executor; "" on a mismatch."""
        run, ex = self.run, self.run.ex
        try:
            covered = [a.label for a in ex.expected_human_actions()]
            here = None if ex.node is None else ex.node.id
            if list(turn.expected) != covered or turn.node != here:
                self.fail(f"the tree waits for the human at node {turn.node} expecting "
                          f"{list(turn.expected)}; the executor is at node {here} expecting "
                          f"{covered}")
                return ""
            k = len(run.choices)
            i = run.prefix[k] if k < len(run.prefix) else 0
            run.choices.append((i, len(covered)))
            run.path.append(f"{ex.human_name} {covered[i]}")
            ex.observe_human_action(covered[i])
            return covered[i]
        except ExecutionError as e:
            self.fail(str(e))
            return ""


def _tick(root: Any, run: _Run, ticks: int) -> Any:
    """Tick ``root`` until it stops running, the run fails, or ``ticks`` ticks; return the
    tree's status."""
    from py_trees.common import Status

    status = Status.RUNNING
    for _ in range(ticks):
        root.tick_once()
        status = root.status
        if status != Status.RUNNING or run.error:
            break
    return status


def _tree_failure(run: _Run, status: Any, ticks: int) -> str:
    """Return why the run's branch failed ("" when the tree succeeded at the goal leaf the
    executor reached, reporting that goal only)."""
    from py_trees.common import Status

    ex = run.ex
    if run.error:
        return run.error
    if status != Status.SUCCESS:
        return (f"the tree is still running after {ticks} ticks" if status == Status.RUNNING
                else f"the tree ends in {status.value}"
                + (f" (uncovered: {', '.join(run.uncovered)})" if run.uncovered else ""))
    if not (ex.done and ex.goal_reached):
        return "the tree succeeds where the executor has not reached the goal"
    if ex.node is None or run.goals != [ex.node.id]:
        return f"the tree reports the goals {run.goals}, the executor is at a leaf " + (
            "" if ex.node is None else str(ex.node.id))
    return ""


def _next_branch(choices: list[tuple[int, int]]) -> list[int] | None:
    """Return the human's choices that start the next branch, depth first (the last choice
    that has a next option, taken), or None after the last branch."""
    choices = list(choices)
    while choices and choices[-1][0] + 1 >= choices[-1][1]:
        choices.pop()
    if not choices:
        return None
    return [i for i, _ in choices[:-1]] + [choices[-1][0] + 1]


MOVES_SHOWN = 12  # the last moves of a failing branch that its message lists


def _failure(n: int, path: list[str], error: str) -> str:
    moves = "; ".join(path[-MOVES_SHOWN:]) if path else "no move"
    if len(path) > MOVES_SHOWN:
        moves = f"{len(path) - MOVES_SHOWN} moves, then {moves}"
    return f"branch {n} ({moves}): {error}"


__all__ = ["DEFAULT_CAP", "WalkReport", "positions", "tick_py_trees", "walk_from",
           "walk_policy"]
