"""The human's worlds kept as classes (issue 17 §2; docs/semantics.md §3, "Worlds as classes").

A search over canonical states (:mod:`.symmetry`) keeps every world of ``W``. Many of them are
renamings of one another under a renaming that leaves the whole node as it is: at 16 cubes /
3 boxes / K=8 the node with the most worlds holds 2,007 of them in 20 classes. This module
keeps such a ``W`` as one representative per class with its multiplicity
(:class:`WorldClasses`), and gives the canonical form of a node over classes
(:class:`ClassSymmetry`); :mod:`.classsemantics` applies the rules to them.

**The group.** Only objects of *unary* classes are renamed: interchangeable objects no atom and
no task names two of (with the greedy choice of :class:`Classer`, the cubes of the cube
domain, not its boxes, since ``in(c, b)`` names one of each). A world is then its part naming
no such object and, per unary object ``o``, its *profile*: the atoms of the world's state and
the positions and tasks of its robot agenda that name ``o``, with ``o`` as "self". A renaming
``g`` within the unary classes moves profiles, no more: the world ``g·w`` has at ``g(o)`` the
profile ``w`` has at ``o``.

The *cells* of a node are the classes of the relation "swapping ``a`` and ``b`` leaves the
true state, the robot's agenda, each human agenda of ``A_H`` and ``W`` as they are", within
one unary class. It is an equivalence (``(a c) = (a b)(b c)(a b)``), so the cells are a
function of the node, and every permutation within the cells (the group ``G`` they generate)
leaves the node as it is. ``W`` is a union of ``G``-orbits; an orbit's representative is the
world whose profiles are sorted within each cell (objects in index order), and its size is
``∏ |C|! / ∏ m_p!`` over the cells ``C`` and the multiplicities ``m_p`` of the profiles in
``C``. Stored this way, ``W`` is a function of the node: equal nodes have equal forms.

**Finding the cells** (:meth:`Classer.fit`). A subgroup ``H`` of ``G`` whose cells are known
to leave the node as it is (the parent's, split where the move changed a profile; or one
object per cell) gives the classes of ``W`` under ``H``; two cells ``C1``, ``C2`` whose objects
agree on the true state and the agendas merge exactly when ``W`` is invariant under the
permutations of ``C1 ∪ C2``, that is when the orbits of the representatives under the merged
cells have sizes that add up to ``|W|`` (``W`` is within their union, so it is their union
exactly when the counts agree). Since the relation is an equivalence, merging greedily finds
the cells.

**Multiplicities and |W|.** ``len`` of a ``WorldClasses`` (``epistemic/classworlds.py``) is
its number of classes (it is a tuple of representatives, as every container of worlds the
rules may read is a tuple); its ``count`` is ``|W|``, the sum of the multiplicities, which is
what the search reports.
:meth:`Classer.expand` lists the worlds, sorted, as the rules without a class form and the
policy's nodes read them.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from itertools import combinations, product
from typing import Any

from ..epistemic.classworlds import Cells, WorldClasses
from ..epistemic.state import EState, World, Worlds
from ..model.agenda import Agenda
from ..model.grounded import Grounded
from .symmetry import Symmetry, _WorldColumns

Profile = tuple[int, int]  # (state profile id, agenda profile id) of one object in one world

_FACT = [1]
for _i in range(1, 200):
    _FACT.append(_FACT[-1] * _i)

PROFILE_CACHE = 1 << 18
"""How many states' (agendas') profiles :class:`Classer` remembers before it starts afresh."""

EXPANDED_CACHE = 8
"""How many sets of classes :meth:`Classer.expand` keeps listed (a node's worlds are listed
for its moves, its goal test and its policy node; at 30 cubes / 4 boxes / K=8 one holds
35,916 worlds)."""


def _distinct_permutations(items: Sequence[Profile]) -> Iterator[tuple[Profile, ...]]:
    """Each distinct ordering of the multiset ``items`` (sorted), once, in sorted order."""
    pool = sorted(items)
    n = len(pool)
    counts = Counter(pool)
    keys = sorted(counts)
    out: list[Profile] = []

    def rec() -> Iterator[tuple[Profile, ...]]:
        if len(out) == n:
            yield tuple(out)
            return
        for k in keys:
            if counts[k]:
                counts[k] -= 1
                out.append(k)
                yield from rec()
                out.pop()
                counts[k] += 1

    return rec()


def _splits(pool: tuple[Profile, ...], sizes: Sequence[int]) -> Iterator[list[tuple[Profile, ...]]]:
    """Each way to share the multiset ``pool`` (sorted) among parts of ``sizes``, each part
    sorted, once."""
    if not sizes:
        yield []
        return
    seen: set[tuple[Profile, ...]] = set()
    for idx in combinations(range(len(pool)), sizes[0]):
        part = tuple(pool[i] for i in idx)
        if part in seen:
            continue
        seen.add(part)
        left = list(pool)
        for i in reversed(idx):
            del left[i]
        for rest in _splits(tuple(left), sizes[1:]):
            yield [part, *rest]


def _owned(roles: dict[int, tuple[tuple[int, int], ...]], keys: dict[int, tuple[int, ...]],
           unary: set[int], codes: dict[tuple[int, ...], int]
           ) -> tuple[dict[int, int], dict[int, int], dict[tuple[int, int], int]]:
    """Return, for the atoms (tasks) of ``roles`` that name a unary object: that object, the
    code of the atom with the object as "self" (``codes``, shared, grows), and the atom of
    each (code, object)."""
    owner: dict[int, int] = {}
    code: dict[int, int] = {}
    at: dict[tuple[int, int], int] = {}
    for i, named in roles.items():
        owners = [o for o, _ in named if o in unary]
        if owners:
            o = owners[0]
            c = codes.setdefault(tuple(-1 if x == o else x for x in keys[i]), len(codes))
            owner[i], code[i] = o, c
            at[(c, o)] = i
    return owner, code, at


class Classer:
    """The profiles of a ground problem's unary objects (the module's docstring), and the
    operations on :class:`WorldClasses`: representatives, sizes, expansion, the cells of a
    node."""

    def __init__(self, sym: Symmetry) -> None:
        self.sym = sym
        n = len(sym.objects)
        together: set[tuple[int, int]] = set()  # classes some atom or task names two of
        for roles in (*sym._atom_roles.values(), *sym._task_roles.values()):
            named = [sym.class_of[o] for o, _ in roles]
            for a, b in combinations(named, 2):
                together.add((min(a, b), max(a, b)))
        chosen: list[int] = []
        for c in sorted(range(len(sym.classes)), key=lambda c: (-len(sym.classes[c]), c)):
            if (c, c) in together or any((min(c, d), max(c, d)) in together for d in chosen):
                continue
            chosen.append(c)
        self.unary = sorted(o for c in chosen for o in sym.classes[c])
        unary = set(self.unary)
        codes: dict[tuple[int, ...], int] = {}
        # per atom (task) naming a unary object: that object, the atom's code with it as
        # "self", and back from (code, object) to the atom (task)
        self._atom_owner, self._atom_code, self._atom_at = _owned(
            sym._atom_roles, sym._atom_keys, unary, codes)
        self.atom_mask = 0
        for i in self._atom_owner:
            self.atom_mask |= 1 << i
        self._object_mask = [sym._object_atoms[o] & self.atom_mask for o in range(n)]
        self._task_owner, self._task_code, self._task_at = _owned(
            sym._task_roles, sym._task_keys, unary, codes)
        self._n = n
        self._sp: dict[int, tuple[int, ...]] = {}
        self._ap: dict[Agenda, tuple[int, ...]] = {}
        self._plain: dict[Agenda, bool] = {}  # agenda -> it names no unary object
        self._sprofs: dict[tuple[int, ...], int] = {(): 0}
        self._sprof_values: list[tuple[int, ...]] = [()]
        self._aprofs: dict[tuple[tuple[int, int], ...], int] = {(): 0}
        self._aprof_values: list[tuple[tuple[int, int], ...]] = [()]
        self._atoms_of: dict[tuple[int, int], int] = {}
        self._expanded: dict[WorldClasses, Worlds] = {}

    @property
    def active(self) -> bool:
        """Whether the problem has unary objects to keep worlds as classes by."""
        return bool(self.unary)

    # -- profiles ------------------------------------------------------------------------------
    def sprof(self, s: int) -> tuple[int, ...]:
        """Per object, the id of its state profile in ``s`` (0: none of its atoms holds)."""
        r = self._sp.get(s)
        if r is None:
            acc: dict[int, list[int]] = {}
            owner, code = self._atom_owner, self._atom_code
            m = s & self.atom_mask
            while m:
                low = m & -m
                i = low.bit_length() - 1
                acc.setdefault(owner[i], []).append(code[i])
                m ^= low
            ids = self._interned({o: tuple(sorted(cs)) for o, cs in acc.items()},
                                 self._sprofs, self._sprof_values)
            if len(self._sp) >= PROFILE_CACHE:
                self._sp.clear()
            r = self._sp[s] = ids
        return r

    def aprof(self, ag: Agenda) -> tuple[int, ...]:
        """Per object, the id of its agenda profile in ``ag``: (position, task as "self")."""
        r = self._ap.get(ag)
        if r is None:
            acc: dict[int, list[tuple[int, int]]] = {}
            owner, code = self._task_owner, self._task_code
            for pos, t in enumerate(ag):
                if isinstance(t, int) and t in owner:
                    acc.setdefault(owner[t], []).append((pos, code[t]))
            ids = self._interned({o: tuple(ps) for o, ps in acc.items()},
                                 self._aprofs, self._aprof_values)
            if len(self._ap) >= PROFILE_CACHE:
                self._ap.clear()
                self._plain.clear()
            r = self._ap[ag] = ids
            self._plain[ag] = not acc
        return r

    def _interned(self, acc: dict[int, Any], index: dict[Any, int], values: list[Any]
                  ) -> tuple[int, ...]:
        """Per object, the id in ``index`` (``values``) of its profile in ``acc`` (0: none)."""
        ids = [0] * self._n
        for o, key in acc.items():
            ids[o] = Symmetry._intern(key, index, values)
        return tuple(ids)

    def _atoms(self, o: int, sp: int) -> int:
        """The atoms of state profile ``sp`` at object ``o``, as a mask."""
        key = (o, sp)
        m = self._atoms_of.get(key)
        if m is None:
            m = 0
            for c in self._sprof_values[sp]:
                m |= 1 << self._atom_at[(c, o)]
            self._atoms_of[key] = m
        return m

    def assign(self, w: World, changes: Iterable[tuple[int, Profile]]) -> World:
        """Return ``w`` with each object of ``changes`` given its profile there (the profiles
        changed must be a permutation of the ones they replace within each cell)."""
        s, a = w
        clear = add = 0
        agenda: list[Any] | None = None
        for o, (sp, ap) in changes:
            clear |= self._object_mask[o]
            add |= self._atoms(o, sp)
            if ap:
                if agenda is None:
                    agenda = list(a)
                for pos, c in self._aprof_values[ap]:
                    agenda[pos] = self._task_at[(c, o)]
        return ((s & ~clear) | add, a if agenda is None else tuple(agenda))

    def object_atoms(self, o: int) -> int:
        """The atoms naming unary object ``o``, as a mask."""
        return self._object_mask[o]

    def profiles(self, w: World) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """Per object, its state and agenda profile ids in ``w``."""
        return self.sprof(w[0]), self.aprof(w[1])

    # -- classes -------------------------------------------------------------------------------
    def canonical(self, w: World, cells: Cells) -> World:
        """Return the representative of ``w``'s class under ``cells``: each cell's profiles
        sorted, over its objects in index order."""
        s, a = w
        sp = self._sp.get(s) or self.sprof(s)
        if not a or self._plain.get(a, False):  # its robot agenda names no unary object
            changes: list[tuple[int, Profile]] | None = None
            for cell in cells:
                profs = [sp[o] for o in cell]
                srt = sorted(profs)
                if srt != profs:
                    if changes is None:
                        changes = []
                    changes.extend((o, (q, 0)) for o, p, q in zip(cell, profs, srt, strict=True)
                                   if p != q)
            return self.assign(w, changes) if changes else w
        ap = self.aprof(a)
        changes = None
        for cell in cells:
            pairs = [(sp[o], ap[o]) for o in cell]
            ordered = sorted(pairs)
            if ordered != pairs:
                if changes is None:
                    changes = []
                changes.extend((o, q) for o, p, q in zip(cell, pairs, ordered, strict=True)
                               if p != q)
        return self.assign(w, changes) if changes else w

    def size(self, rep: World, cells: Cells) -> int:
        """Return the size of the class of representative ``rep`` under ``cells``:
        ``∏ |C|! / ∏ m_p!`` (equal profiles are next to one another in a representative)."""
        sp, ap = self.sprof(rep[0]), self.aprof(rep[1])
        size = 1
        for cell in cells:
            n = _FACT[len(cell)]
            prev, run = (sp[cell[0]], ap[cell[0]]), 0
            for o in cell:
                q = (sp[o], ap[o])
                if q == prev:
                    run += 1
                else:
                    n //= _FACT[run]
                    prev, run = q, 1
            size *= n // _FACT[run]
        return size

    def classes_of(self, worlds: Iterable[World], cells: Cells) -> WorldClasses:
        """Return the classes under ``cells`` of the worlds ``worlds`` (each counted once per
        class: a union of classes is what :meth:`make` is given)."""
        reps: dict[World, int] = {}
        canonical, size = self.canonical, self.size
        for w in worlds:
            r = canonical(w, cells)
            if r not in reps:
                reps[r] = size(r, cells)
        return self.make(reps, cells)

    def make(self, reps: dict[World, int], cells: Cells) -> WorldClasses:
        """Return the classes ``reps`` (representative -> size) under ``cells``."""
        order = sorted(reps)
        return WorldClasses(order, cells, [reps[r] for r in order], self)

    def compress(self, worlds: Sequence[World], cells: Cells) -> WorldClasses | None:
        """Return ``worlds`` (distinct) as classes under ``cells``, or None when the set is
        not a union of their orbits (then ``cells`` do not leave it as it is)."""
        wc = self.classes_of(worlds, cells)
        return wc if wc.size == len(worlds) else None

    def expand(self, wc: Worlds) -> Worlds:
        """Return the worlds ``wc`` stands for, sorted (a plain tuple of worlds as it is)."""
        if not isinstance(wc, WorldClasses):
            return wc
        r = self._expanded.get(wc)
        if r is None:
            out: list[World] = []
            for rep in wc:
                sp, ap = self.profiles(rep)
                cols = [(cell, [(sp[o], ap[o]) for o in cell]) for cell in wc.cells]
                orders = [list(_distinct_permutations(p)) for _, p in cols]
                for choice in product(*orders):
                    changes = [(o, q) for (cell, p), ps in zip(cols, choice, strict=True)
                               for o, was, q in zip(cell, p, ps, strict=True) if was != q]
                    out.append(self.assign(rep, changes) if changes else rep)
            out.sort()
            r = tuple(out)
            if len(self._expanded) >= EXPANDED_CACHE:
                self._expanded.clear()
            self._expanded[wc] = r
        return r

    def refine(self, wc: WorldClasses, key: Sequence[Any]) -> WorldClasses:
        """Return ``wc`` under the cells split by ``key`` (per object: objects stay in one cell
        only if their keys are equal), each class split into the classes of the smaller
        group: its cells' profiles shared among the parts in every distinct way."""
        new: list[tuple[int, ...]] = []
        split: list[tuple[tuple[int, ...], list[tuple[int, ...]]]] = []
        for cell in wc.cells:
            parts: dict[Any, list[int]] = {}
            for o in cell:
                parts.setdefault(key[o], []).append(o)
            if len(parts) == 1:
                new.append(cell)
                continue
            ps = [tuple(p) for p in parts.values()]
            split.append((cell, ps))
            new.extend(p for p in ps if len(p) > 1)
        if not split:
            return wc
        cells = tuple(sorted(new))
        worlds: list[World] = []
        for rep in wc:
            sp, ap = self.profiles(rep)
            options = []
            for cell, ps in split:
                pool = tuple(sorted((sp[o], ap[o]) for o in cell))
                options.append([(ps, share) for share in _splits(pool, [len(p) for p in ps])])
            for choice in product(*options):
                changes = []
                for ps, share in choice:
                    for part, profs in zip(ps, share, strict=True):
                        for o, q in zip(part, profs, strict=True):
                            if (sp[o], ap[o]) != q:
                                changes.append((o, q))
                worlds.append(self.assign(rep, changes) if changes else rep)
        out = self.classes_of(worlds, cells)
        assert out.size == wc.size, "a split lost or made worlds"
        return out

    def node_key(self, es: EState) -> list[Any]:
        """Per object, what the node's true state and agendas say of it: objects of one cell
        have equal keys (and a class unary)."""
        sp = self.sprof(es.true)
        rp = self.aprof(es.robot_agenda)
        hps = [self.aprof(h) for h in es.human_agendas]
        cls = self.sym.class_of
        return [(cls.get(o), sp[o], rp[o], tuple(h[o] for h in hps)) for o in range(self._n)]

    def _merged(self, wc: WorldClasses, a: tuple[int, ...], b: tuple[int, ...]
                ) -> WorldClasses | None:
        """``wc`` under its cells with ``a`` and ``b`` one cell, or None when ``W`` is not
        invariant under the permutations of their union (the counts disagree)."""
        union = tuple(sorted(a + b))
        cells = tuple(sorted([c for c in wc.cells if c != a and c != b] + [union]))
        out = self.classes_of(wc, cells)
        return out if out.size == wc.size else None

    def _column(self, wc: WorldClasses, cell: tuple[int, ...]) -> tuple[tuple[Profile, int], ...]:
        """Return the multiset, over the worlds ``wc`` stands for, of the profile of one
        object of ``cell`` (a cell of ``wc``, or one object outside its cells): equal for
        every object of a cell, so two cells whose union leaves ``W`` as it is have equal
        ones."""
        acc: Counter[Profile] = Counter()
        for rep, m in zip(wc, wc.mults, strict=True):
            sp, ap = self.sprof(rep[0]), self.aprof(rep[1])
            for o in cell:
                acc[(sp[o], ap[o])] += m
        return tuple(sorted((p, n // len(cell)) for p, n in acc.items()))

    def maximal(self, wc: WorldClasses, key: Sequence[Any]) -> WorldClasses:
        """Return ``wc`` under the node's cells: its cells (which must leave the node as it
        is) merged greedily wherever the node stays invariant (the module's docstring),
        tried only between cells on which the node's true state and agendas agree and
        whose objects' profiles have the same multiset over ``W``."""
        in_cell = {o for c in wc.cells for o in c}
        groups: dict[Any, list[tuple[int, ...]]] = {}
        for c in wc.cells:
            groups.setdefault(key[c[0]], []).append(c)
        for o in self.unary:
            if o not in in_cell:
                groups.setdefault(key[o], []).append((o,))
        for cs in groups.values():
            if len(cs) < 2:
                continue
            by_column: dict[Any, list[tuple[int, ...]]] = {}
            for c in sorted(cs):
                by_column.setdefault(self._column(wc, c), []).append(c)
            for same in by_column.values():
                kept: list[tuple[int, ...]] = []
                for c in same:
                    for i, m in enumerate(kept):
                        got = self._merged(wc, m, c)
                        if got is not None:
                            wc = got
                            kept[i] = tuple(sorted(m + c))
                            break
                    else:
                        kept.append(c)
        return wc

    def fit(self, es: EState) -> WorldClasses:
        """Return ``es.worlds`` under the cells of ``es`` (the module's docstring): from the
        cells it has (a plain tuple: none), split where the node tells objects apart, then
        merged."""
        key = self.node_key(es)
        ws = es.worlds
        if not isinstance(ws, WorldClasses):
            reps = {w: 1 for w in ws}
            wc = self.make(reps, ())
        else:
            wc = self.refine(ws, key)
        return self.maximal(wc, key)

    def rename(self, pid: int, wc: WorldClasses) -> WorldClasses:
        """Return ``wc`` renamed by ``pid`` (a renaming maps classes onto classes and keeps
        their sizes)."""
        sym = self.sym
        p = sym.perms[pid]
        cells = tuple(sorted(tuple(sorted(p[o] for o in c)) for c in wc.cells))
        reps: dict[World, int] = {}
        for (s, a), m in zip(wc, wc.mults, strict=True):
            reps[self.canonical((sym.state(pid, s), sym.agenda(pid, a)), cells)] = m
        return self.make(reps, cells)

    def columns(self, wc: WorldClasses) -> list[Counter[tuple[int, int]]]:
        """Per object, over the worlds ``wc`` stands for, how many give it each (state role
        signature, agenda role signature) pair (:meth:`Symmetry.canon`'s column): a class of
        ``N`` worlds gives an object of a cell ``C`` each pair the cell's objects have in the
        representative, ``N / |C|`` times per object; any other object its own, ``N``
        times."""
        sym = self.sym
        n = self._n
        cell_of: list[tuple[int, ...] | None] = [None] * n
        for c in wc.cells:
            for o in c:
                cell_of[o] = c
        alone = [o for o in range(n) if cell_of[o] is None]
        own: list[Counter[tuple[int, int]]] = [Counter() for _ in range(n)]
        shared: dict[tuple[int, ...], Counter[tuple[int, int]]] = {c: Counter() for c in wc.cells}
        for (s, a), m in zip(wc, wc.mults, strict=True):
            sids, aids = sym._state_ids(s), sym._agenda_ids(a)
            for o in alone:
                own[o][(sids[o], aids[o])] += m
            for c, acc in shared.items():
                for x in c:
                    acc[(sids[x], aids[x])] += m
        for c, acc in shared.items():
            k = len(c)
            col: Counter[tuple[int, int]] = Counter()
            for pair, v in acc.items():
                assert v % k == 0
                col[pair] = v // k
            for o in c:
                own[o] = col
        return own


class _ClassColumns:
    """:class:`~.symmetry._WorldColumns` read from classes, without listing the worlds."""

    __slots__ = ("cols", "keys", "sym", "worlds")

    def __init__(self, sym: ClassSymmetry, worlds: WorldClasses) -> None:
        self.sym = sym
        self.worlds = worlds
        self.cols: list[Counter[tuple[int, int]]] | None = None
        self.keys: list[list[tuple[Any, int]] | None] = [None] * len(sym.objects)

    def key(self, o: int) -> list[tuple[Any, int]]:
        """As :meth:`~.symmetry._WorldColumns.key`."""
        r = self.keys[o]
        if r is None:
            sym = self.sym
            if self.cols is None:
                self.cols = sym.classer.columns(self.worlds)
            sv, av = sym._sig_values, sym._ag_values
            r = self.keys[o] = sorted([((sv[s], av[a]), -c)
                                       for (s, a), c in self.cols[o].items()])
        return r


class ClassSymmetry(Symmetry):
    """:class:`~.symmetry.Symmetry` whose nodes keep their worlds as classes: the canonical
    form (§3, "Symmetry") is the same renaming, computed from the classes, and the node it
    gives keeps its worlds under its cells (:meth:`Classer.fit`)."""

    def __init__(self, grounded: Grounded, classes: list[list[str]]) -> None:
        super().__init__(grounded, classes)
        self.classer = Classer(self)

    def canon(self, es: EState) -> tuple[EState, int]:
        """§3: :meth:`Symmetry.canon` of the node with its worlds under its cells; the same
        renaming as over the worlds listed (the columns are equal), so the same policies."""
        es = es._replace(worlds=self.classer.fit(es))
        return super().canon(es)

    def _world_columns(self, worlds: Worlds) -> _WorldColumns | _ClassColumns:
        if isinstance(worlds, WorldClasses):
            return _ClassColumns(self, worlds)
        cols: _WorldColumns = super()._world_columns(worlds)
        return cols

    def worlds(self, pid: int, ws: Worlds) -> Worlds:
        """The worlds ``ws`` renamed (classes stay classes)."""
        if isinstance(ws, WorldClasses):
            return ws if pid == 0 else self.classer.rename(pid, ws)
        return super().worlds(pid, ws)

    def explicit(self, es: EState) -> EState:
        """``es`` with its worlds listed."""
        if isinstance(es.worlds, WorldClasses):
            return es._replace(worlds=self.classer.expand(es.worlds))
        return es


__all__ = ["Classer", "ClassSymmetry"]
