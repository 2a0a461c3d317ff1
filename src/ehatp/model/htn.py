"""HTN refinement of totally ordered agendas over ground models.

``refine`` answers, for one state: which first primitive actions can the agent do next, and
with what remaining agenda? ``refine_in_all`` answers the same from the human's perspective over
a set of worlds: a condition (method precondition, done-condition, action precondition) that
holds in some worlds but not all makes that refinement *uncertain*, and the conditions that were
uncertain along the way are returned so the human can ask about them.
"""

from __future__ import annotations

from .domain import DomainError
from .formula import Formula, negate
from .grounding import FINISH, GModel

Agenda = tuple[int, ...]
Option = tuple[int, Agenda]  # (ground action id or FINISH, remaining agenda)

MAX_DECOMPOSITION = 64


class Refiner:
    """Refinement with memoisation: results depend only on (agenda, state(s))."""

    def __init__(self, model: GModel, task_names: list[str]) -> None:
        self.model = model
        self.task_names = task_names
        self._one: dict[tuple[Agenda, int], tuple[Option, ...]] = {}
        self._all: dict[tuple[Agenda, tuple[int, ...]], tuple[Uncertain, ...]] = {}

    def refine(self, agenda: Agenda, s: int) -> tuple[Option, ...]:
        """§1 (Refinement): the (first primitive action, remaining agenda) pairs of ``agenda``
        in the single state ``s``; ``(FINISH, ())`` when it can be completed. A task this model
        does not know gives nothing (the agent is blocked on it)."""
        key = (agenda, s)
        r = self._one.get(key)
        if r is None:
            out: set[Option] = set()
            self._go(agenda, s, out, 0)
            r = self._one[key] = tuple(sorted(out))
        return r

    def _go(self, agenda: Agenda, s: int, out: set[Option], depth: int) -> None:
        m = self.model
        while True:
            if not agenda:
                out.add((FINISH, ()))
                return
            t = agenda[0]
            op = m.ops.get(t)
            if op is not None:
                if op.done is not None and op.done(s):
                    agenda = agenda[1:]
                    continue
                if op.pre(s):
                    out.add((t, agenda[1:]))
                return
            d = m.done.get(t)
            if d is not None and d[1](s):
                agenda = agenda[1:]
                continue
            break
        if depth > MAX_DECOMPOSITION:
            raise DomainError(f"task {self.task_names[t]} decomposes without end "
                              f"(more than {MAX_DECOMPOSITION} nested methods)")
        rest = agenda[1:]
        # a task this model does not know gives nothing: the agent is blocked on it
        for meth in m.methods.get(t, ()):
            if meth.pre(s):
                self._go(meth.subtasks + rest, s, out, depth + 1)

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
                out: dict[tuple[int, Agenda, tuple[Formula, ...]], int], depth: int) -> None:
        m = self.model
        if not agenda:
            key: tuple[int, Agenda, tuple[Formula, ...]] = (FINISH, (), conds)
            out[key] = out.get(key, 0) | ws
            return
        t = agenda[0]
        rest = agenda[1:]
        op = m.ops.get(t)
        if op is not None:
            if op.done is not None and op.done_f is not None:
                dw = _holds(op.done, states, ws)
                if dw:
                    self._go_all(rest, states, dw, _add(conds, op.done_f, dw != ws), out, depth)
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
        d = m.done.get(t)
        if d is not None:
            dw = _holds(d[1], states, ws)
            if dw:
                self._go_all(rest, states, dw, _add(conds, d[0], dw != ws), out, depth)
            ws2 = ws & ~dw
            if not ws2:
                return
            conds = _add(conds, negate(d[0]), dw != 0)
            ws = ws2
        if depth > MAX_DECOMPOSITION:
            raise DomainError(f"task {self.task_names[t]} decomposes without end "
                              f"(more than {MAX_DECOMPOSITION} nested methods)")
        for meth in m.methods.get(t, ()):
            mw = _holds(meth.pre, states, ws)
            if mw:
                self._go_all(meth.subtasks + rest, states, mw,
                             _add(conds, meth.pre_f, mw != ws), out, depth + 1)


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
