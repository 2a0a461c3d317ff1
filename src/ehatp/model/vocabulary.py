"""The words planner, validator and policy file share (docs/semantics.md §4-§5,
docs/policy-format.md): who moves, and what kind of move it is.

Both are enums whose members equal the plain values they replace: an :class:`Agent` is the int
a search node stores for whose turn it is (``0`` the robot, ``1`` the human), a
:class:`MoveKind` the string a policy file writes (``"action"``, ``"inform"``, ...), so code and
files that compare with those values read the same, and the JSON does not change.
"""

from __future__ import annotations

from enum import IntEnum, StrEnum


class Agent(IntEnum):
    """Who moves (§4): the robot, whose options are OR choices, or the human, whose options
    are AND branches."""

    ROBOT = 0
    HUMAN = 1

    @property
    def other(self) -> Agent:
        """Return the agent that moves after this one (§4: the agents alternate)."""
        return Agent.HUMAN if self is Agent.ROBOT else Agent.ROBOT


ROBOT, HUMAN = Agent.ROBOT, Agent.HUMAN


class MoveKind(StrEnum):
    """What a move is (§4-§5), as a policy file writes it in ``kind``."""

    ACTION = "action"  # an action of the agent's model (said with an inform, too)
    WAIT = "wait"  # the robot lets the human move (said with an inform, too)
    PASS = "pass"  # the human lets the robot move
    INFORM = "inform"  # the robot tells the human atoms of the true state
    ASK = "ask"  # the human asks about a condition; the robot asks the human's intention
    SILENCE = "silence"  # the robot says nothing at a speech opening
    ANSWER = "answer"  # the human answers the robot's question about its intention
    ANNOUNCE = "announce"  # the robot tells the human its own agenda


__all__ = ["HUMAN", "ROBOT", "Agent", "MoveKind"]
