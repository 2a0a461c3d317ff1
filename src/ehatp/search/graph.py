"""The explored AND/OR graph (docs/semantics.md §7, "Search"): its nodes, their statuses and
their edges, shared by the search that grows it (:mod:`.andor`), the values computed on it
(:mod:`.values`) and the policy read from it (:mod:`.policy`).

Memory: the graph keeps one :class:`EState` per distinct state, with the worlds tuples and true
states shared between the nodes that have equal ones; an edge keeps the child's id and a move
*descriptor* shared by every edge with the same move (its ``child`` state is not kept, except
for ``inform`` and moves said with one, whose descriptions read the child's true state);
per-node flags are bytes.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from ..epistemic.semantics import INFORM, Move, Semantics
from ..epistemic.state import ROBOT, EState, Worlds
from ..model.problem import Cost
from ..model.vocabulary import MoveKind
from .symmetry import Symmetry


class NodeStatus(IntEnum):
    """Where a node of the graph stands (stored as a byte per node)."""

    OPEN = 0  # created, not expanded yet
    EXPANDED = 1  # its moves are edges
    GOAL = 2  # a goal (§6): a leaf, solved
    DEAD = 3  # a dead end: an inactivity deadlock, or cut by the depth limit


OPEN, EXPANDED, GOAL, DEAD = (NodeStatus.OPEN, NodeStatus.EXPANDED, NodeStatus.GOAL,
                              NodeStatus.DEAD)

KIND_ORDER = {MoveKind.SILENCE: -1, MoveKind.ACTION: 0, MoveKind.INFORM: 1,
              MoveKind.ANNOUNCE: 2, MoveKind.ASK: 3, MoveKind.ANSWER: 4, MoveKind.WAIT: 5,
              MoveKind.PASS: 6}
"""The canonical order of moves by kind (§7, "Ties": a final tie goes to the first)."""


def move_key(move: Move) -> tuple[object, ...]:
    """Return the sort key of ``move`` in the canonical move order: kind, label, then the
    child state (a failing move after the others of its label)."""
    return (KIND_ORDER[move.kind], move.label, move.child is None, move.child or ())


@dataclass(slots=True)
class Edge:
    """One option (robot) or branch (human) of a node. ``move`` describes the move (shared by
    the edges of equal moves; its ``child`` state is not kept: None, or for ``inform`` the
    child node's state); ``child`` is the child node's id, -1 when the move fails. Over
    symmetry-reduced states (:mod:`.symmetry`), ``perm`` is the renaming (an id) that maps the
    move's real child to the child node's canonical state; 0 is none."""

    move: Move
    child: int
    perm: int = 0


NO_EDGES: tuple[Edge, ...] = ()
_make = tuple.__new__  # an EState from a tuple of its fields, as NamedTuple._make does
assert EState._fields[1:5] == ("true", "robot_agenda", "human_agendas", "worlds")


class Graph:
    """The explored AND/OR graph, as parallel per-node arrays indexed by node id."""

    def __init__(self, sem: Semantics) -> None:
        self.sem = sem
        self.states: list[EState] = []
        self.index: dict[EState, int] = {}
        self.status = bytearray()  # a NodeStatus per node
        self.dead_why: dict[int, str] = {}
        self.edges: list[tuple[Edge, ...]] = []  # in canonical move order, once expanded
        # the parents, one entry per edge into the node: -1 for none, a node id for one, a
        # list beyond (most nodes have one parent)
        self._parents: list[int | list[int]] = []
        self.g: list[Cost] = []  # the cheapest path cost from the root found so far
        # §6: each node's least number of moves from the root over the paths found so far
        self.depth: list[int] = []
        self.depth_cut: set[int] = set()  # dead ends made by the depth limit alone
        self.solved = bytearray()
        self.pending: list[int] = []  # human nodes: unsolved edges left
        self._worlds: dict[Worlds, Worlds] = {}
        self._trues: dict[int, int] = {}
        self._moves: dict[tuple[object, ...], Move] = {}
        # search over canonical states (docs/semantics.md §3, "Symmetry"): the renamings, and
        # the one mapping the real root to the root node's state
        self.sym: Symmetry | None = None
        self.root_perm = 0

    def add(self, es: EState, g: Cost, depth: int, parent: int = -1) -> int:
        """Return the id of a new node for ``es`` (worlds and true state shared with equal
        ones), reached at path cost ``g`` and ``depth`` moves."""
        w = self._worlds.setdefault(es.worlds, es.worlds)
        t = self._trues.setdefault(es.true, es.true)
        if w is not es.worlds or t is not es.true:  # what _replace does, without its keywords
            es = _make(EState, (es[0], t, es[2], es[3], w, *es[5:]))
        i = len(self.states)
        self.states.append(es)
        self.index[es] = i
        self.status.append(OPEN)
        self.edges.append(NO_EDGES)
        self._parents.append(parent)
        self.g.append(g)
        self.depth.append(depth)
        self.solved.append(0)
        self.pending.append(0)
        return i

    def add_parent(self, c: int, p: int) -> None:
        """Record one more edge from ``p`` into ``c``."""
        ps = self._parents[c]
        if isinstance(ps, list):
            ps.append(p)
        elif ps < 0:
            self._parents[c] = p
        else:
            self._parents[c] = [ps, p]

    def parents(self, n: int) -> list[int]:
        """Return one entry per edge into ``n`` (a parent with two edges to ``n`` is there
        twice)."""
        ps = self._parents[n]
        if isinstance(ps, list):
            return ps
        return [] if ps < 0 else [ps]

    def descriptor(self, move: Move, child: int) -> Move:
        """Return ``move`` without its child state, shared between equal moves (see
        :class:`Edge`)."""
        if (move.kind == INFORM or move.atoms) and child >= 0:  # what is told reads the child
            return Move(move.agent, move.kind, move.label, move.cost, self.states[child],
                        move.op, move.atoms, move.failure, move.waits)
        key = (move.agent, move.kind, move.label, move.cost, move.op, move.atoms, move.failure,
               move.waits)
        d = self._moves.get(key)
        if d is None:
            d = self._moves[key] = Move(move.agent, move.kind, move.label, move.cost, None,
                                        move.op, move.atoms, move.failure, move.waits)
        return d

    def is_robot(self, n: int) -> bool:
        """Return whether the robot moves at node ``n`` (an OR node)."""
        return self.states[n].turn == ROBOT


__all__ = ["DEAD", "EXPANDED", "GOAL", "KIND_ORDER", "NO_EDGES", "OPEN", "Edge", "Graph",
           "NodeStatus", "move_key"]
