"""Epistemic states ``s = <d, W>`` as immutable, hashable tuples.

``d`` is the designated world (true state and the robot's agenda) with the set ``A_H`` of human
agendas that fit what the robot observed (docs/semantics.md §3, "What the robot observes": it
sees the human's actions, never its method choices); ``W`` the worlds the human entertains,
each a state plus the robot agenda the human attributes to the robot there. A node of the
search also carries whose turn it is, the K-counter and the count of consecutive passive moves:
exactly what the transition rules read, so equal tuples are interchangeable (sound duplicate
detection).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import NamedTuple

from ..model.agenda import Agenda
from ..model.vocabulary import HUMAN, ROBOT, Agent

World = tuple[int, Agenda]
Worlds = tuple[World, ...]


class EState(NamedTuple):
    # Semantics.robot_wait and the human's pass build one field by field (hot): a new
    # field is to be passed there too
    turn: Agent  # whose move it is (§4)
    true: int
    robot_agenda: Agenda
    human_agendas: tuple[Agenda, ...]  # A_H: sorted, distinct, never empty (§3)
    worlds: Worlds
    k: int
    passive: int
    forced: bool = False  # human node: the robot's last move was a forced wait (§4)
    opening: bool = False  # robot node: the speech opening before the human's first move (§5)
    answering: bool = False  # human node: the human answers the robot's question (§5)
    # a joint step's reply node: the move decided first, the other agent to reply
    # (docs/concurrent.md, C4; empty in turn-taking and at a step's start)
    pending: tuple[int, ...] = ()


def normalize(worlds: Iterable[World]) -> Worlds:
    """Canonical form: distinct worlds, sorted (equal state and agenda are one world)."""
    return tuple(sorted(set(worlds)))


def states_of(worlds: Worlds) -> tuple[int, ...]:
    """The distinct world states, sorted."""
    return tuple(sorted({s for s, _ in worlds}))


__all__ = ["HUMAN", "ROBOT", "EState", "World", "Worlds", "normalize", "states_of"]
