"""Agendas as data (docs/semantics.md §1, "Partial order"): what an agenda is, and the
partially ordered blocks in it.

An agenda is a tuple of items done in order. An item is a task id (an ``int``) or, for the
subtasks of a partially ordered method, a :class:`Block`: a set of tasks with an order between
some of them. A totally ordered agenda is a plain tuple of ints, exactly as before partial
order existed. :class:`Networks` keeps blocks in canonical form as members are done or refined,
and prints agendas as policies show them; refining an agenda is :mod:`ehatp.model.htn`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from itertools import permutations, product
from math import factorial

from mypy_extensions import mypyc_attr

from .grounded import FINISH, bits


# a Python class even where this module is compiled (docs/compiled.md): mypyc compiles no
# subclass of tuple
@mypyc_attr(native_class=False)
class Block(tuple[tuple[int, int], ...]):
    """A partially ordered part of an agenda (docs/semantics.md §1, "Partial order").

    Its members are ``(task id, predecessors)`` pairs; ``predecessors`` is a bitmask over the
    block's own members (bit ``j``: member ``j`` comes first), transitively closed. A member is
    *ready* when it has no predecessor left. The form is canonical (see
    :meth:`Networks.normal`): no member is empty, the block cannot be cut in two parts one
    wholly before the other, and members are listed by task name. Blocks compare after every
    task id, so agendas mixing both still sort (worlds and options are kept sorted)."""

    __slots__ = ()

    def __lt__(self, other: object) -> bool:
        if isinstance(other, int):
            return False
        return tuple.__lt__(self, other)  # type: ignore[operator]

    def __le__(self, other: object) -> bool:
        if isinstance(other, int):
            return False
        return tuple.__le__(self, other)  # type: ignore[operator]

    def __gt__(self, other: object) -> bool:
        if isinstance(other, int):
            return True
        return tuple.__gt__(self, other)  # type: ignore[operator]

    def __ge__(self, other: object) -> bool:
        if isinstance(other, int):
            return True
        return tuple.__ge__(self, other)  # type: ignore[operator]


Item = int | Block
Agenda = tuple[Item, ...]
Members = list[tuple[int, int]]  # (task id, predecessor mask over the list's positions)


def _drop_bit(mask: int, i: int) -> int:
    """``m`` without bit ``i``, the bits above it moved down by one."""
    return (mask & ((1 << i) - 1)) | ((mask >> (i + 1)) << i)


def _series(ms: Sequence[tuple[int, int]], ids: list[int]) -> list[list[int]]:
    """§1: ``ids`` cut into consecutive parts, each wholly before the next, as finely as
    possible (every part then cannot be cut again). Each part keeps ``ids``' order."""
    parts: list[list[int]] = []
    left = ids
    while left:
        inside = 0
        for i in left:
            inside |= 1 << i
        # a part that comes first has fewer predecessors than anything after it
        by_preds = sorted(left, key=lambda i: (ms[i][1] & inside).bit_count())
        first = 0
        cut = len(left)
        for k in range(1, len(left)):
            first |= 1 << by_preds[k - 1]
            if all(ms[j][1] & first == first for j in by_preds[k:]):
                cut = k
                break
        part = set(by_preds[:cut])
        parts.append([i for i in left if i in part])
        left = [i for i in left if i not in part]
    return parts


def _orderings(classes: list[list[int]], preds: list[frozenset[int]],
               succs: list[frozenset[int]]) -> Iterable[list[int]]:
    """Every order of the members that keeps ``classes`` (members of one name) in sequence,
    members of a class in any order -- except that *twins* (same predecessors and successors,
    interchangeable) keep one order among themselves, since swapping them changes nothing."""
    def perms(cls: list[int]) -> list[list[int]]:
        groups: dict[tuple[frozenset[int], frozenset[int]], list[int]] = {}
        for k in cls:
            groups.setdefault((preds[k], succs[k]), []).append(k)
        gs = list(groups.values())
        out: list[list[int]] = []

        def go(left: list[int], seq: list[int]) -> None:  # distinct sequences of groups
            if len(seq) == len(cls):
                nxt = [0] * len(gs)
                row = []
                for g in seq:
                    row.append(gs[g][nxt[g]])
                    nxt[g] += 1
                out.append(row)
                return
            for g, n in enumerate(left):
                if n:
                    left[g] -= 1
                    go(left, [*seq, g])
                    left[g] += 1

        go([len(g) for g in gs], [])
        return out

    for parts in product(*(perms(c) if len(c) > 1 else [c] for c in classes)):
        yield [k for part in parts for k in part]


MAX_ORDERINGS = 720
"""§1: a block whose repeated names allow more orders of their occurrences than this (the
product of the factorials of their counts) orders them by rank instead of trying them all."""


def _ways(classes: list[list[int]]) -> int:
    n = 1
    for c in classes:
        n *= factorial(len(c))
    return n


def _ranks(label: list[str], preds: list[frozenset[int]]) -> list[tuple[int, int]]:
    """§1: each member's rank from below: members with fewer predecessors first (a
    predecessor always has fewer, the order being transitively closed); among those with as
    many, by (name, the sorted ranks of its predecessors), equal keys sharing a rank."""
    n = len(label)
    rank: list[tuple[int, int]] = [(0, 0)] * n
    by_count: dict[int, list[int]] = {}
    for k in range(n):
        by_count.setdefault(len(preds[k]), []).append(k)
    for c in sorted(by_count):
        keys = {k: (label[k], tuple(sorted(rank[j] for j in preds[k]))) for k in by_count[c]}
        distinct = sorted(set(keys.values()))
        at = {key: i for i, key in enumerate(distinct)}
        for k, key in keys.items():
            rank[k] = (c, at[key])
    return rank


def _distinct_orders(group: list[int], tasks: list[int], preds: list[frozenset[int]],
                     succs: list[frozenset[int]]) -> list[list[int]]:
    """The orders of ``group`` up to twins (same task, predecessors and successors: swapping
    them changes nothing)."""
    out: list[list[int]] = []
    seen: set[tuple[tuple[int, frozenset[int], frozenset[int]], ...]] = set()
    for perm in permutations(group):
        sig = tuple((tasks[k], preds[k], succs[k]) for k in perm)
        if sig not in seen:
            seen.add(sig)
            out.append(list(perm))
    return out


class Networks:
    """Canonical forms and printing of partially ordered agendas, for one list of task names
    (§1, "Partial order"). Memoised: the same block changes the same way in every state."""

    def __init__(self, task_names: Sequence[str]) -> None:
        self.names = task_names
        self._without: dict[tuple[Block, int], Agenda] = {}
        self._with: dict[tuple[Block, int, Agenda], Agenda] = {}
        self._text: dict[Block, str] = {}

    # -- canonical form -----------------------------------------------------------------------
    def normal(self, ms: Members) -> Agenda:
        """§1: the agenda of the tasks ``ms`` (predecessor masks transitively closed): cut into
        parts each wholly before the next; a part of one task is that task, a larger part a
        :class:`Block` whose members are sorted by task name (then by their predecessors'
        names; full ties keep their order in ``ms``)."""
        if len(ms) == 1:
            return (ms[0][0],)
        out: list[Item] = []
        for part in _series(ms, list(range(len(ms)))):
            out.append(ms[part[0]][0] if len(part) == 1 else self._block(ms, part))
        return tuple(out)

    def _block(self, ms: Members, ids: list[int]) -> Block:
        """The members ``ids`` of ``ms`` as a block: listed by task name; where a name repeats,
        in the order (among those by name) that makes the list of each member's sorted
        predecessor positions smallest, so the order is the network's own (§1)."""
        names = self.names
        loc = {i: k for k, i in enumerate(ids)}
        preds = [frozenset(loc[j] for j in bits(ms[i][1]) if j in loc) for i in ids]
        tasks = [ms[i][0] for i in ids]
        by_name = sorted(range(len(ids)), key=lambda k: names[tasks[k]])
        classes: list[list[int]] = []
        for k in by_name:
            if classes and names[tasks[classes[-1][0]]] == names[tasks[k]]:
                classes[-1].append(k)
            else:
                classes.append([k])
        if len(classes) == len(ids):  # every name once: the order by name is the one
            order = by_name
        elif _ways(classes) > MAX_ORDERINGS:
            order = self._ranked(tasks, preds, classes)
        else:
            succs = [frozenset(k for k in range(len(ids)) if j in preds[k])
                     for j in range(len(ids))]
            best: tuple[tuple[int, ...], ...] | None = None
            order = by_name
            for cand in _orderings(classes, preds, succs):
                pos = {k: p for p, k in enumerate(cand)}
                code = tuple(tuple(sorted(pos[j] for j in preds[k])) for k in cand)
                if best is None or code < best:
                    best, order = code, cand
        pos = {k: p for p, k in enumerate(order)}
        return Block(tuple((tasks[k], sum(1 << pos[j] for j in preds[k])) for k in order))

    def _ranked(self, tasks: list[int], preds: list[frozenset[int]],
                classes: list[list[int]]) -> list[int]:
        """§1: the members of a block with many occurrences of a name: by name, then by rank
        from below and from above (:func:`_ranks`); occurrences whose ranks tie in the order
        that makes their predecessor lists smallest."""
        names = self.names
        n = len(tasks)
        succs = [frozenset(k for k in range(n) if j in preds[k]) for j in range(n)]
        label = [names[t] for t in tasks]
        below, above = _ranks(label, preds), _ranks(label, succs)

        def rank(k: int) -> tuple[tuple[int, int], tuple[int, int]]:
            return below[k], above[k]

        order = [k for cls in classes for k in sorted(cls, key=lambda k: (rank(k), k))]
        # occurrences whose ranks tie (rare): among their orders, the smallest code
        groups = [g for cls in classes for r in sorted({rank(k) for k in cls})
                  if len(g := sorted(k for k in cls if rank(k) == r)) > 1]
        if not groups:
            return order
        best: tuple[tuple[int, ...], ...] | None = None
        result = order
        members = {k for g in groups for k in g}
        for choice in product(*(_distinct_orders(g, tasks, preds, succs) for g in groups)):
            fill = iter([k for g in choice for k in g])
            seq = [next(fill) if k in members else k for k in order]
            pos = {k: p for p, k in enumerate(seq)}
            code = tuple(tuple(sorted(pos[j] for j in preds[k])) for k in seq)
            if best is None or code < best:
                best, result = code, seq
        return result

    def body(self, subtasks: tuple[int, ...], order: tuple[int, ...] | None) -> Agenda:
        """A method's subtasks as an agenda: as listed (``order`` None: totally ordered), or
        in canonical form under the closed predecessor masks ``order``."""
        if order is None or not subtasks:
            return subtasks
        return self.normal(list(zip(subtasks, order, strict=True)))

    def without(self, b: Block, i: int) -> Agenda:
        """§1: the block once member ``i`` is done (canonical form)."""
        key = (b, i)
        r = self._without.get(key)
        if r is None:
            ms = [(t, _drop_bit(preds, i)) for j, (t, preds) in enumerate(b) if j != i]
            r = self._without[key] = self.normal(ms)
        return r

    def replace(self, b: Block, i: int, rest: Agenda) -> Agenda:
        """§1: the block once member ``i`` is refined into the agenda ``rest``: its tasks take
        the member's place, keep their own order and the member's predecessors, and come before
        the member's successors (canonical form)."""
        if not rest:
            return self.without(b, i)
        key = (b, i, rest)
        r = self._with.get(key)
        if r is None:
            new: Members = []
            before = 0
            for it in rest:  # the items of rest in sequence, blocks opened
                if isinstance(it, Block):
                    base = len(new)
                    for t, preds in it:
                        new.append((t, before | (preds << base)))
                    before |= ((1 << len(it)) - 1) << base
                else:
                    new.append((it, before))
                    before |= 1 << (len(new) - 1)
            k = len(new)
            span = ((1 << k) - 1) << i

            def moved(preds: int) -> int:
                low = preds & ((1 << i) - 1)
                high = (preds >> (i + 1)) << (i + k)
                return low | high | (span if preds >> i & 1 else 0)

            own = moved(b[i][1])
            ms: Members = [(t, moved(preds)) for t, preds in b[:i]]
            ms += [(t, (preds << i) | own) for t, preds in new]
            ms += [(t, moved(preds)) for t, preds in b[i + 1:]]
            r = self._with[key] = self.normal(ms)
        return r

    def keep(self, agenda: Agenda, known: Callable[[int], bool]) -> Agenda:
        """The agenda without the tasks ``known`` rejects, blocks included (canonical form)."""
        out: list[Item] = []
        for it in agenda:
            if not isinstance(it, Block):
                if known(it):
                    out.append(it)
                continue
            ms: Members = list(it)
            for j in range(len(ms) - 1, -1, -1):
                if not known(ms[j][0]):
                    del ms[j]
                    ms = [(t, _drop_bit(preds, j)) for t, preds in ms]
            if ms:
                out.extend(self.normal(ms))
        return tuple(out)

    # -- printing -----------------------------------------------------------------------------
    def names_of(self, agenda: Agenda) -> list[str]:
        """The agenda as policies print it (docs/policy-format.md): a task by its name, a block
        as ``{a(x) | b(x) < c}`` (§1, "Partial order")."""
        out: list[str] = []
        for it in agenda:
            if isinstance(it, Block):
                out.append(self.text(it))
            elif it != FINISH:
                out.append(self.names[it])
        return out

    def text(self, b: Block) -> str:
        """§1: a block in words: ``{x | y}`` for tasks in any order, ``x < y`` for one before
        the other, nested as needed; an order that is neither (an N shape) as
        ``{a | b | c | d; a < c, b < c, b < d}``, listing the pairs that no third task links."""
        r = self._text.get(b)
        if r is None:
            r = self._text[b] = self._par(b, list(range(len(b))))
        return r

    def _par(self, b: Block, ids: list[int]) -> str:
        comps: list[list[int]] = []
        for i in ids:  # members linked by the order, in the block's order
            linked = [c for c in comps if any(b[i][1] >> j & 1 or b[j][1] >> i & 1 for j in c)]
            merged = [i]
            for c in linked:
                merged += c
                comps.remove(c)
            comps.append(sorted(merged))
        comps.sort()
        if len(comps) == 1:
            return self._ser(b, ids)
        return "{" + " | ".join(self._ser(b, c) for c in comps) + "}"

    def _ser(self, b: Block, ids: list[int]) -> str:
        if len(ids) == 1:
            return self.names[b[ids[0]][0]]
        parts = _series(b, ids)
        if len(parts) > 1:
            return " < ".join(self._par(b, p) for p in parts)
        pairs = [f"{self.names[b[i][0]]} < {self.names[b[j][0]]}" for i in ids for j in ids
                 if b[j][1] >> i & 1 and not any(b[k][1] >> i & 1 and b[j][1] >> k & 1
                                                 for k in ids)]
        return ("{" + " | ".join(self.names[b[i][0]] for i in ids) + "; " + ", ".join(pairs)
                + "}")
