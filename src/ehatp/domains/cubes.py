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

from collections.abc import Callable
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
    cubes = (_WithVariables if encoding == "variables" else _WithAtoms)(
        turn_before_move, human_reach, waypoints, suffix)
    return cubes.build()


class _Cubes:
    """What both encodings share: the options, the tables and the route between them, and the
    steps a domain is built in (:meth:`build`)."""

    name = "cubes"

    def __init__(self, turn_before_move: bool, human_reach: Literal["fetched", "any"],
                 waypoints: int, suffix: str) -> None:
        self.turn_before_move, self.human_reach, self.waypoints = (
            turn_before_move, human_reach, waypoints)
        self.d = Domain(self.name + suffix, robot=R, human=H, doc=__doc__ or "")

    def build(self) -> Domain:
        """Return the domain: its types, its fluents, the robot's model, the human's."""
        self.types()
        d = self.d
        d.constant(MT, self.Table)
        d.constant(OT, self.Table)
        self.route = [MT, *(d.constant(f"way{i}", self.Table)
                            for i in range(1, self.waypoints + 1)), OT]
        self.a = Var("a", "agent")
        self.t, self.t0, self.t1, self.t2 = (Var(n, self.Table) for n in ("t", "t0", "t1", "t2"))
        self.b, self.b2 = Var("b", self.Box), Var("b2", self.Box)
        self.c, self.c2 = Var("c", self.Cube), Var("c2", self.Cube)
        self.fluents()
        self.robot()
        self.human()
        return d

    Table: str
    Box: str
    Cube: str

    def types(self) -> None:
        raise NotImplementedError

    def fluents(self) -> None:
        raise NotImplementedError

    def robot(self) -> None:
        raise NotImplementedError

    def human(self) -> None:
        raise NotImplementedError

    def go(self, turn: Operator | None, move: Operator) -> Callable[[Var | str, Var | str],
                                                                  list[TaskRef]]:
        """The human's trip from a table to another, through the route's waypoints."""

        def go(src: Var | str, dst: Var | str) -> list[TaskRef]:
            return _trip(turn if self.turn_before_move else None, move,
                         self.route if self.waypoints else [], src, dst)

        return go


class _WithAtoms(_Cubes):
    """The paper's predicates (``encoding = "atoms"``)."""

    def types(self) -> None:
        d = self.d
        self.Table, self.Box, self.Cube = d.type("table"), d.type("box"), d.type("cube")

    def fluents(self) -> None:
        """The static facts, the fluents with what the human sees of them, and the derived
        placement rule and goal."""
        d, a, t, b, b2, c, c2 = self.d, self.a, self.t, self.b, self.b2, self.c, self.c2
        # static facts
        self.origin = origin = d.predicate("origin", c, t)
        transparent = d.predicate("transparent", b)
        # fluents
        self.at = at = d.predicate("at", a, t)
        self.facing = facing = d.predicate("facing", a, t)
        copresent = exists(t, at(R, t) & at(H, t) & facing(R, t) & facing(H, t))
        d.copresence = copresent
        # sight: the human sees a table only while at it and facing it (turning away is enough
        # to miss the robot's work in the K=4 instances; in K=2 ones moving sets facing too)
        self.on = d.predicate("on", c, t, observability=observable(at(H, t) & facing(H, t)))
        box_visible = observable(at(H, MT) & facing(H, MT) & transparent(b))
        self.inside = inside = d.predicate("in", c, b, observability=box_visible)
        self.empty = empty = d.predicate("empty", b, observability=box_visible)
        own_or_seen = observable(eq(a, H) | copresent)
        self.holding = d.predicate("holding", a, c, observability=own_or_seen)
        self.handempty = d.predicate("handempty", a, observability=own_or_seen)

        # placement rule: cubes of one table in one box, different tables in different boxes
        mate_in = d.derived("mate_in", [c, b], exists([c2, t], inside(c2, b) & origin(c2, t)
                                                      & origin(c, t)))
        self.can_put = d.derived("can_put", [c, b], forall(b2, empty(b2)) | mate_in(c, b)
                                 | (~exists(b2, mate_in(c, b2)) & empty(b)))
        self.goal = d.derived("organized", [], forall(c, exists(b, inside(c, b))) & forall(
            [c, c2, b], (inside(c, b) & inside(c2, b)) >> exists(t, origin(c, t)
                                                                 & origin(c2, t))))

    def robot(self) -> None:
        """The robot picks cubes on mt and boxes them."""
        c, b = self.c, self.b
        on, inside, empty, holding, handempty = (self.on, self.inside, self.empty, self.holding,
                                                 self.handempty)
        can_put, at = self.can_put, self.at
        rm = self.d.robot
        r_pick = rm.action("pick", c, pre=on(c, MT) & handempty(R),
                           effects=[holding(R, c), ~on(c, MT), ~handempty(R)])
        r_place = rm.action("place", c, b, pre=holding(R, c) & at(R, MT) & can_put(c, b),
                            effects=[inside(c, b), ~empty(b), ~holding(R, c), handempty(R)])
        r_org = rm.task("organize", done=self.goal())
        r_away = rm.task("put_away", c)
        rm.method(r_org, "near", params=[c], pre=on(c, MT) & handempty(R),
                  subtasks=[r_pick(c), r_away(c), r_org()])
        rm.method(r_away, "box", params=[b], pre=holding(R, c) & can_put(c, b),
                  subtasks=[r_place(c, b)])

    def human(self) -> None:
        """The human fetches the cubes of other tables (all cubes with human_reach="any");
        reach is static data (a cube's origin), so the human never acts on the robot's
        cubes."""
        c, b, t, t0, t1, t2 = self.c, self.b, self.t, self.t0, self.t1, self.t2
        on, inside, empty, holding, handempty = (self.on, self.inside, self.empty, self.holding,
                                                 self.handempty)
        at, facing, can_put = self.at, self.facing, self.can_put
        reach: Formula = ~self.origin(c, MT) if self.human_reach == "fetched" else TRUE
        hm = self.d.human
        h_pick = hm.action("pick", c, pre=reach & exists(t, at(H, t) & on(c, t)) & handempty(H),
                           effects=[holding(H, c), ~handempty(H), for_each(t, ~on(c, t))])
        h_place = hm.action("place", c, b, pre=holding(H, c) & at(H, MT) & can_put(c, b),
                            effects=[inside(c, b), ~empty(b), ~holding(H, c), handempty(H)])
        turn = None
        if self.turn_before_move:
            turn = hm.action("turn", t1, t2, pre=facing(H, t1) & ~eq(t1, t2),
                             effects=[facing(H, t2), ~facing(H, t1)])
            move = hm.action("move", t1, t2, pre=at(H, t1) & facing(H, t2) & ~eq(t1, t2),
                             effects=[at(H, t2), ~at(H, t1)])
        else:
            move = hm.action("move", t1, t2, pre=at(H, t1) & facing(H, t1) & ~eq(t1, t2),
                             effects=[at(H, t2), facing(H, t2), ~at(H, t1), ~facing(H, t1)])
        go = self.go(turn, move)
        h_org = hm.task("organize", done=self.goal())
        h_away = hm.task("put_away", c)
        fetch = hm.task("fetch", c, t)
        hm.method(h_org, "near", params=[c, t], pre=reach & at(H, t) & on(c, t) & handempty(H),
                  subtasks=[h_pick(c), h_away(c), h_org()])
        hm.method(h_org, "far", params=[c, t], pre=reach & on(c, t) & ~at(H, t) & handempty(H),
                  subtasks=[fetch(c, t), h_away(c), h_org()])
        if not self.waypoints:
            hm.method(fetch, "go", params=[t0], pre=at(H, t0) & ~eq(t0, t),
                      subtasks=[*go(t0, t), h_pick(c)])
        else:  # one method per direction: the route is spelt out by name
            for src, dst in ((MT, OT), (OT, MT)):
                hm.method(fetch, f"go_{dst}", pre=at(H, src) & eq(t, dst),
                          subtasks=[*go(src, dst), h_pick(c)])
        hm.method(h_away, "box", params=[b], pre=holding(H, c) & at(H, MT) & can_put(c, b),
                  subtasks=[h_place(c, b)])
        if not self.waypoints:
            hm.method(h_away, "carry", params=[t0], pre=holding(H, c) & at(H, t0)
                      & ~eq(t0, MT), subtasks=[*go(t0, MT), h_away(c)])
        else:
            hm.method(h_away, "carry", pre=holding(H, c) & at(H, OT),
                      subtasks=[*go(OT, MT), h_away(c)])


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


class _WithVariables(_Cubes):
    """The same model with state variables (``encoding = "variables"``); the options are
    checked by :func:`make_domain`."""

    name = "cubes-vars"

    def types(self) -> None:
        d = self.d
        self.Place = d.type("place")
        self.Table, self.Box = d.type("table", parent=self.Place), d.type("box", parent=self.Place)
        d.type("agent", parent=self.Place)  # a hand holds a cube: the agents are places too
        self.Cube = d.type("cube")

    def fluents(self) -> None:
        """The static facts, where the agents and the cubes are with what the human sees of
        it, and the derived emptiness, placement rule and goal."""
        d, t, b, b2, c, c2 = self.d, self.t, self.b, self.b2, self.c, self.c2
        a, a2 = Var("a", "agent"), Var("a2", "agent")
        p = Var("p", self.Place)
        # static facts
        self.origin = origin = d.predicate("origin", c, t)
        transparent = d.predicate("transparent", b)
        # where the agents are and which table they face
        self.at = at = d.variable("at", a, values=self.Table)
        self.facing = facing = d.variable("facing", a, values=self.Table)
        copresent = exists(t, (at(R) == t) & (at(H) == t) & (facing(R) == t)
                           & (facing(H) == t))
        d.copresence = copresent
        # where each cube is, seen per place: on a table while the human is at it and facing
        # it; in a transparent box from mt; in a hand, the human's own or when co-present
        sees = (exists(t, eq(p, t) & (at(H) == t) & (facing(H) == t))
                | exists(b, eq(p, b) & transparent(b)) & (at(H) == MT) & (facing(H) == MT)
                | eq(p, H) | exists(a, eq(p, a)) & copresent)
        self.loc = loc = d.variable("loc", c, values=p, observability=observable(sees))
        empty = d.derived("empty", [b], ~exists(c, loc(c) == b))
        self.handempty = d.derived("handempty", [a2], ~exists(c, loc(c) == a2))

        # placement rule: cubes of one table in one box, different tables in different boxes
        mate_in = d.derived("mate_in", [c, b], exists([c2, t], (loc(c2) == b) & origin(c2, t)
                                                      & origin(c, t)))
        self.can_put = d.derived("can_put", [c, b], forall(b2, empty(b2)) | mate_in(c, b)
                                 | (~exists(b2, mate_in(c, b2)) & empty(b)))
        self.goal = d.derived("organized", [], forall(c, exists(b, loc(c) == b)) & forall(
            [c, c2, b], ((loc(c) == b) & (loc(c2) == b)) >> exists(t, origin(c, t)
                                                                   & origin(c2, t))))

    def robot(self) -> None:
        """The robot picks cubes on mt and boxes them."""
        c, b, loc, at, handempty, can_put = (self.c, self.b, self.loc, self.at, self.handempty,
                                             self.can_put)
        rm = self.d.robot
        r_pick = rm.action("pick", c, pre=(loc(c) == MT) & handempty(R),
                           effects=[loc(c).set(R)])
        r_place = rm.action("place", c, b, pre=(loc(c) == R) & (at(R) == MT) & can_put(c, b),
                            effects=[loc(c).set(b)])
        r_org = rm.task("organize", done=self.goal())
        r_away = rm.task("put_away", c)
        rm.method(r_org, "near", params=[c], pre=(loc(c) == MT) & handempty(R),
                  subtasks=[r_pick(c), r_away(c), r_org()])
        rm.method(r_away, "box", params=[b], pre=(loc(c) == R) & can_put(c, b),
                  subtasks=[r_place(c, b)])

    def human(self) -> None:
        """The human fetches the cubes of other tables (all cubes with human_reach="any")."""
        c, b, t, t0, t1, t2 = self.c, self.b, self.t, self.t0, self.t1, self.t2
        loc, at, facing, handempty, can_put = (self.loc, self.at, self.facing, self.handempty,
                                               self.can_put)
        reach: Formula = ~self.origin(c, MT) if self.human_reach == "fetched" else TRUE
        hm = self.d.human
        h_pick = hm.action("pick", c, pre=reach & exists(t, (at(H) == t) & (loc(c) == t))
                           & handempty(H), effects=[loc(c).set(H)])
        h_place = hm.action("place", c, b, pre=(loc(c) == H) & (at(H) == MT) & can_put(c, b),
                            effects=[loc(c).set(b)])
        turn = None
        if self.turn_before_move:
            turn = hm.action("turn", t1, t2, pre=(facing(H) == t1) & ~eq(t1, t2),
                             effects=[facing(H).set(t2)])
            move = hm.action("move", t1, t2, pre=(at(H) == t1) & (facing(H) == t2)
                             & ~eq(t1, t2), effects=[at(H).set(t2)])
        else:
            move = hm.action("move", t1, t2, pre=(at(H) == t1) & (facing(H) == t1)
                             & ~eq(t1, t2), effects=[at(H).set(t2), facing(H).set(t2)])
        go = self.go(turn, move)
        h_org = hm.task("organize", done=self.goal())
        h_away = hm.task("put_away", c)
        fetch = hm.task("fetch", c, t)
        hm.method(h_org, "near", params=[c, t],
                  pre=reach & (at(H) == t) & (loc(c) == t) & handempty(H),
                  subtasks=[h_pick(c), h_away(c), h_org()])
        hm.method(h_org, "far", params=[c, t],
                  pre=reach & (loc(c) == t) & (at(H) != t) & handempty(H),
                  subtasks=[fetch(c, t), h_away(c), h_org()])
        if not self.waypoints:
            hm.method(fetch, "go", params=[t0], pre=(at(H) == t0) & ~eq(t0, t),
                      subtasks=[*go(t0, t), h_pick(c)])
        else:
            for src, dst in ((MT, OT), (OT, MT)):
                hm.method(fetch, f"go_{dst}", pre=(at(H) == src) & eq(t, dst),
                          subtasks=[*go(src, dst), h_pick(c)])
        hm.method(h_away, "box", params=[b], pre=(loc(c) == H) & (at(H) == MT)
                  & can_put(c, b), subtasks=[h_place(c, b)])
        if not self.waypoints:
            hm.method(h_away, "carry", params=[t0], pre=(loc(c) == H) & (at(H) == t0)
                      & ~eq(t0, MT), subtasks=[*go(t0, MT), h_away(c)])
        else:
            hm.method(h_away, "carry", pre=(loc(c) == H) & (at(H) == OT),
                      subtasks=[*go(OT, MT), h_away(c)])


domain = make_domain()
