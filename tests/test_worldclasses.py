"""The human's worlds kept as classes (issue 17 §2; docs/semantics.md §3, "Worlds as
classes"; ``ehatp.search.worldclasses`` and ``ehatp.search.classsemantics``): the classes and
their sizes derived by hand, the cells checked against every swap, the canonical form equal to
the one over the worlds listed, and the same policies, validated and executed."""

from __future__ import annotations

import json
from itertools import combinations, product

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ehatp import load
from ehatp.check.validator import validate
from ehatp.epistemic.classworlds import WorldClasses, count
from ehatp.epistemic.state import EState, World
from ehatp.experiments.bench import GridPoint
from ehatp.formats.problem_toml import loads
from ehatp.model.grounded import Grounded
from ehatp.model.grounding import ground_problem
from ehatp.model.vocabulary import HUMAN
from ehatp.run.walk import walk_policy
from ehatp.search import classsemantics
from ehatp.search.interchangeable import detect
from ehatp.search.planner import solve
from ehatp.search.symmetry import Symmetry, describe_classes
from ehatp.search.worldclasses import ClassSymmetry

from .conftest import EXAMPLES, Example

FOUR_CUBES = """
[problem]
name = "three-alike"
starts = "human"
K = 2

[domain]
name = "cubes"

[objects]
cube = ["c1", "c2", "c3", "c4"]
box = ["box1", "box2"]

[init]
true = ["at(R, mt)", "facing(R, mt)", "at(H, mt)", "facing(H, mt)", "handempty(R)",
        "handempty(H)", "empty(box1)", "empty(box2)", "on(c1, mt)", "origin(c1, mt)",
        "on(c2, mt)", "origin(c2, mt)", "on(c3, mt)", "origin(c3, mt)", "on(c4, ot)",
        "origin(c4, ot)"]

[agenda]
robot = ["organize"]
human = ["organize"]
"""
CUBES = ("c1", "c2", "c3")


def _setup() -> tuple[Grounded, ClassSymmetry]:
    g = ground_problem(loads(FOUR_CUBES, "three.toml"))
    found = detect(g)
    assert found is not None
    return g, ClassSymmetry(g, describe_classes(found))


def _world(g: Grounded, boxes: tuple[str, ...]) -> World:
    """The initial state with c1, c2, c3 moved into the boxes ``boxes`` (in that order)."""
    s = g.init
    for cube, box in zip(CUBES, boxes, strict=True):
        s &= ~(1 << g.atom_index[f"on({cube}, mt)"])
        s |= 1 << g.atom_index[f"in({cube}, {box})"]
        s &= ~(1 << g.atom_index[f"empty({box})"])
    return s, g.robot_agenda


def _node(g: Grounded, worlds: list[World]) -> EState:
    """A node whose truth is the initial state (c1, c2, c3 alike on the robot's table)."""
    return EState(HUMAN, g.init, g.robot_agenda, (g.human_agenda,), tuple(sorted(set(worlds))),
                  0, 0)


EVERY = list(product(("box1", "box2"), repeat=3))


def test_three_cubes_in_two_boxes_are_eight_worlds_in_four_classes() -> None:
    """Derived by hand. c1, c2, c3 start alike on the robot's table (c4 on the other is told
    apart by its origin), so they are the unary objects: no atom or task names two cubes,
    and ``in(c, b)`` names a box too, which therefore stays fixed. The eight worlds putting
    each of them in box1 or box2 are closed under every permutation of the three, and the
    truth and agendas do not tell them apart: one cell {c1, c2, c3}, and a class per number
    of cubes in box2, of sizes C(3, k) = 1, 3, 3, 1 (the sum is |W| = 8)."""
    g, sym = _setup()
    assert [sym.objects[o] for o in sym.classer.unary] == list(CUBES)
    es = _node(g, [_world(g, b) for b in EVERY])
    wc = sym.classer.fit(es)
    assert [[sym.objects[o] for o in c] for c in wc.cells] == [list(CUBES)]
    assert sorted(wc.mults) == [1, 1, 3, 3]
    assert len(wc) == 4 and count(wc) == 8
    assert sym.classer.expand(wc) == es.worlds


def test_the_cells_are_the_swaps_that_leave_every_world_a_world() -> None:
    """Derived by hand. Without the world "c1 alone in box2" (seven worlds), the swap
    (c2 c3) still maps every world to a world, but (c1 c2) maps "c2 alone in box2" to the
    missing one: the cells are {c2, c3} (c1 alone). The classes are then per box of c1 and
    multiset of the boxes of c2 and c3: c1 in box1 with {1,1}, {1,2}, {2,2} (sizes 1, 2, 1)
    and c1 in box2 with {1,2}, {2,2} (sizes 2, 1; {1,1} was the missing world): five
    classes, sizes 1, 1, 1, 2, 2."""
    g, sym = _setup()
    worlds = [_world(g, b) for b in EVERY if b != ("box2", "box1", "box1")]
    wc = sym.classer.fit(_node(g, worlds))
    assert [[sym.objects[o] for o in c] for c in wc.cells] == [["c2", "c3"]]
    assert sorted(wc.mults) == [1, 1, 1, 2, 2]
    assert sym.classer.expand(wc) == tuple(sorted(worlds))


def test_telling_one_cube_apart_splits_each_class_by_what_it_holds() -> None:
    """Derived by hand. Splitting the cell {c1, c2, c3} of the eight worlds into {c1} and
    {c2, c3} (as when the robot moves c1) gives, per box of c1, the classes {1,1}, {1,2},
    {2,2} of the other two: six classes, sizes 1, 2, 1 twice."""
    g, sym = _setup()
    classer = sym.classer
    wc = classer.fit(_node(g, [_world(g, b) for b in EVERY]))
    c1 = sym.index["c1"]
    split = classer.refine(wc, [o == c1 for o in range(len(sym.objects))])
    assert [[sym.objects[o] for o in c] for c in split.cells] == [["c2", "c3"]]
    assert sorted(split.mults) == [1, 1, 1, 1, 2, 2]
    assert classer.expand(split) == classer.expand(wc)


def _swap_fixes(sym: Symmetry, es: EState, a: int, b: int) -> bool:
    n = len(sym.objects)
    p = list(range(n))
    p[a], p[b] = b, a
    return sym.apply(sym.pid(tuple(p)), es) == es


@settings(max_examples=120, deadline=None)
@given(st.sets(st.sampled_from(EVERY), min_size=1), st.permutations(list(CUBES)))
def test_the_classes_of_any_set_of_worlds_are_its_orbits_under_its_cells(
        chosen: set[tuple[str, ...]], order: list[str]) -> None:
    """Not derived by hand: checked against the definitions. For any set of the eight
    worlds, renamed by any permutation of the cubes, two cubes share a cell exactly when
    swapping them leaves the node as it is (every swap tried on the worlds listed), the
    classes list exactly the worlds, and the canonical form over classes is the canonical
    form over the worlds: the same renaming, the same worlds."""
    g, sym = _setup()
    plain = Symmetry(g, describe_classes(sym))
    rename = {c: o for c, o in zip(CUBES, order, strict=True)}
    worlds = [_world(g, tuple(b[CUBES.index(rename[c])] for c in CUBES)) for b in chosen]
    es = _node(g, worlds)
    wc = sym.classer.fit(es)
    assert sym.classer.expand(wc) == es.worlds and count(wc) == len(es.worlds)
    cell_of = {o: c for c in wc.cells for o in c}
    for a, b in combinations(sym.classer.unary, 2):
        together = a in cell_of and b in cell_of[a]
        assert together == _swap_fixes(plain, es, a, b)
    canon_c, pid_c = sym.canon(es)
    canon_p, pid_p = plain.canon(es)
    assert sym.perms[pid_c] == plain.perms[pid_p]
    assert sym.explicit(canon_c) == canon_p
    assert isinstance(canon_c.worlds, WorldClasses)


GRID = [GridPoint("cubes", 8, 6, 3), GridPoint("cubes", 8, 8, 2), GridPoint("cubes", 6, 7, 3),
        GridPoint("cubes", 4, 8, 3), GridPoint("cubes", 8, 5, 2, transparent=True)]


@pytest.mark.parametrize("point", GRID, ids=lambda p: p.name)
def test_worlds_as_classes_give_the_policy_of_the_worlds_listed(point: GridPoint,
                                                                  monkeypatch: pytest.MonkeyPatch
                                                                  ) -> None:
    """On K=4-8 grid points, where the human's worlds multiply: keeping them as classes gives
    the same policy (its timings aside), the same states and the same |W|; the robot's
    unseen moves and the human's moves apart were taken on classes; the policy validates
    and runs on every branch."""
    p = loads(point.toml(), "grid.toml")
    calls = {"robot": 0, "human": 0}
    robot, human = classsemantics.ClassSemantics._robot_apart, \
        classsemantics.ClassSemantics.human_exec

    def count_robot(self: classsemantics.ClassSemantics, es: EState) -> object:
        calls["robot"] += 1
        return robot(self, es)

    def count_human(self: classsemantics.ClassSemantics, es: EState, *a: object) -> object:
        calls["human"] += isinstance(es.worlds, WorldClasses)
        return human(self, es, *a)  # type: ignore[arg-type]

    monkeypatch.setattr(classsemantics.ClassSemantics, "_robot_apart", count_robot)
    monkeypatch.setattr(classsemantics.ClassSemantics, "human_exec", count_human)
    listed = solve(p)
    classes = solve(p, world_classes=True)
    assert classes.policy is not None and listed.policy is not None
    assert calls["robot"] > 0 and calls["human"] > 0
    assert _without_time(classes.policy.to_json()) == _without_time(listed.policy.to_json())
    for key in ("distinct", "expanded", "generated", "max_worlds"):
        assert classes.stats[key] == listed.stats[key], key
    assert validate(p, classes.policy).ok
    walked = walk_policy(p, classes.policy)
    assert walked.ok, str(walked)


def _without_time(text: str) -> str:
    d = json.loads(text)
    d.pop("stats", None)
    return json.dumps(d, sort_keys=True)


@pytest.mark.parametrize("example", [e for e in EXAMPLES if not e.name.startswith("concurrent")],
                         ids=str)
def test_every_example_has_the_same_policy_with_worlds_as_classes(example: Example) -> None:
    """Every shipped example (joint steps have no symmetry reduction) solves to the same
    policy with its worlds as classes."""
    p = load(example.path)
    a, b = solve(p), solve(p, world_classes=True)
    assert (a.policy is None) == (b.policy is None)
    if a.policy is not None and b.policy is not None:
        assert _without_time(a.policy.to_json()) == _without_time(b.policy.to_json())
