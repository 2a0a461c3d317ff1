"""What an execution records: one move in the domain's words (:class:`Action`) and one executed
move (:class:`Step`), as :class:`~ehatp.run.executor.Executor` gives them to a robot controller
or a simulator and :mod:`ehatp.run.narrative` tells them to people."""

from __future__ import annotations

from dataclasses import dataclass

from ..epistemic.state import EState, Worlds
from ..formats.policy import PolicyNode
from ..model.problem import Cost


@dataclass(frozen=True)
class Action:
    """One move in the domain's vocabulary. ``name``/``args`` split an operator call
    (``place``, ``("w", "box2")``); for ``inform`` the args are the literals told, for ``ask``
    the question; ``wait`` and ``pass`` have none. ``told`` holds the literals the robot says
    while doing an action or a wait (``speech = "with-action"``: ``inform(x) + place(r, b)``)."""

    agent: str
    kind: str  # action | wait | pass | inform | ask | silence | answer | announce
    label: str
    name: str
    args: tuple[str, ...]
    cost: Cost
    told: tuple[str, ...] = ()


@dataclass(frozen=True)
class Step:
    """One executed move: the states around it and the policy node it reached (None within
    the opening). ``assessed`` holds the human's worlds just before situation assessment, when
    it ran on this step. ``replanned`` marks a human move the policy did not cover, after which
    the execution follows a new policy (:meth:`Executor.replan`); ``node`` is that policy's
    root. ``trace`` is the move as a problem's fixed opening names it, when that is not its
    label: ``fetch [shelve]`` where robot moves share a label (:meth:`Semantics.trace_label`,
    read back by :meth:`Executor.as_problem`'s problem)."""

    index: int
    action: Action
    before: EState
    after: EState
    node: PolicyNode | None
    opening: bool
    assessed: Worlds | None
    replanned: bool = False
    trace: str = ""

    @property
    def played(self) -> str:
        """The step as an opening step (``[problem] after``): the agent, then the move."""
        return f"{self.action.agent} {self.trace or self.action.label}"
