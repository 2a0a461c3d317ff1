"""HTN refinement of agendas over ground models (docs/semantics.md §1).

``refine`` answers, for one state: which first primitive actions can the agent do next, and
with what remaining agenda? ``refine_in_all`` answers the same from the human's perspective over
a set of worlds: a condition (method precondition, done-condition, action precondition) that
holds in some worlds but not all makes that refinement *uncertain*, and the conditions that were
uncertain along the way are returned so the human can ask about them.

An agenda is a tuple of items done in order. An item is a task id (an ``int``) or, for the
subtasks of a partially ordered method, a :class:`Block`: a set of tasks with an order between
some of them (§1, "Partial order"). A totally ordered agenda is a plain tuple of ints, exactly
as before partial order existed, and refining it takes the same path.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections.abc import Callable, Iterable, Sequence
from itertools import permutations, product
from math import factorial

from ..errors import DomainError
from .formula import FALSE, Formula, StateFn, negate
from .grounded import FINISH, GModel, bits, no_check

MAX_DECOMPOSITION = 64
"""Default of ``[limits] max_decomposition``: nested method applications allowed before the
first action of a refinement (a task decomposing without end is a DomainError)."""


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
Way = tuple[StateFn, Formula, Agenda, StateFn | None, int, Agenda]
"""A method as the walk reads it: precondition, its formula, body; when the body starts with
an action without a done-condition, that action's precondition (else None), the first item's
task id (-1: a block, or none) and the body after it."""
Ways = tuple[Way, ...]
Option = tuple[int, Agenda]  # (ground action id or FINISH, remaining agenda)
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


_NONE = -(1 << 30)
"""A depth no refinement reaches: "no method applied" or "cannot finish" in :class:`Entry`."""

Entry = tuple[tuple[Option, ...], int, int]
"""What :meth:`Refiner.refine` keeps of an agenda in a state: its options, the deepest nesting
of methods a refinement checks against the limit, and the deepest nesting at which it finishes
(:data:`_NONE` for none), counted from the agenda itself."""


class Refiner:
    """Refinement with memoisation: results depend only on (agenda, state(s)).

    An agenda of several items is refined by splicing (§1, "Refinement"): the first item's
    refinement in the state, each remaining agenda followed by the rest, and -- when the first
    item can finish without an action -- the rest's own refinement. The first item's part is
    kept on its own, so a state met with many agendas that start alike refines their common
    first task once (:meth:`_entry`).
    """

    def __init__(self, model: GModel, task_names: list[str],
                 max_decomposition: int = MAX_DECOMPOSITION,
                 networks: Networks | None = None) -> None:
        self.model = model
        self.task_names = task_names
        self.limit = max_decomposition
        self.net = networks or Networks(task_names)
        self._one: dict[tuple[Agenda, int], Entry] = {}
        # while one item is refined alone (:meth:`_unit`): its options' set, the agenda to
        # refine when it first finishes (None: none, or done), and the deepest nesting met
        self._top: set[Option] | None = None
        self._then: tuple[Agenda, int] | None = None
        self._deep = self._fin = _NONE
        self._all: dict[tuple[Agenda, tuple[int, ...]], tuple[Uncertain, ...]] = {}
        # the subtasks of each method as an agenda (partially ordered ones in canonical form)
        self._bodies: dict[int, tuple[tuple[StateFn, Formula, Agenda], ...]] = {}
        # tasks that give nothing in any state (:meth:`_dead`): task -> the deepest nesting
        # the rule's walk checks inside it; None: a task that may give something
        self._reach: dict[int, int | None] = {}
        # each task's methods without those that start with such a task, and how deep the
        # walk of those left out goes (_NONE: none left out); the model's count of tasks
        # grounded on demand when that was found (-1: final, nothing left to ground)
        self._kept: dict[int, tuple[Ways, Ways, int, int]] = {}
        # called now and then while refining (a time or memory limit may raise from it)
        self.check: Callable[[], None] = no_check
        self._steps = 0

    def _body(self, t: int) -> tuple[tuple[StateFn, Formula, Agenda], ...]:
        """The methods of task ``t``, each as (precondition, its formula, its subtasks as an
        agenda); none for a task this model does not know."""
        r = self._bodies[t] = tuple((me.pre, me.pre_f, self.net.body(me.subtasks, me.order))
                                    for me in self.model.methods.get(t, ()))
        return r

    def _dead(self, u: int, path: set[int]) -> tuple[int | None, bool]:
        """§1: whether task ``u`` gives nothing -- no option, not even ``FINISH`` -- in every
        state, whatever is refined around it; with whether the answer is final. Such a task
        is an operator whose precondition folded to false, or an abstract task with neither a
        done-condition nor a method whose first subtask may give something (a partially
        ordered body counts as one that may). If so, the answer is the deepest nesting of
        methods, counted from ``u``, at which the rule's walk checks the limit inside it
        (:data:`_NONE` for an operator): that walk is what leaving ``u`` out skips, so it is
        left out only where it could not have gone past the limit::

            dead(u):  # path: the tasks being looked at (met again: a loop, may give)
              operator: pre is false and no done-condition -> _NONE, else may give
              abstract: a done-condition -> may give
                        for each method m: body empty or a block, or dead(first(m)) may give
                          -> may give
                        -> max(0, max over m of 1 + dead(first(m)))

        Not final while a task it reads is still to be ground on demand (reading it would
        ground it, and grounding order is part of the result, §1 "Grounding")."""
        r = self._reach.get(u, 0)
        if r != 0 or u in self._reach:
            return r, True
        model = self.model
        if not model.ready(u):
            return None, False
        if u in path:  # a loop: may give, as far as this tells
            return None, True
        op = model.ops.get(u)
        if op is not None:
            r = _NONE if op.done is None and op.pre_f == FALSE else None
        elif u in model.done:
            r = None
        else:
            path.add(u)
            r, final = 0, True
            for _, _, body in self._bodies.get(u) or self._body(u):
                e, fin = (None, True) if not body or isinstance(body[0], Block) \
                    else self._dead(body[0], path)
                if e is None and fin:  # a method that may give: so may u
                    r, final = None, True
                    break
                if e is None:  # not known yet
                    r, final = None, False
                elif r is not None:
                    r = max(r, 1 + e)
            path.discard(u)
            if not final:
                return None, False
        self._reach[u] = r
        return r, True

    def _methods(self, t: int, depth: int) -> Ways:
        """§1: the methods of task ``t`` whose refinement at nesting ``depth`` may give
        something: those that start with a task that gives nothing in any state
        (:meth:`_dead`) are left out, unless the walk inside them could go past the nesting
        limit from there (then the rule's walk is kept, and raises where it did). Each as a
        :data:`Way`: a body that starts with an action without a done-condition carries
        that action's precondition, so the walk need not step into the body to read it."""
        k = self._kept.get(t)
        model = self.model
        if k is None or (k[3] >= 0 and k[3] != model.asked):
            ways: list[Way] = []
            keep: list[Way] = []
            reach, final = _NONE, True
            for pre, pre_f, body in self._bodies.get(t) or self._body(t):
                first, op_pre = -1, None
                if body and not isinstance(body[0], Block):
                    first = body[0]
                    e, fin = self._dead(first, set())
                    final = final and fin
                    if e is not None:
                        reach = max(reach, 1 + e)
                        ways.append((pre, pre_f, body, None, first, body[1:]))
                        continue
                    op = model.ops.get(first) if fin else None  # read only once grounded
                    if op is not None and op.done is None:
                        op_pre = op.pre
                way = (pre, pre_f, body, op_pre, first, body[1:])
                ways.append(way)
                keep.append(way)
            k = (tuple(keep), tuple(ways), reach, -1 if final else model.asked)
            self._kept[t] = k
        if k[2] > _NONE:
            deep = depth + k[2]
            if deep > self.limit:
                return k[1]
            if deep > self._deep:
                self._deep = deep
        return k[0]

    def _endless(self, t: Item, open_: Open = ()) -> DomainError:
        """The error for a refinement nested deeper than the limit, naming the outermost task
        being refined (``open_``), else ``t``."""
        if open_ and open_[0][1] >= 0:
            t = open_[0][0]
        what = self.task_names[t] if isinstance(t, int) else self.net.text(t)
        return DomainError(f"task {what} nests more than {self.limit} methods before its "
                           "first action; raise [limits] max_decomposition if that is "
                           "expected")

    def _done_of(self, t: int) -> tuple[Formula, StateFn] | None:
        """§1: the done-condition of task ``t``: its operator's, or its abstract task's."""
        op = self.model.ops.get(t)
        if op is not None:
            return (op.done_f, op.done) if op.done is not None and op.done_f is not None else None
        return self.model.done.get(t)

    def refine(self, agenda: Agenda, s: int) -> tuple[Option, ...]:
        """§1 (Refinement): the (first primitive action, remaining agenda) pairs of ``agenda``
        in the single state ``s``; ``(FINISH, ())`` when it can be completed. A task this model
        does not know gives nothing (the agent is blocked on it)."""
        e = self._one.get((agenda, s))
        if e is None:
            try:
                e = self._entry(agenda, s)
            except DomainError:
                e = None
            if e is None or e[1] > self.limit:
                # §1: nested too deep somewhere: the rule as written, on the whole agenda,
                # says where (the same error, naming the same task, as without splicing)
                out: set[Option] = set()
                self._deep = _NONE
                self._go(agenda, s, out, 0)
                return tuple(sorted(out))  # pragma: no cover - the line above raises
        return e[0]

    def _entry(self, agenda: Agenda, s: int) -> Entry:
        """§1 (Refinement), spliced: ``agenda``'s options in ``s`` with the depths of
        :data:`Entry`, the refinement of its first item reused across every rest::

            entry(agenda, s):
              if agenda is empty: return ({FINISH}, none, 0)
              head = entry((agenda[0],), s)        # alone: _go with no task open around it
              out = {(a, r + rest) for (a, r) in head if a != FINISH}
              if FINISH in head:                    # the first item can end without an action
                  tail = entry(rest, s)
                  out |= tail;  deep = max(head.deep, head.fin + tail.deep)
              return sorted(out), deep, head.fin + tail.fin

        This is the rule itself: a task opened inside the first item is closed again once the
        agenda is back to ``rest`` (:data:`Open`: its length is counted from the end), so
        ``rest`` is refined as if it came first; only the nesting depth carries on, hence the
        depths kept, which :meth:`refine` compares with the limit. When the first item is
        refined for the first time, ``rest`` is refined at the moment the item first
        finishes, as the rule written as one walk does, so that a model grounded on demand
        meets its tasks in the same order (§1, "Grounding": task ids follow that order)."""
        key = (agenda, s)
        e = self._one.get(key)
        if e is not None:
            return e
        if not agenda:
            e = ((FINISH, ()),), _NONE, 0
        elif len(agenda) == 1:
            e = self._unit(agenda[0], s, ())
        else:
            first, rest = agenda[:1], agenda[1:]
            head = self._one.get((first, s))
            if head is None:
                head = self._one[(first, s)] = self._unit(agenda[0], s, rest)
            out: set[Option] = set()
            finishes = False
            for a, r in head[0]:
                if a == FINISH:
                    finishes = True
                else:
                    out.add((a, r + rest))
            if finishes:
                tail = self._entry(rest, s)
                out.update(tail[0])
                e = (tuple(sorted(out)), max(head[1], head[2] + tail[1]), head[2] + tail[2])
            else:
                e = tuple(sorted(out)), head[1], _NONE
        self._one[key] = e
        return e

    def _unit(self, item: Item, s: int, then: Agenda) -> Entry:
        """§1: the refinement of the agenda ``(item,)`` in ``s``, with its depths; ``then``
        (non-empty) is refined, through :meth:`_entry`, when the item first finishes."""
        saved = self._top, self._then, self._deep, self._fin
        out: set[Option] = set()
        self._top, self._then, self._deep, self._fin = out, (then, s) if then else None, \
            _NONE, _NONE
        try:
            self._go((item,), s, out, 0)
            return tuple(sorted(out)), self._deep, self._fin
        finally:
            self._top, self._then, self._deep, self._fin = saved

    def _finished(self, depth: int) -> None:
        """The item refined alone (:meth:`_unit`) finished at nesting ``depth``: note it, and
        refine what follows it the first time."""
        if depth > self._fin:
            self._fin = depth
        then = self._then
        if then is not None:
            self._then = None
            self._entry(*then)

    def refine_to(self, agenda: Agenda, s: int, op: int) -> tuple[Option, ...]:
        """§1: the refinements of ``agenda`` in ``s`` whose first action is ``op`` (those of
        :meth:`refine`, in its order; found by bisection, since an agenda may have many)."""
        r = self.refine(agenda, s)
        lo = bisect_left(r, op, key=_first)
        return r[lo:bisect_right(r, op, lo, key=_first)]

    def _go(self, agenda: Agenda, s: int, out: set[Option], depth: int,
            open_: Open = ()) -> None:
        """Refine ``agenda``; ``open_``: the tasks being refined around it, each with the
        length of what followed it (still being refined while the agenda is longer)."""
        model = self.model
        while True:
            if not agenda:
                out.add((FINISH, ()))
                if out is self._top:
                    self._finished(depth)
                return
            t = agenda[0]
            if isinstance(t, Block):
                self._go_block(t, agenda[1:], s, out, depth, open_)
                return
            op = model.ops.get(t)
            if op is not None:
                if op.done is not None and op.done(s):
                    agenda = agenda[1:]
                    continue
                if op.pre(s):
                    out.add((t, agenda[1:]))
                return
            d = model.done.get(t)
            if d is not None and d[1](s):
                agenda = agenda[1:]
                continue
            break
        n = len(agenda)
        if open_:
            open_ = _still_open(open_, n)
            if any(u == t for u, _ in open_):
                return  # §1: refined again inside its own refinement: a loop, closed
        if depth > self._deep:
            self._deep = depth
            if depth > self.limit:
                raise self._endless(t, open_)
        self._steps += 1
        if not self._steps & 1023:
            self.check()
        rest = agenda[1:]
        inner = (*open_, (t, n - 1))
        # a task this model does not know gives nothing: the agent is blocked on it
        for pre, _, body, op_pre, first, after in self._methods(t, depth):
            if pre(s):
                if op_pre is None:
                    self._go(body + rest, s, out, depth + 1, inner)
                elif op_pre(s):  # the body starts with an action: what _go would add
                    out.add((first, after + rest))

    def _go_block(self, b: Block, rest: Agenda, s: int, out: set[Option], depth: int,
                  open_: Open = ()) -> None:
        """§1 (Partial order): a ready member that is done is skipped first; then every ready
        member is refined in place (its first action, the block with what is left of it).
        ``open_``: the tasks being refined around the block (:data:`Open`)."""
        net = self.net
        around = _around(open_, 1 + len(rest))
        for i, (t, preds) in enumerate(b):
            if not preds:
                d = self._done_of(t)
                if d is not None and d[1](s):
                    self._go(net.without(b, i) + rest, s, out, depth, open_)
                    return
        if depth > self._deep:
            self._deep = depth
            if depth > self.limit:
                raise self._endless(b)
        for i, (t, preds) in enumerate(b):
            if preds:
                continue
            sub: set[Option] = set()
            self._go((t,), s, sub, depth + 1, around)
            for a, r in sub:
                if a == FINISH:  # the member finished without an action: go on with the rest
                    self._go(net.without(b, i) + rest, s, out, depth + 1, open_)
                else:
                    out.add((a, net.replace(b, i, r) + rest))

    def refine_in_all(self, agenda: Agenda, states: tuple[int, ...]) -> tuple[Uncertain, ...]:
        """§1 (the human's perspective): refinements over ``states`` (sorted, distinct), each
        with the mask of worlds (bit i = states[i]) in which it applies and the conditions that
        were uncertain on the way."""
        key = (agenda, states)
        r = self._all.get(key)
        if r is None:
            out: dict[tuple[int, Agenda, tuple[Formula, ...]], int] = {}
            full = (1 << len(states)) - 1
            self._go_all(agenda, states, full, (), out, 0)
            r = self._all[key] = tuple(sorted(
                (Uncertain(op, rest, ws, conds) for (op, rest, conds), ws in out.items()),
                key=lambda u: (u.op, u.rest, -u.worlds, [str(c) for c in u.conds])))
        return r

    def _go_all(self, agenda: Agenda, states: tuple[int, ...], ws: int,
                conds: tuple[Formula, ...],
                out: dict[tuple[int, Agenda, tuple[Formula, ...]], int], depth: int,
                open_: Open = ()) -> None:
        model = self.model
        if not agenda:
            key: tuple[int, Agenda, tuple[Formula, ...]] = (FINISH, (), conds)
            out[key] = out.get(key, 0) | ws
            return
        t = agenda[0]
        rest = agenda[1:]
        n = len(agenda)
        if isinstance(t, Block):
            self._go_all_block(t, rest, states, ws, conds, out, depth, open_)
            return
        op = model.ops.get(t)
        if op is not None:
            if op.done is not None and op.done_f is not None:
                dw = _holds(op.done, states, ws)
                if dw:
                    self._go_all(rest, states, dw, _add(conds, op.done_f, dw != ws), out, depth,
                                 open_)
                ws2 = ws & ~dw
                if not ws2:
                    return
                conds = _add(conds, negate(op.done_f), dw != 0)
                ws = ws2
            pw = _holds(op.pre, states, ws)
            if pw:
                k2 = (t, rest, _add(conds, op.pre_f, pw != ws))
                out[k2] = out.get(k2, 0) | pw
            return
        d = model.done.get(t)
        if d is not None:
            dw = _holds(d[1], states, ws)
            if dw:
                self._go_all(rest, states, dw, _add(conds, d[0], dw != ws), out, depth, open_)
            ws2 = ws & ~dw
            if not ws2:
                return
            conds = _add(conds, negate(d[0]), dw != 0)
            ws = ws2
        if open_:
            open_ = _still_open(open_, n)
            if any(u == t for u, _ in open_):
                return  # §1: refined again inside its own refinement: a loop, closed
        if depth > self.limit:
            raise self._endless(t, open_)
        inner = (*open_, (t, n - 1))
        for pre, pre_f, body, _, _, _ in self._methods(t, depth):
            mw = _holds(pre, states, ws)
            if mw:
                self._go_all(body + rest, states, mw, _add(conds, pre_f, mw != ws), out,
                             depth + 1, inner)

    def _go_all_block(self, b: Block, rest: Agenda, states: tuple[int, ...], ws: int,
                      conds: tuple[Formula, ...],
                      out: dict[tuple[int, Agenda, tuple[Formula, ...]], int],
                      depth: int, open_: Open = ()) -> None:
        """§1 (Partial order, over worlds): a ready member done in some worlds is skipped in
        those (the condition uncertain if not in all) and kept in the others; then every ready
        member is refined in place."""
        net = self.net
        around = _around(open_, 1 + len(rest))
        for i, (t, preds) in enumerate(b):
            if preds:
                continue
            d = self._done_of(t)
            if d is None:
                continue
            dw = _holds(d[1], states, ws)
            if dw:
                self._go_all(net.without(b, i) + rest, states, dw, _add(conds, d[0], dw != ws),
                             out, depth, open_)
                ws &= ~dw
                if not ws:
                    return
                conds = _add(conds, negate(d[0]), True)
        if depth > self.limit:
            raise self._endless(b)
        for i, (t, preds) in enumerate(b):
            if preds:
                continue
            sub: dict[tuple[int, Agenda, tuple[Formula, ...]], int] = {}
            self._go_all((t,), states, ws, conds, sub, depth + 1, around)
            for (a, r, c), w in sub.items():
                if a == FINISH:
                    self._go_all(net.without(b, i) + rest, states, w, c, out, depth + 1, open_)
                else:
                    k = (a, net.replace(b, i, r) + rest, c)
                    out[k] = out.get(k, 0) | w


Open = tuple[tuple[int, int], ...]
"""The tasks being refined around a point of a refinement (§1, "Refinement"): each with the
length of the agenda that followed it when it was opened, so that it is still being refined
while the agenda is longer; -1 marks one being refined around a block member."""


def _still_open(open_: Open, n: int) -> Open:
    """Those of ``open_`` still being refined at an agenda of length ``n`` (the others' part
    is done: they are closed for good)."""
    return tuple(e for e in open_ if e[1] < n)


def _around(open_: Open, n: int) -> Open:
    """For a member of a block at the front of an agenda of length ``n``: the tasks of
    ``open_`` still being refined there, each around the whole of the member's refinement."""
    return tuple((u, -1) for u, k in open_ if k < n)


def _first(o: Option) -> int:
    return o[0]


class Uncertain(tuple[int, Agenda, int, tuple[Formula, ...]]):
    """(op, rest, worlds mask, uncertain conditions) as a light named tuple."""

    __slots__ = ()

    def __new__(cls, op: int, rest: Agenda, worlds: int,
                conds: tuple[Formula, ...]) -> Uncertain:
        return tuple.__new__(cls, (op, rest, worlds, conds))

    @property
    def op(self) -> int:
        return self[0]

    @property
    def rest(self) -> Agenda:
        return self[1]

    @property
    def worlds(self) -> int:
        return self[2]

    @property
    def conds(self) -> tuple[Formula, ...]:
        return self[3]


def _holds(fn: object, states: tuple[int, ...], ws: int) -> int:
    out = 0
    i = 0
    while ws >> i:
        if ws >> i & 1 and fn(states[i]):  # type: ignore[operator]
            out |= 1 << i
        i += 1
    return out


def _add(conds: tuple[Formula, ...], f: Formula, uncertain: bool) -> tuple[Formula, ...]:
    if not uncertain or f in conds:
        return conds
    return (*conds, f)
