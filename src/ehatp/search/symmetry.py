"""Search over symmetry-reduced epistemic states (docs/semantics.md §3, "Symmetry").

Interchangeable objects (the cubes of one table, two empty boxes) multiply the states the search
meets: a state and the same state with two cubes' names swapped have the same value, and their
policies are each other's image. :mod:`.interchangeable` finds such objects from the ground
problem as data; this module gives the search a *canonical* representative of each state,
with the renaming that maps the state to it, so that extraction can map the chosen policy back
to the real objects.

**Symmetries.** A renaming of objects (within one type) is an *automorphism* of the ground
problem when it maps it onto itself: the initial state, the belief worlds with their robot
agendas, both agendas, the observable / inferable / hidden atoms and the visibility groups, the
co-presence and goal formulas, and the three models' ground operators (precondition, effects,
cost, done-condition), methods (precondition, subtasks, order) and done-conditions (static atoms
are folded into those formulas). Objects named by the problem — in an agenda, a goal literal,
``after``, a belief world's robot agenda, a cost or objective weight by ground label, or a
domain constant — are fixed. Two objects of one own type are *interchangeable* when swapping
them is an automorphism (checked formula by formula, conjunctions and disjunctions compared as
sets); interchangeability is an equivalence (a swap ``(a c)`` is ``(a b)(b c)(a b)``), so its
classes are found with one check per object and class, and every permutation within the classes
is an automorphism (transpositions generate them).

**Equivariance.** The transition rules commute with an automorphism, except where they decide
by index or name order: belief revision observes units one at a time in index order (§2), and
the informing set's last tie-break is by name (§5). :class:`SymSemantics` watches both: an
observation whose result could depend on the order of the units it touches (two or more units
on which the worlds differ, no world agreeing with the truth on all of them, one of them naming
an interchangeable object), or an informing set tied with another on everything but names,
marks the search *unsafe*, and the planner solves again without symmetry. Extraction replays
every policy node on the real problem and checks each move against the real semantics; a
mismatch also falls back (it would be a bug, never a wrong policy).
"""

from __future__ import annotations

import re
import warnings
from collections import Counter
from collections.abc import Iterable
from itertools import combinations
from typing import Any

from ..epistemic.semantics import Semantics
from ..epistemic.state import EState, Worlds, states_of
from ..model.agenda import Agenda
from ..model.grounded import Grounded
from ..model.problem import Limits

OVERRIDE: bool | None = None
"""Deprecated, goes in the next release: pass ``symmetry=`` to ``solve`` instead. When not
None, replaces every problem's ``[limits] symmetry`` in a solve whose caller does not say
(worker processes forked later inherit it)."""


def enabled(symmetry: bool | None, limits: Limits) -> bool:
    """Return whether a solve searches over canonical states: ``symmetry`` when the caller
    says, else the problem's ``[limits] symmetry`` (unless the deprecated :data:`OVERRIDE`
    says otherwise)."""
    if symmetry is not None:
        return symmetry
    if OVERRIDE is not None:
        warnings.warn("ehatp.search.symmetry.OVERRIDE is deprecated and goes in the next "
                      "release: pass symmetry=True/False to solve()", DeprecationWarning,
                      stacklevel=3)
        return OVERRIDE
    return limits.symmetry

RENAMED_CACHE = 1 << 20
"""How many renamed world states :meth:`Symmetry.state` remembers before it starts afresh."""

COLUMNS_CACHE = 1 << 10
"""How many sets of worlds :meth:`Symmetry.canon` keeps the signatures of."""

_TOKEN = re.compile(r"[^\s(),=\[\]<>!|{}+;:]+")

Perm = tuple[int, ...]  # image of each movable object, by index into Symmetry.objects


def _split(name: str) -> tuple[str, tuple[str, ...], str]:
    """``loc(c1) = box1`` -> ("loc", ("c1",), " = box1"); ``on(a, b)`` -> ("on", ("a", "b"),
    ""); ``washed`` -> ("washed", (), "")."""
    head, par, rest = name.partition("(")
    if not par:
        return head, (), ""
    inside, _, suffix = rest.partition(")")
    args = tuple(a.strip() for a in inside.split(",")) if inside.strip() else ()
    return head, args, suffix


def _table(tables: dict[int, dict[int, int]], pid: int) -> dict[int, int]:
    """Return renaming ``pid``'s table in ``tables``, made empty the first time."""
    r = tables.get(pid)
    if r is None:
        r = tables[pid] = {}
    return r


class NotSymmetric(Exception):
    """A renaming that is not an automorphism of the ground problem."""


class Symmetry:
    """The interchangeable objects of a ground problem, and canonical forms of states.

    ``classes`` lists, per class, the indices (into ``objects``) of its objects in name order.
    A permutation is a tuple giving each movable object's image; permutations are interned
    (:meth:`pid`), 0 being the identity."""

    def __init__(self, grounded: Grounded, classes: list[list[str]]) -> None:
        self.grounded = grounded
        self.objects = [o for cls in classes for o in cls]
        self.index = {o: i for i, o in enumerate(self.objects)}
        self.classes = [[self.index[o] for o in cls] for cls in classes]
        self.class_of = {i: c for c, cls in enumerate(self.classes) for i in cls}
        n = len(self.objects)
        self.perms: list[Perm] = [tuple(range(n))]
        self._pid: dict[Perm, int] = {self.perms[0]: 0}
        self._atom_maps: dict[int, dict[int, int]] = {}
        self._task_maps: dict[int, dict[int, int]] = {}
        self._moving: dict[int, int] = {}  # renaming -> the atoms it moves, as a mask
        self._inverse: dict[int, int] = {0: 0}
        # atoms and tasks naming a movable object: each object's role in them, and each as
        # an integer key (:meth:`_key`), by which a renaming finds its image without text
        self.movable_mask = 0
        self._codes: dict[str, int] = {}  # names and heads other than movable objects -> n + i
        self._atom_roles: dict[int, tuple[tuple[int, int], ...]] = {}
        self._atom_keys: dict[int, tuple[int, ...]] = {}
        self._atom_of_key: dict[tuple[int, ...], int] = {}
        self._object_atoms = [0] * n  # per movable object, the atoms naming it, as a mask
        roles: dict[tuple[Any, ...], int] = {}
        for i, a in enumerate(grounded.atoms):
            parts = _split(a)
            roles_i = self._roles(parts, roles)
            if roles_i:
                self.movable_mask |= 1 << i
                self._atom_roles[i] = roles_i
                key = self._atom_keys[i] = self._key(parts)
                self._atom_of_key[key] = i
                for o, _ in roles_i:
                    self._object_atoms[o] |= 1 << i
        self._task_roles: dict[int, tuple[tuple[int, int], ...]] = {}
        self._task_keys: dict[int, tuple[int, ...]] = {}
        self._task_of_key: dict[tuple[int, ...], int] = {}
        for t, name in enumerate(grounded.task_names):
            parts = _split(name)
            roles_t = self._roles(parts, roles)
            if roles_t:
                self._task_roles[t] = roles_t
                key = self._task_keys[t] = self._key(parts)
                self._task_of_key[key] = t
        # renaming -> atom (task) -> its image, filled as renamings are applied
        self._atom_images: dict[int, dict[int, int]] = {}
        self._task_images: dict[int, dict[int, int]] = {}
        self._ag_sig: dict[Agenda, tuple[tuple[tuple[int, int], ...], ...]] = {}
        self._renamed: dict[int, dict[int, int]] = {}  # renaming -> state -> its image
        self._renamed_count = 0
        self._renamed_ag: dict[tuple[int, Agenda], Agenda] = {}
        self._columns: dict[Worlds, Any] = {}  # the worlds' part of signatures, per set
        self._sig_ids: dict[int, tuple[int, ...]] = {}
        self._ag_ids: dict[Agenda, tuple[int, ...]] = {}
        self._sig_index: dict[tuple[int, ...], int] = {}
        self._sig_values: list[tuple[int, ...]] = []
        self._ag_index: dict[tuple[tuple[int, int], ...], int] = {}
        self._ag_values: list[tuple[tuple[int, int], ...]] = []

    @property
    def g(self) -> Grounded:
        """The ground problem, by its older name (:attr:`grounded`)."""
        return self.grounded

    def _roles(self, parts: tuple[str, tuple[str, ...], str],
               roles: dict[tuple[Any, ...], int]) -> tuple[tuple[int, int], ...]:
        """Each movable object named in an atom or task, with its *role* there: the name with
        that object as "self", other movable objects by their class, fixed ones by name."""
        head, args, suffix = parts
        names = [*args, suffix[3:]] if suffix.startswith(" = ") else list(args)
        out = []
        for o in dict.fromkeys(x for x in names if x in self.index):
            key = (head, suffix if not suffix.startswith(" = ") else " = ",
                   tuple("" if x == o else (self.class_of[self.index[x]],)
                         if x in self.index else x for x in names))
            r = roles.setdefault(key, len(roles))
            out.append((self.index[o], r))
        return tuple(out)

    # -- permutations -------------------------------------------------------------------------
    def pid(self, p: Perm) -> int:
        i = self._pid.get(p)
        if i is None:
            i = self._pid[p] = len(self.perms)
            self.perms.append(p)
        return i

    def inverse(self, pid: int) -> int:
        r = self._inverse.get(pid)
        if r is None:
            p = self.perms[pid]
            inv = [0] * len(p)
            for i, j in enumerate(p):
                inv[j] = i
            r = self._inverse[pid] = self.pid(tuple(inv))
        return r

    def compose(self, a: int, b: int) -> int:
        """The permutation ``a`` after ``b`` (``b`` first)."""
        if a == 0:
            return b
        if b == 0:
            return a
        pa, pb = self.perms[a], self.perms[b]
        return self.pid(tuple(pa[j] for j in pb))

    def rename(self, pid: int) -> dict[str, str]:
        """The object renaming of ``pid``, by name (moved objects only)."""
        p = self.perms[pid]
        return {self.objects[i]: self.objects[j] for i, j in enumerate(p) if i != j}

    def _key(self, parts: tuple[str, tuple[str, ...], str]) -> tuple[int, ...]:
        """An atom's or task's name as integers: its head (with a state variable's ``=``),
        then its arguments (and value), a movable object by its index, any other name by a
        code of its own (``n + i``), so that a renaming maps a key onto its image's key by
        reading the permutation alone."""
        head, args, suffix = parts
        names = list(args)
        if suffix.startswith(" = "):
            names.append(suffix[3:])
            suffix = " = "
        codes, index, n = self._codes, self.index, len(self.objects)
        out = [codes.setdefault(f"{head}\x00{suffix}", n + len(codes))]
        for x in names:
            i = index.get(x)
            out.append(i if i is not None else codes.setdefault(x, n + len(codes)))
        return tuple(out)

    def _renamed_key(self, pid: int, key: tuple[int, ...]) -> tuple[int, ...]:
        p, n = self.perms[pid], len(self.objects)
        return tuple([p[x] if x < n else x for x in key])

    def atom_image(self, pid: int, i: int) -> int:
        """§3: the image of atom ``i`` under ``pid`` (an integer table per renaming, filled
        as atoms are renamed; an atom naming no movable object is its own)."""
        images = _table(self._atom_images, pid)
        j = images.get(i)
        if j is None:
            key = self._atom_keys.get(i)
            j = images[i] = i if key is None else self._atom_of_key[self._renamed_key(pid, key)]
        return j

    def task_image(self, pid: int, t: int) -> int:
        """§3: the image of task ``t`` under ``pid`` (as :meth:`atom_image`; a task grounded
        after the reduction was set up, or naming no movable object, is its own)."""
        images = _table(self._task_images, pid)
        u = images.get(t)
        if u is None:
            key = self._task_keys.get(t)
            if key is None:
                u = t
            else:
                u = self._task_of_key.get(self._renamed_key(pid, key))
                if u is None:
                    raise NotSymmetric(f"task {self.grounded.task_names[t]} has no image")
            images[t] = u
        return u

    def atom_map(self, pid: int) -> dict[int, int]:
        """Atom index -> its image under ``pid`` (moved atoms only); KeyError when an image
        is no atom (detection turns that into "not an automorphism")."""
        amap = self._atom_maps.get(pid)
        if amap is None:
            amap = {}
            for i in self._atom_keys:
                j = self.atom_image(pid, i)
                if j != i:
                    amap[i] = j
            self._atom_maps[pid] = amap
        return amap

    def task_map(self, pid: int) -> dict[int, int]:
        """Task id -> its image under ``pid`` (moved tasks only); NotSymmetric when an image
        is no task."""
        tmap = self._task_maps.get(pid)
        if tmap is None:
            tmap = {}
            for t in self._task_keys:
                u = self.task_image(pid, t)
                if u != t:
                    tmap[t] = u
            self._task_maps[pid] = tmap
        return tmap

    def named(self, text: str) -> frozenset[int]:
        """Return the movable objects a move label or a message names (indices)."""
        index = self.index
        return frozenset(index[x] for x in _TOKEN.findall(text) if x in index)

    def label(self, pid: int, text: str) -> str:
        """A move label or a message with the objects renamed."""
        if pid == 0:
            return text
        ren = self.rename(pid)
        return _TOKEN.sub(lambda mt: ren.get(mt.group(0), mt.group(0)), text)

    # -- applying a permutation ---------------------------------------------------------------
    def state(self, pid: int, s: int) -> int:
        """The state ``s`` with its objects renamed by ``pid`` (memoised: the worlds of many
        belief sets share states, so most renamings have been done before)."""
        if pid == 0 or not s & self.movable_mask:
            return s
        moved = s & self.moving(pid)
        if not moved:
            return s
        cache = self._renamed.get(pid)
        if cache is None:
            cache = self._renamed[pid] = {}
        r = cache.get(s)
        if r is None:
            r = self._keep_renamed(pid, cache, s, self._rename_state(pid, s, moved))
        return r

    def moving(self, pid: int) -> int:
        """The atoms ``pid`` moves (to another atom), as a mask: a state without any is its
        own image. A canonical renaming often swaps a few objects of many, so this is a
        small part of the atoms naming interchangeable objects. An atom naming an object
        ``pid`` moves is moved (that argument changes), and only those are."""
        m = self._moving.get(pid)
        if m is None:
            m = 0
            atoms = self._object_atoms
            for i, j in enumerate(self.perms[pid]):
                if i != j:
                    m |= atoms[i]
            self._moving[pid] = m
        return m

    def _keep_renamed(self, pid: int, cache: dict[int, int], s: int, r: int) -> int:
        """Keep ``r`` as the image of ``s`` under ``pid`` (``cache``: ``pid``'s table; every
        table starts afresh once :data:`RENAMED_CACHE` states are kept). One table per
        renaming, keyed by the state alone: a (renaming, state) key cost a tuple per entry
        (78 MB of 464 at 16 cubes / 3 boxes / K=8)."""
        if self._renamed_count >= RENAMED_CACHE:
            self._renamed.clear()
            self._renamed_count = 0
            cache = self._renamed[pid] = {}
        cache[s] = r
        self._renamed_count += 1
        return r

    def _rename_state(self, pid: int, s: int, moved: int) -> int:
        """:meth:`state`, computed: each atom of ``s`` that ``pid`` moves (``moved``, the
        part of ``s`` in :meth:`moving`) taken to its image."""
        image = self.atom_image
        out = s & ~self.moving(pid)
        while moved:
            low = moved & -moved
            out |= 1 << image(pid, low.bit_length() - 1)
            moved ^= low
        return out

    def agenda(self, pid: int, ag: Agenda) -> Agenda:
        """The agenda ``ag`` with its objects renamed by ``pid`` (memoised)."""
        if pid == 0 or not ag:
            return ag
        key = (pid, ag)
        r = self._renamed_ag.get(key)
        if r is None:
            if len(self._renamed_ag) >= RENAMED_CACHE:
                self._renamed_ag.clear()
            r = self._renamed_ag[key] = self._rename_agenda(pid, ag)
        return r

    def _rename_agenda(self, pid: int, ag: Agenda) -> Agenda:
        """:meth:`agenda`, computed."""
        image = self.task_image
        out: list[int] = []
        for t in ag:  # no blocks: partial order turns the reduction off (detect)
            assert isinstance(t, int)
            out.append(image(pid, t))
        return tuple(out)

    def worlds(self, pid: int, ws: Worlds) -> Worlds:
        """The worlds ``ws`` renamed, in canonical order (a renaming maps distinct worlds to
        distinct worlds, so sorting is enough)."""
        if pid == 0:
            return tuple(sorted(ws))
        moving, agenda, renamed = self.moving(pid), self.agenda, self._renamed
        cache = renamed.get(pid)
        if cache is None:
            cache = renamed[pid] = {}
        agendas: dict[Agenda, Agenda] = {}  # the worlds' robot agendas are few
        out = []
        for s, a in ws:
            moved = s & moving
            if moved:
                r = cache.get(s)
                if r is None:
                    r = self._keep_renamed(pid, cache, s, self._rename_state(pid, s, moved))
                    cache = renamed[pid]  # a new table when they all started afresh
                s = r
            b = agendas.get(a)
            if b is None:
                b = agendas[a] = agenda(pid, a)
            out.append((s, b))
        out.sort()
        return tuple(out)

    def apply(self, pid: int, es: EState) -> EState:
        """The epistemic state ``es`` with its objects renamed by ``pid``."""
        if pid == 0:
            return es
        return es._replace(true=self.state(pid, es.true),
                           robot_agenda=self.agenda(pid, es.robot_agenda),
                           human_agendas=tuple(sorted(self.agenda(pid, h)
                                                      for h in es.human_agendas)),
                           worlds=self.worlds(pid, es.worlds))

    # -- canonical form -----------------------------------------------------------------------
    def _state_sig(self, s: int) -> tuple[tuple[int, ...], ...]:
        """Per movable object, the roles of its true atoms in ``s`` (sorted). Not kept: a
        state's signature is kept interned (:meth:`_state_ids`), one int per object, since
        the states of the human's worlds are many (at 16 cubes / 3 boxes / K=8 the tuples
        kept here took 147 MB)."""
        acc: list[list[int]] = [[] for _ in self.objects]
        moved = s & self.movable_mask
        roles = self._atom_roles
        while moved:
            low = moved & -moved
            for o, role in roles[low.bit_length() - 1]:
                acc[o].append(role)
            moved ^= low
        return tuple([tuple(sorted(x)) if len(x) > 1 else tuple(x) for x in acc])

    def _agenda_sig(self, ag: Agenda) -> tuple[tuple[tuple[int, int], ...], ...]:
        """Per movable object, (position, role) of the agenda's tasks naming it."""
        r = self._ag_sig.get(ag)
        if r is None:
            acc: list[list[tuple[int, int]]] = [[] for _ in self.objects]
            roles = self._task_roles
            for pos, t in enumerate(ag):
                assert isinstance(t, int)
                for o, role in roles.get(t, ()):
                    acc[o].append((pos, role))
            r = self._ag_sig[ag] = tuple(tuple(x) for x in acc)
        return r

    def _state_ids(self, s: int) -> tuple[int, ...]:
        """:meth:`_state_sig` with each object's signature interned as an int."""
        r = self._sig_ids.get(s)
        if r is None:
            index, values = self._sig_index, self._sig_values
            ids = []
            for x in self._state_sig(s):
                i = index.get(x)
                if i is None:
                    i = index[x] = len(values)
                    values.append(x)
                ids.append(i)
            r = self._sig_ids[s] = tuple(ids)
        return r

    def _agenda_ids(self, ag: Agenda) -> tuple[int, ...]:
        """:meth:`_agenda_sig` with each object's signature interned as an int."""
        r = self._ag_ids.get(ag)
        if r is None:
            r = self._ag_ids[ag] = tuple(self._intern(x, self._ag_index, self._ag_values)
                                         for x in self._agenda_sig(ag))
        return r

    @staticmethod
    def _intern(x: Any, index: dict[Any, int], values: list[Any]) -> int:
        i = index.get(x)
        if i is None:
            i = index[x] = len(values)
            values.append(x)
        return i

    def _world_columns(self, worlds: Worlds) -> Any:
        """Return what the canonical form reads of ``worlds``: each object's column of
        signatures over them (:class:`_WorldColumns`)."""
        return _WorldColumns(self, worlds)

    def explicit(self, es: EState) -> EState:
        """Return ``es`` with its worlds listed (they are: :mod:`.worldclasses` keeps them
        as classes)."""
        return es

    def forget(self, worlds: Worlds) -> None:
        """Drop what :meth:`canon` kept of ``worlds`` (their signatures), so that the next
        canonical form of a state with these worlds computes them again (a benchmark's
        timing: ``experiments/classes.py``)."""
        self._columns.pop(worlds, None)

    def canon(self, es: EState) -> tuple[EState, int]:
        """The canonical representative of ``es`` and the permutation that maps ``es`` to it.

        Sort roles, never enumerate permutations (docs/semantics.md §3, "Symmetry")::

            canon(s):
                for each object o that has an interchangeable twin:
                    sig[o] = (roles of o's true atoms in T,
                              (position, role) of the tasks naming o in either agenda,
                              the sorted multiset, over the worlds (S, tn) of W, of
                                  (roles of o's true atoms in S, tasks naming o in tn))
                for each class C (its objects in name order c_1 < ... < c_n):
                    sort C by sig, stably (equal signatures keep name order)
                    rename the k-th object of that order to c_k
                return (s renamed, the renaming)

        A role names an atom or task with ``o`` as "self" and every other interchangeable
        object by its class, so a renaming maps signatures onto signatures: renamed states
        get equal signatures, hence the same canonical form, unless two objects tie without
        being interchangeable (then the stable order decides, and two members of one orbit may
        keep two representatives: less reduction, never a wrong one). Whatever the order,
        the renaming is a permutation within classes, an automorphism of the problem, so the
        representative is a real state of the same value (§3).

        The worlds' part of a signature is computed only for an object that ties with another
        on the rest, and kept with the set of worlds (:class:`_WorldColumns`): most generated
        states share their worlds with one met before. Signatures are compared by value, never
        by the order they were first met in, so the form does not depend on history."""
        sv = self._sig_values
        tsig = [sv[i] for i in self._state_ids(es.true)]
        rsig = self._agenda_sig(es.robot_agenda)
        hsigs = [self._agenda_sig(h) for h in es.human_agendas]
        n = len(self.objects)
        cols = self._columns.get(es.worlds)
        if cols is None:
            if len(self._columns) >= COLUMNS_CACHE:
                self._columns.clear()
            cols = self._columns[es.worlds] = self._world_columns(es.worlds)
        perm: list[int] | None = None
        for cls in self.classes:
            keys: list[tuple[Any, ...]] = [
                (tsig[o], rsig[o], tuple(sorted(h[o] for h in hsigs))) for o in cls]
            tied = Counter(keys)
            for k, o in enumerate(cls):
                if tied[keys[k]] > 1:  # else the true state and agendas already place it
                    keys[k] = (*keys[k], cols.key(o))
            order = sorted(range(len(cls)), key=keys.__getitem__)
            if any(k != j for j, k in enumerate(order)):
                if perm is None:
                    perm = list(range(n))
                for rank, k in enumerate(order):
                    perm[cls[k]] = cls[rank]
        if perm is None:
            return es, 0
        pid = self.pid(tuple(perm))
        return self.apply(pid, es), pid


class _WorldColumns:
    """The part of an object's signature that a set of worlds gives (:meth:`Symmetry.canon`),
    computed per object when first needed and kept with the worlds: most generated states
    share their worlds with one seen before."""

    __slots__ = ("keys", "scols", "acols", "sym", "worlds")

    def __init__(self, sym: Symmetry, worlds: Worlds) -> None:
        self.sym = sym
        self.worlds = worlds
        self.keys: list[list[tuple[Any, int]] | None] = [None] * len(sym.objects)
        self.scols: list[tuple[int, ...]] | None = None
        self.acols: list[tuple[int, ...]] = []

    def key(self, o: int) -> list[tuple[Any, int]]:
        """Return the sorted multiset, over the worlds, of object ``o``'s (state role, agenda
        role) signature, run-length encoded as (value, -count): every object has one entry
        per world, so these order exactly as the sorted lists of entries would."""
        r = self.keys[o]
        if r is None:
            sym = self.sym
            if self.scols is None:  # per object, its column over the worlds (zip transposes)
                n = len(sym.objects)
                ws = self.worlds
                rows = [sym._state_ids(s) for s, _ in ws]
                self.scols = list(zip(*rows, strict=True)) if ws else [()] * n
                rows = [sym._agenda_ids(a) for _, a in ws]
                self.acols = list(zip(*rows, strict=True)) if ws else [()] * n
            sv, av = sym._sig_values, sym._ag_values
            column = Counter(zip(self.scols[o], self.acols[o], strict=True))
            r = self.keys[o] = sorted([((sv[s], av[a]), -c) for (s, a), c in column.items()])
        return r


# -- semantics that notice order-dependent decisions ---------------------------------------------
class SymSemantics(Semantics):
    """The transition rules, unchanged, plus a watch on the two decisions taken by index or
    name order (docs/semantics.md §3, "Symmetry"): ``unsafe`` says why the search over
    canonical states may not stand for the renamed states (the planner then solves again
    without symmetry)."""

    def __init__(self, grounded: Grounded, sym: Symmetry) -> None:
        super().__init__(grounded)
        self.sym = sym
        self.watch = True
        self.unsafe = ""

    def observe(self, t: int, worlds: Worlds, mask: int) -> Worlds:
        if self.watch and not self.unsafe and mask & self.sym.movable_mask:
            self._check_observe(t, worlds, mask)
        return super().observe(t, worlds, mask)

    def _check_observe(self, t: int, worlds: Worlds, mask: int) -> None:
        """§2 observes unit by unit in index order. The order cannot matter when at most one
        unit varies between the worlds, or when some world agrees with ``t`` on every unit
        that varies: a unit on which the worlds agree is kept or revised the same way in any
        order (it touches its own bits only), and the varying ones are then filters that
        keep exactly the worlds agreeing on all of them. Otherwise, if a varying unit names
        an interchangeable object, a renaming may reorder them: unsafe."""
        varying = 0
        count = 0
        for u in self.grounded.units(mask):
            part = u & mask
            first = worlds[0][0] & part
            if any(s & part != first for s, _ in worlds):
                varying |= part
                count += 1
        if count < 2 or not varying & self.sym.movable_mask:
            return
        tv = t & varying
        if any(s & varying == tv for s, _ in worlds):
            return
        self.unsafe = ("a belief revision whose result depends on the order of the atoms "
                       "observed")

    def informing_set(self, es: EState, plan: bool) -> int:
        mask = super().informing_set(es, plan)
        if mask and self.watch and not self.unsafe and self._tied(es, mask, plan):
            self.unsafe = ("an informing set chosen by name among equally good ones that "
                           "are not each other's image")
        return mask

    def _tied(self, es: EState, chosen: int, plan: bool) -> bool:
        """Whether another set of the chosen size is as good as ``chosen`` on everything but
        names (§5), one of them naming an interchangeable object, and telling it leads to a
        state with another canonical form than telling ``chosen``. When every tied set's
        state has the same canonical form, whichever set a renamed state picks by name, its
        ``inform`` leads to a renaming of the same state, of the same value (extraction then
        takes the real state's own set)."""
        grounded, t = self.grounded, es.true
        states = states_of(es.worlds)
        div = 0
        for s in states:
            div |= s ^ t
        cands = grounded.units(div)
        size = len(grounded.units(chosen))

        def valid(w2: Worlds, want_r: bool) -> bool:
            return self.fixes(es, w2, want_r, plan)

        def rank(mask: int, combo: Iterable[int]) -> tuple[int, int]:
            w2 = self.observe(t, es.worlds, mask)
            return len(w2), -sum(1 for u in combo if t & u or u in grounded.unit_names)

        w_chosen = self.observe(t, es.worlds, chosen)
        want_r = valid(w_chosen, True)
        if not want_r and not valid(w_chosen, False):
            return True  # not understood: be safe
        best = rank(chosen, grounded.units(chosen))
        movable = self.sym.movable_mask
        key: EState | None = None
        for combo in combinations(cands, size):
            mask = 0
            for u in combo:
                mask |= u
            if mask == chosen:
                continue
            w2 = self.observe(t, es.worlds, mask)
            if valid(w2, want_r) and rank(mask, combo) == best and (mask | chosen) & movable:
                if key is None:
                    key = self.sym.canon(self.inform(es, chosen))[0]
                if self.sym.canon(self.inform(es, mask))[0] != key:
                    return True
        return False


def describe_classes(sym: Symmetry) -> list[list[str]]:
    return [[sym.objects[i] for i in cls] for cls in sym.classes]


__all__ = ["OVERRIDE", "NotSymmetric", "Symmetry", "SymSemantics", "describe_classes",
           "enabled"]
