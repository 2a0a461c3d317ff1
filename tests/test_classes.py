"""The human's worlds as classes under the swaps that fix a node (issue 17 §2,
``ehatp.experiments.classes``), and the canonical form's kept renamings
(docs/semantics.md §3, "Symmetry"): what is kept changes no policy."""

from __future__ import annotations

import re
from itertools import permutations, product

import pytest

from ehatp.check.validator import validate
from ehatp.epistemic.state import EState
from ehatp.experiments.bench import GridPoint
from ehatp.experiments.classes import cells, count, orbits
from ehatp.formats.problem_toml import loads
from ehatp.model.grounded import Grounded
from ehatp.model.grounding import ground_problem
from ehatp.model.vocabulary import HUMAN
from ehatp.run.walk import walk_policy
from ehatp.search import symmetry
from ehatp.search.andor import search
from ehatp.search.interchangeable import detect
from ehatp.search.planner import solve
from ehatp.search.symmetry import Symmetry

THREE_CUBES = GridPoint("cubes", 2, 3, 2).toml()  # c1, c2 on mt; c3 on ot; box1, box2 empty


def _state(g: Grounded, atoms: list[str]) -> int:
    s = 0
    for a in atoms:
        s |= 1 << g.atom_index[a]
    return s


def _node(worlds_in: list[str]) -> tuple[Symmetry, EState]:
    """A node of the three-cube grid point whose true state is the initial one and whose
    worlds put one cube in one box each (``"c1 box2"``), everything else as in the truth."""
    g = ground_problem(loads(THREE_CUBES, "three.toml"))
    sym = detect(g)
    assert sym is not None
    base = [a for a in g.atoms if g.init >> g.atom_index[a] & 1]
    worlds = []
    for w in worlds_in:
        cube, box = w.split()
        atoms = [a for a in base
                 if a not in (f"on({cube}, mt)", f"on({cube}, ot)", f"empty({box})")]
        s = _state(g, [*atoms, f"in({cube}, {box})"])
        worlds.append((s, g.robot_agenda))
    es = EState(HUMAN, g.init, g.robot_agenda, (g.human_agenda,), tuple(sorted(worlds)), 0, 0)
    return sym, es


def test_the_worlds_a_swap_fixing_the_node_renames_form_one_class() -> None:
    """Derived by hand. The truth has c1 and c2 on the robot's table (mt), c3 on the other,
    both boxes empty: c3 differs from the others in the initial state, so the
    interchangeable objects are c1, c2, box1 and box2, and the swaps that fix the truth are
    (c1 c2) and (box1 box2). The worlds are
    {c1 in box1, c2 in box1, c1 in box2}. (c1 c2) maps "c1 in box2" to "c2 in box2", not a
    world: c1 and c2 are not one cell. (box1 box2) maps "c2 in box1" to "c2 in box2", not a
    world either. So each of the four is a cell alone, the group is trivial, and the three worlds
    are three classes. Adding "c2 in box2" makes W closed under both swaps: the cells are
    {c1, c2} and {box1, box2}, and the four worlds are one orbit (c1 in box1 -> c2 in box1 by
    the cube swap, -> c2 in box2 by the box swap, -> c1 in box2 by the cube swap): one
    class."""
    sym, es = _node(["c1 box1", "c2 box1", "c1 box2"])
    node_cells = cells(sym, es)
    assert sorted(len(c) for c in node_cells) == [1, 1, 1, 1]
    assert orbits(sym, es, node_cells) == 3

    sym, es = _node(["c1 box1", "c2 box1", "c1 box2", "c2 box2"])
    node_cells = cells(sym, es)
    named = sorted(sorted(sym.objects[o] for o in c) for c in node_cells if len(c) > 1)
    assert named == [["box1", "box2"], ["c1", "c2"]]
    assert orbits(sym, es, node_cells) == 1


def test_a_cube_alone_in_its_cell_splits_its_class() -> None:
    """Derived by hand. Worlds {c1 in box1, c2 in box1, c3 in box1}: the truth fixes c3 (it
    is alone on ot), so the only cube swap that can fix the node is (c1 c2), and it maps the
    worlds onto themselves; (box1 box2) does not (c1 in box2 is not a world). Cells {c1, c2},
    and the orbits are {c1 in box1, c2 in box1} and {c3 in box1}: two classes."""
    sym, es = _node(["c1 box1", "c2 box1", "c3 box1"])
    node_cells = cells(sym, es)
    named = sorted(sorted(sym.objects[o] for o in c) for c in node_cells if len(c) > 1)
    assert named == [["c1", "c2"]]
    assert orbits(sym, es, node_cells) == 2


def _brute_force_orbits(sym: Symmetry, es: EState, node_cells: list[list[int]]) -> int:
    """The orbits of ``es.worlds`` under every permutation within the cells, enumerated."""
    n = len(sym.objects)
    group = []
    for images in product(*(permutations(c) for c in node_cells)):
        p = list(range(n))
        for cell, image in zip(node_cells, images, strict=True):
            for a, b in zip(cell, image, strict=True):
                p[a] = b
        group.append(sym.pid(tuple(p)))
    seen: set[tuple[int, tuple[int, ...]]] = set()
    k = 0
    for w in es.worlds:
        if w in seen:
            continue
        k += 1
        for pid in group:
            seen.add((sym.state(pid, w[0]), sym.agenda(pid, w[1])))
    return k


def test_the_union_find_counts_the_orbits_that_enumerating_the_group_finds() -> None:
    """On the search's own nodes of a K=8 grid point (not derived by hand: checked against
    the orbits of every element of the group, enumerated), the count agrees, and the
    largest node's classes are fewer than its worlds."""
    p = loads(GridPoint("cubes", 8, 6, 3).toml(), "grid.toml")
    out = search(ground_problem(p), symmetry=True, max_states=3000)
    sym = out.graph.sym
    assert sym is not None
    nodes = sorted(out.graph.states, key=lambda e: -len(e.worlds))[:6]
    for es in nodes:
        node_cells = cells(sym, es)
        assert orbits(sym, es, node_cells) == _brute_force_orbits(sym, es, node_cells)
    report = count(p, top=3, every=True)
    assert report.status == "solved" and len(report.nodes) == 3
    assert report.nodes[0].worlds == report.max_worlds
    assert all(1 <= n.classes <= n.worlds for n in report.nodes)
    assert report.nodes[0].classes < report.nodes[0].worlds
    assert report.total_worlds is not None and report.total_classes is not None
    assert report.distinct <= report.total_classes < report.total_worlds


def test_keeping_fewer_renamed_states_changes_no_policy(monkeypatch: pytest.MonkeyPatch) -> None:
    """The renamed world states the canonical form keeps start afresh past
    ``RENAMED_CACHE``: with a table of 64 states, starting afresh many times during the
    search, the policy is the same, byte for byte, validated and walked on every branch."""
    p = loads(GridPoint("cubes", 8, 5, 3).toml(), "grid.toml")
    kept = solve(p)
    monkeypatch.setattr(symmetry, "RENAMED_CACHE", 64)
    afresh = solve(p)
    assert kept.policy is not None and afresh.policy is not None
    assert afresh.policy.to_json() == kept.policy.to_json()
    report = validate(p, afresh.policy)
    assert report.ok, report.message
    walked = walk_policy(p, afresh.policy)
    assert walked.ok, str(walked)


def test_a_swap_that_fixes_a_node_and_names_nothing_of_a_move_fixes_its_child() -> None:
    """The property a representation of W as classes would rest on (docs/benchmarks.md,
    "Worlds as classes"): the rules commute with an automorphism (§3, "Symmetry"), so a swap
    that fixes a node and maps a move onto itself (it names none of the move's objects: its
    arguments, the literals told, the question asked) fixes the move's child, worlds included;
    the child's cells can be had from its parent's without reading its worlds. Checked on
    every move of the first 300 nodes of a K=8 grid point."""
    p = loads(GridPoint("cubes", 8, 6, 3).toml(), "grid.toml")
    out = search(ground_problem(p), symmetry=True)
    sym, sem = out.graph.sym, out.graph.sem
    assert sym is not None
    n = len(sym.objects)
    checked = 0
    for es in out.graph.states[:300]:
        parent = [c for c in cells(sym, es) if len(c) > 1]
        for move in sem.moves(es):
            if move.child is None:
                continue
            named = set(re.findall(r"\w+", move.label))
            for cell in parent:
                kept = [o for o in cell if sym.objects[o] not in named]
                for a, b in zip(kept, kept[1:], strict=False):
                    swap = list(range(n))
                    swap[a], swap[b] = b, a
                    assert sym.apply(sym.pid(tuple(swap)), move.child) == move.child
                    checked += 1
    assert checked > 100
