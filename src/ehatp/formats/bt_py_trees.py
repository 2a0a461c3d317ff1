"""The behaviours of an exported policy tree for py_trees (``pip install 'ehatp[bt]'``).

:func:`ehatp.formats.bt.build_py_tree` builds the tree of a policy from these classes; a module
written by ``ehatp export bt --format py_trees`` builds the same one. The behaviours talk to the
robot and to whatever perceives the human through an :class:`Interface` of plain callables:

- ``robot(command)`` for every :class:`RobotCommand` (an action, a wait, something to say, a
  silence): called at each tick while the command runs, it returns True when it is done, False
  when it failed, None while it is still running;
- ``human(turn)`` at each tick while the human is to act (:class:`HumanTurn`: the policy node
  and the actions the policy covers): the action the human did, as the policy prints it
  (``pick(w)``, ``ask(can_put(w, box2))``, ``pass``), or None while it has not acted;
- ``on_goal(node)`` when a goal is reached, ``on_uncovered(observed, expected)`` when the human
  did something the policy has no branch for (the tree then fails).

A state the policy reaches by several paths is one ``SubTree`` behaviour per use, whose
behaviours are built the first time it is ticked: memory grows with what is executed, not with
the tree unfolding of the policy (which can be exponentially larger). What each
``WaitHumanAction`` observed is kept in the interface's own ``blackboard`` dict, one key per
human choice (isolated from py_trees' global blackboard).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from py_trees.behaviour import Behaviour
from py_trees.behaviours import Failure
from py_trees.common import Status
from py_trees.composites import Selector, Sequence

from .bt_tree import SEP, BTNode, Forest
from .policy import label_key


@dataclass(frozen=True)
class RobotCommand:
    """What the robot must do now.

    ``kind``: ``action`` (``name(args)``), ``wait``, ``say`` (``told`` the literals to inform,
    or ``question`` answered with ``answer``, yes/no, None when the tree does not know: answer
    from what the robot knows; or, ``name`` ``ask``, the question ``ask(intention)`` to the
    human; or, ``name`` ``announce``, the robot's own tasks in ``args``) or ``silence``
    (nothing). ``completes`` is the label of the
    policy's robot move this command finishes (``inform(x) + place(r, box1)`` is a ``say``
    then an ``action``, the second completing it), None for the first part of such a move and
    for an answer (part of the human's question)."""

    kind: str
    action: str
    name: str = ""
    args: tuple[str, ...] = ()
    told: tuple[str, ...] = ()
    question: str | None = None
    answer: str | None = None
    completes: str | None = None


@dataclass(frozen=True)
class HumanTurn:
    """The human is to act at policy ``node``; ``expected`` are the actions the policy covers."""

    node: int
    expected: tuple[str, ...]


RobotFn = Callable[[RobotCommand], bool | None]
HumanFn = Callable[[HumanTurn], str | None]
OnGoal = Callable[[int], None]
OnUncovered = Callable[[str, list[str]], None]


@dataclass
class Interface:
    """The callables the behaviours use, and where the human's observed actions are kept."""

    robot: RobotFn
    human: HumanFn
    on_goal: OnGoal | None = None
    on_uncovered: OnUncovered | None = None
    blackboard: dict[str, str] = field(default_factory=dict)


def _split(v: str) -> tuple[str, ...]:
    return tuple(x for x in v.split(SEP) if x)


def _key(port: str) -> str:
    """``{human_action_3}`` -> ``human_action_3`` (a blackboard reference)."""
    return port[1:-1] if port.startswith("{") and port.endswith("}") else port


def _same(a: str, b: str) -> bool:
    return label_key(a) == label_key(b)


def _status(done: bool | None) -> Status:
    return Status.RUNNING if done is None else Status.SUCCESS if done else Status.FAILURE


class _RobotBehaviour(Behaviour):
    """Runs one :class:`RobotCommand` through ``io.robot``."""

    def __init__(self, io: Interface, command: RobotCommand, name: str) -> None:
        super().__init__(name)
        self.io, self.command = io, command

    def update(self) -> Status:
        return _status(self.io.robot(self.command))


class RobotAction(_RobotBehaviour):
    """The robot does one action of its domain."""

    def __init__(self, io: Interface, action: str, action_name: str, args: str,
                 completes: str | None = None) -> None:
        super().__init__(io, RobotCommand("action", action, action_name, _split(args),
                                          completes=completes), action)


class RobotWait(_RobotBehaviour):
    """The robot waits, letting the human take a turn."""

    def __init__(self, io: Interface, completes: str | None = None) -> None:
        super().__init__(io, RobotCommand("wait", "wait", "wait", completes=completes), "wait")


class Silence(_RobotBehaviour):
    """The robot stays silent at a speech opening (it does nothing)."""

    def __init__(self, io: Interface, completes: str | None = None) -> None:
        super().__init__(io, RobotCommand("silence", "silence", "silence",
                                          completes=completes), "silence")


class Say(_RobotBehaviour):
    """The robot informs the human of ``literals``, answers ``question``, asks the human its
    intention (``kind`` ask) or announces its own (``kind`` announce, ``intention``)."""

    def __init__(self, io: Interface, kind: str, literals: str = "", question: str = "",
                 answer: str | None = None, completes: str | None = None,
                 intention: str = "") -> None:
        if kind == "answer":
            cmd = RobotCommand("say", f"answer({question})", "answer", (question,),
                               question=question, answer=answer, completes=completes)
            label = f"answer {question}: {answer or '?'}"
        elif kind == "ask":
            cmd = RobotCommand("say", f"ask({question})", "ask", (question,),
                               completes=completes)
            label = cmd.action
        elif kind == "announce":
            cmd = RobotCommand("say", f"announce({intention})", "announce", (intention,),
                               completes=completes)
            label = cmd.action
        else:
            told = _split(literals)
            cmd = RobotCommand("say", f"inform({', '.join(told)})", "inform", told, told,
                               completes=completes)
            label = cmd.action
        super().__init__(io, cmd, label)


class WaitHumanAction(Behaviour):
    """Runs until ``io.human`` reports the human's action, then writes it to the blackboard."""

    def __init__(self, io: Interface, action: str, expected: str) -> None:
        self.io, self.key = io, _key(action)
        node = self.key.rsplit("_", 1)[-1]
        self.turn = HumanTurn(int(node) if node.isdigit() else -1, _split(expected))
        super().__init__(f"wait for the human at node {self.turn.node}")

    def initialise(self) -> None:
        self.io.blackboard.pop(self.key, None)

    def update(self) -> Status:
        seen = self.io.human(self.turn)
        if seen is None:
            return Status.RUNNING
        self.io.blackboard[self.key] = seen
        self.feedback_message = seen
        return Status.SUCCESS


class WaitHumanStart(WaitHumanAction):
    """Joint steps: runs until ``io.human`` reports the action the human *starts* (or
    ``pass``, when its decision timed out), then writes it to the blackboard; the robot's reply
    runs after it while the human acts."""


class HumanDid(Behaviour):
    """Succeeds when the human action observed is ``action`` (spaces ignored)."""

    def __init__(self, io: Interface, observed: str, action: str) -> None:
        super().__init__(f"did {action}?")
        self.io, self.key, self.action = io, _key(observed), action

    def update(self) -> Status:
        seen = self.io.blackboard.get(self.key)
        return Status.SUCCESS if seen is not None and _same(seen, self.action) \
            else Status.FAILURE


class ReportUncovered(Behaviour):
    """Reports an observed action the policy does not cover (``io.on_uncovered``), then
    succeeds; an action among ``expected`` had its branch, which failed below, and is not
    reported again."""

    def __init__(self, io: Interface, observed: str, expected: str) -> None:
        super().__init__("report uncovered")
        self.io, self.key, self.expected = io, _key(observed), list(_split(expected))

    def update(self) -> Status:
        seen = self.io.blackboard.get(self.key, "")
        if not any(_same(seen, e) for e in self.expected) and self.io.on_uncovered is not None:
            self.io.on_uncovered(seen, self.expected)
        return Status.SUCCESS


class GoalReached(Behaviour):
    """A goal of the policy: calls ``io.on_goal`` and succeeds."""

    def __init__(self, io: Interface, node: str) -> None:
        super().__init__(f"goal (node {node})")
        self.io, self.node = io, int(node)

    def update(self) -> Status:
        if self.io.on_goal is not None:
            self.io.on_goal(self.node)
        return Status.SUCCESS


class SubTree(Behaviour):
    """The tree of a shared policy node, built by ``factory`` when first ticked, then ticked
    as this behaviour's own (BehaviorTree.CPP's ``<SubTree>``)."""

    def __init__(self, tree_id: str, factory: Callable[[], Behaviour]) -> None:
        super().__init__(tree_id)
        self.factory = factory
        self.tree: Behaviour | None = None

    def update(self) -> Status:
        if self.tree is None:
            self.tree = self.factory()
        self.tree.tick_once()
        return self.tree.status

    def terminate(self, new_status: Status) -> None:
        if (new_status == Status.INVALID and self.tree is not None
                and self.tree.status == Status.RUNNING):
            self.tree.stop(Status.INVALID)


def build(forest: Forest, io: Interface) -> Behaviour:
    """The behaviours of ``forest`` (:func:`ehatp.formats.bt.from_policy`), root first."""

    def make(node: BTNode) -> Behaviour:
        a = node.attrs
        kids: list[Behaviour] = []
        for c in node.children:  # a loop, not a comprehension: one frame less per level
            kids.append(make(c))
        if node.tag == "Sequence":
            return Sequence(a.get("name", "Sequence"), memory=True, children=kids)
        if node.tag == "Fallback":
            return Selector(a.get("name", "Fallback"), memory=True, children=kids)
        if node.tag == "SubTree":
            tid = a["ID"]
            return SubTree(tid, lambda: make(forest.trees[tid]))
        if node.tag == "AlwaysFailure":
            return Failure(a.get("name", "AlwaysFailure"))
        if node.tag == "RobotAction":
            return RobotAction(io, a["action"], a["action_name"], a["args"], node.completes)
        if node.tag == "RobotWait":
            return RobotWait(io, node.completes)
        if node.tag == "Silence":
            return Silence(io, node.completes)
        if node.tag == "Say":
            return Say(io, a["kind"], a.get("literals", ""), a.get("question", ""),
                       a.get("answer"), node.completes, a.get("intention", ""))
        if node.tag == "WaitHumanAction":
            return WaitHumanAction(io, a["action"], a["expected"])
        if node.tag == "WaitHumanStart":
            return WaitHumanStart(io, a["action"], a["expected"])
        if node.tag == "HumanDid":
            return HumanDid(io, a["observed"], a["action"])
        if node.tag == "ReportUncovered":
            return ReportUncovered(io, a["observed"], a["expected"])
        if node.tag == "GoalReached":
            return GoalReached(io, a["node"])
        raise ValueError(f"no py_trees behaviour for {node.tag}")

    return make(forest.trees[forest.main])


__all__ = ["GoalReached", "HumanDid", "HumanFn", "HumanTurn", "Interface", "OnGoal",
           "OnUncovered", "ReportUncovered", "RobotAction", "RobotCommand", "RobotFn",
           "RobotWait", "Say", "Silence", "SubTree", "WaitHumanAction", "WaitHumanStart", "build"]
