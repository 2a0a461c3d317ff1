"""Subtypes (docs/modelling.md, docs/semantics.md §1): a type's objects include its subtypes',
for parameters, quantifiers and state variables; errors name the hierarchy."""

from __future__ import annotations

from pathlib import Path

import pytest

import ehatp
from ehatp import Domain, DomainError, InputError, Problem, Var, exists, forall
from ehatp.model.grounding import ground_problem


def shelf_domain() -> Domain:
    """Objects are cubes and boxes (small boxes are boxes); the robot tidies any object, puts a
    cube in a box, and a cube's place is any place: a table or a box."""
    d = Domain("shelf")
    Thing = d.type("object")
    Place = d.type("place")
    Cube = d.type("cube", parent=Thing)
    Box = d.type("box", parent=Thing)
    d.type("smallbox", parent=Box)
    d.type("table", parent=Place)
    d.type("bin", parent=Place)
    x, c, b = Var("x", Thing), Var("c", Cube), Var("b", Box)
    tidy = d.predicate("tidy", x)
    loc = d.variable("loc", c, values=Place)
    inside = d.predicate("inside", c, b)
    d.goal = forall(x, tidy(x)) & ~exists([c, b], inside(c, b))
    r = d.robot
    t = r.action("tidy_up", x, pre=~tidy(x), effects=[tidy(x)])
    r.action("put", c, b, pre=~inside(c, b), effects=[inside(c, b)])
    r.action("to_bin", c, effects=[loc(c).set("bin1")])
    all_ = r.task("tidy_all", done=forall(x, tidy(x)))
    r.method(all_, "one", params=[x], pre=~tidy(x), subtasks=[t(x), all_()])
    return d


def shelf_problem() -> Problem:
    return Problem(name="shelf", domain=shelf_domain(),
                   objects={"cube": ["red"], "box": ["crate"], "smallbox": ["tin"],
                            "table": ["desk"], "bin": ["bin1"]},
                   init=frozenset({("loc", ("red", "desk"))}),
                   robot_agenda=(("tidy_all", ()),), human_agenda=())


def test_a_type_ranges_over_its_subtypes_objects() -> None:
    p = shelf_problem()
    objs = p.all_objects()
    assert objs["object"] == ["crate", "red", "tin"]
    assert objs["box"] == ["crate", "tin"] and objs["smallbox"] == ["tin"]
    assert objs["place"] == ["bin1", "desk"]
    g = ground_problem(p)
    # tidy(x) over every object, loc(c) over every place (a table and a bin)
    assert [a for a in g.atoms if a.startswith("tidy")] == ["tidy(crate)", "tidy(red)",
                                                            "tidy(tin)"]
    assert [a for a in g.atoms if a.startswith("loc")] == ["loc(red) = bin1", "loc(red) = desk"]
    assert [a for a in g.atoms if a.startswith("inside")] == ["inside(red, crate)",
                                                              "inside(red, tin)"]


def test_a_problem_with_subtypes_solves_and_validates() -> None:
    p = shelf_problem()
    r = ehatp.solve(p)
    assert r.policy is not None and ehatp.validate(p, r.policy).ok
    acts = {m.action for n in r.policy.nodes for m in n.moves if m.agent == "R"}
    assert {"tidy_up(crate)", "tidy_up(red)", "tidy_up(tin)"} <= acts


def test_a_subtype_variable_is_accepted_where_its_parent_is_wanted() -> None:
    d = shelf_domain()
    sb = Var("s", "smallbox")
    assert str(d.predicates["tidy"](sb)) == "tidy(?s)"          # object <- smallbox
    assert str(d.predicates["inside"](Var("c", "cube"), sb)) == "inside(?c, ?s)"  # box <- small
    assert str(d.variables["loc"](Var("c", "cube")) == Var("t", "table")) == "loc(?c) = ?t"


def test_errors_name_the_hierarchy_in_a_domain() -> None:
    d = shelf_domain()
    with pytest.raises(DomainError) as e:
        d.predicates["inside"](Var("b", "box"), Var("b2", "box"))
    assert str(e.value) == ("predicate inside: argument b is a box, a subtype of object; "
                            "inside(c: cube, b: box) wants a cube for c")
    d.robot.operators["put"](Var("c", "cube"), Var("t", "smallbox"))  # a small box is a box
    with pytest.raises(DomainError) as e:
        d.robot.operators["to_bin"](Var("t", "smallbox"))
    assert str(e.value) == ("action to_bin: argument t is a smallbox, a subtype of box, of "
                            "object; to_bin(c: cube) wants a cube for c")
    d.type("other")
    with pytest.raises(DomainError, match="t is an other, but its values are places"):
        d.variables["loc"](Var("c", "cube")) == Var("t", "other")  # noqa: B015


def test_declaring_types_is_checked() -> None:
    d = Domain("types")
    with pytest.raises(DomainError, match="unknown parent type 'object'; declare it first"):
        d.type("cube", parent="object")
    d.type("place")
    d.type("agent", parent="place")  # the built-in type, given a parent once
    with pytest.raises(DomainError, match="type 'agent' is declared twice"):
        d.type("agent", parent="place")
    d.type("room", parent="place")
    with pytest.raises(DomainError, match="room is a room, a subtype of place, so place "
                                          "cannot be a subtype of it"):
        d.type("place", parent="room")


# --- problem files ---------------------------------------------------------------------------

DOMAIN_PY = '''
import sys
sys.path.insert(0, {tests!r})
from test_subtypes import shelf_domain
domain = shelf_domain()
'''


def write(tmp_path: Path, objects: str, init: str, agenda: str = '"tidy_all"') -> Path:
    (tmp_path / "domain.py").write_text(DOMAIN_PY.format(tests=str(Path(__file__).parent)),
                                        encoding="utf-8")
    f = tmp_path / "shelf.toml"
    f.write_text(f"""[problem]
name = "shelf"
[domain]
name = "domain.py:domain"
[objects]
{objects}
[init]
true = [{init}]
[agenda]
robot = [{agenda}]
""", encoding="utf-8")
    return f


OBJECTS = 'cube = ["red"]\nbox = ["crate"]\nsmallbox = ["tin"]\ntable = ["desk"]\nbin = ["b1"]'


def test_subtype_objects_fill_parent_parameters_in_a_file(tmp_path: Path) -> None:
    p = ehatp.load(write(tmp_path, OBJECTS, '"loc(red) = b1", "tidy(tin)", "inside(red, tin)"',
                         '"tidy_up(red)", "tidy_up(crate)"'))
    assert ("inside", ("red", "tin")) in p.init and ("tidy", ("tin",)) in p.init


@pytest.mark.parametrize(("init", "agenda", "message"), [
    ('"loc(red) = desk", "inside(red, red)"', '"tidy_all"',
     "'red' is a cube, a subtype of object; inside(c: cube, b: box) wants a box for b"),
    ('"loc(red) = crate"', '"tidy_all"',
     "'crate' is a box, a subtype of object; loc(c: cube, value: place) wants a place for "
     "value"),
    ('"loc(red) = desk"', '"put(red, desk)"',
     "'desk' is a table, a subtype of place; put(c: cube, b: box) wants a box for b"),
])
def test_problem_errors_name_the_hierarchy(tmp_path: Path, init: str, agenda: str,
                                           message: str) -> None:
    with pytest.raises(InputError) as e:
        ehatp.load(write(tmp_path, OBJECTS, init, agenda))
    assert message in str(e.value) and "\n" not in str(e.value)


def test_a_subtask_of_the_wrong_type_names_the_hierarchy() -> None:
    d = shelf_domain()
    r = d.robot
    bad = r.task("bad")
    r.method(bad, "m", subtasks=[r.operators["put"]("red", "desk")])
    p = Problem(name="bad", domain=d, objects={"cube": ["red"], "box": ["crate"],
                                               "table": ["desk"], "bin": ["bin1"]},
                init=frozenset({("loc", ("red", "desk"))}), robot_agenda=(("bad", ()),),
                human_agenda=())
    with pytest.raises(DomainError, match="'desk' is a table, a subtype of place; put"
                                          r"\(c: cube, b: box\) wants a box for b"):
        ground_problem(p)
