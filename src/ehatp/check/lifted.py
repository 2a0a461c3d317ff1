"""Lifted policies (policy format version 3) as the validator checks them, without expanding
them (docs/semantics.md §3, "Symmetry"; the format: the policy's ``symmetry`` table and each
move's ``renaming``).

A lifted policy's nodes are canonical states; its ``symmetry`` table lists the movable
objects, their classes and the renamings (permutations of the objects by index), ``root`` the
renaming that maps the real initial node onto the root node, and each move the renaming that
maps the real successor of its (canonical) parent onto its child node. The validator checks
(a) that every renaming it meets is a permutation within the declared classes, each class's
objects of one type, and an automorphism of the ground problem (:mod:`.automorphism`); (b)
that the root node is its own initial node renamed by ``renamings[root]``; (c) along every
edge, that its own successor of the canonical parent, renamed by the edge's renaming, is the
child node's state. Every other rule is then checked on the canonical nodes as for version 2:
values, costs and counts do not change under a renaming.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import Any

from ..formats.policy import Policy
from ..model.grounding import ground_problem
from ..model.problem import Problem
from .automorphism import TOKEN, Renaming, lazy, named_objects, ordered_methods
from .communication import Semantics
from .rules import Rules, Worlds


@dataclass
class Lifted:
    """A lifted policy's symmetry table and the renaming of each move, as recorded (not yet
    checked: :class:`LiftedCheck` does)."""

    objects: list[Any]
    classes: list[Any]
    renamings: list[Any]
    root: Any = 0
    edges: dict[tuple[int, int], Any] = field(default_factory=dict)  # (node, move) -> id

    def renaming_of(self, node: int, move: int) -> Any:
        return self.edges.get((node, move), 0)


def _field(x: Any, key: str, default: Any = None) -> Any:
    if isinstance(x, dict):
        return x.get(key, default)
    return getattr(x, key, default)


def lifted_of(policy: Policy) -> Lifted | None:
    """The symmetry table of a policy read as version 3 (its ``symmetry`` and the moves'
    ``renaming``), or None for a policy of real states (version 1 or 2)."""
    sym = getattr(policy, "symmetry", None)
    if sym is None:
        return None
    edges = {(n.id, j): r for n in policy.nodes for j, m in enumerate(n.moves)
             if (r := getattr(m, "renaming", 0))}
    return Lifted(list(_field(sym, "objects", []) or []), list(_field(sym, "classes", []) or []),
                  list(_field(sym, "renamings", []) or []), _field(sym, "root", 0), edges)


def split_v3(d: dict[str, Any]) -> tuple[dict[str, Any], Lifted | None]:
    """A policy's JSON object as version 2 fields and its lifted table (None for version 1
    or 2): for a reader that does not keep ``symmetry`` and ``renaming`` itself."""
    if d.get("version") != 3 or "symmetry" not in d:
        return d, None
    sym = d["symmetry"]
    nodes, edges = [], {}
    for n in d.get("nodes", []):
        moves = []
        for j, m in enumerate(n.get("moves", [])):
            m = dict(m)
            r = m.pop("renaming", 0)
            if r != 0:
                edges[n.get("id"), j] = r
            moves.append(m)
        nodes.append({**n, "moves": moves})
    v2 = {k: v for k, v in d.items() if k != "symmetry"}
    v2.update(version=2, nodes=nodes)
    return v2, Lifted(list(sym.get("objects", [])), list(sym.get("classes", [])),
                      list(sym.get("renamings", [])), sym.get("root", 0), edges)


class LiftedCheck:
    """The checks of a lifted policy's renamings against one problem: the table's shape, then
    each renaming once, when the replay first uses it (:meth:`renaming`)."""

    def __init__(self, problem: Problem, rules: Rules, lifted: Lifted) -> None:
        self.problem, self.rules, self.lifted = problem, rules, lifted
        self.table_error = self._table()
        self._done: dict[int, Renaming | str] = {}
        self._named = named_objects(problem)
        g = rules.grounded
        self._whole = ground_problem(problem, ahead=sys.maxsize) if lazy(g) else g
        self.order_issue = False  # an observation whose result a renaming could change
        twins = {o for c in lifted.classes if isinstance(c, list) and len(c) > 1 for o in c}
        self.movable = 0  # the atoms naming an interchangeable object
        for i, name in enumerate(g.atoms):
            if twins.intersection(TOKEN.findall(name)):
                self.movable |= 1 << i
        self.tie_issue = False  # an informing set chosen by name, a renaming could change
        rules.watch = self.watch
        if isinstance(rules, Semantics):
            rules.ties = self.tied

    def tied(self, chosen: tuple[int, ...], others: list[tuple[int, ...]]) -> None:
        """§3, §5: the informing set ``chosen`` won over ``others`` by atom names alone; when
        one of them names an interchangeable object, a renaming can change the names' order,
        so the real states the node stands for may choose another set."""
        for units in (chosen, *others):
            if any(u & self.movable for u in units):
                self.tie_issue = True
                return

    def watch(self, worlds: Worlds, t: int, mask: int) -> None:
        """§3: an observation of the atoms ``mask`` (units whole) by worlds ``worlds`` in the
        true state ``t`` on which the order of the units could matter: two or more units on
        which the worlds differ, none agreeing with ``t`` on all of them, one naming an
        interchangeable object. Observation goes unit by unit in index order (§2), which a
        renaming changes, so the reduction does not hold there."""
        if not mask & self.movable or self.order_issue:
            return
        varying = count = 0
        for u in self.rules.grounded.units(mask):
            part = u & mask
            if len({s & part for s, _ in worlds}) > 1:
                varying |= part
                count += 1
        if count < 2 or not varying & self.movable:
            return
        if not any(s & varying == t & varying for s, _ in worlds):
            self.order_issue = True

    def _table(self) -> str | None:
        """Why the declared objects and classes are no table of interchangeable objects
        (§3), or None: objects are the problem's, each in one class, a class's objects of one
        type."""
        lf = self.lifted
        types: dict[str, set[str]] = {}
        for t, objs in self.problem.objects.items():
            for o in objs:
                types.setdefault(o, set()).add(t)
        objs = lf.objects
        if not all(isinstance(o, str) for o in objs) or len(set(objs)) != len(objs):
            return "symmetry.objects must name distinct objects"
        unknown = [o for o in objs if o not in types]
        if unknown:
            return f"symmetry.objects names {unknown[0]!r}, not an object of the problem"
        members = [o for c in lf.classes if isinstance(c, list) for o in c]
        if (not all(isinstance(c, list) for c in lf.classes)
                or not all(isinstance(o, str) for o in members)
                or sorted(members) != sorted(objs)):
            return "symmetry.classes must put each of symmetry.objects in exactly one class"
        for c in lf.classes:
            if len({frozenset(types[o]) for o in c}) > 1:
                return f"symmetry class {c} mixes objects of different types (§3)"
        if not lf.renamings:
            return "symmetry.renamings is empty (renamings[0] is the identity)"
        return None

    def renaming(self, rid: Any) -> Renaming | str:
        """Renaming ``rid`` of the table, checked (§3): a permutation of the objects within
        their classes and an automorphism of the problem; else why not, in one line."""
        if self.table_error is not None:
            return self.table_error
        lf = self.lifted
        if not isinstance(rid, int) or isinstance(rid, bool) or not 0 <= rid < len(lf.renamings):
            return (f"renaming {rid!r} is not in the symmetry table (ids 0 to "
                    f"{len(lf.renamings) - 1})")
        got = self._done.get(rid)
        if got is None:
            got = self._done[rid] = self._check(rid, lf.renamings[rid])
        return got

    def renamed_nodes(self, policy: Policy, order: list[int]) -> set[int]:
        """The nodes (``order``: children first) that stand for a real state through a
        renaming other than the identity on some path from the root: where a step must not
        depend on a decision a renaming changes (§3). Each node keeps at most two of the
        renamings composed along the paths to it (``tau``: the node's names to the real ones),
        enough to tell whether one is not the identity."""
        lf = self.lifted
        perm: dict[Any, tuple[int, ...]] = {}

        def inverse(rid: Any) -> tuple[int, ...] | None:
            if rid not in perm:
                ren = self.renaming(rid)
                if isinstance(ren, str):
                    return None
                inv = [0] * len(lf.renamings[rid])
                for i, j in enumerate(lf.renamings[rid]):
                    inv[j] = i
                perm[rid] = tuple(inv)
            return perm[rid]

        root = inverse(lf.root)
        if root is None:
            return set()
        taus: dict[int, list[tuple[int, ...]]] = {0: [root]}
        for n in reversed(order):  # parents first
            for j, move in enumerate(policy.nodes[n].moves):
                inv = inverse(lf.renaming_of(n, j))
                if inv is None:
                    continue
                kept = taus.setdefault(move.to, [])
                for tau in taus.get(n, []):
                    child = tuple(tau[i] for i in inv)
                    if len(kept) < 2 and child not in kept:
                        kept.append(child)
        ident = tuple(range(len(lf.objects)))
        return {n for n, ts in taus.items() if any(t != ident for t in ts)}

    def checked(self) -> set[int]:
        """The renamings checked so far (the ones the replay used)."""
        return set(self._done)

    def _check(self, rid: int, image: Any) -> Renaming | str:
        lf = self.lifted
        n = len(lf.objects)
        what = f"renaming {rid} {image}"
        if (not isinstance(image, list) or len(image) != n
                or not all(isinstance(i, int) and not isinstance(i, bool) for i in image)
                or sorted(image) != list(range(n))):
            return f"{what} is not a permutation of the {n} objects of symmetry.objects"
        cls = {o: k for k, c in enumerate(lf.classes) for o in c}
        for i, j in enumerate(image):
            if cls[lf.objects[i]] != cls[lf.objects[j]]:
                return (f"{what} maps {lf.objects[i]} onto {lf.objects[j]}, of another class: "
                        "not a permutation within the declared classes (§3)")
        ren = Renaming(self.rules.grounded, lf.objects, image, self.rules.canon)
        if ren.identity:
            return ren
        if ordered_methods(self.rules.grounded):
            return (f"{what} ({ren.shown()}): partially ordered methods turn the reduction "
                    "off (§3)")
        whole = ren if self._whole is self.rules.grounded else Renaming(
            self._whole, lf.objects, image, self.rules.canon)
        why = whole.why_not(self.problem, self._named)
        if why is not None:
            return f"{what} ({ren.shown()}) is not an automorphism of the problem (§3): {why}"
        return ren


def shown(rid: Any, ren: Renaming | str) -> str:
    """How a message names an edge's renaming."""
    if isinstance(ren, str) or ren.identity:
        return ""
    return f", renamed by renaming {rid} ({ren.shown()})"


__all__ = ["Lifted", "LiftedCheck", "lifted_of", "shown", "split_v3"]
