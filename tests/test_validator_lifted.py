"""The validator on lifted policies (format version 3, docs/semantics.md §3 "Symmetry"): checked
on their canonical nodes without expanding them, each renaming an automorphism of the problem,
the root and every edge mapped by their renamings.

The hand-built policies are over ``twins``: two identical items ``a`` and ``b``; the human takes
one, the robot waits, the human takes the other. Taking ``a`` or ``b`` first leads to states that
are renamings of each other, so the lifted policy has one node for both (4 nodes, 2 branches)."""

from __future__ import annotations

import copy
import dataclasses
from fractions import Fraction
from typing import Any

import pytest

import ehatp
from ehatp import HIDDEN, Domain, HumanModel, Objective, Policy, Problem, Var, observable
from ehatp.check.communication import Semantics
from ehatp.check.lifted import Lifted, LiftedCheck, split_v3
from ehatp.check.validator import Report, validate
from ehatp.formats import policy as policy_format
from ehatp.model.formula import exists
from ehatp.model.options import Passes

from .conftest import EXAMPLES, Example, solved
from .scenarios import problem

SWAP = [[0, 1], [1, 0]]


def twins(*, init: tuple[str, ...] = (), preferred: bool = False,
          objective: Objective | None = None, unordered: bool = False,
          beliefs: list[tuple[list[str], list[str]]] | None = None,
          items: tuple[str, ...] = ("a", "b"), agenda: int = 2) -> Problem:
    """Items the human takes one at a time (``take_one``, any item not taken); ``preferred``
    adds a way to take ``a`` by name (then ``a`` and ``b`` are no longer interchangeable)."""
    d = Domain("twins")
    item = d.type("item")
    d.type("place")
    i = Var("i", item)
    taken = d.predicate("taken", i)
    d.predicate("lamp", i)  # observable: seen by the human at every move
    d.predicate("note", i, observability=HIDDEN)
    h = d.human
    take = h.action("take", i, pre=~taken(i), effects=[taken(i)])
    one = h.task("take_one")
    h.method(one, "any", params=[i], pre=~taken(i), subtasks=[take(i)])
    if preferred:
        h.method(one, "pref", pre=~taken("a"), subtasks=[take("a")])
    if unordered:  # a partially ordered method (of one subtask: nothing else changes)
        h.method(one, "loose", params=[i], pre=~taken(i), subtasks=[take(i)], order=[])
    return problem(d, init=init, human=["take_one"] * agenda,
                   objects={"item": list(items), "place": ["p"]}, objective=objective,
                   beliefs=beliefs,
                   human_model=HumanModel(passes=Passes.IDLE))


def _node(i: int, state: list[str], agenda: list[str], to_move: str | None, value: int,
          moves: list[dict[str, Any]]) -> dict[str, Any]:
    return {"id": i, "copresent": True, "k": 0, "worlds": 1, "divergence": [],
            "world_diffs": [{"true": [], "false": []}], "state": state, "robot_agenda": [],
            "human_agenda": agenda, "to_move": to_move, "value": value,
            "goal": to_move is None, "moves": moves}


def _move(agent: str, action: str, to: int, renaming: int = 0) -> dict[str, Any]:
    name, _, rest = action.partition("(")
    kind = "wait" if action == "wait" else "action"
    return {"agent": agent, "kind": kind, "action": action, "name": name,
            "args": [rest[:-1]] if rest else [], "cost": 1, "to": to, "told": [],
            **({"renaming": renaming} if renaming else {})}


def lifted_twins() -> dict[str, Any]:
    """The lifted policy of :func:`twins`, written by hand: node 1 is "b taken"; taking ``a``
    first reaches it through the swap (renaming 1)."""
    nodes = [
        _node(0, [], ["take_one", "take_one"], "H", 3,
              [_move("H", "take(a)", 1, 1), _move("H", "take(b)", 1)]),
        _node(1, ["taken(b)"], ["take_one"], "R", 2, [_move("R", "wait", 2)]),
        _node(2, ["taken(b)"], ["take_one"], "H", 1, [_move("H", "take(a)", 3)]),
        _node(3, ["taken(a)", "taken(b)"], [], None, 0, []),
    ]
    return {"format": "ehatp-policy", "version": 3, "problem": "test", "domain": "twins",
            "agents": {"robot": "R", "human": "H"}, "K": 2,
            "costs": {"inform": 1, "ask": 1, "wait": 1, "pass": 1, "actions": {}},
            "cost": 3, "communications": 0, "leaves": 2, "after": [],
            "objective": {"kind": "worst-case"}, "worst_case": 3, "expected": 3,
            "nodes": nodes,
            "symmetry": {"objects": ["a", "b"], "classes": [["a", "b"]], "renamings": SWAP,
                         "root": 0}}


def check(p: Problem, d: dict[str, Any]) -> Report:
    """Validate a version 3 JSON object (its table passed apart, whatever the reader keeps)."""
    v2, lifted = split_v3(copy.deepcopy(d))
    assert lifted is not None
    return validate(p, Policy.from_dict(v2), lifted)


def caught(p: Problem, d: dict[str, Any], *needles: str) -> Report:
    r = check(p, d)
    assert not r.ok
    assert "\n" not in r.message
    for s in needles:
        assert s in r.message, (s, r.message)
    return r


def reason(p: Problem, renaming: list[int], classes: list[list[str]] | None = None,
           objects: tuple[str, ...] = ("a", "b")) -> str:
    """Why the validator rejects ``renaming`` on ``p`` (an automorphism: "")."""
    table = Lifted(list(objects), classes or [list(objects)], [list(range(len(objects))),
                                                                renaming])
    got = LiftedCheck(p, Semantics(p), table).renaming(1)
    return got if isinstance(got, str) else ""


# -- a lifted policy is checked on its canonical nodes --------------------------------------------

def test_hand_lifted_policy_validates() -> None:
    r = check(twins(), lifted_twins())
    assert r.ok, r.violations
    assert r.message == "valid: 4 nodes, 2 branches checked"


def test_the_swap_is_an_automorphism_of_twins() -> None:
    assert reason(twins(), [1, 0]) == ""
    assert reason(twins(agenda=1), [1, 0]) == ""


def test_a_wrong_edge_renaming_names_the_node_and_move() -> None:
    d = lifted_twins()
    del d["nodes"][0]["moves"][0]["renaming"]  # take(a) reaches "a taken", not node 1's state
    r = caught(twins(), d, "node 1 (H take(a)): recorded facts differ",
               "the edge's renaming does not map the successor onto the node",
               "recorded but false: ['taken(b)']")
    assert r.message.startswith("branch [H take(a)]: ")


def test_a_needless_renaming_is_caught() -> None:
    d = lifted_twins()
    d["nodes"][0]["moves"][1]["renaming"] = 1  # take(b) renamed by the swap: "a taken"
    caught(twins(), d, "node 1 (H take(b), renamed by renaming 1 (a→b, b→a)): recorded facts "
           "differ")


def test_a_renaming_outside_the_table() -> None:
    d = lifted_twins()
    d["nodes"][0]["moves"][0]["renaming"] = 7
    caught(twins(), d, "node 1 (H take(a))", "renaming 7 is not in the symmetry table")


def test_a_renaming_that_is_no_permutation() -> None:
    d = lifted_twins()
    d["symmetry"]["renamings"] = [[0, 1], [0, 0]]
    caught(twins(), d, "node 1 (H take(a))", "renaming 1 [0, 0] is not a permutation")


def test_a_renaming_across_classes() -> None:
    d = lifted_twins()
    d["symmetry"]["classes"] = [["a"], ["b"]]
    caught(twins(), d, "node 1 (H take(a))", "maps a onto b, of another class")


def test_a_class_of_two_types() -> None:
    d = lifted_twins()
    d["symmetry"].update(objects=["a", "p"], classes=[["a", "p"]])
    caught(twins(), d, "symmetry class ['a', 'p'] mixes objects of different types")


def test_unknown_objects_and_classes_that_miss_one() -> None:
    d = lifted_twins()
    d["symmetry"]["objects"] = ["a", "z"]
    caught(twins(), d, "'z', not an object of the problem")
    d["symmetry"].update(objects=["a", "b"], classes=[["a"]])
    caught(twins(), d, "each of symmetry.objects in exactly one class")


def test_a_wrong_root_renaming() -> None:
    # b is taken from the start: a and b are not interchangeable
    p = twins(init=("taken(b)",), agenda=1)
    d = lifted_twins()
    d["nodes"] = [_node(0, ["taken(b)"], ["take_one"], "H", 1, [_move("H", "take(a)", 1)]),
                  _node(1, ["taken(a)", "taken(b)"], [], None, 0, [])]
    d.update(cost=1, leaves=1, worst_case=1, expected=1)
    d["symmetry"]["renamings"] = [[0, 1]]
    assert check(p, d).ok  # the identity alone
    d["symmetry"].update(renamings=SWAP, root=1)
    caught(p, d, "node 0 (start): symmetry.root: renaming 1 [1, 0] (a→b, b→a) is not an "
           "automorphism", "initial state", "taken(b) becomes taken(a)")
    d["symmetry"]["root"] = 2
    caught(p, d, "symmetry.root: renaming 2 is not in the symmetry table")


def test_an_unused_renaming_is_checked_too() -> None:
    p = twins(init=("taken(b)",), agenda=1)
    d = lifted_twins()
    d["nodes"] = [_node(0, ["taken(b)"], ["take_one"], "H", 1, [_move("H", "take(a)", 1)]),
                  _node(1, ["taken(a)", "taken(b)"], [], None, 0, [])]
    d.update(cost=1, leaves=1, worst_case=1, expected=1)
    d["symmetry"]["renamings"] = [[0, 1], [1, 0], [1, 0]]
    r = caught(p, d, "symmetry.renamings[1]: ", "not an automorphism")
    assert any(v.startswith("branch []: symmetry.renamings[2]: ") for v in r.violations)


# -- each part of the ground problem must map onto itself (§3) ------------------------------------

@pytest.mark.parametrize(("p", "why"), [
    (twins(init=("taken(b)",)), "it maps the initial state onto another"),
    (twins(beliefs=[(["taken(b)"], [])]), "it maps the belief worlds"),
    (twins(preferred=True), "the methods of take_one map onto others"),
    (twins(objective=Objective(weights={"take(a)": Fraction(2)})),
     "it renames a, which the problem names (an objective weight given by ground label)"),
    (twins(items=("a", "b", "c")), ""),
], ids=["init", "beliefs", "methods", "cost-by-label", "three-items"])
def test_automorphism_parts(p: Problem, why: str) -> None:
    got = reason(p, [1, 0, 2] if len(p.objects["item"]) == 3 else [1, 0],
                 objects=tuple(p.objects["item"]))
    assert (why in got) if why else got == "", got


def test_a_model_difference_rejects_a_planner_like_policy() -> None:
    # the same hand policy on a problem where a has a way of its own: the swap is refused
    caught(twins(preferred=True), lifted_twins(), "node 1 (H take(a))", "renaming 1",
           "not an automorphism of the problem (§3)", "methods of take_one")


# -- the planner's lifted policies ----------------------------------------------------------------

def _reads_v3() -> bool:
    return 3 in policy_format.READS and hasattr(Policy, "lifted")


needs_v3 = pytest.mark.skipif(not _reads_v3(), reason="the policy reader does not read v3")


@needs_v3
@pytest.mark.parametrize("name", ["twins", "spares"])
def test_the_planner_lifts_twins_and_it_validates(name: str) -> None:
    p = twins() if name == "twins" else spares()
    policy = ehatp.solve(p).policy
    assert policy is not None and getattr(policy, "symmetry", None) is not None
    assert validate(p, policy).ok
    back = Policy.from_dict(policy.to_dict())
    assert validate(p, back).ok


@needs_v3
@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_lifted_example_validates(example: Example) -> None:
    p, policy = solved(example)
    r = validate(p, policy)
    assert r.ok, r.violations
    if getattr(policy, "symmetry", None) is None:
        return
    # a tampered renaming is rejected: the first move with a renaming, set to the identity
    # (or, where none is used, the first move given a renaming that moves something)
    d = policy.to_dict()
    moves = [m for n in d["nodes"] for m in n["moves"]]
    used = [m for m in moves if m.get("renaming")]
    table = d["symmetry"]["renamings"]
    if used:
        tampered = used[0]
        del tampered["renaming"]
    elif len(table) > 1 and moves:
        tampered = moves[0]
        tampered["renaming"] = 1
    else:
        return
    r = validate(p, Policy.from_dict(d))
    assert not r.ok
    assert "\n" not in r.message
    assert f"node {tampered['to']} ({tampered['agent']} {tampered['action']}" in r.message, \
        r.message


@needs_v3
def test_some_shipped_example_is_lifted() -> None:
    lifted = [e.name for e in EXAMPLES if getattr(solved(e).policy, "symmetry", None) is not None]
    assert lifted


def lamps() -> Problem:
    """Both lamps are on, seen only once the light is switched on (the human's one task). The
    human believes one of two worlds, each with one lamp off and a note beside the other:
    switching the light on, it observes lamp(a) then lamp(b) (index order) and keeps the
    world with note(a); in the other order it would keep note(b)."""
    d = Domain("lamps")
    item = d.type("item")
    i = Var("i", item)
    light = d.predicate("light")
    d.predicate("lamp", i, observability=observable(light()))
    d.predicate("note", i, observability=HIDDEN)
    h = d.human
    switch = h.action("switch", pre=~light(), effects=[light()])
    on = h.task("lights_on", done=light())
    h.method(on, "switch", subtasks=[switch()])
    return problem(d, init=["lamp(a)", "lamp(b)"], human=["lights_on"],
                   objects={"item": ["a", "b"]}, human_model=HumanModel(passes=Passes.IDLE),
                   beliefs=[(["note(a)"], ["lamp(b)"]), (["note(b)"], ["lamp(a)"])])


def lifted_lamps() -> dict[str, Any]:
    d = lifted_twins()
    root = _node(0, ["lamp(a)", "lamp(b)"], ["lights_on"], "H", 1, [_move("H", "switch", 1)])
    root.update(worlds=2, divergence=["lamp(a)", "lamp(b)", "not note(a)", "not note(b)"],
                world_diffs=[{"true": ["note(a)"], "false": ["lamp(b)"]},
                             {"true": ["note(b)"], "false": ["lamp(a)"]}])
    leaf = _node(1, ["lamp(a)", "lamp(b)", "light"], [], None, 0, [])
    leaf.update(divergence=["not note(a)"], world_diffs=[{"true": ["note(a)"], "false": []}])
    d.update(nodes=[root, leaf], domain="lamps", cost=1, leaves=1, worst_case=1, expected=1)
    return d


def test_an_observation_whose_order_a_renaming_changes() -> None:
    p = lamps()
    assert reason(p, [1, 0]) == ""  # the swap is an automorphism
    d = lifted_lamps()
    r = check(p, d)
    assert r.ok, r.violations  # the root stands for the real root itself
    # the root standing for the real root renamed: switching on there observes the lamps in
    # the other order, so the leaf does not stand for the real successor (§3)
    d["symmetry"]["root"] = 1
    r = caught(p, d, "node 0 (start, renamed by renaming 1 (a→b, b→a)): a move here observes "
               "atoms in an order a renaming changes", "(§3)")
    assert len(r.violations) == 1


def spares() -> Problem:
    """Two spare parts are available; the human believes neither is, so it cannot fetch one
    (``fetch`` needs some part available). Telling it avail(a) or avail(b) fixes that equally
    well: the robot's inform is chosen by atom name, avail(a) (§5)."""
    d = Domain("spares")
    item = d.type("item")
    i = Var("i", item)
    avail = d.predicate("avail", i, observability=HIDDEN)
    fetched = d.predicate("fetched")
    h = d.human
    fetch = h.action("fetch", pre=exists(i, avail(i)), effects=[fetched()])
    get = h.task("get", done=fetched())
    h.method(get, "fetch", subtasks=[fetch()])
    return problem(d, init=["avail(a)", "avail(b)"], human=["get"], starts="robot",
                   objects={"item": ["a", "b"]}, human_model=HumanModel(passes=Passes.IDLE),
                   beliefs=[([], ["avail(a)", "avail(b)"])])


def lifted_spares() -> dict[str, Any]:
    d = lifted_twins()
    both = ["avail(a)", "avail(b)"]
    root = _node(0, both, ["get"], "R", 2, [_move("R", "inform(avail(a))", 1)])
    root["moves"][0].update(kind="inform", name="inform", args=["avail(a)"])
    root.update(divergence=both, world_diffs=[{"true": [], "false": both}])
    mid = _node(1, both, ["get"], "H", 1, [_move("H", "fetch", 2)])
    leaf = _node(2, [*both, "fetched"], [], None, 0, [])
    for n in (mid, leaf):
        n.update(divergence=["avail(b)"], world_diffs=[{"true": [], "false": ["avail(b)"]}])
    d.update(nodes=[root, mid, leaf], domain="spares", cost=2, leaves=1, worst_case=2,
             communications=1,
             expected=2)
    return d


def test_an_inform_chosen_by_name_at_a_renamed_node() -> None:
    p = spares()
    assert reason(p, [1, 0]) == ""
    d = lifted_spares()
    r = check(p, d)
    assert r.ok, r.violations
    # standing for the real root renamed, the node's inform(avail(a)) is inform(avail(b)) on
    # the real objects, which is not the set the rules choose there (name order, §5)
    d["symmetry"]["root"] = 1
    r = caught(p, d, "node 0 (start, renamed by renaming 1 (a→b, b→a)): the robot's inform "
               "here is chosen by atom names", "(§3, §5)")
    assert len(r.violations) == 1


def test_a_model_grounded_on_demand_is_checked_whole() -> None:
    # [limits] ground_ahead = 1: the validator's models are grounded only in part, so the
    # automorphism check grounds the problem whole
    p = twins()
    p = dataclasses.replace(p, limits=dataclasses.replace(p.limits, ground_ahead=1))
    assert check(p, lifted_twins()).ok
    q = twins(preferred=True)
    q = dataclasses.replace(q, limits=dataclasses.replace(q.limits, ground_ahead=1))
    caught(q, lifted_twins(), "not an automorphism of the problem (§3)", "methods of take_one")


def test_partially_ordered_methods_turn_the_reduction_off() -> None:
    caught(twins(unordered=True), lifted_twins(), "node 1 (H take(a))",
           "partially ordered methods turn the reduction off (§3)")
