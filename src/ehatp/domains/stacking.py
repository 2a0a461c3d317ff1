"""Shared stacking (joint steps): the robot and the human build one tower of cubes together.

After the user study of Favier & Alami (ACS 2024): cubes lie in three zones of one table, the
human's zone (``hzone``, only the human reaches it), the robot's (``rzone``, only the robot)
and a shared zone in between (``shared``, both reach it); the tower's positions are given
bottom to top and each position wants one cube (``target(c, p)``, static, as the pattern the
participants were shown). Both agents stand at the table the whole time, so the human sees
everything (one world) and the interest is in who does what in each step
(``[steps] mode = "concurrent"``, docs/concurrent.md).

Physics (the operators): an agent with an empty hand picks a cube from the table within its
reach, and places the cube it holds on the tower's next position (the one above the top, or
the bottom when the tower is empty). What an operator holds (its ``resources``, C3 c): ``pick``
and ``place`` hold their cube, so the robot never takes **the cube the human is reaching
for** -- the human's ``pick(c)`` is seen as it starts, and the robot's ``pick(c)`` is no reply
to it (the rule is an admissibility constraint, the strictest reading: the robot may not even
choose it); ``place`` also holds the tower (``"tower"``), so two hands never place in one step.

Intentions (the methods, the same for both agents): place the cube held when its position is
next; otherwise pick a cube whose position is next, or the one above it when the cube for the
next is in a hand already (looking one cube ahead is what lets the two work in parallel).
Holding a cube whose turn has not come, an agent is blocked and waits. The rule keeps every
branch free of deadlock: of two held cubes, the lower one can always be placed.

Preferences (C11): the domain declares the metric ``shared_taken``, the cubes the robot takes
from the shared zone (the steps in which it picks a cube whose ``zone`` is ``shared``). A
human who likes to build prefers the robot to leave the shared cubes to it: a profile
``builder = ["shared_taken", "makespan"]`` (``examples/concurrent/stack-prefs.toml``).

Static facts a problem gives: ``zone(c, z)`` for every cube, ``target(c, p)`` for every
position, ``bottom(p)`` for the lowest position and ``below(q, p)`` for each position ``p``
directly above ``q``.
"""

from __future__ import annotations

from ..model.domain import Domain, domain_factory
from ..model.formula import Var, exists, forall

R, H = "R", "H"
HZONE, RZONE, SHARED = "hzone", "rzone", "shared"


@domain_factory
def make_domain() -> Domain:
    """The shared stacking domain (see the module docstring)."""
    d = Domain("stacking", robot=R, human=H, doc=__doc__ or "")
    Cube, Pos, Zone = d.type("cube"), d.type("position"), d.type("zone")
    for name in (HZONE, RZONE, SHARED):
        d.constant(name, Zone)
    c, c2 = Var("c", Cube), Var("c2", Cube)
    p, q = Var("p", Pos), Var("q", Pos)
    z = Var("z", Zone)
    a = Var("a", "agent")

    # static facts
    zone = d.predicate("zone", c, z)
    target = d.predicate("target", c, p)
    bottom = d.predicate("bottom", p)
    below = d.predicate("below", q, p)
    # fluents (the table is in plain sight: every atom is observable, the default)
    ontable = d.predicate("ontable", c)
    holding = d.predicate("holding", a, c)
    handempty = d.predicate("handempty", a)
    filled = d.predicate("filled", p)

    # the next position: the bottom of an empty tower, or the one above the top
    nxt = d.derived("is_next", [p], ~filled(p) & (bottom(p) | exists(q, below(q, p)
                                                                       & filled(q))))
    # a position whose cube may be picked now: the next one, or the one above it when the
    # next one's cube is in a hand already
    in_hand = d.derived("in_hand", [p], exists([c2, a], target(c2, p) & holding(a, c2)))
    wanted = d.derived("wanted", [p], nxt(p) | (~filled(p) & exists(q, below(q, p) & nxt(q)
                                                                        & in_hand(q))))
    d.goal = forall(p, filled(p))

    for m, who, own in ((d.robot, R, RZONE), (d.human, H, HZONE)):
        reach = zone(c, own) | zone(c, SHARED)
        pick = m.action("pick", c, pre=ontable(c) & handempty(who) & reach,
                        effects=[~ontable(c), holding(who, c), ~handempty(who)],
                        resources=[c])
        place = m.action("place", c, p, pre=holding(who, c) & target(c, p) & nxt(p),
                         effects=[~holding(who, c), handempty(who), filled(p)],
                         resources=[c, "tower"])
        stack = m.task("stack", done=d.goal)
        m.method(stack, "place", params=[c, p], pre=holding(who, c) & target(c, p) & nxt(p),
                 subtasks=[place(c, p), stack()])
        m.method(stack, "pick", params=[c, p], pre=handempty(who) & ontable(c) & reach
                 & target(c, p) & wanted(p), subtasks=[pick(c), stack()])

    # a metric a preference profile may order (C11): what a human who likes to build minds
    d.metric("shared_taken", agent="robot", actions=["pick"], when=zone(c, SHARED),
             doc="the cubes the robot takes from the shared zone")
    return d


domain = make_domain()
