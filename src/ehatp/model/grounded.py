"""A ground problem as the planner reads it (docs/semantics.md §1-§2): integer bitset states,
compiled formulas, ground agent models, and the units of state variables and counters.

Built by :func:`~ehatp.model.grounding.ground_problem`; data and lookups only.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, MutableMapping
from dataclasses import dataclass, field

from .formula import Formula, StateFn, Var, compile_ground, substitute
from .problem import Cost, Problem

FINISH = -1
"""Pseudo task id: the agenda can be completed (nothing left to do)."""


@dataclass(frozen=True, slots=True, eq=False)
class GOp:
    """A ground primitive action of one agent model."""

    id: int
    name: str
    schema: str
    args: tuple[str, ...]
    pre_f: Formula
    pre: StateFn
    add: int
    dele: int
    cond: tuple[tuple[StateFn, int, int], ...]
    cost: Cost
    done_f: Formula | None
    done: StateFn | None
    # the domain's metrics this action counts towards, each with its condition compiled
    # (docs/concurrent.md C11): (metric name, test of the state at the step's start);
    # empty in the human's estimate of the robot's model
    metrics: tuple[tuple[str, StateFn], ...] = ()

    def apply(self, s: int) -> int:
        add, dele = self.add, self.dele
        for fn, a, d in self.cond:
            if fn(s):
                add |= a
                dele |= d
        return (s & ~dele) | add


@dataclass(frozen=True, slots=True, eq=False)
class GMethod:
    name: str
    pre_f: Formula
    pre: StateFn
    subtasks: tuple[int, ...]
    # partial order: each subtask's predecessors (bitmask over subtasks, transitively closed);
    # None: the subtasks in the order listed (docs/semantics.md §1)
    order: tuple[int, ...] | None = None


@dataclass(eq=False)
class GModel:
    """A ground agent model: task id -> primitive action or (done condition, methods)."""

    agent: str
    # MutableMapping, not dict: grounded on demand they are ``_OnDemand`` dicts
    # (model/grounding.py) whose get/[]/in ground a task first, and code compiled with mypyc
    # (docs/compiled.md) reads a field typed dict through the C dict API, past those overrides
    ops: MutableMapping[int, GOp] = field(default_factory=dict)
    methods: MutableMapping[int, tuple[GMethod, ...]] = field(default_factory=dict)
    done: MutableMapping[int, tuple[Formula, StateFn]] = field(default_factory=dict)
    # grounded on demand: a task reached but not yet grounded is grounded when one of the
    # three tables is first asked about it; the tables then hold only what was asked for
    lazy: bool = False
    # on demand, the tasks reached but not yet grounded (asking a table about one grounds
    # it); None when the model was grounded whole
    pending: set[int] | None = None
    asked: int = 0  # how many tasks were grounded on demand so far


    def ready(self, t: int) -> bool:
        """Whether asking the tables about task ``t`` grounds nothing (§1, "Grounding")."""
        return self.pending is None or t not in self.pending


@dataclass(eq=False)
class Grounded:
    """Everything the planner needs, in compact form."""

    problem: Problem
    atoms: list[str]
    atom_index: dict[str, int]
    task_names: list[str]
    task_index: dict[str, int]
    robot: GModel
    human: GModel
    robot_seen_by_human: GModel
    init: int
    beliefs: list[tuple[int, tuple[int, ...]]]
    robot_agenda: tuple[int, ...]
    human_agenda: tuple[int, ...]
    visible: list[tuple[StateFn, int]]
    observable_mask: int
    inferable_mask: int
    hidden_mask: int
    copresent_f: Formula
    copresent: StateFn
    goal_f: Formula
    goal: StateFn
    fns: dict[Formula, StateFn]
    # ground formula -> the formula the domain wrote and its binding, read as text only when
    # a label or a message shows it (:meth:`reading`; most are never shown)
    written: dict[Formula, tuple[Formula, Mapping[Var, str]]]
    # finite-domain variables (one-hot: one bit per value, exactly one set) and counters
    # (binary: one bit per power of two), each a *unit* of several bits (docs/semantics.md §2)
    var_units: tuple[int, ...] = ()
    counter_units: tuple[int, ...] = ()
    unit_names: dict[int, str] = field(default_factory=dict)  # unit mask -> "loc(r)"
    counter_max: dict[int, int] = field(default_factory=dict)  # counter mask -> max
    multi_mask: int = 0  # the bits of every variable and counter
    unit_of: dict[int, int] = field(default_factory=dict)  # bit index -> its unit's mask
    readings: dict[Formula, str] = field(default_factory=dict)  # :meth:`reading`'s, kept

    def reading(self, f: Formula) -> str | None:
        """Return the ground formula ``f`` as the domain wrote it (derived predicates by
        name; remembered), or None when grounding met it only inside another formula."""
        r = self.readings.get(f)
        if r is None:
            w = self.written.get(f)
            if w is None:
                return None
            r = self.readings[f] = str(substitute(w[0], w[1]))
        return r

    def compile(self, f: Formula) -> StateFn:
        fn = self.fns.get(f)
        if fn is None:
            fn = self.fns[f] = compile_ground(f)
        return fn

    # -- units: a plain atom is one bit; a variable or a counter is all of its bits --
    def unit(self, i: int) -> int:
        """The mask of the unit bit ``i`` belongs to (§2)."""
        return self.unit_of.get(i, 1 << i)

    def expand(self, mask: int) -> int:
        """§2, §4: ``m`` with every variable and counter it touches made whole (what the
        human learns of an inferable unit whose value an action changed)."""
        if not mask & self.multi_mask:
            return mask
        for i in bits(mask & self.multi_mask):
            mask |= self.unit_of[i]
        return mask

    def units(self, mask: int) -> list[int]:
        """§2, §5: the (whole) units ``m`` touches, by their lowest bit: the candidates of an
        informing set, the order of observation."""
        if not mask & self.multi_mask:
            return [1 << i for i in bits(mask)]
        out: list[int] = []
        seen = 0
        for i in bits(mask):
            if not seen >> i & 1:
                u = self.unit(i)
                seen |= u
                out.append(u)
        return out

    def is_counter(self, unit: int) -> bool:
        """§2: whether ``unit`` is a counter (else an atom or a state variable)."""
        return unit in self.counter_max

    def counter_value(self, s: int, unit: int) -> int:
        """§2: the value of the counter ``unit`` in ``s`` (its bits, lowest first)."""
        return (s & unit) >> _low(unit)

    def fact(self, s: int, unit: int) -> str:
        """§2: what ``s`` says of a variable or counter: ``loc(r) = mt``, ``balls(b1) = 2``."""
        if unit in self.counter_max:
            return f"{self.unit_names[unit]} = {self.counter_value(s, unit)}"
        on = s & unit
        return self.atoms[_low(on)] if on else f"{self.unit_names[unit]} = ?"

    def unit_name(self, unit: int) -> str:
        """§5: a unit's name, by which informing sets are ranked: the atom, or the variable
        or counter (``loc(r)``)."""
        return self.unit_names.get(unit) or self.atoms[_low(unit)]

    def literal(self, t: int, unit: int) -> str:
        """``unit`` as ``t`` has it: ``a`` / ``not a`` for an atom, else its value (§5)."""
        if unit in self.unit_names:
            return self.fact(t, unit)
        name = self.atoms[_low(unit)]
        return name if t & unit else f"not {name}"

    def literals(self, t: int, mask: int) -> list[str]:
        """Every unit ``m`` touches as ``t`` has it, by index (divergences, informs)."""
        return [self.literal(t, u) for u in self.units(mask)]

    def world_diff(self, s: int, t: int) -> dict[str, list[str]]:
        """How world ``s`` differs from the truth ``t``: the atoms (and a variable's or
        counter's value in ``s``) true in ``s`` only, and those (with ``t``'s values) true in
        ``t`` only."""
        if not self.counter_units:
            return {"true": self.mask_atoms(s & ~t), "false": self.mask_atoms(t & ~s)}
        plain = ~self.counter_mask()
        diff = [u for u in self.counter_units if (s ^ t) & u]
        lo = [_low(u) for u in diff]
        return {"true": _merge(self, s & ~t & plain, [(i, self.fact(s, u))
                                                     for i, u in zip(lo, diff, strict=True)]),
                "false": _merge(self, t & ~s & plain, [(i, self.fact(t, u))
                                                      for i, u in zip(lo, diff, strict=True)])}

    def counter_mask(self) -> int:
        """The bits of every counter."""
        mask = 0
        for u in self.counter_units:
            mask |= u
        return mask

    def state_atoms(self, s: int) -> list[str]:
        """The true atoms of ``s``, with each variable's value (it is one of its bits) and
        each counter's value (``balls(b1) = 2``, 0 included)."""
        if not self.counter_units:
            return [self.atoms[i] for i in bits(s)]
        return _merge(self, s & ~self.counter_mask(),
                      [(_low(u), self.fact(s, u)) for u in self.counter_units])

    def mask_atoms(self, mask: int) -> list[str]:
        return [self.atoms[i] for i in bits(mask)]

    def visible_mask(self, t: int) -> int:
        out = 0
        for fn, mask in self.visible:
            if fn(t):
                out |= mask
        return out


def _low(mask: int) -> int:
    """The index of the lowest set bit of ``m`` (> 0)."""
    return (mask & -mask).bit_length() - 1


def _merge(g: Grounded, mask: int, extra: list[tuple[int, str]]) -> list[str]:
    """The names of ``m``'s bits and the ``extra`` (index, text) entries, by index."""
    return [name for _, name in sorted([*((i, g.atoms[i]) for i in bits(mask)), *extra])]


def bits(mask: int) -> Iterable[int]:
    """The indices of the set bits of ``m``, lowest first (the atoms of a mask, §2): one step
    per set bit, not per bit (a world's difference from the truth is a few bits of hundreds)."""
    while mask:
        low = mask & -mask
        yield low.bit_length() - 1
        mask ^= low


def no_check() -> None:
    """The ``check`` of grounding and refinement when no limit is watched: does nothing."""


__all__ = ["FINISH", "GMethod", "GModel", "GOp", "Grounded", "bits", "no_check"]
