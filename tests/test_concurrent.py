"""Joint, compliant steps (docs/concurrent.md; the specification's rules C1-C12 and its worked
examples E1-E3): every figure below was derived by hand from the rules before the planner was
run, and the derivation is in each test's docstring."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

import ehatp
from ehatp import (
    INFERABLE,
    Communication,
    Domain,
    DomainError,
    Executor,
    InputError,
    Problem,
    StepFirst,
    StepMode,
    Steps,
    Var,
    Witness,
    forall,
)
from ehatp.formats.policy import Policy
from ehatp.run.walk import walk_policy

from .conftest import EXAMPLES_DIR as EXAMPLES

JOINT = Steps(StepMode.CONCURRENT)


def solved(p: Problem) -> Policy:
    """Return ``p``'s policy, checked by the validator and walked through the Executor."""
    r = ehatp.solve(p)
    assert r.policy is not None, r.reason
    report = ehatp.validate(p, r.policy)
    assert report.ok, report.message
    walked = walk_policy(p, r.policy)
    assert walked.ok, str(walked)
    return r.policy


def replies(policy: Policy) -> dict[tuple[str, ...], str]:
    """Return the robot's reply after each line of human decisions (labels), over the
    policy's branches: what the compliant robot does for each human move."""
    out: dict[tuple[str, ...], str] = {}
    for branch in policy.iter_branches():
        humans: list[str] = []
        for step in branch[1:]:
            assert step.move is not None
            if step.move.step == "reply":
                out[tuple(humans)] = step.move.action
            elif step.move.step in ("human", "ask"):
                humans.append(step.move.action)
    return out


# --- E1: two independent chores -------------------------------------------------------------

def chores(steps: Steps) -> Problem:
    """E1: always co-present; the robot puts ``a``, the human puts ``b``; no common
    resource."""
    d = Domain("chores", robot="R", human="H")
    x = Var("x", d.type("thing"))
    placed = d.predicate("placed", x)
    for m in (d.robot, d.human):
        m.action("put", x, pre=~placed(x), effects=[placed(x)])
    return Problem(name="e1", domain=d, objects={"thing": ["a", "b"]}, init=frozenset(),
                   robot_agenda=(("put", ("a",)),), human_agenda=(("put", ("b",)),),
                   starts="robot", steps=steps)


def test_e1_two_independent_chores_take_two_steps_and_four_turns() -> None:
    """E1 by hand. Concurrent, the human first (C4). Root: the human may ``put(b)``, or pass
    (C5: co-present and the robot has a real action, ``put(a)``).
    - ``put(b)``: the robot's replies are ``put(a)`` (C3: still an option after ``put(b)``,
      ``put(b)`` still applicable after it, the same state either way, no resource) and
      ``wait``; ``put(a)`` reaches the goal: 1 step.
    - ``pass``: (pass, wait) is never a step (C3), so the robot puts ``a``: 1 step; then the
      robot has nothing to do, so the human may not pass (C5) and puts ``b`` while the robot
      waits: 1 step. 2 steps.
    Worst case 2 (the makespan, C11), no communication, and the robot does ``put(a)``
    whatever the human does. Turn-taking, the robot first, fair passes (§4): ``put(a)``, H
    passes, R waits (forced), H ``put(b)``: 4 moves."""
    policy = solved(chores(JOINT))
    assert (policy.cost, policy.communications) == (2, 0)
    assert replies(policy) == {("put(b)",): "put(a)", ("pass",): "put(a)",
                               ("pass", "put(b)"): "wait"}
    assert solved(chores(Steps())).cost == 4


# --- E2: one cube, two hands ----------------------------------------------------------------

def two_hands(steps: Steps) -> Problem:
    """E2: cube ``c`` within reach of both; each agent's task is to have it placed (done once
    it is); ``pick`` and ``place`` hold the cube (C3 c)."""
    d = Domain("two-hands", robot="R", human="H")
    c = Var("c", d.type("cube"))
    ontable, placed = d.predicate("ontable", c), d.predicate("placed", c)
    holding = d.predicate("holding", Var("a", "agent"), c)
    for m, who in ((d.robot, "R"), (d.human, "H")):
        pick = m.action("pick", c, pre=ontable(c), effects=[~ontable(c), holding(who, c)],
                        resources=[c])
        place = m.action("place", c, pre=holding(who, c),
                         effects=[~holding(who, c), placed(c)], resources=[c])
        stack = m.task("stack", c, done=placed(c))
        m.method(stack, "pick_place", pre=ontable(c), subtasks=[pick(c), place(c)])
        m.method(stack, "place", pre=holding(who, c), subtasks=[place(c)])
    return Problem(name="e2", domain=d, objects={"cube": ["c"]},
                   init=frozenset({("ontable", ("c",))}), robot_agenda=(("stack", ("c",)),),
                   human_agenda=(("stack", ("c",)),), steps=steps)


def test_e2_the_robot_yields_the_cube_the_human_reaches_for() -> None:
    """E2 by hand. Root: the human may ``pick(c)``, or pass (the robot can pick).
    - ``pick(c)``: the robot's ``pick(c)`` is no reply (C3 a: not applicable after the human's
      pick; C3 c: both hold ``c``), so it waits: 1 step. Then the robot is blocked (the cube
      is held), so the human may not pass and places it, the robot waiting: 2 steps.
    - ``pass``: the robot must act (no (pass, wait)): it picks: 1 step; the human, blocked,
      passes (the robot can place) and the robot places: 2 steps.
    Worst case 2; compliant replies: pick -> wait, pass -> pick. Turn-taking (§4, the human
    first): H pass, R pick, H pass, R place: 4 moves."""
    policy = solved(two_hands(JOINT))
    assert (policy.cost, policy.communications) == (2, 0)
    assert replies(policy) == {("pick(c)",): "wait", ("pick(c)", "place(c)"): "wait",
                               ("pass",): "pick(c)", ("pass", "pass"): "place(c)"}
    assert solved(two_hands(Steps())).cost == 4


def test_a_shared_resource_alone_keeps_two_actions_apart() -> None:
    """C3 c: the human wipes the table while the robot picks the cube from it. Both orders
    reach the same state, so only the declared resource (the table) keeps the robot from
    picking during the wipe: with it, the robot's reply to ``wipe`` is ``wait`` and that
    branch takes 2 steps (then the human, done, passes while the robot picks); without it,
    the robot picks at once: 1 step. The worst case is 2 either way: the human may pass first
    (the robot can pick), then wipe."""
    def problem(resources: bool) -> Problem:
        d = Domain("wipe", robot="R", human="H")
        c = Var("c", d.type("cube"))
        t = d.constant("table", d.type("surface"))
        ontable, held = d.predicate("ontable", c), d.predicate("held", c)
        wiped = d.predicate("wiped")
        d.robot.action("pick", c, pre=ontable(c), effects=[~ontable(c), held(c)],
                       resources=[c, t] if resources else [c])
        d.human.action("wipe", pre=~wiped(), effects=[wiped()],
                       resources=[t] if resources else [])
        return Problem(name="wipe", domain=d, objects={"cube": ["c"]},
                       init=frozenset({("ontable", ("c",))}), robot_agenda=(("pick", ("c",)),),
                       human_agenda=(("wipe", ()),), steps=JOINT)

    def wipe_first(policy: Policy) -> int:
        branch = next(b for b in policy.iter_branches()
                      if b[1].move is not None and b[1].move.action == "wipe")
        return sum(s.move.cost for s in branch[1:] if s.move is not None)

    held_apart = solved(problem(True))
    assert replies(held_apart)[("wipe",)] == "wait" and wipe_first(held_apart) == 2
    together = solved(problem(False))
    assert replies(together)[("wipe",)] == "pick(c)" and wipe_first(together) == 1
    assert held_apart.cost == together.cost == 2


# --- E3: leaving during a step --------------------------------------------------------------

def drawer(steps: Steps, ask: bool = True) -> Problem:
    """E3: co-present iff the human is in the room; ``c`` in an opaque drawer (where it is is
    inferable: learnt only by seeing it moved); K = 1. The robot moves ``c`` to the box; the
    human goes to the pantry, comes back and takes ``c`` from the box."""
    d = Domain("drawer", robot="R", human="H")
    x = Var("x", d.type("thing"))
    here = d.predicate("h_in_room")
    in_drawer = d.predicate("in_drawer", x, observability=INFERABLE)
    in_box = d.predicate("in_box", x, observability=INFERABLE)
    held = d.predicate("held", x)
    d.copresence = here()
    d.robot.action("move", x, pre=in_drawer(x), effects=[~in_drawer(x), in_box(x)])
    d.human.action("leave", pre=here(), effects=[~here()])
    d.human.action("back", pre=~here(), effects=[here()])
    d.human.action("take", x, pre=in_box(x) & here(), effects=[~in_box(x), held(x)])
    return Problem(name="e3", domain=d, objects={"thing": ["c"]},
                   init=frozenset({("h_in_room", ()), ("in_drawer", ("c",))}),
                   robot_agenda=(("move", ("c",)),),
                   human_agenda=(("leave", ()), ("back", ()), ("take", ("c",))), K=1,
                   steps=steps, communication=Communication(ask=ask))


def test_e3_the_robot_holds_its_move_while_the_human_leaves() -> None:
    """E3 by hand, as the specification tells it: a human who cannot ask (``[communication]
    ask = false``), witness "whole". Root: ``leave``, or pass (the robot can move).
    - ``pass``: the robot moves, seen (C8); then leave, back, take, the robot waiting (it is
      done, so the human may not pass): 4 steps.
    - ``leave``: the human is gone by the step's end, so nothing the robot does is seen (C8).
      Moving now: the human imagines the move (C7.3: W = {drawer, box}, k = 1); back (k = K:
      the robot only waits); take is uncertain and it cannot ask, so it passes, and the robot,
      done, must inform: (pass, inform(in_box(c))), then take: 4 steps, 1 communication,
      cost 5. Holding: W is {drawer, box} too (an unseen wait is an imagined event), back,
      then the human passes and sees the robot move (C7.2 keeps the drawer world, advanced),
      then takes: 4 steps, 0 communications, cost 4. The robot holds.
    Worst case 4 steps, 0 communications, as the specification says. With witness "start"
    the move at once is seen (the human was there when the step began): the leave branch
    takes 3 steps (leave+move, back, take), the worst case is still 4."""
    policy = solved(drawer(JOINT, ask=False))
    assert (policy.cost, policy.communications) == (4, 0)
    assert replies(policy)[("leave",)] == "wait"
    assert replies(policy)[("pass",)] == "move(c)"
    start = solved(drawer(dataclasses.replace(JOINT, witness=Witness.START), ask=False))
    assert (start.cost, start.communications) == (4, 0)
    assert replies(start)[("leave",)] == "move(c)"
    leave = next(b for b in start.iter_branches() if b[1].move and b[1].move.action == "leave")
    assert sum(s.move.cost for s in leave[1:] if s.move is not None) == 3


def test_e3_with_a_human_who_asks_the_robot_moves_at_once() -> None:
    """E3 with the default human, who may ask (where the specification's figure does not
    hold). Holding now costs more: back in the room, uncertain whether the cube was moved
    (the unseen wait was an imagined move, C7.3), the human may ask ``in_box(c)`` (an AND
    branch, a whole step costing 1 + 1, C3, C11); told "no", it waits for the robot's move
    and takes: 1 (leave) + 1 (back) + 2 (ask) + 1 (pass, move) + 1 (take) = 6. Moving at
    once: back, the robot done and the human able to ask, it may not pass (C5), so it asks
    and takes: 1 + 1 + 2 + 1 = 5. The robot moves at once; worst case 5 (the leave branch),
    one communication (the human's question); staying, 4 as before. The turn-taking worst
    case (§4, fair passes) is 9 moves: H pass, R move, H pass, R wait (forced), H leave,
    R wait, H back, R wait, H take (the specification's 6 leaves out the human's passes)."""
    policy = solved(drawer(JOINT))
    assert (policy.cost, policy.communications) == (5, 1)
    assert replies(policy)[("leave",)] == "move(c)"
    assert solved(drawer(Steps())).cost == 9
    assert solved(drawer(Steps(), ask=False)).cost == 9


# --- the options ----------------------------------------------------------------------------

P2 = EXAMPLES / "cubes" / "p2.toml"


def load_with(tmp_path: Path, extra: str) -> Problem:
    """Return examples/cubes/p2.toml with ``extra`` appended, loaded from ``tmp_path``."""
    f = tmp_path / "p.toml"
    f.write_text(P2.read_text(encoding="utf-8") + "\n" + extra, encoding="utf-8")
    return ehatp.load(f)


def test_the_steps_table_reads_each_option(tmp_path: Path) -> None:
    """``[steps]`` gives mode, first, witness, commute and the step's cost; without it the
    agents take turns."""
    p = load_with(tmp_path, '[steps]\nmode = "concurrent"\nwitness = "start"\n'
                            'commute = "label"\ncost = 2\n')
    assert (p.steps.mode, p.steps.witness, p.steps.commute, p.steps.cost) == (
        "concurrent", "start", "label", 2)
    assert not ehatp.load(P2).steps.concurrent


@pytest.mark.parametrize(("extra", "says"), [
    ('[steps]\nmode = "parallel"\n', 'unknown value'),
    ('[steps]\nmode = "concurrent"\nwitness = "end"\n', 'unknown value'),
    ('[steps]\ncost = 0\n', 'positive number'),
    ('[steps]\nmodes = "concurrent"\n', 'modes'),
    ('[steps]\nmode = "concurrent"\n[communication]\nspeech = "with-action"\n',
     'not supported'),
])
def test_a_bad_steps_option_is_one_line_naming_the_place(tmp_path: Path, extra: str,
                                                         says: str) -> None:
    """Bad values are one line, ``file:line: place: problem; fix`` (exit 2 from the CLI)."""
    with pytest.raises(InputError) as e:
        load_with(tmp_path, extra)
    line = str(e.value)
    assert "\n" not in line and says in line and line.startswith(str(tmp_path / "p.toml"))


def test_a_resource_must_be_a_parameter_or_a_name() -> None:
    """C3 c: an action's resources are its parameters or names; another variable is a
    mistake in the domain."""
    d = Domain("bad", robot="R", human="H")
    x, y = Var("x", d.type("thing")), Var("y", "thing")
    with pytest.raises(DomainError, match="resource"):
        d.robot.action("grab", x, resources=[y])


# --- C4, first = "robot" -------------------------------------------------------------------

ROBOT_FIRST = Steps(StepMode.CONCURRENT, first=StepFirst.ROBOT)


def test_a_robot_deciding_first_takes_the_cube_and_the_human_yields() -> None:
    """C4 with ``first = "robot"``, by hand. E1: the robot puts ``a`` at once; the human puts
    ``b`` beside it (1 step) or passes, and then, the robot having nothing left, puts ``b``
    while it waits (2): worst case 2. E2: the robot picks ``c`` at once; the human sees it
    start (co-present before and after), so its own ``pick(c)`` is no option (C4: it adapts),
    and it passes; then the robot places it while the human, blocked, passes: 2 steps, one
    branch; the robot's wait would leave the human's pick and the robot's later placing no
    quicker. Each move that starts a step is the robot's (``"step": "robot"``)."""
    e1 = solved(chores(ROBOT_FIRST))
    assert (e1.cost, e1.nodes[0].moves[0].action, e1.nodes[0].moves[0].step) == (
        2, "put(a)", "robot")
    e2 = solved(two_hands(ROBOT_FIRST))
    assert (e2.cost, e2.leaves) == (2, 1)
    assert [m.action for m in e2.nodes[e2.nodes[0].moves[0].to].moves] == ["pass"]


def grab_and_go(steps: Steps) -> Problem:
    """The human leaves the room taking the cube, or just leaves once the cube is gone; the
    robot is to clear the cube off the table. Co-present iff the human is in the room."""
    d = Domain("grab-and-go", robot="R", human="H")
    c = Var("c", d.type("cube"))
    here, ontable = d.predicate("h_in_room"), d.predicate("ontable", c)
    d.copresence = here()
    clear = d.robot.task("clear", c, done=~ontable(c))
    d.robot.method(clear, "pick", pre=ontable(c),
                   subtasks=[d.robot.action("pick", c, pre=ontable(c),
                                            effects=[~ontable(c)])(c)])
    leave = d.human.task("leave")
    grab = d.human.action("grab_and_go", c, pre=ontable(c) & here(),
                          effects=[~ontable(c), ~here()])
    go = d.human.action("go", pre=here(), effects=[~here()])
    d.human.method(leave, "with_cube", params=[c], pre=ontable(c), subtasks=[grab(c)])
    d.human.method(leave, "alone", pre=forall(c, ~ontable(c)), subtasks=[go()])
    return Problem(name="grab", domain=d, objects={"cube": ["c"]},
                   init=frozenset({("h_in_room", ()), ("ontable", ("c",))}),
                   robot_agenda=(("clear", ("c",)),), human_agenda=(("leave", ()),),
                   steps=steps)


@pytest.mark.parametrize(("witness", "fails"), [(Witness.WHOLE, True), (Witness.START, False)])
def test_an_unseen_conflict_fails_and_a_seen_one_is_avoided(witness: Witness,
                                                             fails: bool) -> None:
    """C4 (``first = "robot"``), planner and validator alike. The robot starts picking the
    cube while the human grabs it and walks out. With witness "whole" the human, gone by the
    step's end, did not see the robot start: the grab is a failure (a conflict it could not
    foresee). With "start" it saw the robot start, so the grab is no option at all (it
    adapts: it passes). Either way the policy waits (the human grabs the cube: 1 step)."""
    from ehatp.check.concurrent import JointRules
    from ehatp.epistemic.concurrent import semantics_for
    from ehatp.model.grounding import ground_problem

    p = grab_and_go(dataclasses.replace(ROBOT_FIRST, witness=witness))
    sem = semantics_for(ground_problem(p))
    root = sem.initial()
    pick = next(m for m in sem.moves(root) if m.label == "pick(c)")
    assert pick.child is not None
    grabs = [m for m in sem.moves(pick.child) if m.label == "grab_and_go(c)"]
    rules = JointRules(p)
    chosen = next(st for st in rules.robot_choices(rules.initial()) if st.label == "pick(c)")
    assert chosen.after is not None
    checked = [st for st in rules.human_options(chosen.after) if st.label == "grab_and_go(c)"]
    if fails:
        assert len(grabs) == 1 and grabs[0].child is None and "unaware" in grabs[0].failure
        assert len(checked) == 1 and checked[0].after is None
    else:
        assert grabs == [] and checked == []
    policy = solved(p)
    assert (policy.cost, policy.nodes[0].moves[0].action) == (1, "wait")


# --- the validator and the executor ---------------------------------------------------------

def test_the_validator_refuses_a_reply_that_grabs_the_cube_the_human_holds() -> None:
    """C3: in E2 the policy's reply to the human's ``pick(c)`` changed from ``wait`` to
    ``pick(c)`` is not admissible, and the validator says which rule."""
    p = two_hands(JOINT)
    policy = solved(p)
    root = policy.nodes[0]
    reply_node = policy.nodes[next(m.to for m in root.moves if m.action == "pick(c)")]
    move = reply_node.moves[0]
    assert move.action == "wait"
    reply_node.moves[0] = dataclasses.replace(move, action="pick(c)", kind="action",
                                              name="pick", args=["c"])
    report = ehatp.validate(p, policy)
    assert not report.ok and "C3" in report.message


def test_the_validator_wants_each_move_to_say_its_part_of_the_step() -> None:
    """docs/policy-format.md: a joint policy's moves record ``step``; a missing one is a
    violation."""
    p = chores(JOINT)
    policy = solved(p)
    policy.nodes[0].moves[0] = dataclasses.replace(policy.nodes[0].moves[0], step="")
    report = ehatp.validate(p, policy)
    assert not report.ok and "step is ''" in report.message


def test_the_executor_observes_the_human_then_gives_the_compliant_reply() -> None:
    """C4, C9: the executor takes the human's move at the start of a step, then says the
    robot's reply; the policy file round-trips with its steps."""
    p = two_hands(JOINT)
    policy = Policy.from_dict(solved(p).to_dict())
    ex = Executor(p, policy)
    assert ex.next_robot_action() is None
    ex.observe_human_action("pick(c)")
    reply = ex.next_robot_action()
    assert reply is not None and reply.label == "wait"
    ex.robot_action_done()
    ex.observe_human_action("place(c)")
    ex.robot_action_done()
    assert ex.goal_reached
    assert policy.step_options == {"mode": "concurrent", "first": "human",
                                   "witness": "whole", "commute": "state", "cost": 1}


def test_turns_stay_the_default_and_write_no_steps() -> None:
    """In turn-taking the policy file has neither ``steps`` nor a move's ``step``."""
    text = solved(chores(Steps())).to_json()
    assert '"steps"' not in text and '"step"' not in text


# --- Table 1 in joint steps -----------------------------------------------------------------

TABLE1 = ["cubes/p1", "cubes/p2", "cubes/p3", "cubes/p4", "cubes/p5", "cubes/p6",
          "cooking/cooking1", "cooking/cooking2", "cooking/cooking3"]


@pytest.mark.parametrize("name", TABLE1)
def test_table1_in_joint_steps_is_never_slower_than_in_turns(name: str) -> None:
    """Issue 20: each of Table 1's instances solves and validates in joint steps, every
    branch runs through the Executor, and its makespan is at most the turn-taking worst case
    (a turn is a step in which the other agent waits, C12)."""
    p = ehatp.load(EXAMPLES / f"{name}.toml")
    joint = solved(dataclasses.replace(p, steps=JOINT))
    assert joint.cost <= ehatp.solve(p).stats["cost"]


# --- resources from an HDDL sidecar ---------------------------------------------------------

def test_an_hddl_sidecar_declares_what_an_action_holds(tmp_path: Path) -> None:
    """docs/hddl.md: the sidecar's ``[resources]`` gives an imported action its resources
    (``?t``: its parameter; a name as it is); a parameter the action lacks, or an action the
    domain lacks, is one line."""
    pytest.importorskip("unified_planning", reason="ehatp[hddl] (unified-planning) not installed")
    from ehatp.formats import hddl

    data = Path(__file__).parent / "data" / "hddl"

    def imported(resources: str) -> hddl.Imported:
        side = tmp_path / "side.toml"
        side.write_text(f"[resources]\n{resources}\n", encoding="utf-8")
        return hddl.import_hddl(data / "transport-domain.hddl", data / "transport-p1.hddl",
                                sidecar=side)

    d = imported('drive = ["?t", "road"]').domain()
    assert [str(x) for x in d.robot.operators["drive"].resources] == ["?t", "road"]
    with pytest.raises(hddl.HddlUnsupported, match=r"\?x is not a parameter of drive"):
        imported('drive = ["?x"]')
    with pytest.raises(hddl.HddlUnsupported, match="'fly'"):
        imported('fly = ["?t"]')


# --- openings and replanning ----------------------------------------------------------------

@pytest.mark.parametrize(("first", "after", "cost"), [
    (StepFirst.HUMAN, ("H move(mt, ot)", "R pick(r)", "H pick(w)"), 4),
    (StepFirst.ROBOT, ("R pick(r)", "H move(mt, ot)"), 4),
])
def test_an_opening_is_played_move_by_move_in_joint_steps(first: StepFirst,
                                                          after: tuple[str, ...],
                                                          cost: int) -> None:
    """``[problem] after`` names the moves of the steps played (each step two moves, the
    one who decides first named first); the policy starts where they end, mid-step or not,
    and is checked and walked from there. P2: after the human leaves and the robot picks
    ``r`` unseen, 4 steps remain in the worst case either way."""
    p = dataclasses.replace(ehatp.load(P2), after=after,
                            steps=dataclasses.replace(JOINT, first=first))
    policy = solved(p)
    assert policy.cost == cost and policy.after == list(after)


def test_the_executor_replans_in_the_middle_of_a_step() -> None:
    """A replan from a reply node (the human's move seen, the robot's not chosen yet) plays
    the history as an opening and follows the new policy: the robot's reply comes next."""
    ex = Executor(dataclasses.replace(ehatp.load(P2), steps=JOINT))
    ex.observe_human_action("move(mt, ot)")
    assert ex.replan().status == "solved"
    reply = ex.next_robot_action()
    assert reply is not None and reply.label == "pick(r)"


def test_commute_label_lets_actions_that_do_not_commute_share_a_step() -> None:
    """C3 b. The robot switches the light on while the human switches it off (each also
    marks its own chore done): in either order the other is still possible, but the two
    orders leave the light differently. Under ``commute = "state"`` they are never one step
    (the reply to the human's switch is ``wait``); under ``"label"`` they are, and the step
    ends as the robot's action after the human's leaves it (C6: the light on)."""
    from ehatp import Commute

    def problem(commute: Commute) -> Problem:
        d = Domain("light", robot="R", human="H")
        on, done_r, done_h = d.predicate("on")(), d.predicate("done_r")(), d.predicate("done_h")()
        d.robot.action("switch_on", pre=~done_r, effects=[done_r, on])
        d.human.action("switch_off", pre=~done_h, effects=[done_h, ~on])
        return Problem(name="light", domain=d, objects={}, init=frozenset(),
                       robot_agenda=(("switch_on", ()),), human_agenda=(("switch_off", ()),),
                       steps=dataclasses.replace(JOINT, commute=commute))

    state = solved(problem(Commute.STATE))
    assert replies(state)[("switch_off",)] == "wait"
    label = solved(problem(Commute.LABEL))
    assert replies(label)[("switch_off",)] == "switch_on"
    end = next(b for b in label.iter_branches() if b[1].move is not None
               and b[1].move.action == "switch_off")[-1].node
    assert "on" in end.state
