"""Search over symmetry-reduced states (docs/semantics.md §3, "Symmetry"): the partition of
the objects into interchangeable classes, canonical forms, and the reduced search giving the
same costs as the full one with policies that validate on the real problem."""

from __future__ import annotations

import re
from collections import Counter

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ehatp.check.validator import validate
from ehatp.epistemic.state import EState
from ehatp.experiments.bench import GridPoint
from ehatp.formats.problem_toml import load, loads
from ehatp.model.grounding import ground_problem
from ehatp.model.problem import Problem
from ehatp.search.andor import search
from ehatp.search.interchangeable import detect
from ehatp.search.planner import solve
from ehatp.search.symmetry import Symmetry, describe_classes

from .conftest import EXAMPLES, ROOT, Example

VARIABLES = 'encoding = "variables"\n'


def _to_variables(text: str) -> str:
    """The grid's ``[init]`` in the variables encoding: a cube's place, an agent's table."""
    def one(atom: str) -> str | None:
        m = re.fullmatch(r"(\w+)\(([^)]*)\)", atom)
        assert m is not None
        name, args = m[1], [x.strip() for x in m[2].split(",")]
        if name in ("on", "in"):
            return f"loc({args[0]}) = {args[1]}"
        if name in ("at", "facing"):
            return f"{name}({args[0]}) = {args[1]}"
        return None if name in ("handempty", "empty") else atom

    def init(m: re.Match[str]) -> str:
        facts = [f for f in (one(a) for a in re.findall(r'"([^"]*)"', m[1])) if f]
        return "[init]\ntrue = [" + ", ".join(f'"{f}"' for f in facts) + "]"

    return re.sub(r"\[init\]\s*true = \[(.*?)\]", init, text, flags=re.S)


def grid(cubes: int, boxes: int, K: int, head: str = "", domain: str = "",
         reach: str = "fetched") -> Problem:
    """A cube-grid instance (``ehatp bench scaling``), with top-level keys ``head`` (e.g. a
    goal) and extra ``[domain]`` lines."""
    text = GridPoint("cubes", K, cubes, boxes, reach=reach).toml()
    if VARIABLES in domain:
        text = _to_variables(text)
    if domain:
        text = text.replace('[domain]\nname = "cubes"\n', f'[domain]\nname = "cubes"\n{domain}')
    return loads(head + text, "grid.toml")


def classes(p: Problem) -> list[list[str]]:
    sym = detect(ground_problem(p))
    return [] if sym is None else describe_classes(sym)


def test_identical_cubes_and_boxes_are_classes() -> None:
    # c1, c2 start on mt, c3, c4 on ot; the boxes are alike
    assert classes(grid(4, 2, 2)) == [["box1", "box2"], ["c1", "c2"], ["c3", "c4"]]


def test_an_object_named_in_the_goal_is_fixed() -> None:
    p = grid(4, 2, 2, head='goal = ["in(c1, box1)"]\n')
    assert classes(p) == [["c3", "c4"]]


def test_objects_differing_in_the_initial_state_are_not_swapped() -> None:
    # p3: r and y on mt, w on ot: w has no twin
    assert classes(load(ROOT / "examples/cubes/p3.toml")) == [["box1", "box2"], ["r", "y"]]


def test_partial_order_turns_the_reduction_off() -> None:
    assert detect(ground_problem(load(ROOT / "examples/cooking/cooking1.toml"))) is None


def _tidy(special: bool) -> Problem:
    """Two items alike in every fact; with ``special`` the robot's one task also has a
    method, binding nothing, that names item ``a`` alone."""
    from ehatp import Domain, Var
    from ehatp.model.problem import BeliefWorld

    d = Domain("tidy")
    item = d.type("item")
    x = Var("x", item)
    loose = d.predicate("loose", x)
    r = d.robot
    put = r.action("put", x, pre=loose(x), effects=[~loose(x)])
    tidy = r.task("tidy")
    r.method(tidy, "any", params=[x], pre=loose(x), subtasks=[put(x)])
    if special:
        r.method(tidy, "first", params=[], pre=loose("a"), subtasks=[put("a")])
    return Problem(name="tidy", domain=d, objects={"item": ["a", "b"]},
                   init=frozenset({("loose", ("a",)), ("loose", ("b",))}),
                   robot_agenda=(("tidy", ()),), human_agenda=(), beliefs=(BeliefWorld(),))


def test_a_method_naming_one_object_alone_keeps_it_apart() -> None:
    # the task tidy names no item, so the swap of a and b keeps it; its methods must then
    # map onto themselves: "any" does (put(a) <-> put(b)), "first" (put(a) only) does not
    assert classes(_tidy(False)) == [["a", "b"]]
    assert classes(_tidy(True)) == []


def _swap(sym: Symmetry, a: str, b: str) -> int:
    p = list(range(len(sym.objects)))
    i, j = sym.index[a], sym.index[b]
    p[i], p[j] = j, i
    return sym.pid(tuple(p))


@pytest.mark.parametrize("domain", ["", VARIABLES])
def test_canonical_form_identifies_renamed_states(domain: str) -> None:
    p = grid(4, 2, 2, domain=domain)
    out = search(ground_problem(p), max_states=400)
    sym = detect(out.graph.sem.g)
    assert sym is not None
    swaps = [_swap(sym, "c1", "c2"), _swap(sym, "box1", "box2"), _swap(sym, "c3", "c4")]
    moved = 0
    for es in out.graph.states:
        c, pid = sym.canon(es)
        assert sym.apply(pid, es) == c
        assert sym.canon(c) == (c, 0)  # canonical forms are fixed points
        for s in swaps:
            other = sym.apply(s, es)
            moved += other != es
            assert sym.canon(other)[0] == c, "a renamed state has the same canonical form"
    assert moved > 0


def test_apply_and_inverse() -> None:
    sym = detect(ground_problem(grid(4, 2, 2)))
    assert sym is not None
    g = sym.g
    es = EState(0, g.init | 1 << g.atom_index["in(c1, box1)"], g.robot_agenda,
                g.human_agenda, ((g.init, g.robot_agenda),), 0, 0)
    s = sym.compose(_swap(sym, "c1", "c2"), _swap(sym, "box1", "box2"))
    other = sym.apply(s, es)
    assert other.true >> g.atom_index["in(c2, box2)"] & 1
    assert sym.apply(sym.inverse(s), other) == es


@pytest.mark.parametrize("domain", ["", VARIABLES])
def test_a_renamed_atom_or_task_is_the_one_its_name_renamed_names(domain: str) -> None:
    # the integer tables against the text: every object in a name replaced by its image
    sym = detect(ground_problem(grid(4, 2, 2, domain=domain)))
    assert sym is not None
    g = sym.g
    pid = sym.compose(sym.compose(_swap(sym, "c1", "c2"), _swap(sym, "box1", "box2")),
                      _swap(sym, "c3", "c4"))
    ren = {"c1": "c2", "c2": "c1", "box1": "box2", "box2": "box1", "c3": "c4", "c4": "c3"}

    def renamed(name: str) -> str:
        return re.sub(r"\w+", lambda m: ren.get(m[0], m[0]), name)

    moved = 0
    for i, atom in enumerate(g.atoms):
        assert g.atoms[sym.atom_image(pid, i)] == renamed(atom)
        assert (sym.moving(pid) >> i & 1) == (renamed(atom) != atom)
        moved += renamed(atom) != atom
    for t, task in enumerate(g.task_names):
        assert g.task_names[sym.task_image(pid, t)] == renamed(task)
    assert moved and sym.atom_map(pid) == {i: sym.atom_image(pid, i) for i in range(len(g.atoms))
                                           if sym.atom_image(pid, i) != i}


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_same_cost_with_and_without_symmetry(example: Example) -> None:
    p = load(example.path)
    off, on = solve(p, symmetry=False), solve(p, symmetry=True)
    assert on.status == off.status
    if off.policy is None:
        return
    assert on.policy is not None
    assert (on.policy.cost, on.policy.worst_case, on.policy.expected) == \
        (off.policy.cost, off.policy.worst_case, off.policy.expected)
    assert on.optimal == off.optimal
    report = validate(p, on.policy)
    assert report.ok, report.message
    assert on.stats["distinct"] <= off.stats["distinct"]


@pytest.mark.parametrize(("cubes", "boxes", "K", "domain", "reach"), [
    (5, 2, 4, "", "fetched"), (4, 3, 2, "", "fetched"), (4, 2, 2, VARIABLES, "fetched"),
    (4, 2, 2, "", "any"),
])
def test_fewer_states_same_cost_on_a_symmetric_instance(cubes: int, boxes: int, K: int,
                                                        domain: str, reach: str) -> None:
    p = grid(cubes, boxes, K, domain=domain, reach=reach)
    off, on = solve(p, symmetry=False), solve(p, symmetry=True)
    assert off.policy is not None and on.policy is not None
    assert on.policy.cost == off.policy.cost
    assert on.stats["distinct"] < off.stats["distinct"]
    report = validate(p, on.policy)
    assert report.ok, report.message


def test_symmetric_policy_is_deterministic() -> None:
    p = grid(5, 2, 4)
    a, b = solve(p), solve(p)
    assert a.policy is not None and b.policy is not None
    assert a.policy.to_json() == b.policy.to_json()


def test_switch_in_the_problem_file() -> None:
    p = loads(GridPoint("cubes", 2, 4, 2).toml() + "\n[limits]\nsymmetry = false\n",
              "grid.toml")
    assert p.limits.symmetry is False
    q = grid(4, 2, 2)
    assert solve(p).stats["distinct"] > solve(q).stats["distinct"]


def test_an_order_dependent_decision_falls_back_to_the_full_search(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from ehatp.search import symmetry

    def always(self: symmetry.SymSemantics, es: EState, chosen: int, plan: bool) -> bool:
        return True

    p = load(ROOT / "examples/cubes/p4.toml")  # it informs: an informing set is computed
    off = solve(p, symmetry=False)
    monkeypatch.setattr(symmetry.SymSemantics, "_tied", always)
    on = solve(p, symmetry=True)
    assert on.policy is not None and off.policy is not None
    assert on.stats["distinct"] == off.stats["distinct"]
    assert on.policy.to_json() == off.policy.to_json()


def test_a_move_that_does_not_map_back_falls_back_to_the_full_search(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from ehatp.search import policy

    p = grid(4, 2, 2)
    off = solve(p, symmetry=False)
    monkeypatch.setattr(policy, "_match", lambda *a: -1)
    monkeypatch.setattr(policy, "_match_orbit", lambda sym, m, node, real, used: (-1, node, 0))
    on = solve(p, symmetry=True, expand=True)  # mapped back to the real objects
    assert on.policy is not None and off.policy is not None
    assert on.policy.to_json() == off.policy.to_json()


def test_unsolvable_either_way() -> None:
    p = grid(4, 2, 2, head='goal = ["in(c1, box1)", "not in(c1, box1)"]\n')
    on, off = solve(p, symmetry=True), solve(p, symmetry=False)
    assert on.status == off.status == "unsolvable"


def test_the_canonical_form_does_not_depend_on_what_was_canonicalised_before() -> None:
    # canon interns signatures and remembers renamings and world signatures: a fresh
    # Symmetry that meets the states in the reverse order must give the same forms
    p = grid(4, 2, 4)
    out = search(ground_problem(p), max_states=600)
    states = list(out.graph.states)
    first = detect(out.graph.sem.g)
    again = detect(out.graph.sem.g)
    assert first is not None and again is not None
    forward = [first.canon(es) for es in states]
    backward = [again.canon(es) for es in reversed(states)][::-1]
    assert [c for c, _ in forward] == [c for c, _ in backward]
    assert [first.perms[p] for _, p in forward] == [again.perms[p] for _, p in backward]
    assert any(len(es.worlds) > 1 for es in states)


@given(st.lists(st.integers(0, 3), min_size=1, max_size=8), st.data())
def test_run_length_keys_order_multisets_as_sorted_lists_do(xs: list[int],
                                                            data: st.DataObject) -> None:
    # canon compares the worlds' part of two objects' signatures as (value, -count) runs;
    # both multisets have one entry per world, so the order must be that of the sorted lists
    ys = data.draw(st.lists(st.integers(0, 3), min_size=len(xs), max_size=len(xs)))

    def runs(zs: list[int]) -> list[tuple[int, int]]:
        return sorted((v, -c) for v, c in Counter(zs).items())

    assert (runs(xs) < runs(ys)) == (sorted(xs) < sorted(ys))
    assert (runs(xs) == runs(ys)) == (sorted(xs) == sorted(ys))
