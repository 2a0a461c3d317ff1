"""Cube organization (the paper's case study, Table 1 P1-P6).

Two tables: ``mt`` (robot and boxes) and ``ot``. Only the human moves. The cubes of each table
must end in one box, different tables in different boxes.

Reach: the robot picks cubes on ``mt``; the human handles only the cubes it must fetch, those
whose origin is not ``mt`` (the robot's cubes are the robot's). Sight: what lies on a table, and
what a transparent box on ``mt`` holds, is visible only while the human is at *and facing* that
table; what an agent holds is visible when co-present (same table, both facing it), and the
human always knows what it holds itself.

Options:

- ``turn_before_move`` (the K=4 instances): going to a table takes ``turn`` then ``move``, and
  turning away already breaks co-presence and sight; otherwise one ``move`` does both (K=2).
- ``human_reach``: ``"fetched"`` (default, the paper's rule above) or ``"any"`` (the human may
  also pick and box the robot's cubes on ``mt``, this project's reach before issue 7).
- ``waypoints`` (default 0; for longer trips in the scaling benchmark): the number of places
  ``way1`` … ``wayN`` (tables on which nothing lies) on the way from ``mt`` to ``ot``; a trip
  goes through them in order, one ``move`` per leg (``turn`` then ``move`` per leg with
  ``turn_before_move``). A round trip then keeps the agents apart for ``2 * (N + 1)`` robot
  turns (``4 * (N + 1)`` with ``turn_before_move``), the K it needs.
- ``encoding``: ``"atoms"`` (default, the paper's predicates) or ``"variables"``: the same
  model with state variables (docs/modelling.md): a cube's place ``loc(c)`` is one of the
  places -- tables, boxes and the agents' hands (``agent`` is a subtype of ``place``) --, an
  agent's ``at(a)`` and ``facing(a)`` are tables; ``empty(b)`` and ``handempty(a)`` are derived.
  Problems then write ``loc(r) = mt``, ``at(H) = mt`` in ``[init]``. Sight is per value: the
  human sees whether a cube is on a table while at and facing it, in a box when the box is
  transparent and the human at and facing ``mt``, in a hand (its own, or when co-present).
  Plans, costs and communication are those of ``"atoms"`` (tests/test_variables.py).

Our modelling choices: the placement rule ``can_put`` and the goal are derived predicates
(printed by name in asks); ``pick`` names only the cube (the table is where the cube lies).
"""

from __future__ import annotations

from typing import Literal

from ..model.domain import Domain, Operator, TaskRef, domain_factory, for_each, observable
from ..model.formula import TRUE, Formula, Var, eq, exists, forall

R, H = "R", "H"
MT, OT = "mt", "ot"
HUMAN_REACH = ("fetched", "any")


ENCODINGS = ("atoms", "variables")


@domain_factory
def make_domain(turn_before_move: bool = False,
                human_reach: Literal["fetched", "any"] = "fetched",
                waypoints: int = 0, encoding: Literal["atoms", "variables"] = "atoms") -> Domain:
    """The cube domain; see the module docstring for the four options."""
    if encoding not in ENCODINGS:
        raise ValueError(f"encoding must be one of {', '.join(map(repr, ENCODINGS))}, "
                         f"got {encoding!r}")
    if human_reach not in HUMAN_REACH:
        raise ValueError(f"human_reach must be one of {', '.join(map(repr, HUMAN_REACH))}, "
                         f"got {human_reach!r}")
    if isinstance(waypoints, bool) or not isinstance(waypoints, int) or waypoints < 0:
        raise ValueError(f"waypoints must be a whole number of places, 0 or more, "
                         f"got {waypoints!r}")
    # the name tells the variant, so that a policy file says which model it was planned for
    suffix = ("-turn" if turn_before_move else "") + ("-reach-any" if human_reach == "any" else "")
    suffix += f"-way{waypoints}" if waypoints else ""
    if encoding == "variables":
        return _with_variables(turn_before_move, human_reach, waypoints, suffix)
    d = Domain("cubes" + suffix, robot=R, human=H, doc=__doc__ or "")
    Table, Box, Cube = d.type("table"), d.type("box"), d.type("cube")
    d.constant(MT, Table)
    d.constant(OT, Table)
    route = [MT, *(d.constant(f"way{i}", Table) for i in range(1, waypoints + 1)), OT]
    a = Var("a", "agent")
    t, t0, t1, t2 = (Var(n, Table) for n in ("t", "t0", "t1", "t2"))
    b, b2 = Var("b", Box), Var("b2", Box)
    c, c2 = Var("c", Cube), Var("c2", Cube)

    # static facts
    origin = d.predicate("origin", c, t)
    transparent = d.predicate("transparent", b)
    # fluents
    at = d.predicate("at", a, t)
    facing = d.predicate("facing", a, t)
    copresent = exists(t, at(R, t) & at(H, t) & facing(R, t) & facing(H, t))
    d.copresence = copresent
    # sight: the human sees a table only while at it and facing it (turning away is enough to
    # miss the robot's work in the K=4 instances; in K=2 ones moving sets facing too)
    on = d.predicate("on", c, t, observability=observable(at(H, t) & facing(H, t)))
    box_visible = observable(at(H, MT) & facing(H, MT) & transparent(b))
    inside = d.predicate("in", c, b, observability=box_visible)
    empty = d.predicate("empty", b, observability=box_visible)
    own_or_seen = observable(eq(a, H) | copresent)
    holding = d.predicate("holding", a, c, observability=own_or_seen)
    handempty = d.predicate("handempty", a, observability=own_or_seen)

    # placement rule: cubes of one table in one box, different tables in different boxes
    mate_in = d.derived("mate_in", [c, b], exists([c2, t], inside(c2, b) & origin(c2, t)
                                                  & origin(c, t)))
    can_put = d.derived("can_put", [c, b], forall(b2, empty(b2)) | mate_in(c, b)
                        | (~exists(b2, mate_in(c, b2)) & empty(b)))
    goal = d.derived("organized", [], forall(c, exists(b, inside(c, b))) & forall(
        [c, c2, b], (inside(c, b) & inside(c2, b)) >> exists(t, origin(c, t) & origin(c2, t))))

    # -- robot: picks cubes on mt and boxes them --
    rm = d.robot
    r_pick = rm.action("pick", c, pre=on(c, MT) & handempty(R),
                       effects=[holding(R, c), ~on(c, MT), ~handempty(R)])
    r_place = rm.action("place", c, b, pre=holding(R, c) & at(R, MT) & can_put(c, b),
                        effects=[inside(c, b), ~empty(b), ~holding(R, c), handempty(R)])
    r_org = rm.task("organize", done=goal())
    r_away = rm.task("put_away", c)
    rm.method(r_org, "near", params=[c], pre=on(c, MT) & handempty(R),
              subtasks=[r_pick(c), r_away(c), r_org()])
    rm.method(r_away, "box", params=[b], pre=holding(R, c) & can_put(c, b),
              subtasks=[r_place(c, b)])

    # -- human: fetches the cubes of other tables (all cubes with human_reach="any") --
    # reach is static data (a cube's origin), so the human never acts on the robot's cubes
    reach: Formula = ~origin(c, MT) if human_reach == "fetched" else TRUE
    hm = d.human
    h_pick = hm.action("pick", c, pre=reach & exists(t, at(H, t) & on(c, t)) & handempty(H),
                       effects=[holding(H, c), ~handempty(H), for_each(t, ~on(c, t))])
    h_place = hm.action("place", c, b, pre=holding(H, c) & at(H, MT) & can_put(c, b),
                        effects=[inside(c, b), ~empty(b), ~holding(H, c), handempty(H)])
    if turn_before_move:
        turn = hm.action("turn", t1, t2, pre=facing(H, t1) & ~eq(t1, t2),
                         effects=[facing(H, t2), ~facing(H, t1)])
        move = hm.action("move", t1, t2, pre=at(H, t1) & facing(H, t2) & ~eq(t1, t2),
                         effects=[at(H, t2), ~at(H, t1)])
    else:
        move = hm.action("move", t1, t2, pre=at(H, t1) & facing(H, t1) & ~eq(t1, t2),
                         effects=[at(H, t2), facing(H, t2), ~at(H, t1), ~facing(H, t1)])

    def go(src: Var | str, dst: Var | str) -> list[TaskRef]:
        return _trip(turn if turn_before_move else None, move, route if waypoints else [],
                     src, dst)

    h_org = hm.task("organize", done=goal())
    h_away = hm.task("put_away", c)
    fetch = hm.task("fetch", c, t)
    hm.method(h_org, "near", params=[c, t], pre=reach & at(H, t) & on(c, t) & handempty(H),
              subtasks=[h_pick(c), h_away(c), h_org()])
    hm.method(h_org, "far", params=[c, t], pre=reach & on(c, t) & ~at(H, t) & handempty(H),
              subtasks=[fetch(c, t), h_away(c), h_org()])
    if not waypoints:
        hm.method(fetch, "go", params=[t0], pre=at(H, t0) & ~eq(t0, t),
                  subtasks=[*go(t0, t), h_pick(c)])
    else:  # one method per direction: the route is spelt out by name
        for src, dst in ((MT, OT), (OT, MT)):
            hm.method(fetch, f"go_{dst}", pre=at(H, src) & eq(t, dst),
                      subtasks=[*go(src, dst), h_pick(c)])
    hm.method(h_away, "box", params=[b], pre=holding(H, c) & at(H, MT) & can_put(c, b),
              subtasks=[h_place(c, b)])
    if not waypoints:
        hm.method(h_away, "carry", params=[t0], pre=holding(H, c) & at(H, t0) & ~eq(t0, MT),
                  subtasks=[*go(t0, MT), h_away(c)])
    else:
        hm.method(h_away, "carry", pre=holding(H, c) & at(H, OT),
                  subtasks=[*go(OT, MT), h_away(c)])
    return d


def _trip(turn: Operator | None, move: Operator, route: list[str], src: Var | str,
          dst: Var | str) -> list[TaskRef]:
    """The human's steps from ``src`` to ``dst``: one ``move`` (after a ``turn`` when turning
    breaks sight), or one per leg through the waypoints of ``route``, in order (``src`` and
    ``dst`` are then the two tables, by name)."""
    legs: list[tuple[Var | str, Var | str]] = [(src, dst)]
    if route:
        path = route if src == MT else route[::-1]
        legs = list(zip(path, path[1:], strict=False))
    return [step for u, v in legs for step in ([turn(u, v)] if turn else []) + [move(u, v)]]


def _with_variables(turn_before_move: bool, human_reach: Literal["fetched", "any"],
                    waypoints: int, suffix: str) -> Domain:
    """The same model with state variables (``encoding = "variables"``); the options are
    checked by :func:`make_domain`."""
    d = Domain("cubes-vars" + suffix, robot=R, human=H, doc=__doc__ or "")
    Place = d.type("place")
    Table, Box = d.type("table", parent=Place), d.type("box", parent=Place)
    d.type("agent", parent=Place)  # a hand holds a cube: the agents are places too
    Cube = d.type("cube")
    d.constant(MT, Table)
    d.constant(OT, Table)
    route = [MT, *(d.constant(f"way{i}", Table) for i in range(1, waypoints + 1)), OT]
    a, a2 = Var("a", "agent"), Var("a2", "agent")
    p = Var("p", Place)
    t, t0, t1, t2 = (Var(n, Table) for n in ("t", "t0", "t1", "t2"))
    b, b2 = Var("b", Box), Var("b2", Box)
    c, c2 = Var("c", Cube), Var("c2", Cube)

    # static facts
    origin = d.predicate("origin", c, t)
    transparent = d.predicate("transparent", b)
    # where the agents are and which table they face
    at = d.variable("at", a, values=Table)
    facing = d.variable("facing", a, values=Table)
    copresent = exists(t, (at(R) == t) & (at(H) == t) & (facing(R) == t) & (facing(H) == t))
    d.copresence = copresent
    # where each cube is, seen per place: on a table while the human is at it and facing it;
    # in a transparent box from mt; in a hand, the human's own or when co-present
    sees = (exists(t, eq(p, t) & (at(H) == t) & (facing(H) == t))
            | exists(b, eq(p, b) & transparent(b)) & (at(H) == MT) & (facing(H) == MT)
            | eq(p, H) | exists(a, eq(p, a)) & copresent)
    loc = d.variable("loc", c, values=p, observability=observable(sees))
    empty = d.derived("empty", [b], ~exists(c, loc(c) == b))
    handempty = d.derived("handempty", [a2], ~exists(c, loc(c) == a2))

    # placement rule: cubes of one table in one box, different tables in different boxes
    mate_in = d.derived("mate_in", [c, b], exists([c2, t], (loc(c2) == b) & origin(c2, t)
                                                  & origin(c, t)))
    can_put = d.derived("can_put", [c, b], forall(b2, empty(b2)) | mate_in(c, b)
                        | (~exists(b2, mate_in(c, b2)) & empty(b)))
    goal = d.derived("organized", [], forall(c, exists(b, loc(c) == b)) & forall(
        [c, c2, b], ((loc(c) == b) & (loc(c2) == b)) >> exists(t, origin(c, t)
                                                               & origin(c2, t))))

    # -- robot: picks cubes on mt and boxes them --
    rm = d.robot
    r_pick = rm.action("pick", c, pre=(loc(c) == MT) & handempty(R), effects=[loc(c).set(R)])
    r_place = rm.action("place", c, b, pre=(loc(c) == R) & (at(R) == MT) & can_put(c, b),
                        effects=[loc(c).set(b)])
    r_org = rm.task("organize", done=goal())
    r_away = rm.task("put_away", c)
    rm.method(r_org, "near", params=[c], pre=(loc(c) == MT) & handempty(R),
              subtasks=[r_pick(c), r_away(c), r_org()])
    rm.method(r_away, "box", params=[b], pre=(loc(c) == R) & can_put(c, b),
              subtasks=[r_place(c, b)])

    # -- human: fetches the cubes of other tables (all cubes with human_reach="any") --
    reach: Formula = ~origin(c, MT) if human_reach == "fetched" else TRUE
    hm = d.human
    h_pick = hm.action("pick", c, pre=reach & exists(t, (at(H) == t) & (loc(c) == t))
                       & handempty(H), effects=[loc(c).set(H)])
    h_place = hm.action("place", c, b, pre=(loc(c) == H) & (at(H) == MT) & can_put(c, b),
                        effects=[loc(c).set(b)])
    if turn_before_move:
        turn = hm.action("turn", t1, t2, pre=(facing(H) == t1) & ~eq(t1, t2),
                         effects=[facing(H).set(t2)])
        move = hm.action("move", t1, t2, pre=(at(H) == t1) & (facing(H) == t2) & ~eq(t1, t2),
                         effects=[at(H).set(t2)])
    else:
        move = hm.action("move", t1, t2, pre=(at(H) == t1) & (facing(H) == t1) & ~eq(t1, t2),
                         effects=[at(H).set(t2), facing(H).set(t2)])

    def go(src: Var | str, dst: Var | str) -> list[TaskRef]:
        return _trip(turn if turn_before_move else None, move, route if waypoints else [],
                     src, dst)

    h_org = hm.task("organize", done=goal())
    h_away = hm.task("put_away", c)
    fetch = hm.task("fetch", c, t)
    hm.method(h_org, "near", params=[c, t],
              pre=reach & (at(H) == t) & (loc(c) == t) & handempty(H),
              subtasks=[h_pick(c), h_away(c), h_org()])
    hm.method(h_org, "far", params=[c, t],
              pre=reach & (loc(c) == t) & (at(H) != t) & handempty(H),
              subtasks=[fetch(c, t), h_away(c), h_org()])
    if not waypoints:
        hm.method(fetch, "go", params=[t0], pre=(at(H) == t0) & ~eq(t0, t),
                  subtasks=[*go(t0, t), h_pick(c)])
    else:
        for src, dst in ((MT, OT), (OT, MT)):
            hm.method(fetch, f"go_{dst}", pre=(at(H) == src) & eq(t, dst),
                      subtasks=[*go(src, dst), h_pick(c)])
    hm.method(h_away, "box", params=[b], pre=(loc(c) == H) & (at(H) == MT) & can_put(c, b),
              subtasks=[h_place(c, b)])
    if not waypoints:
        hm.method(h_away, "carry", params=[t0], pre=(loc(c) == H) & (at(H) == t0)
                  & ~eq(t0, MT), subtasks=[*go(t0, MT), h_away(c)])
    else:
        hm.method(h_away, "carry", pre=(loc(c) == H) & (at(H) == OT),
                  subtasks=[*go(OT, MT), h_away(c)])
    return d


domain = make_domain()
