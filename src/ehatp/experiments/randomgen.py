"""Random small problems (the agreement check that runs planner, validator and executor on them
is :mod:`ehatp.experiments.agreement`).

``draw(seed)`` gives a :class:`Spec`, plain immutable data drawn with ``random.Random(seed)``;
``build(spec)`` turns it into an :class:`ehatp.Problem` with its :class:`ehatp.Domain`. The same
seed always gives the same problem, on every machine, so a seed is a complete bug report:

>>> from ehatp.experiments import randomgen
>>> problem = randomgen.problem(42)
>>> print(randomgen.draw(42).describe())           # doctest: +SKIP

What a spec draws (probabilities are per problem unless said otherwise):

- **Atoms.** ``home`` (the human is at home; always observable), 2-5 generic atoms ``a0..``,
  and with probability 0.5 two items ``x``, ``y`` with ``mark(i)`` (a robot puts a mark the
  human may take) and the static ``glass(i)``. Each generic atom's observability class is
  drawn: observable always (0.1), only when together (0.25), when the human is home (0.1),
  when the human is away (0.05), inferable (0.2), hidden (0.3); ``mark`` is visible when home
  and the item is glass (0.4), together (0.2), inferable or hidden (0.2 each).
- **Co-presence** is ``home`` (0.75) or ``home and aK`` (0.25: a door the agents may close).
- **Conditions fitted to an intended run.** Preconditions, task done-conditions and goal
  literals are drawn so that one interleaving of the two agendas goes through (see
  ``_Drawer``); about half of the problems are solvable, and their solutions need what one
  agent does for the other, seen or unseen.
- **Operators.** 1-3 generic robot and human operators: 0-2 precondition literals, 1-2 effect
  literals, a conditional effect (0.15), a done-condition (0.15), cost 1-3 (mostly 1). The
  human also has ``leave``/``back``, and ``take(i)`` (0.5 with items); the robot ``put(i)``
  (0.6 with items).
- **Tasks.** The robot's ``job`` (done-condition 0.35; 1-2 methods with a precondition 0.35,
  one with a free item parameter 0.25) and ``sub`` (0.5), ``fetch(i)`` (0.3 with ``put``); the
  human's ``chore`` (1-3 methods, a second one sharing the first's first step 0.4) whose
  methods go on a trip (leave, up to two actions away, back, then more) with probability 0.55
  each; the human starts away (0.1), then its methods begin with ``back``. The robot's
  agenda holds 1-3 tasks, the human's 1-2.
- **Partial order** (:data:`ORDERS`): in 0.3 of the problems, half the methods of two subtasks
  or more get an order: none (0.3) or some of the listed order's pairs, so both agents may
  interleave their subtasks (docs/semantics.md §1).
- **Loops** (:data:`LOOPS`): in 0.15 of the problems the robot's ``job`` (and the human's
  ``chore``, 0.5 of those) gets a method that refines the task itself first, then a step
  (docs/semantics.md §1, "Loops").
- **State variables and counters** (:data:`VALUES`): in 0.35 of the problems one generic atom
  (two, 0.4) is written as a state variable over 2-3 spots (it holds when the value is ``p1``;
  seen whole, or per value) or as a counter up to 2-3 (it holds when at least 1; an effect
  making it true adds 1 or 2, saturating); the worlds draw values within the atom's truth, so
  the human may also be wrong about which spot or how many (docs/semantics.md §2, §5).
- **Methods sharing a first action** (:data:`SHARED`): in 0.3 of the problems a robot method
  (0.3 a human one) gets an alternative of its task that starts with the same ground action and
  goes on otherwise: the robot cannot see which the human follows (docs/semantics.md §3), and
  two robot moves share a label (an executor must follow the policy's recorded edge).
- **Blocked attributed robot agendas** (:data:`BLOCKED`): in 0.2 of the problems one world's
  robot agenda starts with an action the human believes not applicable there (§5: the human
  then expects the robot not done in that world).
- **The shelf case** (:data:`COMMIT`): in 0.12 of the problems the human also shelves an object
  on a side it does not show until after ``grab``, and the robot clears one side: it must
  commit blind unless it may ask the human's intention (or intentions are visible).
- **Interchangeable objects** (:data:`TWINS`): in 0.4 of the problems with items (and ``put``
  or ``take``) two more items ``u``, ``v``, alike in everything and named by nothing, that the
  robot may ``stow`` and the human take: the symmetry reduction (§3) has states to merge.
- **M_R^H** is M_R itself (0.35), an equal copy (0.05), or M_R changed 1-3 times: an operator
  dropped (with the methods using it), an extra operator the robot does not have (used by an
  extra method), a method dropped or added, an operator's precondition or effects redrawn, a
  task dropped, a done-condition added or removed, or only the top task with a done-condition.
- **Beliefs.** One true world (0.25), one world with 1-2 false beliefs (0.35), or 2-3 worlds
  (uncertainty, 0.4); each world flips 0-2 atoms (favouring those the human's preconditions
  read) and attributes another robot agenda with probability 0.25 (empty, shortened, or
  different).
- **Goal literals** (0.3), an action cost override (0.15), and the problem's settings
  (:data:`SETTINGS`): who starts (even), K in 0..4 (weights 1, 3, 3, 2, 1), the costs of
  inform (1-5 or 1.5), ask (1-5), wait (1, 2 or 0.5) and pass (1 or 2). On a share
  :data:`PLAIN` (0.4) of the seeds every model option keeps its default; elsewhere each is
  drawn: a blocked human passes silently (0.75), the largest informing set (3, else 2 or 1),
  and away from the default with probability 0.1 each: the prototype or the idle pass rule,
  visible intentions, a non-anticipating human, inform anywhere, speech with action, relevance
  "plan", no asking, the robot announcing its intention, the expected objective (with ``pass``
  weighted 1/2 one time in ten) and other tie-breaks (0.2); the robot may ask the human's
  intention with probability 0.25. Grounding: one problem in five grounds every task on demand
  (``[limits] ground_ahead = 0``), one in five after 2 tasks, the rest ahead. Joint steps
  (``[steps] mode = "concurrent"``, docs/concurrent.md) with probability 0.2 where the
  options are drawn, witness "start" one time in four, the robot deciding first one time in
  four; those problems leave speech, the
  robot's question and its announcement at their defaults.
- **Preference profiles** (:data:`PREFERENCES`): half of the problems in joint steps take
  ``[objective] kind = "preferences"`` (docs/concurrent.md, C11): 2-3 profiles, each 1-5 of
  the built-in metrics (:data:`METRICS`) in a random order, one of them chosen, the
  worst-case estimate (0.7) or the optimistic one.

Settings are drawn in one place, :data:`SETTINGS`, a dict from ``"table.field"`` to a sampler;
each is drawn from its own generator (seeded by the seed and the key), so adding a setting
changes no other draw. :data:`TABLES` says how a table becomes part of the :class:`Problem`.
The draws of :data:`LOOPS`, :data:`ORDERS`, :data:`VALUES`, :data:`SHARED`, :data:`BLOCKED`,
:data:`COMMIT`, :data:`TWINS` and :data:`PREFERENCES` also have generators of their own: each
changes only the problems it draws on (the last five, and the options added with them,
changed about 60% of the seeds' problems of version 0.2; the rest are the same problems).

The module is over 800 lines on purpose: the draws are one recipe, each step a function, read
top to bottom for one seed (docs/architecture.md).
"""

from __future__ import annotations

import random
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Any

from ..model.domain import (
    HIDDEN,
    INFERABLE,
    AgentModel,
    Domain,
    Effect,
    Observability,
    observable,
    when,
)
from ..model.formula import TRUE, Atom, Formula, Var, conj, eq
from ..model.options import (
    DEFAULT_TIES,
    Communication,
    Estimate,
    HumanModel,
    InformWhere,
    Intentions,
    Metric,
    Objective,
    ObjectiveKind,
    Passes,
    Relevance,
    Speech,
    StepFirst,
    StepMode,
    Steps,
    Witness,
)
from ..model.problem import BeliefWorld, Costs, Limits, Problem

ITEMS = ("x", "y")
Lit = tuple[str, bool]  # ("a0", True), ("mark(?i)", False): "?i" is the item parameter
FIT = "?fit"  # a condition still to be fitted to the intended run

# --- settings: the one place where the problem's options and costs are drawn -----------------

Sampler = Callable[[random.Random], object]


def _weighted(pairs: Sequence[tuple[object, float]]) -> Sampler:
    values, weights = [v for v, _ in pairs], [w for _, w in pairs]
    return lambda r: r.choices(values, weights)[0]


SETTINGS: dict[str, Sampler] = {
    "problem.starts": _weighted([("human", 1), ("robot", 1)]),
    "problem.K": _weighted([(0, 1), (1, 3), (2, 3), (3, 2), (4, 1)]),
    "costs.inform": _weighted([(1, 4), (2, 2), (3, 1), (4, 1), (5, 1), (1.5, 1)]),
    "costs.ask": _weighted([(1, 4), (2, 2), (3, 1), (5, 1)]),
    "costs.wait": _weighted([(1, 6), (2, 1), (0.5, 1)]),
    "costs.pass_": _weighted([(1, 6), (2, 1)]),
    "human.passes_when_blocked": _weighted([(True, 3), (False, 1)]),
    # FAIR first then PROTOTYPE last: a seed drawing the prototype rule before "idle" existed
    # still does
    "human.passes": _weighted([(Passes.FAIR, 8), (Passes.IDLE, 1), (Passes.PROTOTYPE, 1)]),
    "human.intentions": _weighted([(Intentions.HIDDEN, 9), (Intentions.VISIBLE, 1)]),
    "human.anticipates": _weighted([(True, 9), (False, 1)]),
    "communication.inform_max_atoms": _weighted([(3, 4), (2, 1), (1, 1)]),
    "communication.inform": _weighted([(InformWhere.COPRESENT, 9), (InformWhere.ANYWHERE, 1)]),
    "communication.speech": _weighted([(Speech.TURN, 9), (Speech.WITH_ACTION, 1)]),
    "communication.relevance": _weighted([(Relevance.NEXT, 9), (Relevance.PLAN, 1)]),
    "communication.ask": _weighted([(True, 9), (False, 1)]),
    # relevant only where the human's hidden intentions call for different robot moves
    "communication.robot_asks": _weighted([(False, 3), (True, 1)]),
    "communication.announce": _weighted([(False, 9), (True, 1)]),
    "objective.kind": _weighted([(ObjectiveKind.WORST_CASE, 9), (ObjectiveKind.EXPECTED, 1)]),
    "objective.weights": _weighted([({}, 9), ({"pass": Fraction(1, 2)}, 1)]),
    "objective.ties": _weighted([(DEFAULT_TIES, 8), (("waits", "communications", "length"), 1),
                                 (("length",), 1)]),
    # tasks grounded before the search, the rest on demand (docs/semantics.md §1, "Grounding")
    "limits.ground_ahead": _weighted([(Limits.ground_ahead, 3), (0, 1), (2, 1)]),
    # joint, compliant steps (docs/concurrent.md)
    "steps.mode": _weighted([(StepMode.TURNS, 4), (StepMode.CONCURRENT, 1)]),
    "steps.witness": _weighted([(Witness.WHOLE, 3), (Witness.START, 1)]),
    "steps.first": _weighted([(StepFirst.HUMAN, 3), (StepFirst.ROBOT, 1)]),
}
"""``"table.field"`` -> sampler. Add a problem setting with one line here (and, for a new
table, one line in :data:`TABLES`); a field not drawn keeps its default."""

TABLES: dict[str, type | None] = {
    "problem": None,  # fields of Problem itself
    "costs": Costs,
    "human": HumanModel,
    "communication": Communication,
    "objective": Objective,
    "limits": Limits,
    "steps": Steps,
}
"""Each table of :data:`SETTINGS`: the dataclass its fields build, given to :class:`Problem`
under the table's name (None: the fields are :class:`Problem`'s own)."""
OPTION_TABLES = ("human", "communication", "objective", "steps")
"""The tables that choose a model (docs/semantics.md); :meth:`Spec.options` lists what they
set away from the defaults."""


PLAIN = 0.4
"""The share of problems whose model options (:data:`OPTION_TABLES`) all keep their defaults."""


def draw_settings(seed: int) -> tuple[tuple[str, object], ...]:
    """The settings of :data:`SETTINGS`, each from its own generator; on a share
    :data:`PLAIN` of the seeds, those of :data:`OPTION_TABLES` are left at their defaults."""
    plain = random.Random(f"{seed}:plain").random() < PLAIN
    drawn = tuple((key, SETTINGS[key](random.Random(f"{seed}:{key}")))
                  for key in sorted(SETTINGS)
                  if not (plain and key.partition(".")[0] in OPTION_TABLES))
    if dict(drawn).get("steps.mode") != StepMode.CONCURRENT:
        return tuple((k, v) for k, v in drawn if k not in ("steps.witness", "steps.first"))
    # joint steps read neither speech with an action nor the robot's question or
    # announcement (docs/concurrent.md): those keep their defaults
    return tuple((k, v) for k, v in drawn if k not in NOT_JOINT)


NOT_JOINT = frozenset({"communication.speech", "communication.robot_asks",
                       "communication.announce"})
"""Settings a problem in joint steps leaves at their defaults."""


# --- the spec: plain data ---------------------------------------------------------------------


@dataclass(frozen=True)
class OpSpec:
    """An operator; ``param`` makes it take the item ``?i``."""

    name: str
    param: bool = False
    pre: tuple[Lit, ...] = ()
    eff: tuple[Lit, ...] = ()
    cond: tuple[tuple[Lit, tuple[Lit, ...]], ...] = ()  # when(lit, effects)
    cost: int = 1
    done: tuple[Lit, ...] | None = None


@dataclass(frozen=True)
class TaskSpec:
    """An abstract task; ``param`` makes it take the item ``?i``."""

    name: str
    param: bool = False
    done: tuple[Lit, ...] | None = None


@dataclass(frozen=True)
class MethodSpec:
    """A method; ``free`` gives it its own item parameter ``?i`` (one alternative per item).
    Subtasks are written ``"r0"``, ``"put(x)"`` or ``"put(?i)"``."""

    task: str
    name: str
    pre: tuple[Lit, ...] = ()
    subtasks: tuple[str, ...] = ()
    free: bool = False
    # pairs (before, after) of subtask indices; None: in the order listed (see ORDERS)
    order: tuple[tuple[int, int], ...] | None = None


@dataclass(frozen=True)
class ModelSpec:
    """One HTN model: M_R, M_H or M_R^H."""

    ops: tuple[OpSpec, ...]
    tasks: tuple[TaskSpec, ...] = ()
    methods: tuple[MethodSpec, ...] = ()

    def op(self, name: str) -> OpSpec | None:
        return next((o for o in self.ops if o.name == name), None)


@dataclass(frozen=True)
class WorldSpec:
    """A world the human entertains: the atoms it has wrong, the robot agenda it assumes.
    ``blocked`` names the robot action the human expects first there but believes not
    applicable now (see :data:`BLOCKED`)."""

    flips: tuple[str, ...] = ()
    robot_agenda: tuple[str, ...] | None = None
    blocked: str = ""


@dataclass(frozen=True)
class ValueSpec:
    """A generic atom written as a state variable or a counter (see :data:`VALUES`).

    ``kind = "variable"``: ``atom`` is a variable over the spots ``p0..p{size-1}``; the atom
    holds when its value is ``p1``; an effect making the atom true sets ``p1``, one making it
    false sets ``p{off}``; ``sight`` is how the human sees it when the atom's class says it
    does: ``"whole"``, ``"value"`` (only whether it is ``p1``) or ``"others"`` (whether it is
    anything but ``p0``). ``kind = "counter"``: ``atom`` is a counter in ``0..size``; the atom
    holds when it is at least 1; making it true adds ``step`` (saturating), false sets 0.
    ``init`` and ``worlds`` are the value (a spot's index, or the number) in the initial state
    and in each belief world."""

    atom: str
    kind: str
    size: int
    init: int
    worlds: tuple[int, ...]
    sight: str = "whole"
    off: int = 0
    step: int = 1

    def holds(self, value: int) -> bool:
        """Whether the atom this stands for holds at ``value``."""
        return value == 1 if self.kind == "variable" else value >= 1


@dataclass(frozen=True)
class Spec:
    """Everything one seed draws; :func:`build` makes it a :class:`Problem`."""

    seed: int
    atoms: tuple[tuple[str, str], ...]  # (atom, observability kind)
    items: bool
    glass: tuple[str, ...]
    door: str | None  # co-presence is home, or home and this atom
    robot: ModelSpec
    human: ModelSpec
    robot_seen: ModelSpec | None  # None: M_R^H is M_R itself
    mutations: tuple[str, ...]
    init: tuple[str, ...]
    worlds: tuple[WorldSpec, ...]
    robot_agenda: tuple[str, ...]
    human_agenda: tuple[str, ...]
    goal: tuple[Lit, ...]
    action_costs: tuple[tuple[str, int], ...]
    settings: tuple[tuple[str, object], ...]  # ("table.field", value), see SETTINGS
    values: tuple[ValueSpec, ...] = ()  # atoms written as state variables or counters
    twins: tuple[str, ...] = ()  # interchangeable items besides ITEMS (see TWINS)
    shared: tuple[str, ...] = ()  # methods added with another's first action (see SHARED)
    commit: bool = False  # the shelf case of COMMIT

    def setting(self, key: str) -> object:
        """A drawn setting (KeyError for an option left at its default)."""
        return dict(self.settings)[key]

    def options(self) -> tuple[str, ...]:
        """The model options (:data:`OPTION_TABLES`) drawn away from their defaults, as
        ``table.field=value``: what to suspect first when a seed fails."""
        out = []
        for key, value in self.settings:
            table, _, name = key.partition(".")
            cls = TABLES[table]
            if table in OPTION_TABLES and cls is not None and value != getattr(cls(), name):
                out.append(f"{key}={_show(value)}")
        return tuple(out)

    def describe(self) -> str:
        """The spec, readable: what to look at when a seed fails."""
        def lits(ls: Iterable[Lit] | None) -> str:
            return " & ".join(a if v else f"~{a}" for a, v in ls or ()) or "true"

        def model(m: ModelSpec) -> list[str]:
            out = []
            for o in m.ops:
                extra = "".join(f" when {lits([c])}: {lits(e)};" for c, e in o.cond)
                done = f" done {lits(o.done)}" if o.done is not None else ""
                out.append(f"  op {o.name}{'(?i)' if o.param else ''}: pre {lits(o.pre)}; "
                           f"eff {lits(o.eff)};{extra} cost {o.cost}{done}")
            for t in m.tasks:
                done = f" done {lits(t.done)}" if t.done is not None else ""
                out.append(f"  task {t.name}{'(?i)' if t.param else ''}{done}")
            for me in m.methods:
                out.append(f"  method {me.task}.{me.name}{'[?i free]' if me.free else ''}: "
                           f"pre {lits(me.pre)} -> {', '.join(me.subtasks)}"
                           + ("" if me.order is None else
                              f" order {' '.join(f'{i}<{j}' for i, j in me.order) or 'none'}"))
            return out

        cop = "home" + (f" & {self.door}" if self.door else "")
        lines = [f"seed {self.seed}",
                 "atoms: " + ", ".join(f"{a}:{k}" for a, k in self.atoms),
                 f"items: {list(ITEMS) if self.items else []} glass {list(self.glass)}"
                 + (f", interchangeable {list(self.twins)}" if self.twins else ""),
                 f"copresence: {cop}", "M_R:", *model(self.robot), "M_H:", *model(self.human)]
        if self.robot_seen is None:
            lines.append("M_R^H: M_R")
        else:
            lines += [f"M_R^H ({', '.join(self.mutations) or 'copy'}):",
                      *model(self.robot_seen)]
        lines += [f"init: {list(self.init)}",
                  *(f"world {i}: flips {list(w.flips)}"
                    + ("" if w.robot_agenda is None else f", robot agenda {list(w.robot_agenda)}")
                    + (f" ({w.blocked} believed blocked)" if w.blocked else "")
                    for i, w in enumerate(self.worlds)),
                  f"agendas: robot {list(self.robot_agenda)}, human {list(self.human_agenda)}",
                  f"goal: {lits(self.goal)}", f"action costs: {dict(self.action_costs)}",
                  "settings: " + ", ".join(f"{k}={_show(v)}" for k, v in self.settings)]
        if self.shared:
            lines.append("methods sharing another's first action: " + ", ".join(self.shared))
        for v in self.values:
            what = (f"variable over p0..p{v.size - 1} (holds at p1, false sets p{v.off}, "
                    f"seen {v.sight})" if v.kind == "variable" else
                    f"counter 0..{v.size} (holds at >= 1, true adds {v.step}, false sets 0)")
            lines.append(f"value {v.atom}: {what}; init {v.init}, worlds {list(v.worlds)}")
        return "\n".join(lines)


def _show(v: object) -> str:
    """A setting's value as a problem file would write it."""
    if isinstance(v, str):  # a StrEnum prints its value
        return str(v)
    if isinstance(v, tuple):
        return "[" + ", ".join(map(_show, v)) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}: {_show(x)}" for k, x in v.items()) + "}"
    return str(v)


# --- drawing ----------------------------------------------------------------------------------

OBS_KINDS = (("always", 0.1), ("together", 0.25), ("home", 0.1), ("away", 0.05),
             ("inferable", 0.2), ("hidden", 0.3))
MARK_KINDS = (("glass", 0.4), ("together", 0.2), ("inferable", 0.2), ("hidden", 0.2))
MUTATIONS = (("drop_op", 2), ("extra_op", 2), ("drop_method", 2), ("extra_method", 2),
             ("change_pre", 3), ("change_eff", 1), ("drop_task", 1), ("toggle_done", 1),
             ("top_only", 1))
"""How M_R^H may differ from M_R, with relative weights (see :meth:`_Drawer.mutate`)."""


class _Drawer:
    """Draws one spec.

    The structure (atoms, effects, methods, agendas) is random. Then one *intended run* is
    simulated: each agenda decomposed with a random method per task, the two interleaved at
    random. Preconditions, task done-conditions and goal literals are fitted to it, preferring
    literals the run changed, so that most problems have a solution in which one agent needs
    the other's work. One fitted precondition in 12 gets an extra random literal (the run
    may then block: unsolvable problems are drawn too). A structure whose intended run breaks
    a fixed precondition (``put``, ``take``, ``leave``, ``back``) is redrawn, up to 3 times.
    """

    def __init__(self, seed: int) -> None:
        self.r = random.Random(seed)
        self.seed = seed

    def pick(self, pairs: Sequence[tuple[str, float]]) -> str:
        return self.r.choices([v for v, _ in pairs], [w for _, w in pairs])[0]

    def chance(self, p: float) -> bool:
        return self.r.random() < p

    def lits(self, atoms: Sequence[str], lo: int, hi: int) -> tuple[Lit, ...]:
        n = min(self.r.randint(lo, hi), len(atoms))
        return tuple((a, self.chance(0.5)) for a in sorted(self.r.sample(list(atoms), n)))

    def among(self, cands: list[Lit], favoured: Callable[[Lit], bool], n: int
              ) -> tuple[Lit, ...]:
        """``n`` of ``cands`` (fewer if short), three times likelier when ``favoured``."""
        cands = list(cands)
        weights = [3 if favoured(c) else 1 for c in cands]
        out: list[Lit] = []
        for _ in range(min(n, len(cands))):
            k = self.r.choices(range(len(cands)), weights)[0]
            out.append(cands.pop(k))
            weights.pop(k)
        return tuple(sorted(out))

    def cost(self) -> int:
        return self.r.choices([1, 2, 3], [6, 2, 1])[0]

    def op(self, name: str, atoms: Sequence[str], pre: tuple[Lit, ...] = ()) -> OpSpec:
        """An operator with random effects (its precondition is fitted later)."""
        eff = self.lits(atoms, 1, 2)
        cond: tuple[tuple[Lit, tuple[Lit, ...]], ...] = ()
        if self.chance(0.15):
            cond = ((self.lits(atoms, 1, 1)[0], self.lits(atoms, 1, 1)),)
        return OpSpec(name, False, pre, eff, cond, self.cost(),
                      (eff[0],) if self.chance(0.15) else None)

    def body(self, pool: Sequence[str], lo: int, hi: int) -> tuple[str, ...]:
        return tuple(self.r.choice(pool) for _ in range(self.r.randint(lo, hi)))

    def fit_later(self, p: float) -> tuple[Lit, ...] | None:
        """A placeholder for a condition fitted to the intended run (with probability p)."""
        return ((FIT, True),) if self.chance(p) else None

    def spec(self) -> Spec:
        for _ in range(3):
            spec = self.attempt()
            if spec is not None:
                return spec
        spec = self.attempt(accept=True)
        assert spec is not None
        return spec

    def attempt(self, accept: bool = False) -> Spec | None:
        r = self.r
        atoms = [(f"a{k}", self.pick(OBS_KINDS)) for k in range(r.randint(2, 5))]
        generic = [a for a, _ in atoms]
        items = self.chance(0.5)
        if items:
            atoms.append(("mark(?i)", self.pick(MARK_KINDS)))
        glass = tuple(i for i in ITEMS if self.chance(0.5)) if items else ()
        door = r.choice(generic) if self.chance(0.25) else None
        fluents = generic + ([f"mark({i})" for i in ITEMS] if items else [])

        robot, r_ops, robot_agenda, agenda_pool = self.robot_part(items, generic)
        human, h_ops, human_agenda, home = self.human_part(items, generic)

        init = (("home",) if home else ()) + tuple(a for a in fluents if self.chance(0.35))
        goal = self.fit_later(0.3) or ()
        feasible, robot, human, goal, final = self.fit(robot, human, init, robot_agenda,
                                                      human_agenda, generic, fluents, goal)
        if not feasible and not accept:
            return None
        robot_seen, mutations = self.robot_seen(robot, generic, fluents, final, init)
        worlds = self.worlds(fluents, robot_agenda, agenda_pool, human)
        ops_named = [o.name for o in r_ops + h_ops if o.name not in ("leave", "back")]
        action_costs = ((r.choice(ops_named), r.randint(1, 3)),) if self.chance(0.15) else ()
        return Spec(self.seed, tuple(atoms), items, glass, door, robot, human, robot_seen,
                    mutations, init, worlds, robot_agenda, human_agenda, goal, action_costs,
                    draw_settings(self.seed))

    def robot_part(self, items: bool, generic: list[str]
                   ) -> tuple[ModelSpec, list[OpSpec], tuple[str, ...], list[str]]:
        """Return the robot's model (operators r0.., put(i); tasks job, sub, fetch(i)), its
        operators, its agenda and what the agendas draw from."""
        r = self.r
        r_ops = [self.op(f"r{k}", generic) for k in range(r.randint(1, 3))]
        if items and self.chance(0.6):
            r_ops.append(OpSpec("put", True, (("mark(?i)", False),), (("mark(?i)", True),),
                                cost=self.cost(),
                                done=(("mark(?i)", True),) if self.chance(0.6) else None))
        has_put = any(o.name == "put" for o in r_ops)
        r_prims = [o.name for o in r_ops if not o.param] + (["put(x)", "put(y)"] if has_put
                                                             else [])
        tasks = [TaskSpec("job", False, self.fit_later(0.35))]
        methods: list[MethodSpec] = []
        if self.chance(0.5):
            tasks.append(TaskSpec("sub", False, self.fit_later(0.25)))
            for k in range(r.randint(1, 2)):
                methods.append(MethodSpec("sub", f"s{k}", self.fit_later(0.3) or (),
                                          self.body(r_prims, 1, 2)))
        if has_put and self.chance(0.3):
            tasks.append(TaskSpec("fetch", True, (("mark(?i)", True),)))
            methods.append(MethodSpec("fetch", "f", (), ("put(?i)",)))
        job_pool = r_prims + [t.name if not t.param else "fetch(x)" for t in tasks[1:]]
        for k in range(r.choices([1, 2], [3, 2])[0]):
            if has_put and self.chance(0.25):  # a free parameter: put any unmarked item
                methods.append(MethodSpec("job", f"j{k}", (("mark(?i)", False),),
                                          ("put(?i)", *self.body(job_pool, 0, 1)), free=True))
            else:
                methods.append(MethodSpec("job", f"j{k}", self.fit_later(0.35) or (),
                                          self.body(job_pool, 1, 3)))
        robot = ModelSpec(tuple(r_ops), tuple(tasks), tuple(methods))
        agenda_pool = ["job", *job_pool]
        robot_agenda = ("job",) if self.chance(0.6) else self.body(agenda_pool, 1, 3)
        return robot, r_ops, robot_agenda, agenda_pool

    def human_part(self, items: bool, generic: list[str]
                   ) -> tuple[ModelSpec, list[OpSpec], tuple[str, ...], bool]:
        """Return the human's model (operators h0.., leave, back, take(i); task chore), its
        operators, its agenda and whether it starts at home."""
        r = self.r
        h_ops = [self.op(f"h{k}", generic) for k in range(r.randint(1, 3))]
        h_ops += [OpSpec("leave", False, (("home", True),), (("home", False),)),
                  OpSpec("back", False, (("home", False),), (("home", True),))]
        if items and self.chance(0.5):
            h_ops.append(OpSpec("take", True, (("mark(?i)", True),), (("mark(?i)", False),),
                                cost=self.cost(),
                                done=(("mark(?i)", False),) if self.chance(0.3) else None))
        h_prims = [o.name for o in h_ops if o.name.startswith("h")] + (
            ["take(x)", "take(y)"] if any(o.name == "take" for o in h_ops) else [])
        home = self.chance(0.9)  # else the human starts away, and comes back first thing
        h_methods: list[MethodSpec] = []
        for k in range(r.choices([1, 2, 3], [4, 4, 1])[0]):
            if self.chance(0.55):  # a trip: leave (when home), act away, come back, act
                body: tuple[str, ...] = (*(("leave",) if home else ()),
                                         *self.body(h_prims, 0, 2), "back",
                                         *self.body(h_prims, 0, 2))
            else:
                body = (*(() if home else ("back",)), *self.body(h_prims, 1, 3))
            first = h_methods[0].subtasks[0] if h_methods else ""
            if first in h_prims and body[0] in h_prims and self.chance(0.4):
                body = (first, *body[1:])  # the same first step, then another way
            h_methods.append(MethodSpec("chore", f"c{k}", self.fit_later(0.3) or (), body))
        human = ModelSpec(tuple(h_ops), (TaskSpec("chore", False, self.fit_later(0.2)),),
                          tuple(h_methods))
        human_agenda = ("chore",) + ((r.choice(h_prims),) if self.chance(0.25) else ())
        return human, h_ops, human_agenda, home

    # -- fitting conditions to one intended run ----------------------------------------------

    def fit(self, robot: ModelSpec, human: ModelSpec, init: Sequence[str],
            robot_agenda: Sequence[str], human_agenda: Sequence[str], generic: Sequence[str],
            fluents: Sequence[str], goal: tuple[Lit, ...]
            ) -> tuple[bool, ModelSpec, ModelSpec, tuple[Lit, ...], frozenset[str]]:
        """Whether the run keeps the fixed preconditions, the models with fitted conditions,
        the goal and the run's final state."""
        models = (robot, human)
        runs = [self.expand(robot, robot_agenda), self.expand(human, human_agenda)]
        state = frozenset(init)
        feasible = True
        snaps: dict[tuple[int, str], list[frozenset[str]]] = {}
        while runs[0] or runs[1]:
            who = self.r.choice([k for k in (0, 1) if runs[k]])
            kind = "method"
            while kind == "method" and runs[who]:  # methods are chosen with their first action
                kind, name, arg = runs[who].pop(0)
                snaps.setdefault((who, name), []).append(state)
            op = models[who].op(name)
            if op is None or (op.done is not None and _holds(op.done, arg, state)):
                continue
            if (op.param or op.name in ("leave", "back")) and not _holds(op.pre, arg, state):
                feasible = False
            state = _apply(op, arg, state)

        def pre(who: int, name: str, most: int) -> tuple[Lit, ...]:
            seen = snaps.get((who, name))
            if not seen:
                return self.lits(generic, 0, 1)
            first = seen[0]
            cands = [(a, a in first) for a in generic
                     if all((a in s) == (a in first) for s in seen)]
            out = self.among(cands, lambda c: (c[0] in init) != c[1],
                             self.r.randint(0 if most > 1 else 1, most))
            if self.chance(0.08):
                extra = self.lits(generic, 1, 1)[0]
                if extra[0] not in {a for a, _ in out}:
                    out = tuple(sorted((*out, extra)))
            return out

        def at_end(atoms: Sequence[str]) -> tuple[Lit, ...]:
            return self.among([(a, a in state) for a in atoms],
                              lambda c: (c[0] in init) != c[1], 1)

        def done(t: TaskSpec) -> TaskSpec:
            return replace(t, done=at_end(fluents)) if t.done == ((FIT, True),) else t

        fitted = []
        for who, m in enumerate(models):
            ops = tuple(o if o.param or o.name in ("leave", "back")
                        else replace(o, pre=pre(who, o.name, 2)) for o in m.ops)
            meths = tuple(replace(me, pre=pre(who, f"{me.task}.{me.name}", 1))
                          if me.pre == ((FIT, True),) else me for me in m.methods)
            fitted.append(ModelSpec(ops, tuple(map(done, m.tasks)), meths))
        if goal:
            goal = self.among([(a, a in state) for a in generic],
                              lambda c: (c[0] in init) != c[1], self.r.randint(1, 2))
        return feasible, fitted[0], fitted[1], goal, state

    def expand(self, m: ModelSpec, agenda: Sequence[str]) -> list[tuple[str, str, str]]:
        """One decomposition of ``agenda``: ("op" | "method", name, item) in order."""
        out: list[tuple[str, str, str]] = []

        def go(calls: Sequence[str], depth: int) -> None:
            for c in calls:
                head, _, arg = c.partition("(")
                arg = arg.rstrip(")")
                if m.op(head) is not None:
                    out.append(("op", head, arg))
                    continue
                ms = [me for me in m.methods if me.task == head]
                if not ms or depth > 8:
                    continue
                me = self.r.choice(ms)
                if me.free:
                    arg = self.r.choice(ITEMS)
                out.append(("method", f"{head}.{me.name}", arg))
                go([s.replace("?i", arg) for s in me.subtasks], depth + 1)

        go(agenda, 0)
        return out

    # -- the human's beliefs -------------------------------------------------------------------

    def worlds(self, fluents: Sequence[str], agenda: tuple[str, ...], pool: Sequence[str],
               human: ModelSpec) -> tuple[WorldSpec, ...]:
        """One true world, one with false beliefs, or several (uncertainty). Flips favour the
        atoms the human's own preconditions read (three times likelier)."""
        r = self.r
        read = {_head(a) if "?i" in a else a for o in human.ops for a, _ in o.pre}
        read |= {f"mark({i})" for i in ITEMS if "mark" in read}
        kind = self.pick((("true", 0.25), ("false", 0.35), ("uncertain", 0.4)))
        if kind == "true":
            count, lo, hi = 1, 0, 0
        elif kind == "false":
            count, lo, hi = 1, 1, 2
        else:
            count, lo, hi = r.randint(2, 3), 0, 2
        out = []
        for _ in range(count):
            cands = [(a, a in read) for a in fluents]
            flips = tuple(a for a, _ in self.among(cands, lambda c: c[1], r.randint(lo, hi)))
            ag: tuple[str, ...] | None = None
            if self.chance(0.25):
                ag = r.choice([(), agenda[1:], self.body(pool, 1, 2)])
            out.append(WorldSpec(flips, ag))
        return tuple(out)

    def robot_seen(self, robot: ModelSpec, generic: Sequence[str], fluents: Sequence[str],
                   final: frozenset[str], init: Sequence[str]
                   ) -> tuple[ModelSpec | None, tuple[str, ...]]:
        """M_R^H: M_R itself, an equal copy, or M_R changed a few times."""
        r = self.r
        u = r.random()
        if u < 0.35:
            return None, ()
        if u < 0.4:
            return robot, ()
        m, done = robot, []
        end = self.among([(a, a in final) for a in fluents],
                         lambda c: (c[0] in init) != c[1], 1)
        for _ in range(r.choices([1, 2, 3], [5, 3, 1])[0]):
            kind = self.pick(MUTATIONS)
            m2 = self.mutate(m, kind, generic, end)
            if m2 is not None:
                m = m2
                done.append(kind)
        return m, tuple(done)

    def mutate(self, m: ModelSpec, kind: str, generic: Sequence[str],
               end: tuple[Lit, ...]) -> ModelSpec | None:
        """``m`` changed once (None when the change does not apply). ``end`` is a literal
        true at the end of the intended run, for new done-conditions."""
        r = self.r
        plain = [o for o in m.ops if not o.param]
        if kind == "drop_op" and m.ops:
            return _without(m, {r.choice(m.ops).name})
        if kind == "extra_op":
            task = r.choice(m.tasks) if m.tasks else None
            if task is None or task.param or m.op("ghost"):
                return None
            ghost = self.op("ghost", generic, self.lits(generic, 0, 1))
            pool = ["ghost", *(o.name for o in plain)]
            meth = MethodSpec(task.name, "g", (), ("ghost", *self.body(pool, 0, 1)))
            return replace(m, ops=(*m.ops, ghost), methods=(*m.methods, meth))
        if kind == "drop_method" and m.methods:
            i = r.randrange(len(m.methods))
            return replace(m, methods=m.methods[:i] + m.methods[i + 1:])
        if kind == "extra_method" and plain:
            task = r.choice([t for t in m.tasks if not t.param] or [None])
            if task is None:
                return None
            meth = MethodSpec(task.name, f"x{len(m.methods)}", self.lits(generic, 0, 1),
                              self.body([o.name for o in plain], 1, 2))
            return replace(m, methods=(*m.methods, meth))
        if kind in ("change_pre", "change_eff") and plain:
            o = r.choice(plain)
            new = (replace(o, pre=self.lits(generic, 1, 2)) if kind == "change_pre"
                   else replace(o, eff=self.lits(generic, 1, 2), cond=()))
            if new == o:
                return None
            return replace(m, ops=tuple(new if x is o else x for x in m.ops))
        if kind == "drop_task":
            subs = [t for t in m.tasks if t.name != "job"]
            return _without(m, {r.choice(subs).name}) if subs else None
        if kind == "toggle_done" and m.tasks:
            t = r.choice(m.tasks)
            t2 = replace(t, done=None if t.done is not None else
                         (("mark(?i)", True),) if t.param else end)
            return replace(m, tasks=tuple(t2 if x is t else x for x in m.tasks))
        if kind == "top_only":
            job = next(t for t in m.tasks if t.name == "job")
            return ModelSpec(m.ops, (replace(job, done=job.done or end),), ())
        return None


def _holds(ls: Iterable[Lit], arg: str, state: frozenset[str]) -> bool:
    return all((a.replace("?i", arg) in state) == v for a, v in ls)


def _apply(op: OpSpec, arg: str, state: frozenset[str]) -> frozenset[str]:
    """``op(arg)`` on a set of true atoms (deletes before adds, conditions read before)."""
    def name(a: str) -> str:
        return a.replace("?i", arg)

    effs = list(op.eff)
    for (c, v), e in op.cond:
        if (name(c) in state) == v:
            effs += e
    out = state - {name(a) for a, v in effs if not v}
    return out | {name(a) for a, v in effs if v}


def _without(m: ModelSpec, gone: set[str]) -> ModelSpec:
    """``m`` without the named operators/tasks, their methods and the methods using them
    (until nothing refers to a missing task)."""
    ops = tuple(o for o in m.ops if o.name not in gone)
    tasks = tuple(t for t in m.tasks if t.name not in gone)
    methods = m.methods
    while True:
        known = {o.name for o in ops} | {t.name for t in tasks}
        keep = tuple(me for me in methods if me.task in known
                     and all(_head(s) in known for s in me.subtasks))
        if keep == methods:
            return ModelSpec(ops, tasks, keep)
        methods = keep


def _head(call: str) -> str:
    return call.partition("(")[0]


ORDERS = (0.3, 0.5, 0.3)
"""Partially ordered methods: the share of problems that have some, the share of their methods
of two subtasks or more that get an order, and the share of those left unordered (the others
keep each pair of the listed order with probability 1/2). Drawn after everything else, from
generators of their own (see :func:`draw_orders`), so no other draw changes."""


def draw_orders(spec: Spec) -> Spec:
    """``spec`` with the partial orders of :data:`ORDERS` drawn. The listed order always
    remains allowed, so the intended run the conditions were fitted to still goes through. A
    method of M_R^H equal to one of M_R gets the same order."""
    share, per_method, unordered = ORDERS
    if random.Random(f"{spec.seed}:orders").random() >= share:
        return spec

    def model(m: ModelSpec, who: str) -> ModelSpec:
        out = []
        for me in m.methods:
            r = random.Random(f"{spec.seed}:order:{who}:{me.task}.{me.name}:{me.subtasks}")
            n = len(me.subtasks)
            if n < 2 or r.random() >= per_method:
                out.append(me)
                continue
            pairs = () if r.random() < unordered else tuple(
                (i, j) for i in range(n) for j in range(i + 1, n) if r.random() < 0.5)
            out.append(replace(me, order=pairs))
        return replace(m, methods=tuple(out))

    seen = None if spec.robot_seen is None else model(spec.robot_seen, "robot")
    return replace(spec, robot=model(spec.robot, "robot"), human=model(spec.human, "human"),
                   robot_seen=seen)


VALUES = (0.35, 0.4)
"""State variables and counters: the share of problems where a generic atom is written as one,
and the share of those where a second atom is too (the other kind first). Drawn after
everything else, from generators of their own (see :func:`draw_values`), so no other draw
changes."""


def draw_values(spec: Spec) -> Spec:
    """``spec`` with generic atoms written as a state variable or a counter (:data:`VALUES`).
    The atom's truth is kept in every state (conditions, effects, the goal read it as before),
    so the intended run still goes through; the worlds also draw a value within the atom's
    truth, so the human may be wrong about which spot or how many."""
    share, second = VALUES
    r = random.Random(f"{spec.seed}:values")
    if r.random() >= share:
        return spec
    kinds = dict(spec.atoms)
    generic = [a for a, _ in spec.atoms if "(" not in a and a != spec.door]
    order = ["variable", "counter"] if r.random() < 0.5 else ["counter", "variable"]
    chosen = r.sample(generic, min(len(generic), 2 if r.random() < second else 1))
    out = []
    for atom, kind in zip(chosen, order, strict=False):
        true0 = atom in spec.init
        size = r.choice([2, 3])
        if kind == "variable":
            falses = [0, 2] if size == 3 else [0]
            init = 1 if true0 else r.choice(falses)
            seen = kinds[atom] not in ("inferable", "hidden")
            sight = r.choice(["whole", "value", "others"]) if seen else "whole"
            off = r.choice(falses)
            trues = [1]
        else:
            falses, trues = [0], list(range(1, size + 1))
            init = r.randint(1, size) if true0 else 0
            sight, off = "whole", 0
        worlds = []
        for w in spec.worlds:
            true = true0 != (atom in w.flips)
            same = init if true == true0 else None
            pool = trues if true else falses
            worlds.append(same if same is not None and r.random() < 0.6 else r.choice(pool))
        out.append(ValueSpec(atom, kind, size, init, tuple(worlds), sight, off,
                             r.choice([1, 1, 2]) if kind == "counter" else 1))
    return replace(spec, values=tuple(out))


LOOPS = (0.15, 0.5)
"""Loops: the share of problems where a task gets a left-recursive method (its own task first,
then the first step of one of its methods), and the share of those where the human's task gets
one too (docs/semantics.md §1, "Loops"). Drawn before the orders (a loop may then sit in a
block), from a generator of its own (see :func:`draw_loops`), so no other draw changes."""


def draw_loops(spec: Spec) -> Spec:
    """``spec`` with the loops of :data:`LOOPS`: the robot's ``job`` (and M_R^H's, when it has
    one) and maybe the human's ``chore`` get a method ``loop`` that refines the task itself
    first. Refinement closes such loops, so the intended run still goes through."""
    share, human = LOOPS
    r = random.Random(f"{spec.seed}:loops")
    if r.random() >= share:
        return spec

    def model(m: ModelSpec | None, task: str) -> ModelSpec | None:
        if m is None:
            return None
        steps = [me.subtasks[0] for me in m.methods
                 if me.task == task and me.subtasks and "?i" not in me.subtasks[0]]
        if not steps:
            return m
        step = steps[0]
        return replace(m, methods=(*m.methods, MethodSpec(task, "loop", (), (task, step))))

    robot = model(spec.robot, "job")
    assert robot is not None
    spec = replace(spec, robot=robot, robot_seen=model(spec.robot_seen, "job"))
    if r.random() < human:
        chore = model(spec.human, "chore")
        assert chore is not None
        spec = replace(spec, human=chore)
    return spec




SHARED = (0.3, 0.3)
"""Methods sharing a first action: the share of problems where a robot method (of ``job`` or
``sub``) gets an alternative that starts with the same ground action and goes on otherwise, and
the share where a human ``chore`` method does. The robot cannot see which of the human's two
methods is followed (docs/semantics.md §3); two robot moves share a label where the robot's
two methods start (§4: an executor must follow the policy's recorded edge, not the first
label that matches). The alternative keeps the method's precondition (1/2), then the method's
rest turned by one step, one step shorter, one step longer, or redrawn; it is declared at a
random place among the methods; M_R^H gets the robot's alternative too (1/2) when it has the
method. Drawn after the orders, from a generator of its own (see :func:`draw_shared`), so no
other draw changes."""


def _prims(m: ModelSpec) -> list[str]:
    """The ground actions of ``m``, but ``leave`` and ``back``."""
    out: list[str] = []
    for o in m.ops:
        if o.name not in ("leave", "back"):
            out += [f"{o.name}({i})" for i in ITEMS] if o.param else [o.name]
    return out


def _alternative(r: random.Random, m: ModelSpec, tasks: Sequence[str]
                 ) -> tuple[MethodSpec, MethodSpec] | None:
    """A method of one of ``tasks`` in ``m`` that starts with a ground action, and a new
    method of the same task starting with that action and going on otherwise (None: no
    such method)."""
    bases = [me for me in m.methods if me.task in tasks and me.order is None and not me.free
             and me.subtasks and "?i" not in me.subtasks[0]
             and m.op(_head(me.subtasks[0])) is not None]
    if not bases:
        return None
    base = r.choice(bases)
    first, rest = base.subtasks[0], list(base.subtasks[1:])
    pool = _prims(m) or [first]
    way = r.choice(("turn", "shorter", "longer", "other"))
    droppable = [k for k, s in enumerate(rest) if s not in ("leave", "back")]
    if way == "turn" and len(set(rest)) > 1:
        new = rest[1:] + rest[:1]  # differs: not every step is the same
    elif way == "shorter" and droppable:
        k = r.choice(droppable)
        new = rest[:k] + rest[k + 1:]
    elif way == "other":
        new = [r.choice(pool) for _ in range(r.randint(1, 2))]
    else:
        new = list(rest)
    if new == rest:  # one step longer
        new.insert(r.randint(0, len(rest)), r.choice(pool))
    pre = base.pre if r.random() < 0.5 else ()
    return base, MethodSpec(base.task, f"{base.name}s", pre, (first, *new))


def _insert(m: ModelSpec, k: int, me: MethodSpec) -> ModelSpec:
    k = min(k, len(m.methods))
    return replace(m, methods=(*m.methods[:k], me, *m.methods[k:]))


def draw_shared(spec: Spec) -> Spec:
    """``spec`` with the methods of :data:`SHARED` that share another method's first
    action (their names in ``Spec.shared``)."""
    robot_share, human_share = SHARED
    r = random.Random(f"{spec.seed}:shared")
    added: list[str] = []
    if r.random() < robot_share:
        alt = _alternative(r, spec.robot, ("job", "sub"))
        if alt is not None:
            base, me = alt
            k = r.randint(0, len(spec.robot.methods))
            seen = spec.robot_seen
            if (seen is not None and base in seen.methods and r.random() < 0.5
                    and all(seen.op(_head(x)) for x in me.subtasks)):
                seen = _insert(seen, k, me)
            spec = replace(spec, robot=_insert(spec.robot, k, me), robot_seen=seen)
            added.append(f"robot {me.task}.{me.name}")
    if r.random() < human_share:
        alt = _alternative(r, spec.human, ("chore",))
        if alt is not None:
            _, me = alt
            spec = replace(spec, human=_insert(spec.human, r.randint(0, len(spec.human.methods)),
                                               me))
            added.append(f"human {me.task}.{me.name}")
    return replace(spec, shared=tuple(added)) if added else spec


BLOCKED = 0.2
"""Blocked attributed robot agendas: the share of problems where one belief world's robot
agenda starts with an action (of M_R and M_R^H) that the human believes not applicable now
(one of its precondition literals false in that world, flipped there if need be; its
done-condition not holding): either the robot's own agenda (when it starts with such an
action, 1/2) or that action alone (followed by the robot's agenda, 1/2). The human then
expects "the robot is not done" in that world whatever the robot did (docs/semantics.md §5:
expectations are read per world; a blocked world contributes "not done"). Drawn before the
values (a flipped atom may then become a state variable or a counter), from a generator of
its own (see :func:`draw_blocked`)."""


def draw_blocked(spec: Spec) -> Spec:
    """``spec`` with the blocked world agenda of :data:`BLOCKED` (``WorldSpec.blocked`` names
    the action)."""
    r = random.Random(f"{spec.seed}:blocked")
    if r.random() >= BLOCKED:
        return spec
    seen = spec.robot_seen or spec.robot
    ops = [o for o in seen.ops if not o.param and o.pre and spec.robot.op(o.name)]
    if not ops:
        return spec
    k = r.randrange(len(spec.worlds))
    w = spec.worlds[k]
    own = seen.op(spec.robot_agenda[0]) if spec.robot_agenda else None
    agenda: tuple[str, ...] | None
    if w.robot_agenda is None and own in ops and r.random() < 0.5:
        assert own is not None
        op, agenda = own, None
    else:
        op = r.choice(ops)
        agenda = (op.name, *(spec.robot_agenda if r.random() < 0.5 else ()))
    a, v = r.choice(op.pre)
    flips = list(w.flips)
    if ((a in spec.init) != (a in flips)) == v:  # the literal holds there: flip its atom
        flips = [f for f in flips if f != a] if a in flips else [*flips, a]
    state = frozenset(set(spec.init) ^ set(flips))
    if op.done is not None and _holds(op.done, "", state):
        return spec  # done there, not blocked
    world = WorldSpec(tuple(flips), agenda, op.name)
    return replace(spec, worlds=(*spec.worlds[:k], world, *spec.worlds[k + 1:]))


COMMIT = 0.12
"""The shelf case (docs/semantics.md §3): the share of problems where the human also has a task
``shelve`` (appended to its agenda) of two methods that both start with ``grab`` and then put
the object on side a (``put_a``) or b (``put_b``), each only when that side is clear (``ca``,
``cb``: false in the truth and in every world, with one observability class drawn for both),
and the robot a task ``clear`` (first or last on its agenda) that clears one side, either one,
once the human holds the object.
Under hidden intentions the robot sees ``grab`` but not the side, and must commit blind: no
policy, unless the robot may ask (``robot_asks``) or intentions are visible. M_R^H gets the
robot's new task too (0.7) when it is not M_R itself. Drawn after the values, from a generator
of its own (see :func:`draw_commit`)."""


def draw_commit(spec: Spec) -> Spec:
    """``spec`` with the shelf case of :data:`COMMIT` (``Spec.commit``)."""
    r = random.Random(f"{spec.seed}:commit")
    if r.random() >= COMMIT:
        return spec
    side = r.choices([k for k, _ in OBS_KINDS], [w for _, w in OBS_KINDS])[0]
    atoms = (*spec.atoms, ("ca", side), ("cb", side), ("held", "always"))
    # the robot clears a side once the human holds the object, not before (committing then
    # would fail on the other side whatever the human's intention is seen or not)
    ops = tuple(OpSpec(f"clr_{x}", False, (("held", True),), ((f"c{x}", True),)) for x in "ab")

    def with_clear(m: ModelSpec) -> ModelSpec:
        return replace(m, ops=(*m.ops, *ops), tasks=(*m.tasks, TaskSpec("clear")),
                       methods=(*m.methods, MethodSpec("clear", "ka", (), ("clr_a",)),
                                MethodSpec("clear", "kb", (), ("clr_b",))))

    human = replace(spec.human, ops=(
        *spec.human.ops, OpSpec("grab", eff=(("held", True),)),
        *(OpSpec(f"put_{x}", False, ((f"c{x}", True), ("held", True)), (("held", False),))
          for x in "ab")),
        tasks=(*spec.human.tasks, TaskSpec("shelve")),
        methods=(*spec.human.methods, MethodSpec("shelve", "sa", (), ("grab", "put_a")),
                 MethodSpec("shelve", "sb", (), ("grab", "put_b"))))
    agenda = ("clear", *spec.robot_agenda) if r.random() < 0.5 else (*spec.robot_agenda, "clear")
    seen = spec.robot_seen
    if seen is not None and r.random() < 0.7:
        seen = with_clear(seen)
    return replace(spec, atoms=atoms, robot=with_clear(spec.robot), robot_seen=seen,
                   human=human, robot_agenda=agenda,
                   human_agenda=(*spec.human_agenda, "shelve"), commit=True)


TWINS = 0.4
TWIN_ITEMS = ("u", "v")
"""Interchangeable objects: the share of problems with items, and the robot's ``put`` or the
human's ``take``, that get two more items :data:`TWIN_ITEMS`, named by no agenda, method or
goal and alike in every respect (both glass or neither; marked alike in the truth and in every
world), so that swapping them maps the problem onto itself and the symmetry reduction
(docs/semantics.md §3) has states to merge. With ``put`` the twins start unmarked and the robot
gets a task ``stow`` (put any unmarked item: a free method), appended to its agenda and to
M_R^H's model when that has ``put``; with ``take`` the human's ``chore`` gets a method that
takes any marked item. Drawn last, from a generator of its own (see :func:`draw_twins`)."""


def draw_twins(spec: Spec) -> Spec:
    """``spec`` with the interchangeable items of :data:`TWINS` (in ``Spec.twins``)."""
    r = random.Random(f"{spec.seed}:twins")
    if not spec.items or r.random() >= TWINS:
        return spec
    put = spec.robot.op("put") is not None
    take = spec.human.op("take") is not None
    if not (put or take):
        return spec
    marks = tuple(f"mark({t})" for t in TWIN_ITEMS)
    glass = spec.glass + (TWIN_ITEMS if r.random() < 0.5 else ())
    worlds = tuple(replace(w, flips=(*w.flips, *marks)) if r.random() < 0.2 else w
                   for w in spec.worlds)
    stow = MethodSpec("stow", "st", (("mark(?i)", False),), ("put(?i)",), free=True)

    def with_stow(m: ModelSpec) -> ModelSpec:
        return replace(m, tasks=(*m.tasks, TaskSpec("stow")), methods=(*m.methods, stow))

    robot, seen, agenda, human = spec.robot, spec.robot_seen, spec.robot_agenda, spec.human
    if put:
        robot, agenda = with_stow(robot), (*agenda, "stow")
        if seen is not None and seen.op("put") is not None:
            seen = with_stow(seen)
    if take:
        human = replace(human, methods=(*human.methods, MethodSpec(
            "chore", "ct", (("mark(?i)", True),), ("take(?i)",), free=True)))
    return replace(spec, twins=TWIN_ITEMS, glass=glass, worlds=worlds,
                   init=spec.init + (() if put else marks), robot=robot, robot_seen=seen,
                   robot_agenda=agenda, human=human)


PREFERENCES = 0.5
METRICS = ("makespan", "human_end", "human_effort", "effort", "communications")
"""Preference profiles (C11, docs/concurrent.md "Preferences"): the share of the problems in
joint steps that take ``[objective] kind = "preferences"``, and the metrics their profiles are
drawn from (the built-in ones, named here so that a metric added later changes no draw). The
problem gets 2-3 profiles ``p0``, ``p1``, ... (settings ``objective.profiles``), each 1-5 of
the metrics in a random order; the one chosen (``objective.profile``), and the estimate
(``objective.estimate``: worst-case 0.7, else optimistic). Drawn last, from a generator of
its own (see :func:`draw_preferences`): a problem in turns, or in joint steps without
preferences, is the one it was before."""


def draw_preferences(spec: Spec) -> Spec:
    """``spec`` with the preference profiles of :data:`PREFERENCES` when it is in joint steps
    and drawn to have them (its ``objective`` settings then say so)."""
    settings = dict(spec.settings)
    if settings.get("steps.mode") != StepMode.CONCURRENT:
        return spec
    r = random.Random(f"{spec.seed}:preferences")
    if r.random() >= PREFERENCES:
        return spec
    profiles = {f"p{i}": tuple(Metric(m) for m in r.sample(METRICS, r.randint(1, len(METRICS))))
                for i in range(r.randint(2, 3))}
    settings.update({
        "objective.kind": ObjectiveKind.PREFERENCES,
        "objective.profiles": profiles,
        "objective.profile": r.choice(sorted(profiles)),
        "objective.estimate": Estimate.WORST_CASE if r.random() < 0.7 else Estimate.OPTIMISTIC,
    })
    return replace(spec, settings=tuple(sorted(settings.items())))


def draw(seed: int) -> Spec:
    """The spec of seed ``seed`` (deterministic)."""
    spec = draw_shared(draw_orders(draw_loops(_Drawer(seed).spec())))
    return draw_preferences(draw_twins(draw_commit(draw_values(draw_blocked(spec)))))


# --- building ---------------------------------------------------------------------------------


def build(spec: Spec, *, reverse: bool = False) -> Problem:
    """The problem of ``spec``; ``reverse`` declares everything in the reverse order (the
    result must not change)."""
    return _Builder(spec, reverse).problem()


class _Builder:
    """The problem of one spec, built in the order :func:`build` has always declared it: the
    domain's types, predicates, variables and counters, the agents' models, then the
    problem's truth, worlds, goal and settings."""

    def __init__(self, spec: Spec, reverse: bool) -> None:
        self.spec, self.reverse = spec, reverse
        self.d = Domain(f"random-{spec.seed}")
        self.i = Var("i", self.d.type("item"))
        self.valued = {v.atom: v for v in spec.values}
        self.spots = [f"p{k}" for k in range(max((v.size for v in spec.values
                                                  if v.kind == "variable"), default=0))]

    def order(self, xs: Iterable[Any]) -> list[Any]:
        xs = list(xs)
        return xs[::-1] if self.reverse else xs

    def problem(self) -> Problem:
        """Return the problem: the domain declared and modelled, then the problem's data."""
        spec, valued = self.spec, self.valued
        self.declare()
        self.model_of(spec.robot, self.d.robot)
        self.model_of(spec.human, self.d.human)
        if spec.robot_seen is not None:
            self.d.robot_seen_by_human = self.model_of(spec.robot_seen,
                                                       AgentModel(self.d.robot_name))
        init = set(spec.init) - set(valued) | {f"glass({g})" for g in spec.glass}
        worlds = self.worlds(init)
        objects = {"item": self.order((*ITEMS, *spec.twins)),
                   **({"spot": self.order(self.spots)} if self.spots else {})}
        return Problem(
            name=f"random-{spec.seed}", domain=self.d, objects=objects,
            init=frozenset({*(_call(a) for a in init),
                            *(_value_of(vs, vs.init) for vs in spec.values)}),
            robot_agenda=tuple(map(_call, spec.robot_agenda)),
            human_agenda=tuple(map(_call, spec.human_agenda)),
            beliefs=tuple(self.order(worlds)),
            goal=tuple(self.goal(a, v) for a, v in spec.goal), **self.settings())

    def declare(self) -> None:
        """Declare the spot type, the predicates, state variables and counters with their
        observability, and co-presence."""
        spec, d, i = self.spec, self.d, self.i
        Spot = d.type("spot") if self.spots else ""
        at = Var("s", Spot) if self.spots else i
        home_vis = observable(Atom("home", ()))
        kinds: dict[str, Observability] = {
            "always": observable(), "home": home_vis, "away": observable(~Atom("home", ())),
            "inferable": INFERABLE, "hidden": HIDDEN,
            "glass": observable(Atom("home", ()) & Atom("glass", (i,))),
        }
        cop = conj(Atom("home", ()), *([Atom(spec.door, ())] if spec.door else []))
        kinds["together"] = observable(cop)
        decls: list[tuple[str, tuple[Var, ...], Observability]] = [
            ("home", (), observable())]
        for name, kind in spec.atoms:
            head = _head(name)
            decls.append((head, (i,) if head != name else (), kinds[kind]))
        if spec.items:
            decls.append(("glass", (i,), observable()))
        for head, params, obs in self.order(decls):
            vs = self.valued.get(head)
            if vs is None:
                d.predicate(head, *params, observability=obs)
            elif vs.kind == "counter":
                d.counter(head, max=vs.size, observability=obs)
            else:  # seen whole, or only whether it is p1, or whether it is not p0
                if obs.kind == "observable" and vs.sight != "whole":
                    which = eq(at, "p1") if vs.sight == "value" else ~eq(at, "p0")
                    obs = observable(conj(obs.when, which))
                d.variable(head, values=at, observability=obs)
        d.copresence = cop

    def atom(self, text: str) -> Atom:
        head, _, arg = text.partition("(")
        if not arg:
            return Atom(head, ())
        a = arg.rstrip(")")
        return Atom(head, (self.i if a == "?i" else a,))

    def lit(self, a: str, v: bool) -> Formula:
        vs = self.valued.get(a)
        if vs is None:
            return self.atom(a) if v else ~self.atom(a)
        if vs.kind == "variable":
            return self.d.variables[a]() == "p1" if v else self.d.variables[a]() != "p1"
        return self.d.counters[a]() >= 1 if v else self.d.counters[a]() == 0

    def formula(self, ls: Iterable[Lit] | None) -> Formula:
        parts = [self.lit(a, v) for a, v in ls or ()]
        return conj(*parts) if parts else TRUE

    def effect(self, a: str, v: bool) -> Effect:
        vs = self.valued.get(a)
        if vs is None:
            return self.atom(a) if v else ~self.atom(a)
        if vs.kind == "variable":
            return self.d.variables[a]().set("p1" if v else f"p{vs.off}")
        return self.d.counters[a]().incr(vs.step) if v else self.d.counters[a]().set(0)

    def effects(self, ls: Iterable[Lit]) -> list[Effect]:
        return [self.effect(a, v) for a, v in ls]

    def model_of(self, ms: ModelSpec, m: AgentModel) -> AgentModel:
        """Return ``m`` with the tasks, operators and methods of ``ms``."""
        i, formula = self.i, self.formula
        for t in self.order(ms.tasks):
            m.task(t.name, *((i,) if t.param else ()),
                   done=formula(t.done) if t.done is not None else None)
        for o in self.order(ms.ops):
            effs: list[Effect] = self.effects(o.eff)
            effs += [when(formula([c]), *self.effects(e)) for c, e in o.cond]
            m.action(o.name, *((i,) if o.param else ()), pre=formula(o.pre), effects=effs,
                     cost=o.cost, done=formula(o.done) if o.done is not None else None)
        for me in self.order(ms.methods):
            task = m.tasks[me.task]
            subs = []
            for s in me.subtasks:
                head, _, arg = s.partition("(")
                target = m.operators.get(head) or m.tasks[head]
                a = arg.rstrip(")")
                subs.append(target(i if a == "?i" else a) if arg else target())
            m.method(task, me.name, params=(i,) if me.free and not task.params else (),
                     pre=formula(me.pre), subtasks=subs, order=me.order)
        return m

    def worlds(self, init: set[str]) -> list[BeliefWorld]:
        """Return the worlds the human entertains, as differences from ``init``."""
        out = []
        for n, w in enumerate(self.spec.worlds):
            flips = set(w.flips) - set(self.valued)
            told = {_value_of(vs, vs.worlds[n]) for vs in self.spec.values
                    if vs.worlds[n] != vs.init}
            out.append(BeliefWorld(frozenset({*(_call(a) for a in flips - init), *told}),
                                   frozenset(_call(a) for a in flips & init),
                                   None if w.robot_agenda is None
                                   else tuple(_call(t) for t in w.robot_agenda)))
        return out

    def goal(self, a: str, v: bool) -> tuple[bool, tuple[str, tuple[str, ...]]]:
        vs = self.valued.get(a)
        if vs is None:
            return v, _call(a)
        if vs.kind == "variable":
            return v, (a, ("p1",))
        return not v, (a, ("0",))  # at least 1: not 0

    def settings(self) -> dict[str, Any]:
        """Return the Problem's keyword arguments the spec's settings give (:data:`TABLES`)."""
        tables: dict[str, dict[str, Any]] = {}
        for key, value in self.spec.settings:
            table, _, name = key.partition(".")
            tables.setdefault(table, {})[name] = value
        tables.setdefault("costs", {})["actions"] = dict(self.spec.action_costs)
        kwargs: dict[str, Any] = {}
        for table, fields in tables.items():
            cls = TABLES[table]
            kwargs.update(fields if cls is None else {table: cls(**fields)})
        return kwargs


def _call(text: str) -> tuple[str, tuple[str, ...]]:
    head, _, arg = text.partition("(")
    return head, (arg.rstrip(")"),) if arg else ()


def _value_of(vs: ValueSpec, k: int) -> tuple[str, tuple[str, ...]]:
    return vs.atom, (f"p{k}" if vs.kind == "variable" else str(k),)


def problem(seed: int, *, reverse: bool = False) -> Problem:
    """The random problem of ``seed``."""
    return build(draw(seed), reverse=reverse)


__all__ = ["BLOCKED", "COMMIT", "METRICS", "PREFERENCES", "SETTINGS", "SHARED", "TABLES", "TWINS",
           "VALUES", "ModelSpec", "Spec", "ValueSpec", "build", "draw", "draw_preferences",
           "problem"]
