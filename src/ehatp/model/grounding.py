"""Grounding: a problem becomes integer bitset states, compiled formulas and ground HTNs, once.

Objects are sorted by name and predicates by name, so atom indices, task ids and every later
order are canonical: the planner's output does not depend on declaration order.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from fractions import Fraction
from math import prod
from typing import Any, TypeVar

from ..errors import DomainError
from .bindings import Facts, Plan, binding_plan, bindings
from .domain import (
    AgentModel,
    Assign,
    Domain,
    Effect,
    ForEach,
    Method,
    TaskRef,
    When,
    article,
    signature,
)
from .formula import (
    FALSE,
    TRUE,
    And,
    Atom,
    Cmp,
    Formula,
    GAtom,
    GTest,
    Not,
    StateFn,
    Var,
    compile_ground,
    ground,
    product,
    simplify_and,
    value_in,
)
from .grounded import FINISH, GMethod, GModel, GOp, Grounded, _low, bits, no_check
from .problem import Cost, Problem, call_str


def ground_problem(problem: Problem, check: Callable[[], None] | None = None,
                   ahead: int | None = None) -> Grounded:
    """Ground ``problem`` after checking it (a Problem built in Python is checked as a problem
    file is: unknown predicates, objects or tasks raise InputError, not a KeyError later).
    ``check`` is called once per ground task (a time or memory limit may raise from it).

    §1, "Grounding": ``ahead`` tasks per agent model (default ``[limits] ground_ahead``) are
    grounded before the search; a model that reaches more is grounded the rest of the way on
    demand, as the refinement reaches its tasks. Task ids then follow the order the search
    meets tasks in (still deterministic), and object symmetry is not looked for (it needs the
    whole model)."""
    problem.check()
    return _Grounder(problem, check, ahead).run()


class _Grounder:
    def __init__(self, problem: Problem, check: Callable[[], None] | None = None,
                 eager: int | None = None) -> None:
        self.p = problem
        self.check = check or no_check
        # while the problem is grounded ahead (before anything uses it), the limit is also
        # looked at inside one formula's grounding (a quantifier over hundreds of objects can
        # take seconds); grounding on demand stops only between tasks, never in one
        self._ahead = True
        self._atoms_met = 0
        self.eager = problem.limits.ground_ahead if eager is None else eager
        self.d: Domain = problem.domain
        self.objects = problem.all_objects()
        # each object's own type (a subtype's objects are in their parents' lists too)
        self.obj_type = {**self.d.constants,
                         **{o: t for t, os in problem.objects.items() for o in os}}
        self.fns: dict[Formula, StateFn] = {}
        # ground formula -> how the domain wrote it (derived predicates kept by name), with
        # its binding
        self.written: dict[Formula, tuple[Formula, Mapping[Var, str]]] = {}
        self.task_names: list[str] = []
        self.task_index: dict[str, int] = {}
        self._derived: dict[tuple[str, tuple[str, ...]], Formula] = {}
        self.facts = Facts(problem.init, {n: len(x.params) for n, x in self.d.predicates.items()},
                           self.objects)
        self._subtasks_ok: set[tuple[int, str, tuple[str, ...]]] = set()  # (model, call)

    def run(self) -> Grounded:
        """Return the ground problem, built in named steps (GTPyhop-style pseudo-code)::

            ground(problem):
                fluent = the predicates an effect or a belief world changes; the rest static
                atoms = every fluent predicate, variable value and counter bit, by name,
                    the families of over LARGE_FAMILY atoms last
                init = the initial state's fluent facts, as bits
                visible, observable, inferable, hidden = the observability of every atom
                robot, human, robot-as-seen = the models' tasks the agendas reach, ground
                goal, co-presence = the ground formulas
        """
        names = self._fluents()
        units = self._atoms(names)
        self._static_facts()
        init = 0
        for n, a in self.p.init:
            if n not in self.static:
                init = self.put(init, n, a)
        visible, (obs, inf, hid) = self._observability(names)
        self.models: dict[int, GModel] = {}
        r_ag = self.agenda(self.p.robot_agenda)
        h_ag = self.agenda(self.p.human_agenda)
        robot, human, rh, beliefs = self._models(init, r_ag, h_ag)
        cop_f = self.ground_f(self.d.copresence, {})
        goal_f = self._goal()
        self._ahead = False
        return Grounded(
            problem=self.p, atoms=self.atoms, atom_index=self.atom_index,
            task_names=self.task_names, task_index=self.task_index, robot=robot, human=human,
            robot_seen_by_human=rh, init=init, beliefs=beliefs, robot_agenda=r_ag,
            human_agenda=h_ag, visible=visible, observable_mask=obs, inferable_mask=inf,
            hidden_mask=hid, copresent_f=cop_f, copresent=self.compile(cop_f), goal_f=goal_f,
            goal=self.compile(goal_f), fns=self.fns, written=self.written,
            var_units=tuple(mask for k, _, mask, _ in units if k == "variable"),
            counter_units=tuple(mask for k, _, mask, _ in units if k == "counter"),
            unit_names={mask: head for _, head, mask, _ in units},
            counter_max={mask: top for k, _, mask, top in units if k == "counter"},
            multi_mask=sum(mask for _, _, mask, _ in units),
            unit_of=self.unit_mask,
        )

    def _fluents(self) -> list[str]:
        """Return the predicates, state variables and counters in one namespace sorted by
        name, after setting which are static (no effect or belief world changes them, §2:
        folded into the formulas) and which can be made true (``added``)."""
        d, p = self.d, self.p
        fluent: set[str] = set()
        added: set[str] = set()
        for model in d.models().values():
            for op in model.operators.values():
                fluent |= _effect_preds(op.effects)
                added |= _effect_preds(op.effects, added_only=True)
        for w in p.beliefs:
            fluent |= {a[0] for a in w.true | w.false}
            added |= {a[0] for a in w.true}
        names = sorted({*d.predicates, *d.variables, *d.counters})
        self.static = {n for n in names if n not in fluent}
        # a predicate nothing makes true (actions only delete it, no world adds it): its
        # atoms false at the start are false in every state and world (§2), so read FALSE
        self.shrinking = {n for n in d.predicates if n in fluent and n not in added}
        return names

    def _atoms(self, names: list[str]) -> list[tuple[str, str, int, int]]:
        """Lay out the atoms (§2): one per ground fluent predicate; a state variable one bit
        per value (one-hot), a counter one bit per power of two. Return the variables' and
        counters' units as (kind, name, mask, max)."""
        d = self.d
        atoms: list[str] = []
        self.value_index: dict[str, int] = {}  # value view "loc(r, mt)" -> its bit
        self.counter_at: dict[str, int] = {}  # "balls(b1)" -> the counter's mask
        self.unit_mask: dict[int, int] = {}  # bit index -> its variable's or counter's mask
        units: list[tuple[str, str, int, int]] = []
        # families over LARGE_FAMILY atoms last: a state is an int as long as its highest bit
        for name in sorted(names, key=lambda n: self._family_size(n) > LARGE_FAMILY):
            if name in self.static:
                continue
            if name in d.predicates:
                for args in product([self.objects[v.type] for v in d.predicates[name].params]):
                    atoms.append(call_str(name, args))
                continue
            sv = d.variables.get(name)
            params = sv.params if sv is not None else d.counters[name].params
            for args in product([self.objects[v.type] for v in params]):
                head, lo = call_str(name, args), len(atoms)
                if sv is not None:
                    if not self.objects[sv.values]:
                        raise DomainError(f"variable {head} has no value: there is no "
                                          f"{sv.values}")
                    for val in self.objects[sv.values]:
                        self.value_index[call_str(name, (*args, val))] = len(atoms)
                        atoms.append(f"{head} = {val}")
                    top = 0
                else:
                    top = d.counters[name].max
                    atoms.extend(f"{head}[{1 << j}]" for j in range(top.bit_length()))
                mask = (1 << len(atoms)) - (1 << lo)
                self.unit_mask.update(dict.fromkeys(range(lo, len(atoms)), mask))
                units.append(("counter" if sv is None else "variable", head, mask, top))
                if sv is None:
                    self.counter_at[head] = mask
        self.atoms = atoms
        self.atom_index = {a: i for i, a in enumerate(atoms)}
        self.atom_index.update(self.value_index)  # loc(r, mt) reads as loc(r) = mt
        return units

    def _family_size(self, name: str) -> int:
        """Return how many atoms the predicate, variable or counter ``name`` grounds to."""
        d, sv, c = self.d, self.d.variables.get(name), self.d.counters.get(name)
        n = len(self.objects[sv.values]) if sv else c.max.bit_length() if c else 1
        return n * prod(len(self.objects[v.type])
                        for v in (d.predicates.get(name) or sv or d.counters[name]).params)

    def _static_facts(self) -> None:
        """The initial facts static and shrinking atoms are read from (§2), and the
        predicates a method's binding may be drawn from (true only where the initial state
        says, :meth:`_ModelGrounding.bindings`)."""
        d, p = self.d, self.p
        self.init_static = {call_str(n, a) for n, a in p.init if n in self.static}
        self.init_shrinking = {call_str(n, a) for n, a in p.init if n in self.shrinking}
        self.factual = {n for n in d.predicates if n in self.static or n in self.shrinking}
        self.init_counter = {call_str(n, a[:-1]): int(a[-1]) for n, a in p.init
                             if n in self.static and n in d.counters}

    def _observability(self, names: list[str]
                       ) -> tuple[list[tuple[StateFn, int]], tuple[int, int, int]]:
        """Return §2's observability: the visibility groups (a compiled ground condition and
        the atoms it shows; atoms grouped by their ground condition), and the masks of the
        observable, inferable and hidden atoms. A variable is read value by value (the
        condition may name the value), a counter whole."""
        d = self.d
        groups: dict[Formula, int] = {}
        obs = inf = hid = 0
        for name in names:
            if name in self.static:
                continue
            decl = d.predicates.get(name) or d.variables.get(name) or d.counters[name]
            kind = decl.observability.kind
            for args in product([self.objects[v.type] for v in decl.params]):
                b = dict(zip(decl.params, args, strict=True))
                if name in d.predicates:
                    cases = [(b, 1 << self.atom_index[call_str(name, args)])]
                elif name in d.variables:  # per value: the condition may name the value
                    sv = d.variables[name]
                    cases = [({**b, sv.value: val},
                              1 << self.value_index[call_str(name, (*args, val))])
                             for val in self.objects[sv.values]]
                else:  # a counter is seen whole
                    cases = [(b, self.counter_at[call_str(name, args)])]
                for binding, mask in cases:
                    if kind == "observable":
                        obs |= mask
                        gf = self.ground_f(decl.observability.when, binding)
                        if gf != FALSE:
                            groups[gf] = groups.get(gf, 0) | mask
                    elif kind == "inferable":
                        inf |= mask
                    else:
                        hid |= mask
        return [(self.compile(gf), mask) for gf, mask in groups.items()], (obs, inf, hid)

    def _models(self, init: int, r_ag: tuple[int, ...], h_ag: tuple[int, ...]
                ) -> tuple[GModel, GModel, GModel, list[tuple[int, tuple[int, ...]]]]:
        """Return the ground robot, human and robot-as-the-human-sees-it models (§1, the
        tasks the agendas reach) and the belief worlds as (state, the robot agenda the human
        attributes there). The robot's model reaches the belief worlds' agendas too when the
        human's view of it is the robot's own."""
        d = self.d
        robot = self.ground_model(d.robot, [r_ag], who="robot")
        human = self.ground_model(d.human, [h_ag], who="human")
        beliefs = []
        belief_agendas = [r_ag]
        for w in self.p.beliefs:
            s = init
            for n, a in sorted(w.true):
                s = self.put(s, n, a)
            s &= ~self.bits(call_str(*a) for a in w.false)
            ag = self.agenda(w.robot_agenda) if w.robot_agenda is not None else r_ag
            belief_agendas.append(ag)
            beliefs.append((s, ag))
        rh = (robot if d.robot_seen_by_human is d.robot
              else self.ground_model(d.robot_seen_by_human, belief_agendas, estimate=True))
        if rh is robot and any(ag != r_ag for ag in belief_agendas):
            robot = rh = self.ground_model(d.robot, belief_agendas, who="robot")
        return robot, human, rh, beliefs

    def _goal(self) -> Formula:
        """Return the ground goal: the domain's goal formula and the problem's goal
        literals, conjoined (§6)."""
        parts = [self.ground_f(self.d.goal, {})] if self.d.goal is not None else []
        for positive, (n, a) in self.p.goal:
            gf = self.ground_f(Atom(n, a), {})
            parts.append(gf if positive else Not(gf))
        return simplify_and(parts)

    def put(self, s: int, name: str, args: tuple[str, ...]) -> int:
        """``s`` with the fact ``name(args)`` made true: an atom set; a variable given the
        value ``args[-1]``; a counter given the number ``args[-1]``."""
        if name in self.d.variables:
            idx = self.value_index[call_str(name, args)]
            return (s & ~self.unit_mask[idx]) | 1 << idx
        if name in self.d.counters:
            unit = self.counter_at[call_str(name, args[:-1])]
            return (s & ~unit) | int(args[-1]) << _low(unit)
        return s | 1 << self.atom_index[call_str(name, args)]

    def bits(self, names: Iterable[str]) -> int:
        b = 0
        for n in names:
            b |= 1 << self.atom_index[n]
        return b

    def compile(self, f: Formula) -> StateFn:
        fn = self.fns.get(f)
        if fn is None:
            fn = self.fns[f] = compile_ground(f)
        return fn

    def met(self) -> None:
        """One more atom or binding met while grounding ahead: every 1024, the limit is
        looked at (on demand, only between tasks)."""
        if self._ahead:
            self._atoms_met += 1
            if not self._atoms_met & 1023:
                self.check()

    def atom(self, pred: str, args: tuple[str, ...]) -> Formula:
        self.met()
        if pred in self.d.counters:  # balls(b1, 2), the value view: balls(b1) = 2
            c = self.d.counters[pred]
            if len(args) != len(c.params) + 1 or not args[-1].isdigit():
                raise DomainError(f"{call_str(pred, args)}: write a counter's value as "
                                  f"{pred}(...) = k")
            return self.compare(pred, args[:-1], "==", int(args[-1]))
        for a in args:
            if a not in self.obj_type:
                raise DomainError(f"{pred}({', '.join(args)}): unknown object {a!r}")
        if pred in self.d.variables:  # loc(r, mt), the value view: loc(r) = mt
            name = call_str(pred, args)
            if pred in self.static:
                return TRUE if name in self.init_static else FALSE
            idx = self.value_index.get(name)
            if idx is None:
                sv = self.d.variables[pred]
                raise DomainError(f"{Atom(pred, args[:-1])} = {args[-1]}: an argument or the "
                                  f"value has the wrong type (values are {sv.values}s)")
            return GAtom(idx, self.atoms[idx])
        dv = self.d.derived_predicates.get(pred)
        if dv is not None:  # grounded once per arguments (can_put(c, b) is in many formulas)
            key = (pred, args)
            g = self._derived.get(key)
            if g is None:
                g = self._derived[key] = self.ground_f(dv.body,
                                                       dict(zip(dv.params, args, strict=True)))
            return g
        if pred not in self.d.predicates:
            raise DomainError(f"unknown predicate {pred!r}")
        name = call_str(pred, args)
        if pred in self.static:
            return TRUE if name in self.init_static else FALSE
        if pred in self.shrinking and name not in self.init_shrinking:
            return FALSE
        idx = self.atom_index.get(name)
        if idx is None:
            raise DomainError(f"{name}: an argument has the wrong type")
        return GAtom(idx, name)

    def compare(self, name: str, args: tuple[str, ...], op: str, k: int) -> Formula:
        """The ground counter comparison ``name(args) op k``: a test over the counter's bits
        (values above its max never occur), printed as written; TRUE or FALSE if decided."""
        c = self.d.counters.get(name)
        if c is None:
            raise DomainError(f"unknown counter {name!r}")
        for a in args:
            if a not in self.obj_type:
                raise DomainError(f"{call_str(name, args)}: unknown object {a!r}")
        key = call_str(name, args)
        test = Cmp(name, args, op, k)
        if name in self.static:
            return TRUE if test.holds(self.init_counter.get(key, 0)) else FALSE
        unit = self.counter_at.get(key)
        if unit is None:
            raise DomainError(f"{key}: an argument has the wrong type")
        lo = _low(unit)
        digits = [GAtom(lo + j, self.atoms[lo + j]) for j in range(c.max.bit_length())]
        body = value_in(digits, {v for v in range(c.max + 1) if test.holds(v)}, c.max)
        return body if body in (TRUE, FALSE) else GTest(body, str(test))

    def ground_f(self, f: Formula, binding: Mapping[Var, str]) -> Formula:
        return ground(f, binding, self.objects, self.atom, self.compare)

    def never_false(self, c: Formula) -> bool:
        """Whether ``c`` grounds to a fluent atom or its negation for every binding of its
        variables by objects of their types, never to FALSE (§1, "Grounding": only static and
        shrinking atoms are read off the initial state): a literal of a predicate an effect
        both adds and deletes, its arguments variables of a type the predicate takes. Such a
        conjunct cannot rule out a method's binding, so binding it need not read it."""
        a = c.arg if isinstance(c, Not) else c
        if type(a) is not Atom:
            return False
        d = self.d
        decl = d.predicates.get(a.pred)
        if decl is None or a.pred in self.static or a.pred in self.shrinking \
                or a.pred in d.derived_predicates or a.pred in d.variables \
                or a.pred in d.counters or len(a.args) != len(decl.params):
            return False
        return all(isinstance(x, Var) and d.is_subtype(x.type, v.type)
                   for x, v in zip(a.args, decl.params, strict=True))

    def shown(self, f: Formula, binding: Mapping[Var, str]) -> Formula:
        """Ground ``f`` and remember how each conjunct reads in the domain's vocabulary: as
        written, with its binding, made text only if shown (``Grounded.reading``)."""
        written = self.written
        if not isinstance(f, And):
            g = self.ground_f(f, binding)
            if g not in written:
                written[g] = (f, binding)
            return g
        # each conjunct grounded once: the conjunction is their simplified And (as ground()
        # makes it), and each keeps its own reading too, first: a conjunction that simplifies
        # to one of its conjuncts reads as that conjunct, whichever formula was grounded first
        parts = [(part, self.ground_f(part, binding)) for part in f.args]
        g = simplify_and([gp for _, gp in parts])
        for part, gp in parts:
            if gp not in written:
                written[gp] = (part, binding)
        if g not in written:
            written[g] = (f, binding)
        return g

    # -- tasks --
    def task_id(self, name: str) -> int:
        i = self.task_index.get(name)
        if i is None:
            i = self.task_index[name] = len(self.task_names)
            self.task_names.append(name)
        return i

    def agenda(self, calls: Iterable[tuple[str, tuple[str, ...]]]) -> tuple[int, ...]:
        return tuple(self.task_id(call_str(n, a)) for n, a in calls)

    def ground_model(self, model: AgentModel, agendas: Sequence[tuple[int, ...]],
                     estimate: bool = False, who: str = "") -> GModel:
        """Ground the tasks reachable from ``agendas``: ``[limits] ground_ahead`` of them ahead,
        the rest when first asked for (§1; an estimate is always ground whole, so that
        "a task it does not know" means one it cannot reach, §4). In the human's
        ``estimate`` of the robot model a task it does not know has no way to be done (the
        human cannot expect it). ``who``: the agent whose metrics count (C11; "" for none)."""
        g = GModel(model.agent)
        mg = _ModelGrounding(self, model, g, estimate, who)
        for ag in agendas:
            for t in ag:
                mg.mention(t)
        if not mg.run(None if estimate else self.eager):
            mg.on_demand()
        return g

    def _check_subtask(self, model: AgentModel, st: TaskRef, args: tuple[str, ...]) -> None:
        key = (id(model), st.name, args)
        if key in self._subtasks_ok:  # each call checked once
            return
        decl = model.operators.get(st.name) or model.tasks.get(st.name)
        if decl is None:
            raise DomainError(f"{model.agent}: subtask {st.name!r} is neither a task nor an action")
        for a, v in zip(args, decl.params, strict=True):
            t = self.obj_type.get(a)
            if t is None or not self.d.is_subtype(t, v.type):
                kind = f"is {self.d.hierarchy.a(t)}" if t is not None else "is no object"
                raise DomainError(f"{model.agent}: subtask {st}: {a!r} {kind}; "
                                  f"{signature(decl.name, decl.params)} wants "
                                  f"{article(v.type)} {v.type} for {v.name}")
        self._subtasks_ok.add(key)

    def effects(self, effs: Sequence[Effect], b: Mapping[Var, str],
                cond: Formula) -> tuple[int, int, list[tuple[StateFn, int, int]]]:
        add = dele = 0
        conds: list[tuple[StateFn, int, int]] = []
        for e in effs:
            if isinstance(e, Atom | Not):
                atom = e if isinstance(e, Atom) else e.arg
                if not isinstance(atom, Atom):
                    raise DomainError(f"effect {e} is not an atom or its negation")
                if atom.pred in self.d.variables or atom.pred in self.d.counters:
                    raise DomainError(f"effect {e}: {atom.pred} has a value; change it with "
                                      f"{atom.pred}(...).set(...)")
                g = self.ground_f(atom, b)
                if g == FALSE and atom.pred in self.shrinking:
                    continue  # deletes an atom that is never true
                if not isinstance(g, GAtom):
                    raise DomainError(f"effect {e}: {atom.pred} is not a fluent predicate")
                bit = 1 << g.index
                if cond == TRUE:
                    if isinstance(e, Atom):
                        add |= bit
                    else:
                        dele |= bit
                else:
                    conds.append((self.compile(cond), bit if isinstance(e, Atom) else 0,
                                  0 if isinstance(e, Atom) else bit))
            elif isinstance(e, When):
                c = simplify_and([cond, self.ground_f(e.cond, b)])
                if c != FALSE:
                    a2, d2, c2 = self.effects(e.effects, b, c)
                    conds.extend(c2)
                    if a2 or d2:
                        conds.append((self.compile(c), a2, d2))
            elif isinstance(e, ForEach):
                for vals in product([self.objects[v.type] for v in e.vars]):
                    a2, d2, c2 = self.effects(e.effects,
                                              {**b, **dict(zip(e.vars, vals, strict=True))}, cond)
                    add |= a2
                    dele |= d2
                    conds.extend(c2)
            elif isinstance(e, Assign):
                unit, sets = self.assignment(e, b)
                for c_f, new_bits in sets:
                    c = simplify_and([cond, c_f])
                    if c == TRUE:
                        if (add | dele) & unit:  # one value at a time
                            raise DomainError(f"effect {e}: the action already changes "
                                              f"{Atom(e.name, e.args)}; give it one value")
                        add |= new_bits
                        dele |= unit & ~new_bits
                    elif c != FALSE:
                        conds.append((self.compile(c), new_bits, unit & ~new_bits))
            else:
                raise DomainError(f"not an effect: {e!r}")
        return add, dele & ~add, conds

    def assignment(self, e: Assign, b: Mapping[Var, str]) -> tuple[int, list[tuple[Formula, int]]]:
        """The unit an assignment changes and its (condition, new bits) cases: one for a set,
        one per value that changes for ``+=``/``-=`` (saturating at 0 and max)."""
        args = tuple(b[a] if isinstance(a, Var) else a for a in e.args)
        head = call_str(e.name, args)
        if e.name in self.d.variables:
            val = b[e.value] if isinstance(e.value, Var) else e.value
            idx = self.value_index.get(call_str(e.name, (*args, str(val))))
            if idx is None:
                sv = self.d.variables[e.name]
                raise DomainError(f"effect {e}: {val} is not a value of {head} (a {sv.values})")
            return self.unit_mask[idx], [(TRUE, 1 << idx)]
        c = self.d.counters.get(e.name)
        unit = self.counter_at.get(head)
        if c is None or unit is None:
            raise DomainError(f"effect {e}: {head} is not a state variable or a counter"
                              if c is None else f"effect {e}: an argument has the wrong type")
        lo = _low(unit)
        if e.value is not None:
            return unit, [(TRUE, int(e.value) << lo)]  # type: ignore[arg-type]
        digits = [GAtom(lo + j, self.atoms[lo + j]) for j in range(c.max.bit_length())]
        cases = []
        for v in range(c.max + 1):
            new = min(c.max, max(0, v + e.delta))
            if new != v:
                cases.append((value_in(digits, {v}, c.max), new << lo))
        return unit, cases


LARGE_FAMILY = 1024
"""Predicates, variables and counters of more ground atoms are laid out after the others
(docs/semantics.md §2): a state is an int as long as its highest bit, and IPC Entertainment's
five families of 5,184 atoms, which no state holds, came first by name, so that every state
was a 26,000-bit int, hashed at every lookup (half the search's time)."""
_V = TypeVar("_V")


class _OnDemand(dict[int, _V]):
    """A table of a ground model (task id -> entry) that grounds a task reached but not yet
    grounded (one of ``pending``) before answering about it."""

    __slots__ = ("_pending", "_ground")

    def __init__(self, data: Mapping[int, _V], pending: set[int],
                 ground: Callable[[int], None]) -> None:
        super().__init__(data)
        self._pending, self._ground = pending, ground

    def get(self, key: int, default: Any = None) -> Any:
        if key in self._pending:
            self._ground(key)
        return dict.get(self, key, default)

    def __getitem__(self, key: int) -> _V:
        if key in self._pending:
            self._ground(key)
        return dict.__getitem__(self, key)

    def __contains__(self, key: object) -> bool:
        if key in self._pending:
            self._ground(key)
        return dict.__contains__(self, key)


class _ModelGrounding:
    """Grounds one agent model task by task (§1): an action's precondition, effects and
    done-condition; an abstract task's done-condition and its methods, one per binding of
    their own parameters whose precondition is not false before any action."""

    def __init__(self, gr: _Grounder, model: AgentModel, g: GModel, estimate: bool,
                 who: str = "") -> None:
        self.gr, self.model, self.g, self.estimate, self.who = gr, model, g, estimate, who
        self.calls: dict[int, tuple[str, tuple[str, ...]]] = {}
        self.todo: list[int] = []
        self.seen: set[int] = set()
        self.methods_of: dict[str, list[Method]] = {}
        for method in model.methods:
            self.methods_of.setdefault(method.task.name, []).append(method)
        for ms in self.methods_of.values():
            ms.sort(key=lambda method: method.name)
        self.pending: set[int] | None = None  # on demand: reached, not yet grounded
        self._plans: dict[Method, Plan] = {}

    def mention(self, t: int, call: tuple[str, tuple[str, ...]] | None = None) -> None:
        """Task ``t`` is reached: ground it later (ahead, or on demand)."""
        if t not in self.calls:
            self.calls[t] = call or _split(self.gr.task_names[t])
        if self.pending is None:
            self.todo.append(t)
        elif t not in self.seen:
            self.pending.add(t)

    def run(self, limit: int | None) -> bool:
        """Ground ahead, depth first, until everything reached is grounded (True) or
        ``limit`` tasks are (False)."""
        todo, seen = self.todo, self.seen
        while todo:
            if limit is not None and len(seen) >= limit:
                return False
            t = todo.pop()
            if t not in seen:
                self.one(t)
        return True

    def on_demand(self) -> None:
        """Make the model's tables ground the rest of the reached tasks when asked."""
        pending = self.pending = {t for t in self.todo if t not in self.seen}
        self.todo = []
        g = self.g
        g.lazy = True
        g.pending = pending
        g.ops = _OnDemand(g.ops, pending, self.ask)
        g.methods = _OnDemand(g.methods, pending, self.ask)
        g.done = _OnDemand(g.done, pending, self.ask)

    def ask(self, t: int) -> None:
        """Ground ``t``, a pending task, now."""
        self.one(t)
        assert self.pending is not None
        self.pending.discard(t)
        self.g.asked += 1

    def one(self, t: int) -> None:
        """Ground task ``t``, mentioning the subtasks its methods reach."""
        gr, g, model = self.gr, self.g, self.model
        gr.check()  # a limit may stop here, before anything changed
        self.seen.add(t)
        name, args = self.calls[t]
        op = model.operators.get(name)
        if op is not None:
            b = dict(zip(op.params, args, strict=True))
            pre_f = gr.shown(op.pre, b)
            add, dele, cond = gr.effects(op.effects, b, TRUE)
            cost = gr.p.costs.actions.get(name, _exact(op.cost))
            done_f = gr.ground_f(op.done, b) if op.done is not None else None
            # C11: the metrics counting it, each condition compiled once (false: left out)
            counts = [(m.name, gr.ground_f(m.when, b)) for m in gr.d.metrics_of(self.who, name)]
            g.ops[t] = GOp(
                t, gr.task_names[t], name, args, pre_f, gr.compile(pre_f), add, dele,
                tuple(cond), cost, done_f, gr.compile(done_f) if done_f is not None else None,
                tuple((n, gr.compile(f)) for n, f in counts if f != FALSE))
            return
        task = model.tasks.get(name)
        if task is None and self.estimate:
            g.methods[t] = ()
            return
        if task is None:
            raise DomainError(f"{model.agent} has no task or action {name!r}")
        tb = dict(zip(task.params, args, strict=True))
        if task.done is not None:
            df = gr.ground_f(task.done, tb)
            g.done[t] = (df, gr.compile(df))
        gms = []
        for method in self.methods_of.get(name, []):
            plan = self._plans.get(method)
            if plan is None:
                plan = self._plans[method] = binding_plan(method, set(tb), gr.factual,
                                                          gr.never_false)
            for vals in bindings(method, tb, plan, gr.facts, gr.ground_f, gr.met):
                b = {**tb, **dict(zip(method.params, vals, strict=True))}
                pre_f = gr.shown(method.pre, b)
                if pre_f == FALSE:
                    continue
                subs = []
                for st in method.subtasks:
                    sargs = tuple(b[a] if isinstance(a, Var) else a for a in st.args)
                    gr._check_subtask(model, st, sargs)
                    sid = gr.task_id(call_str(st.name, sargs))
                    self.mention(sid, (st.name, sargs))
                    subs.append(sid)
                label = f"{method.name}({', '.join(vals)})" if vals else method.name
                gms.append(GMethod(f"{name}.{label}", pre_f, gr.compile(pre_f),
                                   tuple(subs), method.predecessors()))
        g.methods[t] = tuple(gms)


def _exact(c: int | float) -> Cost:
    """Costs are summed and compared exactly: a float becomes the Fraction it reads as."""
    return c if isinstance(c, int) else Fraction(str(c))


def _effect_preds(effs: Iterable[Effect], added_only: bool = False) -> set[str]:
    """The predicates, variables and counters ``effs`` change (``added_only``: those they
    may make true, or set)."""
    out: set[str] = set()
    for e in effs:
        if isinstance(e, Atom):
            out.add(e.pred)
        elif isinstance(e, Not) and isinstance(e.arg, Atom):
            if not added_only:
                out.add(e.arg.pred)
        elif isinstance(e, Assign):
            out.add(e.name)
        elif isinstance(e, When | ForEach):
            out |= _effect_preds(e.effects, added_only)
    return out


def _split(name: str) -> tuple[str, tuple[str, ...]]:
    head, _, rest = name.partition("(")
    args = tuple(a.strip() for a in rest.rstrip(")").split(",")) if rest.strip(")") else ()
    return head, args


__all__ = ["FINISH", "GMethod", "GModel", "GOp", "Grounded", "bits", "ground_problem", "no_check"]
