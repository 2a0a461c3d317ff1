"""A lifted policy (policy format version 3) on the real objects: renamings as integer
permutation tables, a node or a move seen through a renaming, and the version 2 graph.

A lifted policy's nodes are the search's canonical states (docs/semantics.md §3, "Symmetry");
each move carries the renaming that maps its child, seen from the node it is played at, onto the
node it leads to. A reader realises the branch it follows lazily: it keeps ``tau``, the renaming
from the current node to the real state (at the root, the inverse of ``symmetry.root``), reads
the node and its moves through ``tau`` (:meth:`Renamings.node`), and following move ``m`` goes
on with ``tau . inverse(renamings[m.renaming])`` (:meth:`Renamings.child`). Renamings are
tuples of ints (the image of each object, by index into ``symmetry.objects``); a name map is made
only where text is produced (:meth:`Renamings.names`), once per renaming.

:func:`expand` writes the whole version 2 graph of a lifted policy (``ehatp expand``,
``ehatp solve --expand``; the renderers, ``ehatp show`` and ``ehatp export bt`` draw it):
one node per real state, found by following every move from the real root and renaming. It
imports neither the planner nor the validator (docs/policy-format.md, "Version 3").
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Iterator, Mapping
from dataclasses import replace
from typing import Any

from ..errors import PolicyTooLarge
from .policy import PathStep, Policy, PolicyMove, PolicyNode

Perm = tuple[int, ...]  # the image of each object, by index into symmetry.objects

# an object name in a label or a fact (the planner's own tokenisation, search/symmetry.py)
TOKEN = re.compile(r"[^\s(),=\[\]<>!|{}+;:]+")
_CACHE = 4096  # node views kept per Renamings (a walk revisits the same few)
EXPAND_LIMIT = 20_000
"""How many nodes over the real objects the readers that need a lifted policy whole (``ehatp
show``'s tree, ``render``, ``export bt``) make at most by default (``--expand-limit``): at 16
cubes / 2 boxes / K=2 the 413 canonical nodes stand for 795,237, which took 196 s."""


class Renamings:
    """The ``symmetry`` table of a version 3 policy, applied: ``atoms`` and ``tasks`` (the
    ground problem's indices by name, when the reader has them) put renamed facts in the order
    a version 2 file lists them; without them, facts keep their positions."""

    def __init__(self, table: Mapping[str, Any], atoms: Mapping[str, int] | None = None,
                 tasks: Mapping[str, int] | None = None) -> None:
        self.objects: list[str] = list(table["objects"])
        self.table: list[Perm] = [tuple(p) for p in table["renamings"]]
        self.identity: Perm = tuple(range(len(self.objects)))
        self.root: Perm = self.inverse(self.table[table["root"]])
        self.atoms, self.tasks = atoms, tasks
        self._inverse: dict[int, Perm] = {}
        self._child: dict[tuple[Perm, int], Perm] = {}
        self._names: dict[Perm, dict[str, str]] = {}
        self._views: dict[tuple[int, Perm], PolicyNode] = {}

    # -- permutations ---------------------------------------------------------------------------
    @staticmethod
    def inverse(p: Perm) -> Perm:
        inv = [0] * len(p)
        for i, j in enumerate(p):
            inv[j] = i
        return tuple(inv)

    @staticmethod
    def compose(a: Perm, b: Perm) -> Perm:
        """``a`` after ``b`` (``b`` first)."""
        return tuple(a[j] for j in b)

    def child(self, tau: Perm, renaming: int) -> Perm:
        """The renaming from a move's node to the real state, the move played at a node whose
        renaming is ``tau``: ``tau . inverse(renamings[renaming])``."""
        if not renaming:
            return tau
        key = (tau, renaming)
        out = self._child.get(key)
        if out is None:
            inv = self._inverse.get(renaming)
            if inv is None:
                inv = self._inverse[renaming] = self.inverse(self.table[renaming])
            out = self._child[key] = self.compose(tau, inv)
        return out

    def names(self, tau: Perm) -> dict[str, str]:
        """The object names ``tau`` moves, by name (the one place text meets a renaming)."""
        ren = self._names.get(tau)
        if ren is None:
            objects = self.objects
            ren = self._names[tau] = {objects[i]: objects[j] for i, j in enumerate(tau)
                                      if i != j}
        return ren

    # -- text -----------------------------------------------------------------------------------
    def text(self, tau: Perm, s: str) -> str:
        """``s`` (a label, a literal, a task) with every object token renamed by ``tau``."""
        ren = self.names(tau)
        if not ren:
            return s
        return TOKEN.sub(lambda mt: ren.get(mt.group(0), mt.group(0)), s)

    def texts(self, tau: Perm, xs: list[str], ordered: bool = False) -> list[str]:
        """Each of ``xs`` renamed; ``ordered``: put back in the ground problem's atom order."""
        out = [self.text(tau, x) for x in xs]
        return sorted(out, key=self._atom_key) if ordered and self.atoms is not None else out

    def _atom_key(self, literal: str) -> int:
        atoms = self.atoms
        assert atoms is not None
        atom = literal[4:] if literal.startswith("not ") else literal
        i = atoms.get(atom)
        if i is None:  # a counter's value (balls(b1) = 2): by its first atom
            i = atoms.get(atom.partition(" = ")[0], len(atoms))
        return i

    def move(self, tau: Perm, m: PolicyMove) -> PolicyMove:
        """The move ``m`` on the real objects (its ``to`` and ``renaming`` unchanged)."""
        if not self.names(tau):
            return m
        return replace(m, action=self.text(tau, m.action),
                       args=self.texts(tau, m.args, ordered=m.kind == "inform"),
                       told=self.texts(tau, m.told, ordered=True))

    def node(self, tau: Perm, n: PolicyNode) -> PolicyNode:
        """The canonical node ``n`` as the real state ``tau`` maps it to: its facts and its
        moves renamed (each move's ``to`` still the canonical node's id)."""
        key = (n.id, tau)
        view = self._views.get(key)
        if view is not None:
            return view
        if not self.names(tau):
            view = n
        else:
            t = self.text
            hyps = [[t(tau, x) for x in h] for h in n.hypotheses]
            if len(hyps) > 1 and self.tasks is not None:
                tasks = self.tasks
                hyps.sort(key=lambda h: [tasks.get(x, -1) for x in h])
            view = replace(
                n, divergence=self.texts(tau, n.divergence, ordered=True),
                world_diffs=self._world_diffs(tau, n),
                state=self.texts(tau, n.state, ordered=True),
                robot_agenda=[t(tau, x) for x in n.robot_agenda],
                human_agenda=hyps[0] if len(hyps) > 1 else [t(tau, x) for x in n.human_agenda],
                moves=[self.move(tau, m) for m in n.moves], hypotheses=hyps)
        if len(self._views) >= _CACHE:
            self._views.clear()
        self._views[key] = view
        return view

    def _world_diffs(self, tau: Perm, n: PolicyNode) -> list[dict[str, list[str]]]:
        """``n``'s worlds renamed, in the order a version 2 file lists them (by the world's
        state as a bitset) when the atom order is known."""
        diffs = [{"true": self.texts(tau, d["true"], ordered=True),
                  "false": self.texts(tau, d["false"], ordered=True)} for d in n.world_diffs]
        atoms = self.atoms
        if atoms is None or len(diffs) < 2:
            return diffs
        try:
            t = sum(1 << atoms[a] for a in self.texts(tau, n.state))
            keys = [(t | sum(1 << atoms[a] for a in d["true"]))
                    & ~sum(1 << atoms[a] for a in d["false"]) for d in diffs]
        except KeyError:  # counters: keep the canonical order
            return diffs
        return [d for _, d in sorted(zip(keys, diffs, strict=True), key=lambda kd: kd[0])]


def renamings(policy: Policy, atoms: Mapping[str, int] | None = None,
              tasks: Mapping[str, int] | None = None) -> Renamings | None:
    """The renamings of a lifted policy, None for a policy over real states."""
    if policy.symmetry is None:
        return None
    return Renamings(policy.symmetry, atoms, tasks)


def content(view: PolicyNode) -> str:
    """What tells two real nodes of one canonical node apart: the node seen through a renaming,
    as JSON, without where its moves lead (two renamings that give the same facts and the same
    moves give one real node, :func:`expand`)."""
    d = view.to_dict()
    for m in d["moves"]:
        del m["to"]
        m.pop("renaming", None)
    return json.dumps(d, sort_keys=True)


def expand(policy: Policy, atoms: Mapping[str, int] | None = None,
           tasks: Mapping[str, int] | None = None,
           check: Callable[[], None] | None = None, max_nodes: int | None = None) -> Policy:
    """The version 2 graph of a lifted policy (the policy itself when it is not lifted): one
    node per real state the policy reaches, ids in the depth-first preorder of first visits,
    moves in order, as ``ehatp solve`` without symmetry numbers them.

    A real node is a canonical node seen through a renaming (:meth:`Renamings.node`); two
    renamings that give the same facts and the same moves give one node (the sub-policies
    below are then images of one). Values, leaves and communications are those of the lifted
    graph (a renaming keeps costs and counts). ``atoms``/``tasks`` (the ground problem's
    indices by name) list the facts in the problem's order; ``check`` is called once per real
    node and may raise to stop the work; past ``max_nodes`` real nodes it raises
    :class:`~ehatp.errors.PolicyTooLarge`."""
    ren = renamings(policy, atoms, tasks)
    if ren is None:
        return policy
    keys: dict[tuple[int, Perm], tuple[int, str]] = {}

    def key(n: int, tau: Perm) -> tuple[int, str]:
        k = keys.get((n, tau))
        if k is None:
            k = keys[(n, tau)] = (n, content(ren.node(tau, policy.nodes[n])))
        return k

    order: list[tuple[int, Perm]] = []
    index: dict[tuple[int, str], int] = {}
    stack = [(0, ren.root)]
    while stack:
        n, tau = stack.pop()
        k = key(n, tau)
        if k in index:
            continue
        if check is not None:
            check()
        if max_nodes is not None and len(order) >= max_nodes:
            raise PolicyTooLarge(max_nodes, len(policy.nodes))
        index[k] = len(order)
        order.append((n, tau))
        for m in reversed(policy.nodes[n].moves):
            stack.append((m.to, ren.child(tau, m.renaming)))
    nodes: list[PolicyNode] = []
    for i, (n, tau) in enumerate(order):
        view = ren.node(tau, policy.nodes[n])
        moves = [replace(m, to=index[key(m.to, ren.child(tau, m.renaming))], renaming=0)
                 for m in view.moves]
        nodes.append(replace(view, id=i, moves=moves))
    out = replace(policy, nodes=nodes, symmetry=None)
    out.leaves = out.count_branches()
    out.communications = out.count_communications()
    return out


def expanded(policy: Policy, max_nodes: int | None = None) -> Policy:
    """``policy`` as a version 2 graph, for the readers that draw or print the whole graph
    (``ehatp show``, ``render``, ``export bt``): :func:`expand` without the problem (facts keep
    their canonical positions), the policy itself when it is not lifted. Past ``max_nodes``
    real nodes, :class:`~ehatp.errors.PolicyTooLarge`."""
    return expand(policy, max_nodes=max_nodes) if policy.symmetry is not None else policy


def real_branches(policy: Policy) -> Iterator[list[PathStep]]:
    """Every root-to-leaf branch of ``policy`` over the real objects, lazily, in move order,
    as :meth:`Policy.iter_branches` gives them for its expansion (the same nodes and moves,
    facts in their canonical positions; a node's ``id`` is its canonical node's): each branch
    realised by composing the renamings along it, never the whole graph (docs/policy-format.md,
    "Version 3"). A policy that is not lifted gives its own branches."""
    ren = renamings(policy)
    if ren is None:
        yield from policy.iter_branches()
        return
    nodes = policy.nodes
    stack: list[tuple[list[PathStep], Perm]] = [
        ([PathStep(None, ren.node(ren.root, nodes[0]))], ren.root)]
    while stack:
        path, tau = stack.pop()
        last = path[-1].node
        if not last.moves:
            yield path
        for m in reversed(last.moves):  # a view's move keeps its canonical to and renaming
            child = ren.child(tau, m.renaming)
            stack.append(([*path, PathStep(m, ren.node(child, nodes[m.to]))], child))


__all__ = ["EXPAND_LIMIT", "TOKEN", "Perm", "Renamings", "content", "expand", "expanded",
           "real_branches", "renamings"]
