"""Partially ordered methods (docs/semantics.md §1, "Partial order"): both agents' options, the
human's anticipation of the robot, the canonical form, printing, the validator's independent
reading, and the recursion bound ``[limits] max_decomposition``."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

import ehatp
from ehatp import HIDDEN, INFERABLE, Domain, DomainError, HumanModel, Var, observable
from ehatp.check import validator as V
from ehatp.epistemic.semantics import Semantics
from ehatp.model.agenda import Block, Networks
from ehatp.model.grounding import FINISH, ground_problem

from .scenarios import labels, problem, walk


def shop(order: list[tuple[int, int]] | None, *, human_order: bool = False,
         post_done: bool = False) -> Domain:
    """The robot's ``tidy`` is ``sweep`` and ``dust``, ordered by ``order``; the human's
    ``errands`` is ``buy`` and ``post`` (unordered with ``human_order``; ``post`` skipped once
    done with ``post_done``, and then hidden). Robot work is seen from ``home``."""
    d = Domain("shop")
    home = d.predicate("home")
    d.copresence = home()
    seen = observable(home())  # from home
    swept, dusted = d.predicate("swept", observability=seen), d.predicate("dusted",
                                                                          observability=seen)
    bought = d.predicate("bought")
    posted = d.predicate("posted", observability=HIDDEN if post_done else seen)
    sweep = d.robot.action("sweep", pre=~swept(), effects=[swept()])
    dust = d.robot.action("dust", pre=~dusted(), effects=[dusted()])
    tidy = d.robot.task("tidy")
    d.robot.method(tidy, "both", subtasks=[sweep(), dust()], order=order)
    buy = d.human.action("buy", pre=~bought(), effects=[bought()])
    post = d.human.action("post", pre=~posted(), effects=[posted()],
                          done=posted() if post_done else None)
    errands = d.human.task("errands")
    d.human.method(errands, "both", subtasks=[buy(), post()],
                   order=[] if human_order else None)
    return d


# -- options ----------------------------------------------------------------------------------

def test_unordered_robot_method_offers_both_orders() -> None:
    p = problem(shop([]), init=["home"], robot=["tidy"], starts="robot", objects={})
    sem, es = walk(p)
    assert sorted(labels(sem, es)[:2]) == ["dust", "sweep"]
    # and after either, the other one is what is left
    for first, then in (("dust", "sweep"), ("sweep", "dust")):
        sem, es = walk(p, first)
        assert sem.net.names_of(es.robot_agenda) == [then]
    # totally ordered (the default), only the first subtask
    sem, es = walk(problem(shop(None), init=["home"], robot=["tidy"], starts="robot",
                           objects={}))
    assert [x for x in labels(sem, es) if x in ("dust", "sweep")] == ["sweep"]


def test_unordered_human_method_offers_both_orders() -> None:
    p = problem(shop(None, human_order=True), init=["home"], human=["errands"], objects={})
    sem, es = walk(p)
    assert sorted(x for x in labels(sem, es) if x in ("buy", "post")) == ["buy", "post"]
    sem, es = walk(problem(shop(None), init=["home"], human=["errands"], objects={}))
    assert [x for x in labels(sem, es) if x in ("buy", "post")] == ["buy"]


def test_the_human_anticipates_both_orders_of_the_robot() -> None:
    """Unseen, the robot may have swept or dusted first: the human imagines both."""
    d = shop([])
    leave = d.human.action("leave", pre=d.predicates["home"](), effects=[~d.predicates["home"]()])
    out = d.human.task("out")
    d.human.method(out, "go", subtasks=[leave()])
    p = problem(d, init=["home"], robot=["tidy"], human=["out"], objects={})
    sem, es = walk(p, "leave", "sweep")
    seen = sorted((sorted(sem.g.state_atoms(s)), sem.net.names_of(ag)) for s, ag in es.worlds)
    assert seen == [([], ["tidy"]), (["dusted"], ["sweep"]), (["swept"], ["dust"])]


def test_a_partial_order_keeps_the_rest_in_order() -> None:
    """[a, b, c] with a < c and b < c: a and b in either order, then c."""
    d = Domain("abc")
    a_, b_, c_ = d.predicate("a"), d.predicate("b"), d.predicate("c")
    A = d.robot.action("A", pre=~a_(), effects=[a_()])
    B = d.robot.action("B", pre=~b_(), effects=[b_()])
    C = d.robot.action("C", pre=a_() & b_(), effects=[c_()])
    t = d.robot.task("t")
    d.robot.method(t, "m", subtasks=[A(), B(), C()], order=[(0, 2), (1, 2)])
    p = problem(d, init=[], robot=["t"], starts="robot", objects={})
    sem, es = walk(p)
    assert [m.label for m in sem.moves(es) if m.kind == "action"] == ["A", "B"]
    child = sem.follow(es, "A").child
    assert child is not None
    assert sem.net.names_of(child.robot_agenda) == ["B", "C"]  # plain tasks again
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert r.policy.nodes[0].robot_agenda == ["t"]
    assert ehatp.validate(p, r.policy).ok


# -- the order the human can witness ------------------------------------------------------------

def witness(order: list[tuple[int, int]] | None) -> ehatp.Problem:
    """The robot seals (inferable: the human learns it only by seeing it) and sweeps; the human
    is there at first, then leaves for good and ships, which needs the seal."""
    d = Domain("witness")
    home = d.predicate("home")
    d.copresence = home()
    sealed = d.predicate("sealed", observability=INFERABLE)
    swept = d.predicate("swept")
    seal = d.robot.action("seal", pre=~sealed(), effects=[sealed()])
    sweep = d.robot.action("sweep", pre=~swept(), effects=[swept()])
    job = d.robot.task("job")
    d.robot.method(job, "both", subtasks=[sweep(), seal()], order=order)
    d.human.action("leave", pre=home(), effects=[~home()])
    d.human.action("ship", pre=sealed(), effects=[])
    return problem(d, init=["home"], robot=["job"], human=["leave", "ship"], starts="robot",
                   objects={})


def test_the_planner_does_the_hidden_task_in_front_of_the_human() -> None:
    r = ehatp.solve(witness([]))
    assert r.status == "solved" and r.policy is not None
    root = r.policy.nodes[0]
    assert root.copresent and [m.action for m in root.moves] == ["seal"]
    assert r.policy.communications == 0
    assert ehatp.validate(witness([]), r.policy).ok
    # listed sweep first and totally ordered, the human may leave before the seal: no policy
    assert ehatp.solve(witness(None)).status == "unsolvable"


def test_a_member_done_in_some_worlds_only_is_uncertain_to_the_human() -> None:
    """The human's unordered ``errands``, ``post`` done in one world of two: the done member is
    removed in that world only, so even ``buy`` is not certain (what is left after it differs
    between the worlds), and the human asks."""
    d = shop(None, human_order=True, post_done=True)
    p = problem(d, init=["home"], human=["errands"], objects={},
                beliefs=[([], []), (["posted"], [])])
    sem, es = walk(p)
    opts = labels(sem, es)
    assert "ask(posted)" in opts and "buy" not in opts and "post" not in opts
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert ehatp.validate(p, r.policy).ok


# -- canonical form and printing ----------------------------------------------------------------

NAMES = [f"t{i}" for i in range(10)]


def test_equal_networks_are_equal_agendas() -> None:
    net = Networks(NAMES)
    one = net.normal([(1, 0), (2, 0)])
    assert net.normal([(2, 0), (1, 0)]) == one and isinstance(one[0], Block)
    # a member refined into an unordered pair flattens into the block
    outer = one[0]
    assert isinstance(outer, Block)
    inner = net.normal([(3, 0), (4, 0)])
    assert net.replace(outer, 0, inner) == net.normal([(2, 0), (3, 0), (4, 0)])
    # a totally ordered method is its plain tuple of ints, untouched
    assert net.body((5, 6, 7), None) == (5, 6, 7)
    assert net.body((5, 6, 7), (0, 1, 3)) == (5, 6, 7)
    # a first part wholly before the rest is cut off: [a, b, c] with a < c, b < c
    cut = net.body((1, 2, 3), (0, 0, 3))
    assert isinstance(cut[0], Block) and cut[1:] == (3,)
    assert net.names_of(cut) == ["{t1 | t2}", "t3"]


def test_printing() -> None:
    net = Networks(NAMES)
    # {t1 < t2 | t3}
    (b,) = net.normal([(1, 0), (2, 1), (3, 0)])
    assert isinstance(b, Block) and net.text(b) == "{t1 < t2 | t3}"
    # an N: t1 < t3, t2 < t3, t2 < t4
    (n,) = net.normal([(1, 0), (2, 0), (3, 0b11), (4, 0b10)])
    assert isinstance(n, Block)
    assert net.text(n) == "{t1 | t2 | t3 | t4; t1 < t3, t2 < t3, t2 < t4}"
    # {t1 | t2} < t3 inside a group unlinked to t4
    (m,) = net.normal([(1, 0), (2, 0), (3, 0b11), (4, 0)])
    assert isinstance(m, Block) and net.text(m) == "{{t1 | t2} < t3 | t4}"


def _random_members(r: random.Random) -> list[tuple[int, int]]:
    n = r.randint(1, 6)
    preds = [0] * n
    for j in range(n):
        for i in range(j):
            if r.random() < 0.35:
                preds[j] |= 1 << i | preds[i]
    order = list(range(n))
    r.shuffle(order)  # positions need not be a topological order
    pos = {old: new for new, old in enumerate(order)}
    out = [(0, 0)] * n
    for old, new in pos.items():
        m = sum(1 << pos[i] for i in range(n) if preds[old] >> i & 1)
        out[new] = (r.randint(0, 4), m)
    return out


def _listed_otherwise(ms: list[tuple[int, int]], r: random.Random) -> list[tuple[int, int]]:
    """The same network with its members listed in another (random) order."""
    perm = list(range(len(ms)))
    r.shuffle(perm)
    at = {old: new for new, old in enumerate(perm)}
    return [(ms[old][0], sum(1 << at[i] for i in range(len(ms)) if ms[old][1] >> i & 1))
            for old in perm]


def _as_validator(sem: V._Semantics, ag: tuple[object, ...]) -> V.Agenda:
    out: list[int | V.Block] = []
    for it in ag:
        if isinstance(it, Block):
            pairs = {(i, j) for j, (_, m) in enumerate(it) for i in range(len(it)) if m >> i & 1}
            built = sem.canon([t for t, _ in it], pairs)
            assert len(built) == 1
            out.extend(built)
        else:
            assert isinstance(it, int)
            out.append(it)
    return tuple(out)


@pytest.mark.slow  # random problems
def test_planner_and_validator_build_and_print_networks_alike() -> None:
    """The two independent implementations of the canonical form and of printing agree on
    random partial orders (tasks repeat), and after refining or finishing a member; the form
    does not depend on the order the members come in."""
    d = Domain("nets")
    for i in range(5):
        d.robot.action(f"t{i}")
    p = problem(d, init=[], robot=[f"t{i}" for i in range(5)], objects={})
    sem = V._Semantics(p)
    names = sem.g.task_names
    net = Networks(names)
    r = random.Random(5)
    for _ in range(400):
        ms = _random_members(r)
        mine = net.normal(ms)
        # the same network listed in another order is the same agenda (canonical)
        assert net.normal(_listed_otherwise(ms, r)) == mine
        pairs = {(i, j) for j, (_, m) in enumerate(ms) for i in range(len(ms)) if m >> i & 1}
        theirs = sem.canon([t for t, _ in ms], pairs)
        assert _as_validator(sem, mine) == theirs
        assert net.names_of(mine) == sem.shown(theirs)
        for k, it in enumerate(mine):
            if not isinstance(it, Block):
                continue
            vb = theirs[k]
            assert isinstance(vb, V.Block)
            for i in range(len(it)):
                assert _as_validator(sem, net.without(it, i)) == sem.drop(vb, i)
                rest = net.normal(_random_members(r))
                assert (_as_validator(sem, net.replace(it, i, rest))
                        == sem.put(vb, i, _as_validator(sem, rest)))


def _big_members(r: random.Random) -> list[tuple[int, int]]:
    """A network of 7-11 members over 3 task names (more than 720 orders of occurrences):
    two or three chains, linked here and there."""
    n = r.randint(7, 11)
    preds = [0] * n
    chain = [r.randrange(3) for _ in range(n)]
    for j in range(n):
        for i in range(j):
            if chain[i] == chain[j] or r.random() < 0.1:
                preds[j] |= 1 << i | preds[i]
    order = list(range(n))
    r.shuffle(order)
    pos = {old: new for new, old in enumerate(order)}
    out = [(0, 0)] * n
    for old, new in pos.items():
        out[new] = (r.randint(0, 2), sum(1 << pos[i] for i in range(n) if preds[old] >> i & 1))
    return out


def test_large_networks_are_ordered_by_rank_alike() -> None:
    """§1: with more than 720 orders of repeated names, members are ordered by rank; the
    planner's and the validator's forms agree, and do not depend on the listing order."""
    d = Domain("nets")
    for i in range(3):
        d.robot.action(f"t{i}")
    p = problem(d, init=[], robot=[f"t{i}" for i in range(3)], objects={})
    sem = V._Semantics(p)
    net = Networks(sem.g.task_names)
    r = random.Random(7)
    ranked = 0
    for _ in range(150):
        ms = _big_members(r)
        mine = net.normal(ms)
        ranked += any(isinstance(it, Block) and len(it) > 6 for it in mine)
        assert net.normal(_listed_otherwise(ms, r)) == mine
        pairs = {(i, j) for j, (_, m) in enumerate(ms) for i in range(len(ms)) if m >> i & 1}
        theirs = sem.canon([t for t, _ in ms], pairs)
        assert _as_validator(sem, mine) == theirs
        assert net.names_of(mine) == sem.shown(theirs)
    assert ranked > 50  # the rank rule was exercised, not only small blocks


# -- the domain checks the order; the decomposition bound ---------------------------------------

@pytest.mark.parametrize(("order", "says"), [
    ([(0, 2)], "names a subtask it does not have"),
    ([(1, 1)], "before itself"),
    ([(0, 1), (1, 0)], "cycle"),
    ([(0,)], "not a pair"),
])
def test_a_bad_order_is_a_domain_error(order: list[tuple[int, int]], says: str) -> None:
    with pytest.raises(DomainError, match=says):
        shop(order)


def looping() -> ehatp.Problem:
    """``deep(a)`` may refine into itself (a loop) or into ``tick(a)``."""
    d = Domain("loop")
    x = Var("x", d.type("thing"))
    count = d.predicate("count", x)
    tick = d.robot.action("tick", x, pre=~count(x), effects=[count(x)])
    deep = d.robot.task("deep", x)
    d.robot.method(deep, "again", pre=~count(x), subtasks=[deep(x)])
    d.robot.method(deep, "stop", subtasks=[tick(x)])
    return problem(d, init=[], robot=["deep(a)"], objects={"thing": ["a"]}, starts="robot")


def nesting(depth: int, limit: int) -> ehatp.Problem:
    """``down(n<depth>)`` nests ``depth`` methods (down(n_k) -> down(n_k-1)) before ``tick``."""
    d = Domain("nest")
    N = d.type("num")
    x, y = Var("x", N), Var("y", N)
    succ = d.predicate("succ", x, y)
    zero = d.predicate("zero", x)
    tick = d.robot.action("tick")
    down = d.robot.task("down", x)
    d.robot.method(down, "less", params=[y], pre=succ(y, x), subtasks=[down(y)])
    d.robot.method(down, "stop", pre=zero(x), subtasks=[tick()])
    nums = [f"n{i}" for i in range(depth + 1)]
    p = problem(d, init=["zero(n0)", *(f"succ(n{i}, n{i + 1})" for i in range(depth))],
                robot=[f"down(n{depth})"], objects={"num": nums}, starts="robot")
    p.limits = ehatp.Limits(max_decomposition=limit)
    return p


def test_a_loop_before_any_action_is_closed() -> None:
    """§1: ``deep(a)`` met again inside its own refinement before any action is a loop: that
    way is closed (it could only offer ``tick(a)`` again), so the robot ticks once."""
    g = ground_problem(looping())
    sem = Semantics(g)
    es = sem.initial()
    opts = sem.R.refine(es.robot_agenda, es.true)
    assert [(g.task_names[a], rest) for a, rest in opts] == [("tick(a)", ())]
    r = ehatp.solve(looping())
    assert r.policy is not None and r.policy.cost == 1
    assert V.validate(looping(), r.policy).ok


def test_a_loop_is_closed_only_inside_its_own_refinement() -> None:
    """The same task again *after* the first one's refinement is no loop: ``[deep(a),
    deep(a)]`` where the first is done without an action offers the second's tick."""
    p = looping()
    p.domain.robot.method(p.domain.robot.tasks["deep"], "skip", subtasks=[])
    p.robot_agenda = (("deep", ("a",)), ("deep", ("a",)))
    g = ground_problem(p)
    sem = Semantics(g)
    es = sem.initial()
    got = sorted((g.task_names[a], len(rest)) for a, rest in sem.R.refine(es.robot_agenda, es.true)
                 if a != FINISH)
    assert got == [("tick(a)", 0), ("tick(a)", 1)]  # the second deep(a), or the first
    vs = V._Semantics(p)
    theirs = sorted((g.task_names[a], len(rest)) for a, rest in
                    vs.refine(vs.g.robot, es.robot_agenda, es.true) if a != FINISH)
    assert theirs == got


def test_deep_nesting_names_the_limit() -> None:
    assert ehatp.solve(nesting(6, 8)).status == "solved"
    with pytest.raises(DomainError, match=r"down\(n9\) nests more than 8 methods before its "
                                          r"first action.*max_decomposition"):
        ehatp.solve(nesting(9, 8))


def test_max_decomposition_is_a_problem_limit(tmp_path: Path) -> None:
    text = Path(__file__).parent.parent.joinpath("examples/cubes/p1.toml").read_text("utf-8")
    f = tmp_path / "p.toml"
    f.write_text(text + "\n[limits]\nmax_decomposition = 7\n", encoding="utf-8")
    assert ehatp.load(f).limits.max_decomposition == 7
    assert ehatp.Limits().max_decomposition == 64
    f.write_text(text + "\n[limits]\nmax_decomposition = 0\n", encoding="utf-8")
    with pytest.raises(ehatp.InputError, match="max_decomposition"):
        ehatp.load(f)


def test_uncertain_human_anticipation_is_validated() -> None:
    """A policy over a problem with unordered methods on both sides, the human away for a
    while: the validator (its own reading of §1) accepts the planner's policy."""
    d = shop([], human_order=True)
    home = d.predicates["home"]
    leave = d.human.action("leave", pre=home(), effects=[~home()])
    back = d.human.action("back", pre=~home(), effects=[home()])
    trip = d.human.task("trip")
    d.human.method(trip, "go", subtasks=[leave(), back()])
    p = problem(d, init=["home"], robot=["tidy"], human=["trip", "errands"], objects={},
                human_model=HumanModel())
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert ehatp.validate(p, r.policy).ok


# -- the random generator --------------------------------------------------------------------

def test_the_random_generator_draws_partial_orders() -> None:
    """Some random problems have unordered and partially ordered methods, for either agent,
    and planner and validator agree on them (benchmarks/agreement.py runs many more)."""
    from ehatp.experiments import agreement, randomgen

    with_po = []
    kinds: set[str] = set()
    for seed in range(300):
        spec = randomgen.draw(seed)
        for who, m in (("robot", spec.robot), ("human", spec.human)):
            for me in m.methods:
                if me.order is not None:
                    kinds.add(f"{who}:{'unordered' if not me.order else 'partial'}")
        if any(me.order is not None for m in (spec.robot, spec.human) for me in m.methods):
            with_po.append(seed)
    assert kinds == {"robot:unordered", "robot:partial", "human:unordered", "human:partial"}
    assert 40 <= len(with_po) <= 150
    outcomes = [agreement.check(seed, determinism=True) for seed in with_po[:25]]
    assert not [o for o in outcomes if o.failed], [o for o in outcomes if o.failed]
    assert sum(o.kind == "solved" for o in outcomes) >= 8


def test_the_random_generator_draws_loops() -> None:
    """Some random problems give the robot's (and the human's) task a method that refines
    the task itself first, some inside a block; planner and validator agree on them."""
    from ehatp.experiments import agreement, randomgen

    with_loop, in_block, human = [], 0, 0
    for seed in range(300):
        spec = randomgen.draw(seed)
        loops = [me for m in (spec.robot, spec.human) for me in m.methods if me.name == "loop"]
        if loops:
            with_loop.append(seed)
            in_block += any(me.order is not None for me in loops)
            human += any(me.task == "chore" for me in spec.human.methods if me.name == "loop")
    assert 20 <= len(with_loop) <= 80 and in_block and human
    outcomes = [agreement.check(seed, determinism=True) for seed in with_loop[:25]]
    assert not [o for o in outcomes if o.failed], [o for o in outcomes if o.failed]
    assert sum(o.kind == "solved" for o in outcomes) >= 5
