"""The validator under issue 15's rules (docs/semantics.md §3-§6, revised): hidden human
intentions (the set A_H of human agendas the robot cannot tell apart), the robot asking and
announcing, and the rule fixes (per-world robot expectations, speech judged after the action,
relevance "plan" keeping the next-step sets). Every policy here is written by hand, and every
expected answer derived by hand from the rules, not from the planner."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ehatp import (
    HIDDEN,
    Communication,
    Costs,
    Domain,
    HumanModel,
    Passes,
    Policy,
    Problem,
    Relevance,
    Speech,
    Var,
)
from ehatp.check.validator import _Semantics
from ehatp.formats.policy import FORMAT
from ehatp.model.options import Intentions

from .scenarios import lab_domain, problem
from .test_validator_options import call, caught, ok

Cost = int
Diffs = list[tuple[list[str], list[str]]]


# -- policies written by hand (format version 2: moves on the edges) ----------------------------

@dataclass
class S:
    """One state of a hand-written policy: who moves next (None at a goal), its value, the
    true state, the agendas, the human's worlds (as (atoms true unlike T, atoms false unlike
    T) per distinct world state; ``worlds`` when several worlds share a state), and the moves
    out of it as (agent, label, cost, next state)."""

    to_move: str | None
    value: Cost
    state: list[str]
    robot: list[str] = field(default_factory=list)
    human: list[str] = field(default_factory=list)
    hyps: list[list[str]] = field(default_factory=list)
    diffs: Diffs = field(default_factory=lambda: [([], [])])
    worlds: int | None = None
    cop: bool = True
    k: int = 0
    moves: list[tuple[str, str, Cost, S]] = field(default_factory=list)


def build(p: Problem, root: S) -> Policy:
    """The hand-written policy as a version 2 policy file, read back."""
    nodes: list[dict[str, Any]] = []
    comms = leaves = 0

    def add(n: S) -> int:
        nonlocal comms, leaves
        div = sorted({f"not {a}" for t, _ in n.diffs for a in t}
                     | {a for _, f in n.diffs for a in f})
        node: dict[str, Any] = dict(
            id=len(nodes), copresent=n.cop, k=n.k,
            worlds=n.worlds if n.worlds is not None else len(n.diffs), divergence=div,
            world_diffs=[{"true": t, "false": f} for t, f in n.diffs], state=n.state,
            robot_agenda=n.robot, human_agenda=n.hyps[0] if n.hyps else n.human,
            to_move=n.to_move, value=n.value, goal=n.to_move is None, moves=[])
        if n.hyps:
            node["hypotheses"] = n.hyps
        nodes.append(node)
        leaves += not n.moves
        for agent, label, cost, child in n.moves:
            kind, name, args, told = call(label)
            comms += kind in ("inform", "ask", "announce") or bool(told)
            node["moves"].append(dict(agent=agent, kind=kind, action=label, name=name,
                                      args=args, cost=cost, to=add(child), told=told))
        return int(node["id"])

    add(root)
    c = p.costs
    return Policy.from_dict(dict(
        format=FORMAT, version=2, problem=p.name, domain=p.domain.name,
        agents={"robot": "R", "human": "H"}, K=p.K,
        costs={"inform": c.inform, "ask": c.ask, "wait": c.wait, "pass": c.pass_,
               "actions": dict(c.actions)},
        nodes=nodes, cost=nodes[0]["value"], communications=comms, leaves=leaves))


def edited(policy: Policy, node: int, move: int = 0, **fields: Any) -> Policy:
    """``policy`` with fields of one move changed (``to`` included)."""
    d = policy.to_dict()
    d["nodes"][node]["moves"][move].update(fields)
    return Policy.from_dict(d)


def with_node(policy: Policy, node: int, **fields: Any) -> Policy:
    """``policy`` with fields of one node changed."""
    d = policy.to_dict()
    d["nodes"][node].update(fields)
    return Policy.from_dict(d)


# -- the shelf: the human grabs a cup for the left or the right shelf ---------------------------

def shelf_domain(*, alone: bool = False, ok_r: bool = False) -> Domain:
    """The human stocks a cup on the left or the right shelf (two methods, both starting with
    ``grab``); the robot helps by clearing one shelf (two methods, one clearing action each).
    Everything is observable and the agents are always together. With ``alone`` the human
    may also just grab the cup; with ``ok_r`` placing on the right also needs the hidden
    ``ok_r``."""
    d = Domain("shelf")
    Cup = d.type("cup")
    c = Var("c", Cup)
    held, on_l, on_r = (d.predicate(n, c) for n in ("held", "on_l", "on_r"))
    free_l, free_r = d.predicate("free_l"), d.predicate("free_r")
    okr = d.predicate("ok_r", observability=HIDDEN)
    r = d.robot
    clr_l = r.action("clr_l", pre=~free_l(), effects=[free_l()])
    clr_r = r.action("clr_r", pre=~free_r(), effects=[free_r()])
    wipe = r.action("wipe")
    helps = r.task("help")
    r.method(helps, "left", subtasks=[clr_l()])
    r.method(helps, "right", subtasks=[clr_r()])
    tidy = r.task("tidy")  # two methods starting with the same action
    r.method(tidy, "left", subtasks=[wipe(), clr_l()])
    r.method(tidy, "right", subtasks=[wipe(), clr_r()])
    h = d.human
    grab = h.action("grab", c, pre=~held(c), effects=[held(c)])
    place_l = h.action("place_l", c, pre=held(c) & free_l(), effects=[on_l(c), ~held(c)])
    right = held(c) & free_r() & okr() if ok_r else held(c) & free_r()
    place_r = h.action("place_r", c, pre=right, effects=[on_r(c), ~held(c)])
    stock = h.task("stock", c)
    h.method(stock, "left", subtasks=[grab(c), place_l(c)])
    h.method(stock, "right", subtasks=[grab(c), place_r(c)])
    if alone:
        h.method(stock, "just", subtasks=[grab(c)])
    return d


def shelf(intentions: Intentions = Intentions.HIDDEN, *, robot_asks: bool = False,
          passes: Passes = Passes.IDLE, **kw: Any) -> Problem:
    """The human (who starts, and passes only with nothing to do) stocks cup c1; the robot
    must clear the shelf the human chose (it may clear only one)."""
    args: dict[str, Any] = dict(init=[], robot=["help"], human=["stock(c1)"])
    args.update(kw)
    return problem(shelf_domain(), objects={"cup": ["c1"]},
                   human_model=HumanModel(passes=passes, intentions=intentions),
                   communication=Communication(robot_asks=robot_asks), **args)


HELD = ["held(c1)"]
L, R_ = ["place_l(c1)"], ["place_r(c1)"]
BOTH = [L, R_]


def per_side(grab_labels: tuple[str, str], *, record: tuple[list[list[str]], ...] = ([], [])
             ) -> S:
    """The policy that replies to the human's grab by clearing the shelf of its method: the
    two grabs labelled ``grab_labels``, their nodes recording hypotheses ``record``."""
    def side(label: str, rest: list[str], clr: str, free: str, placed: str,
             hyps: list[list[str]]) -> tuple[str, str, Cost, S]:
        return ("H", label, 1, S("R", 2, HELD, ["help"], rest, hyps, moves=[
            ("R", clr, 1, S("H", 1, [*HELD, free], [], rest, hyps, moves=[
                ("H", rest[0], 1, S(None, 0, [free, placed]))]))]))

    return S("H", 3, [], ["help"], ["stock(c1)"], moves=[
        side(grab_labels[0], L, "clr_l", "free_l", "on_l(c1)", record[0]),
        side(grab_labels[1], R_, "clr_r", "free_r", "on_r(c1)", record[1])])


def test_the_robot_sees_the_human_grab_but_not_for_which_shelf() -> None:
    # by hand (§3-§4): both methods start with grab(c1); hidden intentions give one branch,
    # whose node keeps both rests; announced intentions give two, labelled by the rest
    hidden = _Semantics(shelf())
    es = hidden.initial()
    [grab] = hidden.human_options(es)
    assert grab.label == "grab(c1)" and grab.after is not None
    assert sorted(hidden.shown(h) for h in grab.after.humans) == BOTH
    visible = _Semantics(shelf(Intentions.VISIBLE))
    got = [(o.label, [visible.shown(h) for h in o.after.humans])
           for o in visible.human_options(visible.initial()) if o.after is not None]
    assert got == [("grab(c1) [place_l(c1)]", [L]), ("grab(c1) [place_r(c1)]", [R_])]


def test_a_policy_that_replies_to_the_method_is_valid_when_intentions_are_visible() -> None:
    p = shelf(Intentions.VISIBLE)
    ok(p, build(p, per_side(("grab(c1) [place_l(c1)]", "grab(c1) [place_r(c1)]"))))
    # the same labels mean nothing when the robot sees only the action
    caught(shelf(), build(p, per_side(("grab(c1) [place_l(c1)]", "grab(c1) [place_r(c1)]"))),
           "branch [H grab(c1) [place_l(c1)]]", "extra human branch", "['grab(c1)']")


def test_a_policy_branching_on_a_hidden_choice_is_rejected() -> None:
    # two branches both labelled grab(c1), answered by clr_l and by clr_r: a robot that sees
    # only grab(c1) cannot follow it
    p = shelf()
    mind_reader = build(p, per_side(("grab(c1)", "grab(c1)")))
    caught(p, mind_reader, "branch []: node 0 (start): two human branches have the label "
           "grab(c1) (to nodes 1 and 4)", "branches on a hidden choice (§3)")
    # labels are compared without spaces
    caught(p, build(p, per_side(("grab(c1)", "grab( c1)"))), "the label grab( c1)",
           "hidden choice")
    # announced intentions name the intention in a repeated label
    caught(shelf(Intentions.VISIBLE), mind_reader, "hidden choice",
           'under intentions = "visible" a repeated action label names the intention')


def test_the_node_after_a_hidden_choice_holds_every_hypothesis() -> None:
    # one grab branch whose node claims the robot knows the left shelf is meant
    p = shelf()
    left = per_side(("grab(c1)", "grab(c1)"))
    left.moves = left.moves[:1]
    caught(p, build(p, left), "branch [H grab(c1)]: node 1 (H grab(c1))",
           "hypotheses (the human agendas the robot cannot tell apart, §3) are "
           "[['place_l(c1)']], expected [['place_l(c1)'], ['place_r(c1)']]")
    # recording both and committing to the left shelf: if the human meant the right one it
    # has nothing to do and passes (the pass keeps that hypothesis), a branch not covered
    both = per_side(("grab(c1)", "grab(c1)"), record=(BOTH, BOTH))
    both.moves = both.moves[:1]
    caught(p, build(p, both), "branch [H grab(c1), R clr_l]: node 2 (R clr_l)",
           "missing human branch H pass")
    sem = _Semantics(p)
    [grab] = sem.human_options(sem.initial())
    assert grab.after is not None
    es = grab.after
    after = sem.robot_act(es, *next((a, r) for a, r in sem.robot_actions(es)
                                    if sem.g.task_names[a] == "clr_l")).after
    assert after is not None
    got = {o.label: [sem.shown(h) for h in o.after.humans]
           for o in sem.human_options(after) if o.after is not None}
    assert got == {"place_l(c1)": [[]], "pass": [R_]}


def test_a_recorded_hypothesis_list_must_put_the_human_agenda_first() -> None:
    p = shelf()
    both = per_side(("grab(c1)", "grab(c1)"), record=(BOTH, BOTH))
    both.moves = both.moves[:1]
    policy = build(p, both)
    assert policy.nodes[1].human_agendas == BOTH
    caught(p, with_node(policy, 1, human_agenda=R_), "node 1 (H grab(c1))",
           "human_agenda is ['place_r(c1)'], but a node with hypotheses records the first of "
           "them, ['place_l(c1)']")


def asking_robot() -> S:
    """The robot asks what the human is about to do, then clears that shelf. By hand: the
    answer costs nothing; the human, told nothing new, has nothing it could do yet (the shelf
    is not clear) and passes: 1 (grab) + 1 (ask) + 0 + 1 (pass) + 1 (clear) + 1 (place)."""
    def answered(rest: list[str], clr: str, free: str, placed: str) -> tuple[str, str, Cost, S]:
        return ("H", f"answer({rest[0]})", 0, S("H", 3, HELD, ["help"], rest, moves=[
            ("H", "pass", 1, S("R", 2, HELD, ["help"], rest, moves=[
                ("R", clr, 1, S("H", 1, [*HELD, free], [], rest, moves=[
                    ("H", rest[0], 1, S(None, 0, [free, placed]))]))]))]))

    return S("H", 5, [], ["help"], ["stock(c1)"], moves=[
        ("H", "grab(c1)", 1, S("R", 4, HELD, ["help"], hyps=BOTH, moves=[
            ("R", "ask(intention)", 1, S("H", 3, HELD, ["help"], hyps=BOTH, moves=[
                answered(L, "clr_l", "free_l", "on_l(c1)"),
                answered(R_, "clr_r", "free_r", "on_r(c1)")]))]))])


def test_the_robot_may_ask_what_the_human_is_about_to_do() -> None:
    p = shelf(robot_asks=True)
    policy = build(p, asking_robot())
    assert policy.communications == 1  # the question; an answer is no communication
    ok(p, policy)
    caught(shelf(), policy, "branch [H grab(c1), R ask(intention)]", "not a legal robot option",
           "robot_asks = true (§5)")
    # both answers are branches: the robot cannot choose the answer
    d = policy.to_dict()
    del d["nodes"][2]["moves"][1]
    d["leaves"] = 1
    caught(p, Policy.from_dict(d), "branch [H grab(c1), R ask(intention)]: node 2",
           "missing human branch H answer(place_r(c1))")
    # an answer costs nothing
    caught(p, edited(policy, 2, 0, cost=1), "H answer(place_l(c1))]", "cost is 1, but the "
           "move costs 0")


def test_the_robot_asks_only_where_it_cannot_tell_the_human_agendas_apart() -> None:
    p = shelf(robot_asks=True)
    d = build(p, asking_robot()).to_dict()
    # at node 4 (after the answer and the human's pass) one agenda is left: ask there
    d["nodes"][4]["moves"][0].update(kind="ask", action="ask(intention)", name="ask",
                                     args=["intention"])
    caught(p, Policy.from_dict(d), "R ask(intention)]", "only one human agenda fits what the "
           "robot saw: there is nothing to ask (§5)")


def test_an_answer_names_the_agenda_and_an_empty_one_reads_answer() -> None:
    p = problem(shelf_domain(alone=True), objects={"cup": ["c1"]}, init=[], robot=["help"],
                human=["stock(c1)"], communication=Communication(robot_asks=True))
    sem = _Semantics(p)
    [grab, *_] = sem.human_options(sem.initial())
    assert grab.after is not None
    st = sem.robot_ask(grab.after)
    assert not isinstance(st, str) and st.after is not None and st.after.answering
    assert st.cost == 1 and st.after.passive == 0
    got = [(a.label, int(a.cost)) for a in sem.human_options(st.after)]
    assert got == [("answer()", 0), ("answer(place_l(c1))", 0), ("answer(place_r(c1))", 0)]


def wiping_robot(clr: str = "clr_l") -> tuple[Problem, Policy]:
    """The robot tidies: it wipes (both of its methods start so), then clears the left shelf.
    The human, with nothing to do, passes. By hand: the human saw the wipe and cannot tell
    which method follows (two worlds, one state); seeing clr_l leaves one world."""
    p = problem(shelf_domain(), objects={"cup": ["c1"]}, init=[], robot=["tidy"], human=[],
                starts="robot")
    root = S("R", 3, [], ["tidy"], moves=[
        ("R", "wipe", 1, S("H", 2, [], [clr], worlds=2, moves=[
            ("H", "pass", 1, S("R", 1, [], [clr], worlds=2, moves=[
                ("R", "clr_l", 1, S(None, 0, ["free_l"]))]))]))])
    return p, build(p, root)


def test_each_recorded_edge_is_the_move_it_names() -> None:
    ok(*wiping_robot())
    # the edge into node 1 names wipe, yet its node records the right-hand method: the
    # robot then cannot clear the left shelf
    p, policy = wiping_robot("clr_r")
    caught(p, policy, "branch [R wipe, H pass, R clr_l]", "not a legal robot option",
           "clr_l is not the first action of any refinement of the robot agenda ['clr_r']")
    # a node that no wipe leads to is no edge of wipe
    p, policy = wiping_robot("clr_x")
    caught(p, policy, "branch [R wipe]: node 1 (R wipe): the recorded edge is none of the 2 "
           "robot moves labelled wipe here (§4)", "robot agenda ['clr_x']")


# -- the pass rule "idle" (§4) ------------------------------------------------------------------

def lamp_wait(passes: Passes) -> Problem:
    return problem(lab_domain(), init=["human_at(lab)"], human=["trip(s1)"],
                   robot=["set_lamp(a)"], starts="robot", human_model=HumanModel(passes=passes))


def test_an_idle_human_never_passes_when_it_could_act() -> None:
    # the robot waits though it could act; the human, who could leave, does not pass under
    # "idle" (it would under "fair"): the policy need not cover a pass
    out, back = ["human_at(hall)"], ["human_at(lab)", "lamp(a)", "strolled(s1)"]
    unsure: Diffs = [([], ["lamp(a)"]), ([], [])]
    root = S("R", 6, ["human_at(lab)"], ["set_lamp(a)"], ["trip(s1)"], moves=[
        ("R", "wait", 1, S("H", 5, ["human_at(lab)"], ["set_lamp(a)"], ["trip(s1)"], moves=[
            ("H", "go(lab, hall)", 1, S("R", 4, out, ["set_lamp(a)"],
                                        ["stroll(s1)", "go(hall, lab)"], cop=False, moves=[
                ("R", "set_lamp(a)", 1, S("H", 3, [*out, "lamp(a)"], [],
                                          ["stroll(s1)", "go(hall, lab)"], diffs=unsure,
                                          cop=False, k=1, moves=[
                    ("H", "stroll(s1)", 1, S("R", 2, [*out, "lamp(a)", "strolled(s1)"], [],
                                             ["go(hall, lab)"], diffs=unsure, cop=False, k=1,
                                             moves=[
                        ("R", "wait", 1, S("H", 1, [*out, "lamp(a)", "strolled(s1)"], [],
                                           ["go(hall, lab)"], diffs=unsure, cop=False, k=2,
                                           moves=[
                            ("H", "go(hall, lab)", 1, S(None, 0, back))]))]))]))]))]))])
    p = lamp_wait(Passes.IDLE)
    policy = build(p, root)
    ok(p, policy)
    caught(lamp_wait(Passes.FAIR), policy, "branch [R wait]", "missing human branch H pass")


def blocked(passes: Passes, ask: bool) -> Problem:
    """The human does not know whether it may use item a (it may); the robot has nothing to
    do; telling costs 3."""
    return problem(lab_domain(), init=["human_at(lab)", "secret(a)"], human=["use_it(a)"],
                   beliefs=[([], []), ([], ["secret(a)"])], starts="robot",
                   costs=Costs(inform=3), human_model=HumanModel(passes=passes),
                   communication=Communication(ask=ask))


T0, T2 = ["human_at(lab)", "secret(a)"], ["human_at(lab)", "secret(a)", "used(a)"]
UNSURE: Diffs = [([], []), ([], ["secret(a)"])]


def test_an_idle_human_passes_only_with_nothing_to_do_or_ask() -> None:
    # with a question to ask, the blocked human asks: no pass to cover (by hand: 1 + 1 +
    # 1 + 1); "fair" lets a human that passes when blocked also stay silent
    asks = S("R", 4, T0, [], ["use_it(a)"], diffs=UNSURE, moves=[
        ("R", "wait", 1, S("H", 3, T0, [], ["use_it(a)"], diffs=UNSURE, moves=[
            ("H", "ask(secret(a))", 1, S("R", 2, T0, [], ["use_it(a)"], moves=[
                ("R", "wait", 1, S("H", 1, T0, [], ["use_it(a)"], moves=[
                    ("H", "use(a)", 1, S(None, 0, T2))]))]))]))])
    p = blocked(Passes.IDLE, ask=True)
    ok(p, build(p, asks))
    caught(blocked(Passes.FAIR, ask=True), build(p, asks), "branch [R wait]",
           "missing human branch H pass")
    # with nothing to ask, it passes; the robot, after wait and pass, must inform (a third
    # passive move is a dead end): 1 + 1 + 3 + 1
    silent = S("R", 6, T0, [], ["use_it(a)"], diffs=UNSURE, moves=[
        ("R", "wait", 1, S("H", 5, T0, [], ["use_it(a)"], diffs=UNSURE, moves=[
            ("H", "pass", 1, S("R", 4, T0, [], ["use_it(a)"], diffs=UNSURE, moves=[
                ("R", "inform(secret(a))", 3, S("H", 1, T0, [], ["use_it(a)"], moves=[
                    ("H", "use(a)", 1, S(None, 0, T2))]))]))]))])
    p = blocked(Passes.IDLE, ask=False)
    ok(p, build(p, silent))
    caught(blocked(Passes.IDLE, ask=True), build(p, silent), "branch [R wait, H pass]",
           "extra human branch")


# -- §5: the robot's expected options, read per world -------------------------------------------

def chores_domain() -> Domain:
    """The robot vacuums (``clean``, hidden) and mops (``mopped``, hidden, needs ``power``).
    The human believes vacuuming also needs power; the human has nothing to do."""
    d = Domain("chores")
    clean = d.predicate("clean", observability=HIDDEN)
    mopped = d.predicate("mopped", observability=HIDDEN)
    power = d.predicate("power", observability=HIDDEN)
    r = d.robot
    vacuum = r.action("vacuum", pre=~clean(), effects=[clean()])
    mop = r.action("mop", pre=~mopped(), effects=[mopped()])
    vac = r.task("vac", done=clean())
    r.method(vac, "go", subtasks=[vacuum()])
    mopping = r.task("mopping", done=mopped())
    r.method(mopping, "go", pre=power(), subtasks=[mop()])
    rh = r.copy()
    rh.methods = [m for m in rh.methods if m.task.name != "vac"]
    rh.method(vac, "go", pre=power(), subtasks=[vacuum()])
    d.robot_seen_by_human = rh
    return d


def test_a_hidden_finished_chore_is_told_when_the_other_world_has_the_robot_blocked() -> None:
    # by hand (§5, revised): the room is clean, so the robot is done (FINISH); the human
    # also imagines it dirty, where it thinks the robot cannot vacuum (no power): blocked,
    # "not done". {FINISH, not done} differs from {FINISH}: relevant, and telling clean
    # leaves the one world where the robot is done, a goal
    p = problem(chores_domain(), init=["clean"], robot=["vac"], objects={}, starts="robot",
                beliefs=[([], []), ([], ["clean"])])
    told = S("R", 1, ["clean"], ["vac"], diffs=[([], []), ([], ["clean"])], moves=[
        ("R", "inform(clean)", 1, S(None, 0, ["clean"], ["vac"]))])
    ok(p, build(p, told))
    # without the inform, the human still imagines a robot that cannot finish: no goal
    claimed = S(None, 0, ["clean"], ["vac"], diffs=[([], []), ([], ["clean"])])
    caught(p, build(p, claimed), "node 0 (start): recorded facts differ",
           "goal is True, expected False")


def test_a_blocked_robot_believed_blocked_is_no_divergence() -> None:
    # the robot cannot mop (no power) and the human knows it: "not done" in both; the
    # human's wrong belief about clean changes no option, so telling it is not relevant
    p = problem(chores_domain(), init=[], robot=["mopping"], objects={}, starts="robot",
                beliefs=[(["clean"], [])])
    told = S("R", 1, [], ["mopping"], diffs=[(["clean"], [])], moves=[
        ("R", "inform(not clean)", 1, S(None, 0, [], ["mopping"]))])
    caught(p, build(p, told), "branch [R inform(not clean)]", "not a legal robot option",
           "the divergence is not relevant")


# -- §5: the robot announces its agenda ---------------------------------------------------------

def announcing(announce: bool = True, label: str = "announce(clr_l)") -> tuple[Problem, Policy]:
    """After the wipe the human cannot tell which method the robot follows (two worlds, one
    state); the robot tells it (cost: an inform's, 2 here). By hand: 1 + 1 + 2 + 1 + 1."""
    p = problem(shelf_domain(), objects={"cup": ["c1"]}, init=[], robot=["tidy"], human=[],
                starts="robot", costs=Costs(inform=2),
                communication=Communication(announce=announce))
    root = S("R", 6, [], ["tidy"], moves=[
        ("R", "wipe", 1, S("H", 5, [], ["clr_l"], worlds=2, moves=[
            ("H", "pass", 1, S("R", 4, [], ["clr_l"], worlds=2, moves=[
                ("R", label, 2, S("H", 2, [], ["clr_l"], moves=[
                    ("H", "pass", 1, S("R", 1, [], ["clr_l"], moves=[
                        ("R", "clr_l", 1, S(None, 0, ["free_l"]))]))]))]))]))])
    return p, build(p, root)


def test_the_robot_may_announce_the_method_it_follows() -> None:
    p, policy = announcing()
    assert policy.communications == 1
    ok(p, policy)
    caught(*announcing(announce=False), "branch [R wipe, H pass, R announce(clr_l)]",
           "not a legal robot option", "announce = true (§5)")
    caught(*announcing(label="announce(clr_r)"), "R announce(clr_r)]",
           "the robot may announce only its own agenda, announce(clr_l) (§5)")
    # before the wipe the human expects what the robot will do: nothing to announce
    p2, _ = announcing()
    start = S("R", 5, [], ["tidy"], moves=[("R", "announce(tidy)", 2, S(None, 0, []))])
    caught(p2, build(p2, start), "branch [R announce(tidy)]",
           "the robot options the human expects equal the robot's real ones")


# -- §5: speech with an action, judged on the state after it ------------------------------------

def oil_domain() -> Domain:
    """The robot refills the washer and, unknown to the human's model of it, tops up the oil
    (``oil_ok``, hidden); the human drives once the washer is full and the oil fine."""
    d = Domain("car")
    full, oil = d.predicate("washer_full"), d.predicate("oil_ok", observability=HIDDEN)
    driven = d.predicate("driven")
    r = d.robot
    r.action("refill", pre=~full(), effects=[full(), oil()])
    rh = r.copy()
    rh.operators.pop("refill")
    rh.action("refill", pre=~full(), effects=[full()])
    d.robot_seen_by_human = rh
    d.human.action("drive", pre=full() & oil() & ~driven(), effects=[driven()])
    return d


def oil(speech: Speech = Speech.WITH_ACTION) -> Problem:
    return problem(oil_domain(), init=[], robot=["refill"], human=["drive"], objects={},
                   starts="robot", communication=Communication(speech=speech))


def refill(label: str = "inform(oil_ok) + refill") -> S:
    """By hand: before the refill nobody can drive and the human's one world is the truth;
    after it the truth has oil_ok, the human's world not (its model of refill does not top
    up): the human's next action differs, so oil_ok is told, with its value after the refill.
    Then the human drives, or passes and drives after the robot's forced wait: 2 + 3."""
    after = ["oil_ok", "washer_full"]
    return S("R", 5, [], ["refill"], ["drive"], moves=[
        ("R", label, 2, S("H", 3, after, [], ["drive"], moves=[
            ("H", "drive", 1, S(None, 0, [*after, "driven"])),
            ("H", "pass", 1, S("R", 2, after, [], ["drive"], moves=[
                ("R", "wait", 1, S("H", 1, after, [], ["drive"], moves=[
                    ("H", "drive", 1, S(None, 0, [*after, "driven"]))]))]))]))])


def test_what_is_said_with_an_action_is_judged_after_it() -> None:
    p = oil()
    policy = build(p, refill())
    assert policy.root.moves[0].told == ["oil_ok"]
    ok(p, policy)
    # the literal told is the truth after the action, not before it
    caught(p, build(p, refill("inform(not oil_ok) + refill")),
           "branch [R inform(not oil_ok) + refill]", "the label tells oil_ok is false, but it "
           "is true in T after refill (§5, with-action)")
    # a plain inform, before the action, has nothing to tell: no world differs from T
    caught(p, edited(policy, 0, action="inform(not oil_ok)", kind="inform", name="inform",
                     args=["not oil_ok"], told=[], cost=1),
           "every world already agrees with the truth on oil_ok")
    caught(oil(Speech.TURN), policy, 'speech = "with-action"')


def secret_use(speech: Speech = Speech.WITH_ACTION) -> Problem:
    """The human wonders whether it may use item a (it may not yet); the robot sets the
    secret in front of it."""
    return problem(lab_domain(), init=["human_at(lab)"], human=["use_it(a)"],
                   robot=["set_secret(a)"], beliefs=[([], []), (["secret(a)"], [])],
                   starts="robot", communication=Communication(speech=speech))


def test_a_divergence_the_action_itself_settles_is_not_told_with_it() -> None:
    # by hand: before set_secret(a) the human's worlds disagree on secret(a) (false in T),
    # so inform(not secret(a)) would be the set; the human sees set_secret(a), which only
    # its world without the secret expected: after it the one world is the truth, nothing
    # to tell. Judged after the action, both readings of the label are wrong
    p = secret_use()
    after = ["human_at(lab)", "secret(a)"]
    done = [*after, "used(a)"]
    plain = S("R", 4, ["human_at(lab)"], ["set_secret(a)"], ["use_it(a)"],
              diffs=[([], []), (["secret(a)"], [])], moves=[
                  ("R", "set_secret(a)", 1, S("H", 3, after, [], ["use_it(a)"], moves=[
                      ("H", "use(a)", 1, S(None, 0, done)),
                      ("H", "pass", 1, S("R", 2, after, [], ["use_it(a)"], moves=[
                          ("R", "wait", 1, S("H", 1, after, [], ["use_it(a)"], moves=[
                              ("H", "use(a)", 1, S(None, 0, done))]))]))]))])
    policy = build(p, plain)
    ok(p, policy)
    before = edited(policy, 0, action="inform(not secret(a)) + set_secret(a)",
                    told=["not secret(a)"], cost=2)
    caught(p, before, "the label tells secret(a) is false, but it is true in T after "
           "set_secret(a) (§5, with-action)")
    caught(p, edited(policy, 0, action="inform(secret(a)) + set_secret(a)",
                     told=["secret(a)"], cost=2),
           "every world already agrees with the truth on secret(a)", "after set_secret(a)")


# -- §5: relevance per hypothesis, and relevance "plan" keeps the next-step sets ---------------

def test_a_divergence_that_matters_for_one_hypothesis_is_relevant() -> None:
    # by hand: after grab(c1) the human means the left or the right shelf (both clear);
    # only the right needs ok_r, which the human wrongly believes false: for that hypothesis
    # its next action differs, so inform(ok_r) is relevant. Then it places either way
    p = problem(shelf_domain(ok_r=True), objects={"cup": ["c1"]},
                init=["free_l", "free_r", "ok_r"], human=["stock(c1)"],
                beliefs=[([], ["ok_r"])], human_model=HumanModel(passes=Passes.IDLE))
    free = ["free_l", "free_r", "ok_r"]
    gap: Diffs = [([], ["ok_r"])]
    root = S("H", 3, free, [], ["stock(c1)"], diffs=gap, moves=[
        ("H", "grab(c1)", 1, S("R", 2, [*free, "held(c1)"], hyps=BOTH, diffs=gap, moves=[
            ("R", "inform(ok_r)", 1, S("H", 1, [*free, "held(c1)"], hyps=BOTH, moves=[
                ("H", "place_l(c1)", 1, S(None, 0, [*free, "on_l(c1)"])),
                ("H", "place_r(c1)", 1, S(None, 0, [*free, "on_r(c1)"]))]))]))])
    ok(p, build(p, root))


def two_secrets(relevance: Relevance) -> Problem:
    """The human will use items a then b and wrongly believes it may use neither; the
    robot may tell one atom at a time."""
    return problem(lab_domain(), init=["human_at(lab)", "secret(a)", "secret(b)"],
                   human=["use_it(a)", "use_it(b)"],
                   beliefs=[([], ["secret(a)", "secret(b)"])], starts="robot",
                   human_model=HumanModel(passes=Passes.IDLE),
                   communication=Communication(relevance=relevance, inform_max_atoms=1))


def one_at_a_time() -> S:
    """By hand: no single atom fixes the human's plan (both are wrong), but secret(a) fixes
    its next step; after use(a), secret(b) fixes the rest: 1 + 1 + 1 + 1."""
    t = ["human_at(lab)", "secret(a)", "secret(b)"]
    return S("R", 4, t, [], ["use_it(a)", "use_it(b)"], diffs=[([], ["secret(a)", "secret(b)"])],
             moves=[("R", "inform(secret(a))", 1, S("H", 3, t, [], ["use_it(a)", "use_it(b)"],
                                                    diffs=[([], ["secret(b)"])], moves=[
                 ("H", "use(a)", 1, S("R", 2, [*t, "used(a)"], [], ["use_it(b)"],
                                      diffs=[([], ["secret(b)"])], moves=[
                     ("R", "inform(secret(b))", 1, S("H", 1, [*t, "used(a)"], [],
                                                     ["use_it(b)"], moves=[
                         ("H", "use(b)", 1, S(None, 0, [*t, "used(a)", "used(b)"]))]))]))]))])


def test_relevance_plan_still_offers_the_set_that_fixes_the_next_step() -> None:
    for relevance in (Relevance.NEXT, Relevance.PLAN):
        p = two_secrets(relevance)
        ok(p, build(p, one_at_a_time()))
    # the other atom fixes neither the plan nor the next step
    p = two_secrets(Relevance.PLAN)
    caught(p, edited(build(p, one_at_a_time()), 0, action="inform(secret(b))",
                     args=["secret(b)"]),
           "branch [R inform(secret(b))]", "it does not fix the human's views, yet a set of "
           "1 atom(s) does")
