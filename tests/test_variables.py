"""Finite-domain state variables (docs/modelling.md, docs/semantics.md §2 and §5): exactly one
value in every world, per-value sight, revision that draws the conclusion, one inform telling
the value, the problem syntax, and the paper's cube domain rewritten with them."""

from __future__ import annotations

import random
import re
from pathlib import Path

import pytest

import ehatp
from ehatp import (
    HIDDEN,
    INFERABLE,
    BeliefWorld,
    Domain,
    DomainError,
    InputError,
    Problem,
    Var,
    eq,
    exists,
    observable,
)
from ehatp.check.validator import _Semantics as VSemantics
from ehatp.epistemic.semantics import Semantics
from ehatp.epistemic.state import normalize
from ehatp.formats.problem_toml import loads
from ehatp.model.grounding import ground_problem

from .conftest import CUBES_TABLE1, EXAMPLES_DIR, ROOT, example, solved

CUBES = EXAMPLES_DIR / "cubes"


def pasta_domain(*, variables: bool = True, sight: str = "here", places: int = 2) -> Domain:
    """A human fetches the pasta; it sees whether the pasta is where it stands (``sight =
    "here"``), nothing (``"hidden"``), or learns it only by witnessing it move
    (``"inferable"``). The robot may move the pasta (``move_pasta(p)``). With ``variables``
    False the pasta's place is one atom per place, ``pasta_at(p)``. The places are the kitchen
    and the room, and with ``places = 3`` the hall."""
    d = Domain("pasta" + ("" if variables else "-atoms"))
    Place = d.type("place")
    for name in ("kitchen", "room", "hall")[:places]:
        d.constant(name, Place)
    p, q = Var("p", Place), Var("q", Place)
    at = d.variable("at", Var("a", "agent"), values=Place)
    d.copresence = exists(p, (at("R") == p) & (at("H") == p))
    obs = {"here": observable(at("H") == p), "hidden": HIDDEN, "inferable": INFERABLE}[sight]
    if variables:
        pasta = d.variable("pasta_at", values=p, observability=obs)

        def there(x: Var | str) -> ehatp.model.formula.Formula:
            return pasta() == x

        def put(x: Var | str) -> list[ehatp.model.domain.Effect]:
            return [pasta().set(x)]
    else:
        atom = d.predicate("pasta_at", p, observability=obs)

        def there(x: Var | str) -> ehatp.model.formula.Formula:
            return atom(x)

        def put(x: Var | str) -> list[ehatp.model.domain.Effect]:
            return [ehatp.for_each(q, ~atom(q)), atom(x)]
    holding = d.predicate("holding")
    h = d.human
    go = h.action("go", p, q, pre=(at("H") == p) & ~eq(p, q), effects=[at("H").set(q)])
    take = h.action("take", p, pre=(at("H") == p) & there(p), effects=[holding()])
    get = h.task("get_pasta", done=holding())
    h.method(get, "here", params=[p], pre=(at("H") == p) & there(p), subtasks=[take(p)])
    h.method(get, "there", params=[p, q], pre=(at("H") == q) & there(p) & ~eq(p, q),
             subtasks=[go(q, p), take(p)])
    d.robot.action("move_pasta", p, pre=~there(p), effects=put(p))
    # from the kitchen to the room, and nowhere else: what it does depends on the world
    d.robot.action("tidy", effects=[ehatp.when(there("kitchen"), *put("room"))])
    return d


def pasta_problem(*, variables: bool = True, sight: str = "here", places: int = 2,
                  truth: str = "room", believed: str = "kitchen", starts: str = "human",
                  robot_agenda: tuple[tuple[str, tuple[str, ...]], ...] = ()) -> Problem:
    d = pasta_domain(variables=variables, sight=sight, places=places)
    init = {("at", ("R", "kitchen")), ("at", ("H", "kitchen")), ("pasta_at", (truth,))}
    if variables:
        world = BeliefWorld(true=frozenset({("pasta_at", (believed,))}))
    else:
        world = BeliefWorld(true=frozenset({("pasta_at", (believed,))}),
                            false=frozenset({("pasta_at", (truth,))}))
    return Problem(name="pasta", domain=d, objects={}, init=frozenset(init),
                   beliefs=(world,), robot_agenda=robot_agenda, starts=starts,
                   human_agenda=(("get_pasta", ()),))


def root_worlds(problem: Problem) -> list[list[str]]:
    """The human's worlds in the initial state, each as its state's true atoms."""
    sem = Semantics(ground_problem(problem))
    return [sem.g.state_atoms(s) for s, _ in sem.initial().worlds]


# --- seeing "not here" --------------------------------------------------------------------


def test_seeing_not_here_makes_the_human_certain_of_there() -> None:
    p = pasta_problem()
    assert root_worlds(p) == [["at(H) = kitchen", "at(R) = kitchen", "pasta_at = room"]]
    r = ehatp.solve(p)
    assert r.policy is not None and r.policy.communications == 0
    assert ehatp.validate(p, r.policy).ok
    first = [m.action for m in r.policy.root.moves]
    assert "go(kitchen, room)" in first  # straight to the room: it is sure


def test_with_plain_atoms_the_same_human_needs_an_inform() -> None:
    p = pasta_problem(variables=False)
    # it sees the pasta is not in the kitchen, and believes it nowhere
    assert root_worlds(p) == [["at(H) = kitchen", "at(R) = kitchen"]]
    r = ehatp.solve(p)
    assert r.policy is not None and r.policy.communications == 1
    assert ehatp.validate(p, r.policy).ok
    informs = {m.action for n in r.policy.nodes for m in n.moves if m.kind == "inform"}
    assert informs == {"inform(pasta_at(room))"}
    assert r.policy.cost > ehatp.solve(pasta_problem()).policy.cost  # type: ignore[union-attr]


def test_not_here_with_three_places_leaves_each_other_place() -> None:
    p = pasta_problem(places=3)
    assert sorted(w[-1] for w in root_worlds(p)) == ["pasta_at = hall", "pasta_at = room"]
    r = ehatp.solve(p)
    assert r.policy is not None and ehatp.validate(p, r.policy).ok


def test_one_inform_tells_a_hidden_variable_whole() -> None:
    p = pasta_problem(sight="hidden", places=3, starts="robot")  # else it takes in the kitchen
    assert [w[-1] for w in root_worlds(p)] == ["pasta_at = kitchen"]
    r = ehatp.solve(p)
    assert r.policy is not None and ehatp.validate(p, r.policy).ok
    informs = [m for n in r.policy.nodes for m in n.moves if m.kind == "inform"]
    assert [(m.action, m.args) for m in informs] == [
        ("inform(pasta_at = room)", ["pasta_at = room"])]
    told = r.policy.nodes[informs[0].to]
    assert told.worlds == 1 and told.divergence == []
    root = r.policy.root
    assert root.divergence == ["pasta_at = room"]
    assert root.world_diffs == [{"true": ["pasta_at = kitchen"], "false": ["pasta_at = room"]}]


def test_an_inferable_variable_is_learned_whole_by_witnessing() -> None:
    """The human believes the pasta in the hall and watches the robot ``tidy`` (kitchen to
    room): in its world the action changes nothing, but what the human witnesses is the
    variable's new value, whole -- no world holds two places."""
    p = pasta_problem(sight="inferable", places=3, truth="kitchen", believed="hall",
                      robot_agenda=(("tidy", ()),), starts="robot")
    sem = Semantics(ground_problem(p))
    es = sem.initial()
    (move,) = [m for m in sem.moves(es) if m.label == "tidy"]
    assert move.child is not None
    assert [sem.g.state_atoms(s)[-1] for s, _ in move.child.worlds] == ["pasta_at = room"]
    vsem = VSemantics(p)
    worlds = vsem.set_inferable(frozenset(es.worlds), es.true, move.child.true)
    assert set(worlds) != set(es.worlds)
    step = vsem.robot_act(vsem.initial(), sem.g.task_index["tidy"], ())
    assert step.after is not None and set(step.after.worlds) == set(move.child.worlds)


# --- the revision rule, planner and validator -----------------------------------------------


def test_observation_rules_agree_between_planner_and_validator() -> None:
    """Random worlds and observed masks over a three-valued variable and atoms: the planner's
    observe and the validator's, written apart, give the same worlds, and every world keeps
    exactly one value."""
    p = pasta_problem(places=3)
    g = ground_problem(p)
    sem, vsem = Semantics(g), VSemantics(p)
    unit = g.var_units
    rng = random.Random(3)
    n = len(g.atoms)
    for _ in range(400):
        def state() -> int:
            s = rng.getrandbits(n)
            for u in unit:  # one value per variable
                bits = [i for i in range(n) if u >> i & 1]
                s = (s & ~u) | 1 << rng.choice(bits)
            return s
        t = state()
        worlds = normalize((state(), ()) for _ in range(rng.randint(1, 3)))
        mask = rng.getrandbits(n)
        mine = sem.observe(t, worlds, mask)
        theirs = vsem.observe(frozenset(worlds), t, [i for i in range(n) if mask >> i & 1])
        assert set(mine) == set(theirs)
        for s, _ in mine:
            assert all(bin(s & u).count("1") == 1 for u in unit)
            assert s & mask == t & mask  # the human agrees with what it observed


def test_a_value_no_world_has_is_revised_to_the_value() -> None:
    p = pasta_problem(places=3)
    g = ground_problem(p)
    sem = Semantics(g)
    room, kitchen = (1 << g.atom_index[f"pasta_at = {x}"] for x in ("room", "kitchen"))
    other = g.init & ~room
    w = normalize([(other | kitchen, ())])
    assert sem.observe(g.init, w, room) == normalize([(g.init, ())])


# --- the problem syntax ---------------------------------------------------------------------

DOMAIN_PY = '''
from ehatp import domain_factory
import sys
sys.path.insert(0, {root!r})
from tests.test_variables import pasta_domain

@domain_factory
def make(variables: bool = True, sight: str = "here", places: int = 2):
    return pasta_domain(variables=variables, sight=sight, places=places)
'''


def write(tmp_path: Path, body: str, beliefs: str = "") -> Path:
    (tmp_path / "domain.py").write_text(DOMAIN_PY.format(root=str(ROOT)),
                                        encoding="utf-8")
    f = tmp_path / "pasta.toml"
    f.write_text(f"""[problem]
name = "pasta"
[domain]
name = "domain.py:make"
[init]
true = [{body}]
{beliefs}
[agenda]
human = ["get_pasta"]
""", encoding="utf-8")
    return f


def test_a_value_reads_as_name_equals_value_or_as_the_value_view_atom(tmp_path: Path) -> None:
    a = ehatp.load(write(tmp_path, '"at(R) = kitchen", "at(H) = kitchen", "pasta_at = room"',
                         '[beliefs]\ntrue = ["pasta_at = kitchen"]'))
    b = ehatp.load(write(tmp_path, '"at(R, kitchen)", "at(H, kitchen)", "pasta_at(room)"',
                         '[beliefs]\ntrue = ["pasta_at(kitchen)"]'))
    assert a.init == b.init and a.beliefs == b.beliefs
    r = ehatp.solve(a)
    assert r.policy is not None and r.policy.communications == 0


@pytest.mark.parametrize(("init", "beliefs", "message"), [
    ('"at(R) = kitchen", "at(H) = kitchen"', "",
     "[init] true: the state variable pasta_at has no value; give it one, e.g. "
     '"pasta_at = kitchen"'),
    ('"at(R) = kitchen", "at(H) = kitchen", "pasta_at = room", "pasta_at = kitchen"', "",
     "pasta_at is given two values, kitchen and room"),
    ('"at(R) = kitchen", "at(H) = kitchen", "pasta_at = R"', "",
     "'R' is an agent, but pasta_at expects a place there"),
    ('"at(R) = kitchen", "at(H) = kitchen", "pasta_at"', "",
     "pasta_at is a state variable: 'pasta_at' gives no value"),
    ('"at(R) = kitchen", "at(H) = kitchen", "pasta_at = room"',
     '[beliefs]\nfalse = ["pasta_at = room"]',
     "pasta_at = room: a state variable or counter has one value"),
    ('"at(R) = kitchen", "at(H) = kitchen", "pasta_at = room"',
     '[beliefs]\ntrue = ["pasta_at = room"]', "pasta_at = room is already true"),
    ('"at(R) = kitchen", "at(H) = kitchen", "pasta_at = room"',
     '[beliefs]\ntrue = ["pasta_at = room", "pasta_at = kitchen"]',
     "pasta_at is given two values"),
])
def test_values_are_checked_with_one_line_errors(tmp_path: Path, init: str, beliefs: str,
                                                 message: str) -> None:
    with pytest.raises(InputError) as e:
        ehatp.load(write(tmp_path, init, beliefs))
    assert message in str(e.value)
    assert "\n" not in str(e.value)


def test_a_problem_built_in_python_is_checked_too() -> None:
    p = pasta_problem()
    p.init = p.init - {("pasta_at", ("room",))}
    with pytest.raises(InputError, match="the state variable pasta_at has no value"):
        ehatp.solve(p)


def test_variable_effects_and_conditions_are_checked_in_the_domain() -> None:
    d = Domain("bad")
    Place = d.type("place")
    p = Var("p", Place)
    v = d.variable("v", values=Place)
    with pytest.raises(DomainError, match="is a condition, not an effect; .* write v.set"):
        d.robot.action("a", p, effects=[v() == p])
    with pytest.raises(DomainError, match="x is an item, but its values are places"):
        v() == Var("x", "item")  # noqa: B015 - builds a formula
    assert str(v() == p) == "v = ?p" and str(v() != "mt") == "v != mt"
    assert str(v().set(p)) == "v := ?p"
    d.constant("mt", Place)
    d.constant("ot", Place)
    d.robot.action("twice", effects=[v().set("mt"), v().set("ot")])
    p2 = Problem(name="bad", domain=d, objects={}, init=frozenset({("v", ("mt",))}),
                 robot_agenda=(("twice", ()),), human_agenda=())
    with pytest.raises(DomainError, match="the action already changes v; give it one value"):
        ground_problem(p2)


def test_a_parameter_may_be_given_by_its_type() -> None:
    d = Domain("short")
    Cube, Place = d.type("cube"), d.type("place")
    loc = d.variable("loc", Cube, values=Place)
    assert loc.params == (Var("cube", Cube),) and loc.values == Place
    assert str(loc("r") == "mt") == "loc(r) = mt"
    balls = d.counter("balls", Place, Place, max=3)
    assert [v.name for v in balls.params] == ["place", "place2"]


# --- the paper's cube domain, rewritten --------------------------------------------------------


def to_variables(text: str) -> str:
    """A cube problem file in the variables encoding: a cube's place, an agent's table."""
    def one(atom: str) -> str | None:
        m = re.fullmatch(r"(\w+)\(([^)]*)\)", atom)
        if m is None:
            return atom
        name, args = m[1], [x.strip() for x in m[2].split(",")]
        if name in ("on", "in"):
            return f"loc({args[0]}) = {args[1]}"
        if name == "holding":
            return f"loc({args[1]}) = {args[0]}"
        if name in ("at", "facing"):
            return f"{name}({args[0]}) = {args[1]}"
        return None if name in ("handempty", "empty") else atom

    def init(m: re.Match[str]) -> str:
        facts = [f for f in (one(a) for a in re.findall(r'"([^"]*)"', m[1])) if f]
        return "[init]\ntrue = [" + ", ".join(f'"{f}"' for f in facts) + "]"

    text = re.sub(r"\[init\]\s*true = \[(.*?)\]", init, text, flags=re.S)
    return text.replace("[domain]\n", '[domain]\nencoding = "variables"\n', 1)


@pytest.mark.parametrize("name", [e.stem for e in CUBES_TABLE1])
def test_table1_is_unchanged_with_the_cube_domain_in_variables(name: str) -> None:
    f = CUBES / f"{name}.toml"
    text = f.read_text(encoding="utf-8")
    variables = loads(to_variables(text), f)
    assert variables.domain.name.startswith("cubes-vars")
    a, v = solved(f).result, ehatp.solve(variables)
    assert a.policy is not None and v.policy is not None
    assert (a.policy.cost, a.policy.leaves, a.policy.communications) == (
        example(name).cost, example(name).leaves, example(name).communications)
    assert ehatp.validate(variables, v.policy).ok
    for key in ("cost", "leaves", "communications"):
        assert getattr(v.policy, key) == getattr(a.policy, key), key
    # the same search: one state of each encoding per state of the other
    for key in ("generated", "distinct", "max_worlds"):
        assert v.stats[key] == a.stats[key], key
    moves = [sorted({m.action for n in pol.nodes for m in n.moves}) for pol in (a.policy,
                                                                               v.policy)]
    assert moves[0] == moves[1]


def test_the_qualitative_inform_tells_where_the_cube_is() -> None:
    """The paper's qualitative instance: the atoms tell that box2 is empty, the variables
    where r is -- the same worlds are left."""
    f = CUBES / "qualitative.toml"
    text = f.read_text(encoding="utf-8")
    told = []
    for t in (text, to_variables(text)):
        p = loads(t, f)
        r = ehatp.solve(p)
        assert r.policy is not None and ehatp.validate(p, r.policy).ok
        assert (r.policy.cost, r.policy.communications) == (4, 1)
        told += [m.action for n in r.policy.nodes for m in n.moves if m.kind == "inform"]
    assert told == ["inform(empty(box2))", "inform(loc(r) = box1)"]


def test_a_cube_in_a_hand_is_printed_by_value() -> None:
    f = CUBES / "p2.toml"
    p = loads(to_variables(f.read_text(encoding="utf-8")), f)
    g = ground_problem(p)
    assert g.state_atoms(g.init) == [
        "at(H) = mt", "at(R) = mt", "facing(H) = mt", "facing(R) = mt", "loc(r) = mt",
        "loc(w) = ot"]
    # loc(c) ranges over tables, boxes and hands (agent is a subtype of place)
    assert [a for a in g.atoms if a.startswith("loc(r)")] == [
        "loc(r) = H", "loc(r) = R", "loc(r) = box1", "loc(r) = box2", "loc(r) = mt",
        "loc(r) = ot"]


def test_the_cube_domain_refuses_an_unknown_encoding() -> None:
    from ehatp.domains.cubes import make_domain
    with pytest.raises(ValueError, match="encoding must be one of 'atoms', 'variables'"):
        make_domain(encoding="bits")  # type: ignore[arg-type]


# --- the agreement benchmark draws them ---------------------------------------------------------


@pytest.mark.slow  # 80 random problems through the agreement check
def test_the_random_generator_draws_variables_and_counters() -> None:
    """benchmarks/agreement.py's problems include state variables (seen whole, or per value)
    and counters, and planner and validator agree on them."""
    from ehatp.experiments import agreement, randomgen

    drawn = [randomgen.draw(seed) for seed in range(1000)]
    kinds = {(v.kind, v.sight) for s in drawn for v in s.values}
    assert {("variable", "whole"), ("variable", "value"), ("variable", "others"),
            ("counter", "whole")} <= kinds
    sizes = {(v.kind, v.size) for s in drawn for v in s.values}
    assert {("variable", 2), ("variable", 3), ("counter", 2), ("counter", 3)} <= sizes
    # the human is sometimes wrong about the value within the atom's truth
    assert any(w != v.init and v.holds(w) == v.holds(v.init)
               for s in drawn for v in s.values for w in v.worlds)
    with_values = [s.seed for s in drawn if s.values][:80]
    p = randomgen.build(randomgen.draw(with_values[0]))
    assert p.domain.variables or p.domain.counters
    outcomes = agreement.run(with_values, jobs=2)
    bad = [f"{o.seed}: {o.kind} {o.detail}" for o in outcomes if o.failed]
    assert not bad, bad
    assert sum(o.kind == "solved" for o in outcomes) >= len(with_values) // 3
