"""Bounded counters (docs/modelling.md, docs/semantics.md §2 and §5): binary, one atom per
bit; comparisons, saturating changes, sight and informs of the whole number, revision that keeps
it in range, the problem syntax."""

from __future__ import annotations

import itertools
import random
from pathlib import Path

import pytest

import ehatp
from ehatp import (
    HIDDEN,
    BeliefWorld,
    Domain,
    DomainError,
    InputError,
    Problem,
    Var,
    eq,
    observable,
)
from ehatp.check.validator import _Semantics as VSemantics
from ehatp.epistemic.semantics import Semantics
from ehatp.epistemic.state import normalize
from ehatp.model.grounding import ground_problem


def balls_domain(*, sight: str = "home", top: int = 3) -> Domain:
    """The robot drops balls into boxes while the human is out (``balls(b) <= top``); the
    human scoops water from a bucket the robot refills (``bucket <= 3``) and packs a box that
    holds two balls or more. ``sight``: the balls are seen from home, or hidden."""
    d = Domain("balls")
    Box = d.type("box")
    b = Var("b", Box)
    home = d.predicate("home")
    d.copresence = home()
    balls = d.counter("balls", b, max=top,
                      observability=observable(home()) if sight == "home" else HIDDEN)
    bucket = d.counter("bucket", max=3)
    r = d.robot
    drop = r.action("drop", b, pre=balls(b) < top, effects=[balls(b).incr()])
    r.action("pour", effects=[bucket().incr(2)])  # saturates at 3
    fill = r.task("fill", b, done=balls(b) >= 2)
    r.method(fill, "one_more", subtasks=[drop(b), fill(b)])
    h = d.human
    leave = h.action("leave", pre=home(), effects=[~home()])
    back = h.action("back", pre=~home(), effects=[home()])
    scoop = h.action("scoop", pre=bucket() >= 1, effects=[bucket().decr()])
    pack = h.action("pack", b, pre=home() & (balls(b) >= 2), effects=[balls(b).set(0)])
    chores = h.task("chores")
    h.method(chores, "out_and_back", subtasks=[leave(), scoop(), back(), scoop(), pack("b1")])
    h.task("pack_only")
    h.method(h.tasks["pack_only"], "m", subtasks=[pack("b1")])
    return d


def balls_problem(**kw: object) -> Problem:
    return Problem(name="balls", domain=balls_domain(**kw),  # type: ignore[arg-type]
                   objects={"box": ["b1", "b2"]},
                   init=frozenset({("home", ()), ("bucket", ("1",))}),
                   robot_agenda=(("fill", ("b1",)), ("pour", ())),
                   human_agenda=(("chores", ()),), K=3)


def test_a_counter_domain_solves_and_validates_with_one_atom_per_bit() -> None:
    p = balls_problem()
    g = ground_problem(p)
    # balls(b1), balls(b2) and bucket in 0..3: two bits each (a value per atom would be 12)
    assert g.atoms == ["balls(b1)[1]", "balls(b1)[2]", "balls(b2)[1]", "balls(b2)[2]",
                       "bucket[1]", "bucket[2]", "home"]
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert ehatp.validate(p, r.policy).ok
    assert r.policy.root.state == ["balls(b1) = 0", "balls(b2) = 0", "bucket = 1", "home"]
    # back home, the human sees how many balls the robot dropped while it was out
    assert any(m.action == "pack(b1)" for n in r.policy.nodes for m in n.moves)


@pytest.mark.parametrize("top", [1, 2, 3, 4, 5, 7, 8])
def test_bits_grow_with_the_log_of_max(top: int) -> None:
    g = ground_problem(balls_problem(top=top))
    assert len([a for a in g.atoms if a.startswith("balls(b1)")]) == top.bit_length()


@pytest.mark.parametrize("top", [1, 2, 3, 5, 6, 7])
def test_every_comparison_holds_exactly_for_its_values(top: int) -> None:
    d = balls_domain(top=top)
    balls = d.counters["balls"]
    p = Problem(name="cmp", domain=d, objects={"box": ["b1"]}, init=frozenset({("home", ())}),
                robot_agenda=(), human_agenda=())
    g = ground_problem(p)
    unit = g.counter_units[0]
    low = (unit & -unit).bit_length() - 1
    ops = {"==": lambda v, k: v == k, "!=": lambda v, k: v != k, "<": lambda v, k: v < k,
           "<=": lambda v, k: v <= k, ">": lambda v, k: v > k, ">=": lambda v, k: v >= k}
    from ehatp.model.formula import Cmp
    for op, k in itertools.product(ops, range(-1, top + 2)):
        f = g.compile(_ground(p, Cmp("balls", ("b1",), op, k)))
        for v in range(top + 1):
            assert f(v << low) == ops[op](v, k), (op, k, v)
    assert str(balls("b1") >= 2) == "balls(b1) >= 2" and str(balls("b1") == 1) == "balls(b1) = 1"


def _ground(p: Problem, f: ehatp.model.formula.Formula) -> ehatp.model.formula.Formula:
    from ehatp.model.grounding import _Grounder
    gr = _Grounder(p)
    gr.run()
    return gr.ground_f(f, {})


def test_changes_saturate_at_zero_and_max() -> None:
    p = balls_problem()
    g = ground_problem(p)
    bucket = next(u for u, n in g.unit_names.items() if n == "bucket")
    low = (bucket & -bucket).bit_length() - 1
    pour = g.robot.ops[g.task_index["pour"]]
    scoop = g.human.ops[g.task_index["scoop"]]
    for v in range(4):
        s = g.init & ~bucket | v << low
        assert g.counter_value(pour.apply(s), bucket) == min(3, v + 2)
        assert g.counter_value(scoop.apply(s), bucket) == max(0, v - 1)


def test_one_inform_tells_a_hidden_number() -> None:
    """The human believes one ball is in b1 (two are): it cannot pack until told."""
    d = balls_domain(sight="hidden")
    p = Problem(name="told", domain=d, objects={"box": ["b1"]},
                init=frozenset({("home", ()), ("balls", ("b1", "2"))}),
                beliefs=(BeliefWorld(true=frozenset({("balls", ("b1", "1"))})),),
                robot_agenda=(), human_agenda=(("pack_only", ()),), starts="robot")
    r = ehatp.solve(p)
    assert r.policy is not None and ehatp.validate(p, r.policy).ok
    (move,) = r.policy.root.moves
    assert (move.action, move.args) == ("inform(balls(b1) = 2)", ["balls(b1) = 2"])
    assert r.policy.root.divergence == ["balls(b1) = 2"]
    assert r.policy.root.world_diffs == [{"true": ["balls(b1) = 1"],
                                          "false": ["balls(b1) = 2"]}]


def test_revision_keeps_a_counter_in_range_planner_and_validator_alike() -> None:
    p = balls_problem(top=5)  # 3 bits: 6 and 7 never occur
    g = ground_problem(p)
    sem, vsem = Semantics(g), VSemantics(p)
    rng = random.Random(5)
    n = len(g.atoms)

    def state() -> int:
        s = rng.getrandbits(n)
        for u in g.counter_units:
            low = (u & -u).bit_length() - 1
            s = s & ~u | rng.randint(0, g.counter_max[u]) << low
        return s

    for _ in range(300):
        t = state()
        worlds = normalize((state(), ()) for _ in range(rng.randint(1, 3)))
        mask = rng.getrandbits(n)
        mask = g.expand(mask)  # a counter is seen or told whole
        mine = sem.observe(t, worlds, mask)
        theirs = vsem.observe(frozenset(worlds), t, [i for i in range(n) if mask >> i & 1])
        assert set(mine) == set(theirs)
        for s, _ in mine:
            assert all(g.counter_value(s, u) <= g.counter_max[u] for u in g.counter_units)
            assert s & mask == t & mask


def test_counter_declarations_are_checked() -> None:
    d = Domain("bad")
    with pytest.raises(DomainError, match="max must be a whole number >= 1"):
        d.counter("c", max=0)
    c = d.counter("c", max=2)
    with pytest.raises(DomainError, match="3 is out of its range 0..2"):
        c().set(3)
    with pytest.raises(DomainError, match="compare it with a whole number"):
        c() >= "two"  # noqa: B015
    with pytest.raises(DomainError, match="visibility of d: formula .* uses unbound v"):
        d.counter("d", max=2, observability=observable(eq(Var("v", "agent"), "H")))


# --- the problem syntax -----------------------------------------------------------------------

DOMAIN_PY = '''
from ehatp import domain_factory
import sys
sys.path.insert(0, {tests!r})
from test_counters import balls_domain

@domain_factory
def make(sight: str = "home"):
    return balls_domain(sight=sight)
'''


def write(tmp_path: Path, init: str, beliefs: str = "") -> Path:
    (tmp_path / "domain.py").write_text(DOMAIN_PY.format(tests=str(Path(__file__).parent)),
                                        encoding="utf-8")
    f = tmp_path / "balls.toml"
    f.write_text(f"""[problem]
name = "balls"
K = 3
[domain]
name = "domain.py:make"
[objects]
box = ["b1", "b2"]
[init]
true = [{init}]
{beliefs}
[agenda]
robot = ["fill(b1)", "pour"]
human = ["chores"]
""", encoding="utf-8")
    return f


def test_a_number_reads_as_name_equals_value_or_as_the_value_view_atom(tmp_path: Path) -> None:
    a = ehatp.load(write(tmp_path, '"home", "bucket = 1", "balls(b2) = 3"'))
    b = ehatp.load(write(tmp_path, '"home", "bucket(1)", "balls(b2, 3)"'))
    assert a.init == b.init
    g = ground_problem(a)
    assert g.state_atoms(g.init) == ["balls(b1) = 0", "balls(b2) = 3", "bucket = 1", "home"]


@pytest.mark.parametrize(("init", "beliefs", "message"), [
    ('"home", "bucket = 4"', "", "bucket is a counter from 0 to 3, not '4'"),
    ('"home", "bucket = two"', "", "bucket is a counter from 0 to 3, not 'two'"),
    ('"home", "bucket = 1", "bucket = 2"', "", "bucket is given two values, 1 and 2"),
    ('"home", "bucket"', "", "bucket is a counter: 'bucket' gives no value"),
    ('"home"', '[beliefs]\ntrue = ["balls(b1) = 0"]', "balls(b1) = 0 is already true"),
    ('"home"', '[beliefs]\nfalse = ["balls(b1) = 0"]', "a state variable or counter has one"),
])
def test_numbers_are_checked_with_one_line_errors(tmp_path: Path, init: str, beliefs: str,
                                                  message: str) -> None:
    with pytest.raises(InputError) as e:
        ehatp.load(write(tmp_path, init, beliefs))
    assert message in str(e.value) and "\n" not in str(e.value)


def test_a_goal_may_compare_a_counter(tmp_path: Path) -> None:
    f = write(tmp_path, '"home", "bucket = 1"')
    f.write_text('goal = ["balls(b1) = 0", "not bucket = 0"]\n' + f.read_text(),
                 encoding="utf-8")
    p = ehatp.load(f)
    r = ehatp.solve(p)
    assert r.policy is not None and ehatp.validate(p, r.policy).ok
    for leaf in (n for n in r.policy.nodes if n.goal):
        assert "balls(b1) = 0" in leaf.state and "bucket = 0" not in leaf.state
    p.goal = ((True, ("bucket", ("2",))),)  # 1 + 2 - 1 - 1 is never 2
    assert ehatp.solve(p).status == "unsolvable"
