"""The faster refinement (issue 17 §4) gives the rule's answers (docs/semantics.md §1,
"Refinement"): an agenda refined by splicing its first item's refinement onto the rest, and
methods left out that start with a task giving nothing in any state. Hand-made ground models,
answers derived by hand, and the rule's single walk (``Refiner._go`` on the whole agenda) as
the reference on many agendas."""

from __future__ import annotations

import itertools
import random

import pytest

import ehatp
from ehatp import Domain, Var
from ehatp.check.rules import Rules
from ehatp.epistemic.semantics import Semantics
from ehatp.errors import DomainError
from ehatp.model.agenda import Block
from ehatp.model.formula import FALSE, TRUE, And, Formula, GAtom, compile_ground
from ehatp.model.grounded import FINISH, GMethod, GModel, GOp
from ehatp.model.grounding import ground_problem
from ehatp.model.htn import Option, Refiner

from .scenarios import problem as scen_problem

A, B, C = (GAtom(i, n) for i, n in enumerate("abc"))
S0, SA, SC = 0, 0b001, 0b100  # nothing true; a; c


def op(t: int, name: str, pre: Formula, add: int = 0) -> GOp:
    return GOp(t, name, name, (), pre, compile_ground(pre), add, 0, (), 1, None, None)


def method(name: str, *subtasks: int, pre: Formula = TRUE) -> GMethod:
    return GMethod(name, pre, compile_ground(pre), subtasks)


X, Y, Z, T, U, D, S, G, H1, H2, H3 = range(11)
NAMES = ["x", "y", "z", "T", "U", "D", "S", "G", "H1", "H2", "H3"]


def model() -> GModel:
    """x needs a; y always applies; z never (its precondition folded to false). T is done once
    c holds and refines to x, to z then y (z gives nothing: left out), to itself then y (a
    loop) or to nothing. U refines to y, to itself then x (a loop) or to D; D only to tasks
    starting with z (so D gives nothing in any state). S is T then U. G is y, or H1 > H2 > H3
    > z (dead three methods deep)."""
    g = GModel("R")
    g.ops = {X: op(X, "x", A, add=0b010), Y: op(Y, "y", TRUE), Z: op(Z, "z", FALSE)}
    g.methods = {
        T: (method("T.x", X, pre=TRUE), method("T.zy", Z, Y), method("T.loop", T, Y),
            method("T.none")),
        U: (method("U.y", Y), method("U.loop", U, X), method("U.d", D)),
        D: (method("D.z", Z), method("D.zy", Z, Y)),
        S: (method("S", T, U),),
        G: (method("G.y", Y), method("G.h", H1)),
        H1: (method("H1", H2),), H2: (method("H2", H3),), H3: (method("H3", Z, Y),),
    }
    c = compile_ground(C)
    g.done = {T: (C, c)}
    return g


def walk(r: Refiner, agenda: tuple[int | Block, ...], s: int) -> tuple[Option, ...]:
    """The rule as one walk over the whole agenda (no splicing)."""
    out: set[Option] = set()
    r._go(agenda, s, out, 0)
    return tuple(sorted(out))


def test_hand_derived_options() -> None:
    """By hand, in the empty state: T's x needs a, its z-method gives nothing, its loop is
    closed, its empty method finishes it; then U gives y (then y), its loop is closed and D
    gives nothing. With a, T also gives x. With c, T is done and skipped."""
    r = Refiner(model(), NAMES)
    assert r.refine((T, U, Y), S0) == ((Y, (Y,)),)
    assert r.refine((T, U, Y), SA) == ((X, (U, Y)), (Y, (Y,)))
    assert r.refine((T, U, Y), SC) == ((Y, (Y,)),)
    assert r.refine((S, X), SA) == ((X, (U, X)), (Y, (X,)))
    assert r.refine((D, Y), SA) == ()  # blocked on D
    assert r.refine((T,), S0) == ((FINISH, ()),)
    assert r.refine((), S0) == ((FINISH, ()),)
    # the same answers the second time (memoised), and by the rule's single walk
    for agenda in ((T, U, Y), (S, X), (D, Y), (T,)):
        for s in (S0, SA, SC):
            assert r.refine(agenda, s) == walk(Refiner(model(), NAMES), agenda, s)


def test_a_task_that_gives_nothing_is_found_and_left_out() -> None:
    """z (false precondition, no done-condition) and D (only methods starting with z) give
    nothing in any state; T, U and H3's parents may give (H3 starts with z: dead; so are H2 and
    H1, one and two methods further up)."""
    r = Refiner(model(), NAMES)
    assert r._dead(Z, set()) == (-(1 << 30), True)  # an operator: no method in it
    assert r._dead(D, set()) == (0, True)
    assert r._dead(H1, set()) == (2, True)
    assert r._dead(T, set()) == (None, True)  # a done-condition: may give
    assert r._dead(U, set()) == (None, True)
    assert U not in r._kept  # not asked yet
    r.refine((U,), S0)
    kept, every, reach, final = r._kept[U]
    assert [w[2] for w in kept] == [(Y,), (U, X)] and reach == 1 and final == -1
    assert [w[2] for w in every] == [(Y,), (U, X), (D,)]
    # a body that starts with an action carries its precondition (y's: always); U does not
    assert [(w[3] is not None, w[4], w[5]) for w in kept] == [(True, Y, ()), (False, U, (X,))]


def test_left_out_methods_keep_the_nesting_limit() -> None:
    """G's second method walks H1, H2, H3 before meeting z: with a limit of 3 the walk stays
    within it (checks at depths 0-3) and G gives y alone; with 2, the walk goes past the limit
    at H3 (depth 3) and the error names G, as the rule's walk does."""
    assert Refiner(model(), NAMES, max_decomposition=3).refine((G,), S0) == ((Y, ()),)
    with pytest.raises(DomainError, match=r"task G nests more than 2 methods"):
        Refiner(model(), NAMES, max_decomposition=2).refine((G,), S0)
    with pytest.raises(DomainError, match=r"task G nests more than 2 methods"):
        walk(Refiner(model(), NAMES, max_decomposition=2), (G,), S0)


def test_spliced_nesting_carries_on_over_finished_tasks() -> None:
    """Five tasks F0..F4 each refined to nothing: the walk meets F_k at depth k (each
    finished task's method counts), so with a limit of 3 the agenda raises at F4 and names
    it -- although each task alone is one method deep."""
    g = GModel("R")
    g.methods = {k: (method(f"F{k}"),) for k in range(5)}
    names = [f"F{k}" for k in range(5)]
    r = Refiner(g, names, max_decomposition=3)
    assert r.refine((3, 4), S0) == ((FINISH, ()),)
    with pytest.raises(DomainError, match=r"task F4 nests more than 3 methods"):
        r.refine((0, 1, 2, 3, 4), S0)
    assert Refiner(g, names, max_decomposition=4).refine((0, 1, 2, 3, 4), S0) == ((FINISH, ()),)


def test_a_task_still_to_ground_is_not_judged() -> None:
    """On demand (§1, "Grounding"), a task not yet grounded is not read to judge whether it
    gives nothing (reading would ground it out of turn): the method is kept, the answer is
    the same, and it is judged again once the model has grounded more."""
    g = model()
    g.pending = {Z}
    r = Refiner(g, NAMES)
    assert r.refine((D, Y), SA) == ()
    assert r._kept[D][3] == 0  # not final: asked again after the next grounding
    g.pending = set()
    g.asked = 1
    assert r.refine((D, X), SC) == ()  # another state: D is refined again
    assert r._kept[D][3] == -1


def test_spliced_refinement_equals_the_walk_on_many_agendas() -> None:
    """Every agenda of up to three of T, U, D, S, G, x, y (and blocks of two), in every
    state of a, b, c: the spliced answer is the single walk's."""
    items: list[int | Block] = [T, U, D, S, G, X, Y, Block(((T, 0), (Y, 0))),
                                Block(((U, 0), (X, 1)))]
    rng = random.Random(17)
    agendas = [a for n in range(4) for a in itertools.product(items, repeat=n)]
    rng.shuffle(agendas)
    r = Refiner(model(), NAMES)
    for agenda in agendas:
        for s in range(8):
            assert r.refine(agenda, s) == walk(Refiner(model(), NAMES), agenda, s), (agenda, s)


def test_formulas_used_here_compile() -> None:
    assert compile_ground(And((A, C)))(0b101) and not compile_ground(FALSE)(0b111)


def saw_domain() -> Domain:
    """A robot that must ``cut``: each method binds a free size ``?z`` and starts with
    ``saw(?z)``, which needs the static ``fits(?z)``; only ``m`` fits. Then ``stack``."""
    d = Domain("saw")
    size = d.type("size")
    z = Var("z", size)
    fits = d.predicate("fits", z)
    cut_ = d.predicate("cut_done")
    saw = d.robot.action("saw", z, pre=fits(z), effects=[cut_()])
    stack = d.robot.action("stack", pre=cut_(), effects=[~cut_()])
    cut = d.robot.task("cut")
    d.robot.method(cut, "by_size", params=[z], subtasks=[saw(z), stack()])
    return d


def test_the_planner_and_the_validator_leave_out_a_saw_that_never_fits() -> None:
    """By hand: ``cut`` has three ground methods (sizes l, m, s); ``saw(l)`` and ``saw(s)``
    fold to false (``fits`` is static), so only ``m``'s may give: the robot saws m, then
    stacks (cost 2, the human passing in between: 3). The planner's refinement judges the
    other two dead (an operator: no method inside); the validator's leaves them out too and
    accepts the policy."""
    p = scen_problem(saw_domain(), init=["fits(m)"], robot=["cut"], starts="robot",
                     objects={"size": ["l", "m", "s"]})
    sem = Semantics(ground_problem(p))
    g = sem.grounded
    r = sem.R
    saws = {n: g.task_index[f"saw({n})"] for n in "lms"}
    assert r._dead(saws["l"], set()) == (-(1 << 30), True)
    assert r._dead(saws["m"], set()) == (None, True)
    cut = g.task_index["cut"]
    opts = r.refine((cut,), g.init)
    assert [(g.task_names[a], [g.task_names[t] for t in rest]) for a, rest in opts] == \
        [("saw(m)", ["stack"])]
    kept, every, _, _ = r._kept[cut]
    assert len(every) == 3 and [w[4] for w in kept] == [saws["m"]]
    result = ehatp.solve(p)
    assert result.policy is not None and result.policy.cost == 3
    rules = Rules(p)
    rcut = rules.grounded.task_index["cut"]
    live = rules._live(rules.grounded.robot, rcut)
    assert live is not None and [m.subtasks[0] for m in live] == \
        [rules.grounded.task_index["saw(m)"]]
    assert ehatp.validate(p, result.policy).ok
