"""A robot that never idles to force the human (docs/semantics.md §4, the fair pass rule).

Table setting: the human fetches bread from the pantry and then pours water into glass ``g1``;
the robot lays the plate and the fork and washes three glasses, in any order. Everything is
visible from the kitchen, so no communication and no deferral is ever needed: any co-present
robot ``wait`` while the robot could act is idling on purpose.
"""

from __future__ import annotations

import ehatp
from ehatp import Domain, HumanModel, Passes, Var, observable
from ehatp.formats.policy import Policy, PolicyNode

from .scenarios import problem


def table_domain() -> Domain:
    d = Domain("table")
    Place, Thing, Glass = d.type("place"), d.type("thing"), d.type("glass")
    kitchen, pantry = d.constant("kitchen", Place), d.constant("pantry", Place)
    p, p2, x, g = Var("p", Place), Var("p2", Place), Var("x", Thing), Var("g", Glass)
    human_at = d.predicate("human_at", p)
    d.copresence = human_at(kitchen)
    seen = observable(human_at(kitchen))
    laid = d.predicate("laid", x, observability=seen)
    clean = d.predicate("clean", g, observability=seen)
    bread = d.predicate("bread")
    poured = d.predicate("poured", g)

    r = d.robot
    lay = r.action("lay", x, pre=~laid(x), effects=[laid(x)])
    wash = r.action("wash", g, pre=~clean(g), effects=[clean(g)])
    washing = r.task("washing")
    r.method(washing, "one", params=[g], pre=~clean(g), subtasks=[wash(g), washing()])
    r.method(washing, "done", pre=clean("g1") & clean("g2") & clean("g3"))
    setting = r.task("set_table")
    r.method(setting, "all", subtasks=[lay("plate"), lay("fork"), washing()])

    h = d.human
    go = h.action("go", p, p2, pre=human_at(p) & ~human_at(p2),
                  effects=[human_at(p2), ~human_at(p)])
    take = h.action("take_bread", pre=human_at(pantry) & ~bread(), effects=[bread()])
    pour = h.action("pour", g, pre=human_at(kitchen) & clean(g) & bread() & ~poured(g),
                    effects=[poured(g)])
    fetch = h.task("fetch")
    h.method(fetch, "trip", subtasks=[go(kitchen, pantry), take(), go(pantry, kitchen)])
    serve = h.task("serve")
    h.method(serve, "pour", subtasks=[pour("g1")])
    return d


def table(passes: Passes = Passes.FAIR) -> ehatp.Problem:
    return problem(table_domain(), init=["human_at(kitchen)"], robot=["set_table"],
                   human=["fetch", "serve"],
                   objects={"thing": ["plate", "fork"], "glass": ["g1", "g2", "g3"]},
                   human_model=HumanModel(passes=passes))


def _robot_idles(policy: Policy) -> list[str]:
    """Co-present robot waits while the robot still had something to do (not a deferral: in
    this domain the human sees everything from the kitchen)."""
    out = []
    for n in policy.nodes:
        if n.to_move != "R" or not n.copresent or not n.robot_agenda:
            continue
        (c,) = n.moves
        if c.kind == "wait" and _can_act(n):
            out.append(f"node {n.id}: wait with {n.robot_agenda}")
    return out


def _can_act(n: PolicyNode) -> bool:
    # the robot's agenda holds unlaid things or unwashed glasses
    things = {"plate", "fork"} - {a[5:-1] for a in n.state if a.startswith("laid(")}
    glasses = {"g1", "g2", "g3"} - {a[6:-1] for a in n.state if a.startswith("clean(")}
    return bool(things or glasses)


def test_fair_robot_washes_the_needed_glass_after_the_reunion_and_never_idles() -> None:
    p = table()
    r = ehatp.solve(p)
    assert r.policy is not None and r.optimal
    assert ehatp.validate(p, r.policy).ok
    assert _robot_idles(r.policy) == []
    # right after the human is back, with g1 still dirty, the robot washes g1 first
    back = [r.policy.nodes[m.to] for _, m in r.policy.edges()
            if m.action == "go(pantry, kitchen)"]
    assert back
    for n in back:
        (c,) = n.moves
        if "clean(g1)" not in n.state:
            assert c.action == "wash(g1)", (n.id, c.action)


def test_prototype_rule_brings_back_the_idling_robot() -> None:
    fair, proto = ehatp.solve(table()), ehatp.solve(table(Passes.PROTOTYPE))
    assert fair.policy is not None and proto.policy is not None
    assert ehatp.validate(table(Passes.PROTOTYPE), proto.policy).ok
    # with the human's pass taken away after any wait, waiting on purpose pays off
    assert _robot_idles(proto.policy) != []
    assert proto.policy.cost < fair.policy.cost
