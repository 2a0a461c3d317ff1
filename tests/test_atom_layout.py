"""The atoms' layout (docs/semantics.md §2): predicates, state variables and counters by name,
the families of more than 1,024 ground atoms (``LARGE_FAMILY``) after the others, so that a
state, an int as long as its highest atom, stays short when a large family is rarely true."""

from __future__ import annotations

import ehatp
from ehatp import Domain, Problem, Var
from ehatp.model.grounding import LARGE_FAMILY, ground_problem
from ehatp.run.walk import walk_policy

THINGS = [f"t{i:02d}" for i in range(32)]


def layout_problem(big: str) -> Problem:
    """Three fluent families over 32 things and 2 slots: ``big(x, y, s)`` (2,048 atoms),
    ``m(x, y)`` (1,024) and ``p(x)`` (32); the robot makes ``p(t00)`` true, which the goal
    asks."""
    d = Domain("layout")
    thing = d.type("thing")
    slot = d.type("slot")
    x, y, z = Var("x", thing), Var("y", thing), Var("z", slot)
    p = d.predicate("p", x)
    m = d.predicate("m", x, y)
    b = d.predicate(big, x, y, z)
    r = d.robot
    set_p = r.action("set_p", x, effects=[p(x)])
    r.action("set_m", x, y, effects=[m(x, y)])
    r.action("set_big", x, y, z, effects=[b(x, y, z)])
    go = r.task("go", x, done=p(x))
    r.method(go, "do", subtasks=[set_p(x)])
    return Problem(name="layout", domain=d, objects={"thing": THINGS, "slot": ["s0", "s1"]},
                   init=frozenset({("p", ("t01",))}), robot_agenda=(("go", ("t00",)),),
                   human_agenda=(), goal=((True, ("p", ("t00",))),))


def test_a_family_over_the_limit_is_laid_out_after_the_others_whatever_its_name() -> None:
    """By hand: by name the families are a_big, m, p, so a_big would take bits 0-2,047; with
    a_big over 1,024 atoms and m exactly 1,024 (not over), m takes 0-1,023 (m(t00, t00)
    first, m(t31, t31) last), p 1,024-1,055, a_big from 1,056. The initial state holds
    p(t01) alone, bit 1,025: an int of 1,026 bits, not 3,074. Renamed z_big, the big family
    comes last by name too: the same layout."""
    assert LARGE_FAMILY == 1024
    for big in ("a_big", "z_big"):
        g = ground_problem(layout_problem(big))
        i = g.atom_index
        assert (i["m(t00, t00)"], i["m(t31, t31)"]) == (0, 1023), big
        assert (i["p(t00)"], i["p(t01)"], i["p(t31)"]) == (1024, 1025, 1055), big
        assert i[f"{big}(t00, t00, s0)"] == 1056 and len(g.atoms) == 1056 + 2048, big
        assert g.init == 1 << 1025 and g.state_atoms(g.init) == ["p(t01)"], big


def test_a_problem_with_a_large_family_solves_validates_and_runs() -> None:
    """By hand (§4, §6): the human starts (the default) with nothing to do, so it passes
    (cost 1); the robot's one option sets p(t00) (cost 1), and then the goal holds, the
    robot's task is done and the human has none: cost 2, one branch."""
    p = layout_problem("a_big")
    policy = ehatp.solve(p).policy
    assert policy is not None and policy.cost == 2 and policy.leaves == 1
    assert ehatp.validate(p, policy).ok
    report = walk_policy(p, policy)
    assert report.ok and report.branches == 1, report.message
