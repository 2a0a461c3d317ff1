"""Which objects are interchangeable (docs/semantics.md §3, "Symmetry"): the objects the problem
does not name, grouped by type, and a swap of two of them kept when it is an *automorphism* of
the ground problem -- the initial state, the belief worlds with their robot agendas, both
agendas, observability and visibility, co-presence and goal, and the three models' ground
operators, methods and done-conditions map onto themselves (formulas compared with
conjunctions and disjunctions as sets). Interchangeability is an equivalence, so the classes
take one check per object and class; :class:`~.symmetry.Symmetry` then renames and
canonicalises over them."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from typing import Any

from ..model.agenda import Agenda
from ..model.formula import And, Formula, GAtom, GTest, Not, Or
from ..model.grounded import GMethod, GModel, GOp, Grounded
from .symmetry import _TOKEN, NotSymmetric, Symmetry


def fixed_objects(grounded: Grounded) -> set[str]:
    """Objects the problem names (docs/semantics.md §3): never renamed."""
    p = grounded.problem
    out = set(p.domain.constants)
    names: list[str] = []
    for _, args in [*p.robot_agenda, *p.human_agenda]:
        out.update(args)
    for w in p.beliefs:
        for _, args in w.robot_agenda or ():
            out.update(args)
    for _, (_, args) in p.goal:
        out.update(args)
    names.extend(p.after)
    names.extend(k for k in p.costs.actions if "(" in k)
    names.extend(k for k in p.objective.weights if "(" in k)
    for text in names:
        out.update(_TOKEN.findall(text))
    return out


def detect(grounded: Grounded,
           check: Callable[[], None] | None = None) -> Symmetry | None:
    """The classes of interchangeable objects of ``g`` (docs/semantics.md §3), or None when
    there is none (or the problem uses a feature the reduction does not cover: partially
    ordered methods; a model too large to ground ahead, ``[limits] ground_ahead``).
    ``check`` (a limit's) is called between the swaps tried and while each is compared."""
    models = _models(grounded)
    if any(model.lazy for model in models):  # grounded on demand: the whole model is not known
        return None
    for model in models:
        for ms in model.methods.values():
            if any(x.order is not None for x in ms):
                return None
    fixed = fixed_objects(grounded)
    p = grounded.problem
    by_type: dict[str, list[str]] = {}
    for t, objs in p.objects.items():
        for o in objs:
            if o not in fixed:
                by_type.setdefault(t, []).append(o)
    cands = [sorted(v) for _, v in sorted(by_type.items()) if len(v) > 1]
    if not cands:
        return None
    # a Symmetry over every candidate gives the renamings to test; the real one is built on
    # the classes found
    trial = Symmetry(grounded, cands)
    checker = _Checker(grounded, trial, models, check)
    classes: list[list[str]] = []
    for cand in cands:
        found: list[list[str]] = []
        for o in cand:
            for cls in found:
                if checker.swap(cls[0], o):
                    cls.append(o)
                    break
            else:
                found.append([o])
        classes.extend(c for c in found if len(c) > 1)
    if not classes:
        return None
    return Symmetry(grounded, classes)


def _models(grounded: Grounded) -> list[GModel]:
    ms = [grounded.robot, grounded.human]
    if grounded.robot_seen_by_human is not grounded.robot:
        ms.append(grounded.robot_seen_by_human)
    return ms


class _Checker:
    """Whether swapping two objects maps the ground problem onto itself."""

    def __init__(self, grounded: Grounded, sym: Symmetry, models: list[GModel],
                 check: Callable[[], None] | None = None) -> None:
        self.grounded, self.sym, self.models = grounded, sym, models
        self.check = check
        self.formula_of = {id(fn): f for f, fn in grounded.fns.items()}
        # what a renaming is compared against does not depend on it: each formula's and each
        # task's methods' comparable value, computed once for every swap tried
        self._plain: dict[int, tuple[Formula, object]] = {}
        self._plain_methods: dict[tuple[int, int], Counter[Any]] = {}
        self._atoms: dict[int, tuple[object, int]] = {}  # id -> (the item, the atoms it reads)

    def plain(self, f: Formula | None) -> object:
        """Return ``f`` as a comparable value, not renamed (remembered)."""
        if f is None:
            return None
        r = self._plain.get(id(f))
        if r is None:  # the formula is kept with its value, so that its id stays its own
            r = self._plain[id(f)] = (f, _norm(f, {}))
        return r[1]

    def atoms(self, x: GOp | GMethod) -> int:
        """Return the atoms a ground operator or method names, as a mask (remembered): a
        renaming that moves none of them, nor any task it names, maps it onto itself."""
        r = self._atoms.get(id(x))
        if r is None:
            m = _mask(x.pre_f)
            if isinstance(x, GOp):
                m |= x.add | x.dele | _mask(x.done_f)
                for c, a, d in x.cond:
                    form = self.formula_of.get(id(c))
                    if form is None:  # as comparing it would say
                        raise NotSymmetric("an uncompiled condition")
                    m |= a | d | _mask(form)
            r = self._atoms[id(x)] = (x, m)
        return r[1]

    def plain_methods(self, model: GModel, t: int) -> Counter[Any]:
        """Return task ``t``'s methods in ``model`` as a multiset of comparable values, not
        renamed (remembered)."""
        key = (id(model), t)
        r = self._plain_methods.get(key)
        if r is None:
            r = self._plain_methods[key] = Counter(
                (self.plain(x.pre_f), x.subtasks, x.order) for x in model.methods[t])
        return r

    def swap(self, a: str, b: str) -> bool:
        """Return whether swapping ``a`` and ``b`` is an automorphism (§3, "Symmetry"): the
        problem's data (:meth:`_same_problem`) and every model (:meth:`_same_model`) map
        onto themselves."""
        sym = self.sym
        if self.check is not None:
            self.check()
        p = list(range(len(sym.objects)))
        i, j = sym.index[a], sym.index[b]
        p[i], p[j] = j, i
        pid = sym.pid(tuple(p))
        try:
            ren = _Renamed(self, pid, sym.atom_map(pid), sym.task_map(pid))
            return self._same_problem(ren) and all(self._same_model(ren, model)
                                                   for model in self.models)
        except (KeyError, NotSymmetric):
            return False

    def _same_problem(self, ren: _Renamed) -> bool:
        """Return whether the renaming maps the initial state, the agendas, the belief
        worlds, the observability masks and groups, the units, co-presence and the goal
        onto themselves."""
        grounded, st, ag, f, fn = self.grounded, ren.state, ren.agenda, ren.formula, ren.condition
        if st(grounded.init) != grounded.init \
                or ag(grounded.robot_agenda) != grounded.robot_agenda \
                or ag(grounded.human_agenda) != grounded.human_agenda:
            return False
        if sorted((st(s), ag(a)) for s, a in grounded.beliefs) != sorted(grounded.beliefs):
            return False
        for mask in (grounded.observable_mask, grounded.inferable_mask, grounded.hidden_mask,
                     grounded.multi_mask):
            if st(mask) != mask:
                return False
        if {st(u) for u in grounded.var_units} != set(grounded.var_units):
            return False
        counters = set(grounded.counter_max.items())
        if {(st(u), k) for u, k in grounded.counter_max.items()} != counters:
            return False
        vis = Counter((fn(v), st(mask)) for v, mask in grounded.visible)
        if vis != Counter((fn(v, False), mask) for v, mask in grounded.visible):
            return False
        return (f(grounded.copresent_f) == f(grounded.copresent_f, False)
                and f(grounded.goal_f) == f(grounded.goal_f, False))

    def _same_model(self, ren: _Renamed, model: GModel) -> bool:
        """Return whether the renaming maps ``model``'s ground operators (precondition,
        effects, cost, done-condition), methods (precondition, subtasks, order) and
        done-conditions onto the renamed tasks' own."""
        st, ag, f, fn, tmap = ren.state, ren.agenda, ren.formula, ren.condition, ren.tmap
        check, atoms, plain = self.check, self.atoms, self.plain
        # a task the renaming keeps, whose action or methods name nothing it moves, is
        # mapped onto itself: only the others are compared (two multisets with a common part
        # are equal exactly when the rest are)
        moving = self.sym.moving(ren.pid)
        for n, (t, op) in enumerate(model.ops.items()):
            if check is not None and not n & 63:
                check()
            u = tmap.get(t, t)
            if u == t and not atoms(op) & moving:
                continue
            o2 = model.ops.get(u)
            if o2 is None or op.cost != o2.cost or st(op.add) != o2.add \
                    or st(op.dele) != o2.dele or f(op.pre_f) != f(o2.pre_f, False) \
                    or f(op.done_f) != f(o2.done_f, False):
                return False
            c1 = Counter((fn(c), st(a), st(d)) for c, a, d in op.cond)
            c2 = Counter((fn(c, False), a, d) for c, a, d in o2.cond)
            if c1 != c2:
                return False
        for n, (t, methods) in enumerate(model.methods.items()):
            if check is not None and not n & 63:
                check()
            u = tmap.get(t, t)
            if u == t:
                moved = [x for x in methods
                         if atoms(x) & moving or any(s in tmap for s in x.subtasks)]
                if moved and Counter((f(x.pre_f), ag(x.subtasks), x.order) for x in moved) \
                        != Counter((plain(x.pre_f), x.subtasks, x.order) for x in moved):
                    return False
                continue
            if u not in model.methods:
                return False
            k1 = Counter((f(x.pre_f), ag(x.subtasks), x.order) for x in methods)
            if k1 != self.plain_methods(model, u):
                return False
        for t, (df, _) in model.done.items():
            u = tmap.get(t, t)
            if u == t and not _mask(df) & moving:
                continue
            d2 = model.done.get(u)
            if d2 is None or f(df) != f(d2[0], False):
                return False
        for t in model.ops.keys() | model.methods.keys() | model.done.keys():
            u = tmap.get(t, t)
            if (t in model.ops, t in model.methods, t in model.done) != \
                    (u in model.ops, u in model.methods, u in model.done):
                return False
        return True


class _Renamed:
    """One candidate renaming ``pid`` applied to the parts of a ground problem (its atom
    and task maps ``amap`` and ``tmap``)."""

    def __init__(self, checker: _Checker, pid: int, amap: dict[int, int],
                 tmap: dict[int, int]) -> None:
        self.checker, self.pid, self.amap, self.tmap = checker, pid, amap, tmap

    def state(self, s: int) -> int:
        """Return the state ``s`` renamed."""
        return self.checker.sym.state(self.pid, s)

    def agenda(self, a: Agenda) -> Agenda:
        """Return the agenda ``a`` renamed."""
        return self.checker.sym.agenda(self.pid, a)

    def formula(self, x: Formula | None, mapped: bool = True) -> object:
        """Return ``x`` as a comparable value, renamed unless ``mapped`` is False."""
        return _norm(x, self.amap) if mapped else self.checker.plain(x)

    def condition(self, x: Callable[[int], bool], mapped: bool = True) -> object:
        """Return the compiled condition ``x`` as a comparable value (its formula)."""
        form = self.checker.formula_of.get(id(x))
        if form is None:
            raise NotSymmetric("an uncompiled condition")
        return self.formula(form, mapped)


def _mask(f: Formula | None) -> int:
    """Return the atoms a ground formula reads, as a mask."""
    if f is None:
        return 0
    if isinstance(f, GAtom):
        return 1 << f.index
    if isinstance(f, GTest):
        return _mask(f.body)
    if isinstance(f, Not):
        return _mask(f.arg)
    if isinstance(f, And | Or):
        m = 0
        for a in f.args:
            m |= _mask(a)
        return m
    raise NotSymmetric(f"a ground formula of kind {type(f).__name__}")


def _norm(f: Formula | None, amap: dict[int, int]) -> object:
    """A ground formula as a comparable value, atoms renamed by ``amap``, conjunctions and
    disjunctions as sets (ground quantifiers list objects in name order)."""
    if f is None:
        return None
    if isinstance(f, GAtom):
        return amap.get(f.index, f.index)
    if isinstance(f, GTest):
        return ("test", _norm(f.body, amap))
    if isinstance(f, Not):
        return ("not", _norm(f.arg, amap))
    if isinstance(f, And):
        return ("and", frozenset(_norm(a, amap) for a in f.args))
    if isinstance(f, Or):
        return ("or", frozenset(_norm(a, amap) for a in f.args))
    raise NotSymmetric(f"a ground formula of kind {type(f).__name__}")


__all__ = ["detect", "fixed_objects"]
