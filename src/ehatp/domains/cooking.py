"""Cooking (the paper's second domain, Table 1 Cooking 1-3, adapted from Favier et al. 2023).

The robot cuts and washes the vegetables, then seasons them and puts them on the stove, in either
order. The human fetches an ingredient from the pantry, puts it in the boiling pan and serves.
The trip to the pantry separates the agents, so the robot's work may go unseen: ``cut``,
``boiling`` and ``food_ready`` are seen when co-present, ``washed`` and ``seasoned`` never.

Variants: 1 = one move each way (K=2); 2 = the human also gets ready at the pantry (K=3);
3 = turn then move each way, turning away already breaks co-presence (K=4).

``waypoints`` (default 0; for longer trips in the scaling benchmark): the number of places
``way1`` … ``wayN`` on the way to the pantry, passed in order, one leg each (``turn`` then
``move`` per leg in variant 3); each waypoint lengthens the round trip by two legs.

Our modelling choices: ``washed``/``seasoned`` are INFERABLE (learned only by witnessing the
action); the ingredient's place is three nullary atoms; ``cut`` has done-condition ``cut``, so
"cut if needed, then wash" is a single method.
"""

from __future__ import annotations

from ..model.domain import INFERABLE, Domain, TaskRef, domain_factory, observable
from ..model.formula import Var, eq, exists

R, H = "R", "H"
KITCHEN, PANTRY = "kitchen", "pantry"
VARIANTS = {1: "cooking", 2: "cooking-ready", 3: "cooking-turn"}


@domain_factory
def make_domain(variant: int = 1, waypoints: int = 0) -> Domain:
    if variant not in VARIANTS:
        raise ValueError(f"variant must be 1, 2 or 3, got {variant!r}")
    if isinstance(waypoints, bool) or not isinstance(waypoints, int) or waypoints < 0:
        raise ValueError(f"waypoints must be a whole number of places, 0 or more, "
                         f"got {waypoints!r}")
    name = VARIANTS[variant] + (f"-way{waypoints}" if waypoints else "")
    d = Domain(name, robot=R, human=H, doc=__doc__ or "")
    Place = d.type("place")
    d.constant(KITCHEN, Place)
    d.constant(PANTRY, Place)
    route = [KITCHEN, *(d.constant(f"way{i}", Place) for i in range(1, waypoints + 1)), PANTRY]
    a = Var("a", "agent")
    p, p1, p2 = (Var(n, Place) for n in ("p", "p1", "p2"))

    at = d.predicate("at", a, p)
    facing = d.predicate("facing", a, p)
    copresent = exists(p, at(R, p) & at(H, p) & facing(R, p) & facing(H, p))
    d.copresence = copresent
    seen = observable(copresent)
    cut = d.predicate("cut", observability=seen)
    boiling = d.predicate("boiling", observability=seen)
    food_ready = d.predicate("food_ready", observability=seen)
    washed = d.predicate("washed", observability=INFERABLE)
    seasoned = d.predicate("seasoned", observability=INFERABLE)
    # the ingredient only moves by the human's hand, so the human always knows where it is
    in_pantry = d.predicate("in_pantry")
    in_hand = d.predicate("in_hand")
    in_pan = d.predicate("in_pan")

    # -- robot: stays in the kitchen --
    rm = d.robot
    r_cut = rm.action("cut", pre=~cut(), effects=[cut()], done=cut())
    r_wash = rm.action("wash", pre=cut() & ~washed(), effects=[washed()])
    r_season = rm.action("season", pre=washed() & ~seasoned(), effects=[seasoned()])
    r_stove = rm.action("put_on_stove", pre=washed() & ~boiling(), effects=[boiling()])
    r_prep = rm.task("prepare", done=food_ready())
    rm.method(r_prep, "cut_and_wash", pre=~(cut() & washed()),
              subtasks=[r_cut(), r_wash(), r_prep()])
    cook = washed() & ~seasoned() & ~boiling()
    rm.method(r_prep, "season_first", pre=cook, subtasks=[r_season(), r_stove(), r_prep()])
    rm.method(r_prep, "stove_first", pre=cook, subtasks=[r_stove(), r_season(), r_prep()])
    # seasoned and boiling: no method applies, the robot can only wait for the human to serve

    # -- human: fetches the ingredient, adds it, serves --
    hm = d.human
    if variant == 3:
        turn = hm.action("turn", p1, p2, pre=at(H, p1) & facing(H, p1) & ~eq(p1, p2),
                         effects=[facing(H, p2), ~facing(H, p1)])
        move = hm.action("move", p1, p2, pre=at(H, p1) & facing(H, p2) & ~eq(p1, p2),
                         effects=[at(H, p2), ~at(H, p1)])
    else:
        move = hm.action("move", p1, p2, pre=at(H, p1) & facing(H, p1) & ~eq(p1, p2),
                         effects=[at(H, p2), facing(H, p2), ~at(H, p1), ~facing(H, p1)])
    get_pre = at(H, PANTRY) & in_pantry()
    getting_ready: list[TaskRef] = []
    if variant == 2:
        ready = d.predicate("ready")
        get_ready = hm.action("get_ready", pre=at(H, PANTRY) & ~ready(), effects=[ready()])
        getting_ready = [get_ready()]
        get_pre = get_pre & ready()
    get = hm.action("get_ingredient", pre=get_pre, effects=[in_hand(), ~in_pantry()])
    put = hm.action("put_ingredient", pre=at(H, KITCHEN) & in_hand() & boiling(),
                    effects=[in_pan(), ~in_hand()])
    serve = hm.action("serve", pre=seasoned() & in_pan() & ~food_ready(),
                      effects=[food_ready()])

    def go(src: str, dst: str) -> list[TaskRef]:
        path = route if src == KITCHEN else route[::-1]  # [src, dst] without waypoints
        return [step for u, v in zip(path, path[1:], strict=False)
                for step in ([turn(u, v)] if variant == 3 else []) + [move(u, v)]]

    h_prep = hm.task("prepare", done=food_ready())
    bring = hm.task("bring")
    hm.method(h_prep, "cook", pre=at(H, KITCHEN) & in_pantry(),
              subtasks=[bring(), put(), serve()])
    hm.method(bring, "trip", subtasks=[*go(KITCHEN, PANTRY), *getting_ready, get(),
                                       *go(PANTRY, KITCHEN)])
    return d


domain = make_domain()
