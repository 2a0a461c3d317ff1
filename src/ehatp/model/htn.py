"""HTN refinement of agendas over ground models (docs/semantics.md §1).

``refine`` answers, for one state: which first primitive actions can the agent do next, and
with what remaining agenda? ``refine_in_all`` answers the same from the human's perspective over
a set of worlds: a condition (method precondition, done-condition, action precondition) that
holds in some worlds but not all makes that refinement *uncertain*, and the conditions that were
uncertain along the way are returned so the human can ask about them.

What an agenda is -- items in order, a task id or a partially ordered :class:`Block` each (§1,
"Partial order") -- and the blocks' canonical form are :mod:`ehatp.model.agenda`. A totally
ordered agenda is a plain tuple of ints, and refining it takes the same path as before partial
order existed.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections.abc import Callable

from mypy_extensions import mypyc_attr

from ..errors import DomainError
from .agenda import Agenda, Block, Item, Networks
from .formula import FALSE, Formula, StateFn, negate
from .grounded import FINISH, GModel, no_check

MAX_DECOMPOSITION = 64
"""Default of ``[limits] max_decomposition``: nested method applications allowed before the
first action of a refinement (a task decomposing without end is a DomainError)."""

Way = tuple[StateFn, Formula, Agenda, StateFn | None, int, Agenda]
"""A method as the walk reads it: precondition, its formula, body; when the body starts with
an action without a done-condition, that action's precondition (else None), the first item's
task id (-1: a block, or none) and the body after it."""
Ways = tuple[Way, ...]
Option = tuple[int, Agenda]  # (ground action id or FINISH, remaining agenda)


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


# a Python class even where this module is compiled (docs/compiled.md): mypyc compiles no
# subclass of tuple
@mypyc_attr(native_class=False)
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
    """The worlds of ``ws`` (bit i: ``states[i]``) in which ``fn`` holds."""
    out = 0
    bit = 1
    for s in states:
        if bit > ws:
            break
        if ws & bit and fn(s):  # type: ignore[operator]
            out |= bit
        bit <<= 1
    return out


def _add(conds: tuple[Formula, ...], f: Formula, uncertain: bool) -> tuple[Formula, ...]:
    if not uncertain or f in conds:
        return conds
    return (*conds, f)


# Agenda, Block, Item and Networks live in .agenda; they stay importable from here
__all__ = ["MAX_DECOMPOSITION", "Agenda", "Block", "Item", "Networks", "Option", "Refiner",
           "Uncertain", "Way", "Ways"]
