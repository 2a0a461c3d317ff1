"""The validator under the problem options of docs/semantics.md §4-§7: each rule accepted on a
small policy derived by hand (or made by the planner and checked by hand), and each violation
rejected with the rule's message (mutation tests)."""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import ehatp
from ehatp import (
    Communication,
    HumanModel,
    InformWhere,
    Objective,
    ObjectiveKind,
    Passes,
    Policy,
    Problem,
    Relevance,
    Speech,
)
from ehatp.check.validator import Report, _Semantics, validate
from ehatp.formats.policy import FORMAT

from .policy_v1 import tree_dict
from .scenarios import lab_domain, problem

HOME = ["human_at(lab)"]
Cost = int | Fraction | float


# -- policies written by hand -------------------------------------------------------------------

@dataclass
class N:
    """One node of a hand-written policy: the move into it and what holds after it. ``diffs``
    are the worlds as (atoms true unlike T, atoms false unlike T)."""

    agent: str | None
    action: str
    value: Cost
    state: list[str]
    to_move: str | None
    cost: Cost = 1
    diffs: list[tuple[list[str], list[str]]] = field(default_factory=lambda: [([], [])])
    k: int = 0
    cop: bool = True
    robot: list[str] = field(default_factory=list)
    human: list[str] = field(default_factory=list)
    kids: list[N] = field(default_factory=list)


def split_top(s: str) -> list[str]:
    """``"a(x, y), not b"`` -> ``["a(x, y)", "not b"]``: commas outside parentheses."""
    out, depth, cur = [], 0, ""
    for ch in s:
        if ch == "," and depth == 0:
            out.append(cur.strip())
            cur = ""
            continue
        depth += (ch == "(") - (ch == ")")
        cur += ch
    return [*out, cur.strip()] if cur.strip() else out


def call(label: str) -> tuple[str, str, list[str], list[str]]:
    """(kind, name, args, told) of a move label as docs/policy-format.md writes them."""
    if label.startswith("inform(") and " + " in label:
        said, _, act = label.partition(" + ")
        kind, name, args, _ = call(act)
        return kind, name, args, split_top(said[len("inform("):-1])
    if label.startswith("inform("):
        return "inform", "inform", split_top(label[len("inform("):-1]), []
    if label.startswith("ask("):
        return "ask", "ask", [label[len("ask("):-1]], []
    for kind in ("answer", "announce"):
        if label.startswith(kind + "("):
            return kind, kind, [], []
    if label in ("wait", "pass", "silence", "start"):
        return label, label, [], []
    name, _, rest = label.partition(" [")[0].partition("(")  # "grab [place(l)]": visible
    return "action", name, split_top(rest[:-1]), []


def loose(x: Cost | None) -> Any:
    """A number as a policy read from JSON may hold it (a float where it is not whole)."""
    return x


def build(p: Problem, root: N, *, objective: dict[str, Any] | None = None,
          worst_case: Cost | None = None, expected: Cost | None = None) -> Policy:
    """The hand-written tree as a policy file of format version 1 (each node holds the move
    into it), read back as a policy."""
    nodes: list[dict[str, Any]] = []

    def add(n: N) -> int:
        kind, name, args, told = call(n.action)
        div = sorted({f"not {a}" for t, _ in n.diffs for a in t}
                     | {a for _, f in n.diffs for a in f})
        node: dict[str, Any] = dict(
            id=len(nodes), agent=n.agent, kind=kind, action=n.action, name=name, args=args,
            cost=loose(n.cost), copresent=n.cop, k=n.k, worlds=len(n.diffs), divergence=div,
            world_diffs=[{"true": t, "false": f} for t, f in n.diffs], state=n.state,
            robot_agenda=n.robot, human_agenda=n.human, to_move=n.to_move, value=loose(n.value),
            goal=n.to_move is None, told=told)
        nodes.append(node)
        node["children"] = [add(c) for c in n.kids]
        return int(node["id"])

    add(root)
    c = p.costs
    return Policy.from_dict(dict(
        format=FORMAT, version=1, problem=p.name, domain=p.domain.name,
        agents={"robot": "R", "human": "H"}, K=p.K,
        costs={"inform": c.inform, "ask": c.ask, "wait": c.wait, "pass": c.pass_,
               "actions": dict(c.actions)},
        nodes=nodes, cost=nodes[0]["value"],
        communications=sum(1 for n in nodes if n["kind"] in ("inform", "ask") or n["told"]),
        leaves=sum(1 for n in nodes if not n["children"]),
        objective=objective or {"kind": p.objective.kind.value},
        worst_case=loose(worst_case), expected=loose(expected)))


def mutated(policy: Policy, edit: Callable[[dict[str, Any]], None]) -> Policy:
    """``policy`` unfolded into a version 1 tree, edited node by node, and read back."""
    d = copy.deepcopy(tree_dict(policy))
    edit(d)
    return Policy.from_dict(d)


def at(d: dict[str, Any], **want: Any) -> dict[str, Any]:
    """The first node (in id order) whose fields have the given values."""
    for n in d["nodes"]:
        if all(n[k] == v for k, v in want.items()):
            return n  # type: ignore[no-any-return]
    raise LookupError(want)


def ok(p: Problem, policy: Policy) -> Report:
    r = validate(p, policy)
    assert r.ok, "\n".join(r.violations)
    return r


def caught(p: Problem, policy: Policy, *needles: str) -> Report:
    r = validate(p, policy)
    assert not r.ok
    assert r.message == r.violations[0]
    for s in needles:
        assert s in r.message, (s, r.message)
    return r


def solved(p: Problem) -> Policy:
    policy = ehatp.solve(p).policy
    assert policy is not None
    return policy


def moves(policy: Policy) -> list[str]:
    """The first branch, as agent-labelled moves."""
    return [f"{n.agent} {n.action}" for n in next(policy.iter_branches())[1:]]


# -- §4: the pass rule --------------------------------------------------------------------------

def lamp_problem(passes: Passes) -> Problem:
    """The robot could light a lamp; the human goes for a stroll and comes back."""
    return problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_lamp(a)"],
                   starts="robot", human_model=HumanModel(passes=passes))


def waiting_robot() -> N:
    """The robot waits first (voluntarily: it could light the lamp), then lights the lamp
    unseen. Derived by hand: unseen, the human imagines the lamp lit or not (2 worlds, k = 1),
    an unseen wait keeps both (k = 2), back in the lab it sees the lamp (1 world): a goal."""
    out, back = ["human_at(hall)"], ["human_at(lab)", "lamp(a)", "strolled(s1)"]
    unsure: list[tuple[list[str], list[str]]] = [([], ["lamp(a)"]), ([], [])]
    return N(None, "start", 6, HOME, "R", cost=0, robot=["set_lamp(a)"], human=["trip(s1)"],
             kids=[N("R", "wait", 5, HOME, "H", robot=["set_lamp(a)"], human=["trip(s1)"], kids=[
                 N("H", "go(lab, hall)", 4, out, "R", cop=False, robot=["set_lamp(a)"],
                   human=["stroll(s1)", "go(hall, lab)"], kids=[
                     N("R", "set_lamp(a)", 3, [*out, "lamp(a)"], "H", cop=False, k=1,
                       diffs=unsure, human=["stroll(s1)", "go(hall, lab)"], kids=[
                         N("H", "stroll(s1)", 2, [*out, "lamp(a)", "strolled(s1)"], "R",
                           cop=False, k=1, diffs=unsure, human=["go(hall, lab)"], kids=[
                             N("R", "wait", 1, [*out, "lamp(a)", "strolled(s1)"], "H",
                               cop=False, k=2, diffs=unsure, human=["go(hall, lab)"], kids=[
                                 N("H", "go(hall, lab)", 0, back, None)])])])])])])


def test_prototype_pass_rule_takes_the_pass_after_any_wait() -> None:
    p = lamp_problem(Passes.PROTOTYPE)
    ok(p, build(p, waiting_robot()))
    # the planner, under the same rule, waits on purpose to take the human's pass away
    assert moves(solved(p))[0] == "R wait"


def test_fair_pass_rule_a_voluntary_wait_takes_nothing_from_the_human() -> None:
    p = lamp_problem(Passes.FAIR)
    caught(p, build(p, waiting_robot()), "branch [R wait]: node 1 (R wait)",
           "missing human branch H pass")
    assert moves(solved(p))[0] != "R wait"


def test_the_validators_node_says_whether_the_last_wait_was_forced() -> None:
    for passes, forced in ((Passes.FAIR, False), (Passes.PROTOTYPE, True)):
        sem = _Semantics(lamp_problem(passes))
        after = sem.robot_wait(sem.initial()).after
        assert after is not None and after.forced is forced
    # nothing left to do: a wait is forced under either rule
    sem = _Semantics(problem(lab_domain(), init=HOME, human=["trip(s1)"], starts="robot"))
    after = sem.robot_wait(sem.initial()).after
    assert after is not None and after.forced


def test_no_pass_right_after_a_forced_wait_when_the_human_can_act() -> None:
    p = lamp_problem(Passes.FAIR)
    policy = solved(p)
    ok(p, policy)

    def edit(d: dict[str, Any]) -> None:
        # the first wait in front of the human comes when the lamp is lit: it is forced
        wait = at(d, agent="R", kind="wait", copresent=True)
        assert wait["robot_agenda"] == []
        extra = copy.deepcopy(d["nodes"][wait["children"][0]])
        extra.update(id=len(d["nodes"]), kind="pass", action="pass", name="pass", args=[],
                     children=[])
        d["nodes"].append(extra)
        wait["children"].append(extra["id"])

    caught(p, mutated(policy, edit), "R wait, H pass]", "extra human branch")


def blocked_problem(*, passes_when_blocked: bool = True, ask: bool = True) -> Problem:
    """The human does not know whether it may use item a (it may); the robot has nothing to
    do, and telling costs 3."""
    return problem(lab_domain(), init=[*HOME, "secret(a)"], human=["use_it(a)"],
                   beliefs=[([], []), ([], ["secret(a)"])], starts="robot",
                   costs=ehatp.Costs(inform=3),
                   human_model=HumanModel(passes_when_blocked=passes_when_blocked),
                   communication=Communication(ask=ask))


def test_a_blocked_human_asks_rather_than_pass_after_a_forced_wait() -> None:
    p = blocked_problem(passes_when_blocked=False)
    policy = solved(p)
    assert moves(policy) == ["R wait", "H ask(secret(a))", "R wait", "H use(a)"]
    ok(p, policy)
    # a human that passes when blocked may also stay silent after the forced wait
    caught(blocked_problem(), policy, "branch [R wait]", "missing human branch H pass")


def test_a_human_that_never_asks() -> None:
    policy = solved(blocked_problem(passes_when_blocked=False))
    r = caught(blocked_problem(passes_when_blocked=False, ask=False), policy,
               "branch [R wait, H ask(secret(a))]", "extra human branch")
    # with no question to ask, the blocked human passes
    assert any("missing human branch H pass" in v for v in r.violations)
    p = blocked_problem(passes_when_blocked=False, ask=False)
    ok(p, solved(p))


# -- §4: the non-anticipating human -------------------------------------------------------------

def secret_problem(*, anticipates: bool, human: Sequence[str] = ("trip(s1)",)) -> Problem:
    return problem(lab_domain(), init=HOME, human=list(human), robot=["set_secret(a)"],
                   human_model=HumanModel(anticipates=anticipates))


def test_a_non_anticipating_human_imagines_nothing_unseen_but_k_counts() -> None:
    p = secret_problem(anticipates=False)
    policy = solved(p)
    assert moves(policy)[:2] == ["H go(lab, hall)", "R set_secret(a)"]
    unseen = policy.nodes[policy.nodes[policy.root.children[0]].children[0]]
    assert (unseen.worlds, unseen.k) == (1, 1)  # one world, yet a robot turn apart
    # back in the lab with the robot done, the human knows it is done: a goal, although its
    # world still lacks the hidden secret(a) the robot set
    assert moves(policy)[-1] == "H go(hall, lab)"
    ok(p, policy)
    caught(secret_problem(anticipates=True), policy,
           "branch [H go(lab, hall), R set_secret(a)]", "worlds is 1, expected 2")

    def edit(d: dict[str, Any]) -> None:
        at(d, agent="R", action="set_secret(a)", copresent=False)["k"] = 0

    caught(p, mutated(policy, edit), "R set_secret(a)]", "k is 0, expected 1")


def test_an_anticipating_humans_policy_is_wrong_for_a_non_anticipating_one() -> None:
    policy = solved(secret_problem(anticipates=True))
    caught(secret_problem(anticipates=False), policy, "branch [H go(lab, hall), R wait]",
           "worlds is 2, expected 1")


def test_the_human_sees_the_robot_done_only_together() -> None:
    # the human leaves for good: apart, it never learns that the robot set the secret, and
    # still attributes set_secret(a) to it, which cannot finish where secret(a) holds
    p = secret_problem(anticipates=False, human=["go(lab, hall)"])
    hall = ["human_at(hall)"]
    claimed = N(None, "start", 2, HOME, "H", cost=0, robot=["set_secret(a)"],
                human=["go(lab, hall)"], kids=[
                    N("H", "go(lab, hall)", 1, hall, "R", cop=False,
                      robot=["set_secret(a)"], kids=[
                          N("R", "set_secret(a)", 0, [*hall, "secret(a)"], None, cop=False,
                            k=1, diffs=[([], ["secret(a)"])])])])
    r = caught(p, build(p, claimed), "missing human branch H pass")  # at the start
    assert any(v.startswith("branch [H go(lab, hall), R set_secret(a)]: node 2")
               and "to_move is None, expected 'H'; goal is True, expected False" in v
               for v in r.violations)


# -- §5: inform anywhere ------------------------------------------------------------------------

def call_problem(where: InformWhere, **kw: Any) -> Problem:
    """The robot sets the secret while the human strolls; back, the human uses the item."""
    args: dict[str, Any] = dict(init=HOME, human=["trip(s1)", "use_it(a)"],
                                robot=["set_secret(a)"])
    args.update(kw)
    return problem(lab_domain(), communication=Communication(inform=where), **args)


def test_inform_anywhere_is_heard_apart_without_product_or_k() -> None:
    p = call_problem(InformWhere.ANYWHERE)
    policy = solved(p)
    inform = next(policy.nodes[m.to] for _, m in policy.edges() if m.kind == "inform")
    assert not inform.copresent and inform.k == 1 and inform.worlds == 1
    ok(p, policy)
    caught(call_problem(InformWhere.COPRESENT), policy, "R inform(secret(a))]",
           "not a legal robot option", "inform is offered only while co-present")

    def edit(d: dict[str, Any]) -> None:
        at(d, kind="inform")["k"] = 2  # as if the call were a robot turn the human imagines

    caught(p, mutated(policy, edit), "R inform(secret(a))]", "k is 2, expected 1")


def test_inform_anywhere_also_at_k_equal_K() -> None:
    # the K bound limits what the robot does unseen; a call multiplies no world
    p = dataclasses.replace(
        call_problem(InformWhere.ANYWHERE, human=["long_trip", "use_it(a)"]),
        after=("H go(lab, hall)", "R set_secret(a)", "H stroll(s1)", "R wait", "H stroll(s2)",
               "R inform(secret(a))"))
    policy = solved(p)
    assert policy.root.k == 2 == p.K and not policy.root.copresent
    ok(p, policy)


# -- §5: relevance "plan" -----------------------------------------------------------------------

def plan_problem(relevance: Relevance, horizon: int = 8, items: Sequence[str] = ("a",)
                 ) -> Problem:
    """The human will use its items after a stroll and wrongly believes it may not: its next
    move (leaving) is the same whatever it believes; its plan fails later."""
    return problem(lab_domain(), init=[*HOME, *(f"secret({i})" for i in items)],
                   human=["trip(s1)", *(f"use_it({i})" for i in items)],
                   beliefs=[([], [f"secret({i})" for i in items])], starts="robot",
                   communication=Communication(relevance=relevance, plan_horizon=horizon))


def test_a_divergence_that_breaks_a_later_step_is_relevant_under_plan() -> None:
    p = plan_problem(Relevance.PLAN)
    policy = solved(p)
    assert moves(policy)[0] == "R inform(secret(a))"  # before the human leaves
    ok(p, policy)
    caught(plan_problem(Relevance.NEXT), policy, "branch [R inform(secret(a))]",
           "not a legal robot option", "the divergence is not relevant")


def test_the_plan_horizon_bounds_what_is_relevant() -> None:
    policy = solved(plan_problem(Relevance.PLAN))
    # 4 steps see use(a) fail after go, stroll, go; 2 steps see nothing
    ok(plan_problem(Relevance.PLAN, horizon=4), policy)
    caught(plan_problem(Relevance.PLAN, horizon=2), policy, "the divergence is not relevant",
           "and the human's plans on W equal those on T")


def test_the_informing_set_must_also_fix_the_plans() -> None:
    p = plan_problem(Relevance.PLAN, items=("a", "b"))
    policy = solved(p)
    assert moves(policy)[0] == "R inform(secret(a), secret(b))"
    ok(p, policy)

    def edit(d: dict[str, Any]) -> None:
        at(d, kind="inform").update(action="inform(secret(a))", args=["secret(a)"])

    caught(p, mutated(policy, edit), "branch [R inform(secret(a))]",
           "it does not fix the human's views and plans, yet a set of 2 atom(s) does")


# -- §5: speech while acting, and the opening ---------------------------------------------------

def speech_problem(starts: str = "robot", speech: Speech = Speech.WITH_ACTION,
                   objective: Objective | None = None) -> Problem:
    """The human does not know whether it may use item a (it may); the robot lights a lamp."""
    return problem(lab_domain(), init=[*HOME, "secret(a)"], human=["use_it(a)"],
                   robot=["set_lamp(b)"], beliefs=[([], []), ([], ["secret(a)"])],
                   starts=starts, communication=Communication(speech=speech),
                   objective=objective)


T0 = [*HOME, "secret(a)"]
T1 = [*T0, "lamp(b)"]
T2 = [*T1, "used(a)"]
UNSURE: list[tuple[list[str], list[str]]] = [([], []), ([], ["secret(a)"])]


def speaking_robot(values: Sequence[Cost] = (5, 3, 0, 2, 1, 0)) -> N:
    """The robot tells secret(a) while lighting the lamp (one move, cost 1 + 1); the human
    then uses the item, or passes and, after the robot's forced wait, uses it."""
    v = list(values)
    return N(None, "start", v[0], T0, "R", cost=0, diffs=UNSURE, robot=["set_lamp(b)"],
             human=["use_it(a)"], kids=[
                 N("R", "inform(secret(a)) + set_lamp(b)", v[1], T1, "H", cost=2,
                   human=["use_it(a)"], kids=[
                       N("H", "use(a)", v[2], T2, None),
                       N("H", "pass", v[3], T1, "R", human=["use_it(a)"], kids=[
                           N("R", "wait", v[4], T1, "H", human=["use_it(a)"], kids=[
                               N("H", "use(a)", v[5], T2, None)])])])])


def test_speaking_while_acting_is_one_move() -> None:
    p = speech_problem()
    policy = build(p, speaking_robot(), worst_case=5, expected=4)
    assert policy.communications == 1 and policy.root.moves[0].told == ["secret(a)"]
    ok(p, policy)
    ok(p, Policy.from_dict(policy.to_dict()))
    # the planner finds the same policy
    planned = solved(p)
    assert moves(planned)[0] == "R inform(secret(a)) + set_lamp(b)"
    ok(p, planned)


def test_speaking_while_acting_needs_the_option() -> None:
    p = speech_problem(speech=Speech.TURN)
    caught(p, build(p, speaking_robot()), "branch [R inform(secret(a)) + set_lamp(b)]",
           "not a legal robot option", 'speech = "with-action"')


def test_speech_mutations() -> None:
    p = speech_problem()
    policy = build(p, speaking_robot())
    said = "R inform(secret(a)) + set_lamp(b)]"

    def edit_told(d: dict[str, Any]) -> None:
        d["nodes"][1]["told"] = []

    caught(p, mutated(policy, edit_told), said,
           "told is [], but the move says ['secret(a)'] (speech, §5)")

    def edit_cost(d: dict[str, Any]) -> None:
        d["nodes"][1]["cost"] = 1

    caught(p, mutated(policy, edit_cost), said, "cost is 1, but the move costs 2")

    def edit_name(d: dict[str, Any]) -> None:
        d["nodes"][1].update(name="inform", args=["secret(a)"])

    caught(p, mutated(policy, edit_name), said,
           "name and args are 'inform' ['secret(a)'], expected 'set_lamp' ['b']")

    def edit_count(d: dict[str, Any]) -> None:
        d["communications"] = 0

    caught(p, mutated(policy, edit_count), "communications is 0, but the policy has 1")

    def edit_plain(d: dict[str, Any]) -> None:
        at(d, agent="R", kind="wait")["told"] = ["secret(a)"]

    caught(p, mutated(policy, edit_plain), "R wait]",
           "told is ['secret(a)'], but the move says nothing")

    def edit_known(d: dict[str, Any]) -> None:
        d["nodes"][1].update(action="inform(human_at(lab)) + set_lamp(b)", told=["human_at(lab)"])

    caught(p, mutated(policy, edit_known),
           "every world already agrees with the truth on human_at(lab)")


def opening_robot() -> N:
    """The human starts; the robot tells secret(a) before the human's first move."""
    after_use = [*T0, "used(a)"]
    return N(None, "start", 6, T0, "R", cost=0, diffs=UNSURE, robot=["set_lamp(b)"],
             human=["use_it(a)"], kids=[
                 N("R", "inform(secret(a))", 5, T0, "H", robot=["set_lamp(b)"],
                   human=["use_it(a)"], kids=[
                       N("H", "use(a)", 1, after_use, "R", robot=["set_lamp(b)"], kids=[
                           N("R", "set_lamp(b)", 0, T2, None)]),
                       N("H", "pass", 4, T0, "R", robot=["set_lamp(b)"], human=["use_it(a)"],
                         kids=[N("R", "set_lamp(b)", 3, T1, "H", human=["use_it(a)"], kids=[
                             N("H", "use(a)", 0, T2, None),
                             N("H", "pass", 2, T1, "R", human=["use_it(a)"], kids=[
                                 N("R", "wait", 1, T1, "H", human=["use_it(a)"], kids=[
                                     N("H", "use(a)", 0, T2, None)])])])])])])


def test_the_robot_may_speak_before_the_humans_first_move() -> None:
    p = speech_problem(starts="human")
    policy = build(p, opening_robot())
    ok(p, policy)
    assert moves(solved(p))[0] == "R inform(secret(a))"
    # without speech while acting there is no opening: the human moves first
    caught(speech_problem(starts="human", speech=Speech.TURN), policy,
           "branch []: node 0 (start)", "to_move is 'R', expected 'H'")


def test_the_opening_offers_only_inform_and_silence() -> None:
    p = speech_problem(starts="human")

    def edit(d: dict[str, Any]) -> None:
        d["nodes"][1].update(kind="wait", action="wait", name="wait", args=[])

    caught(p, mutated(build(p, opening_robot()), edit), "branch [R wait]",
           "at the speech opening (§5) the robot may only inform or stay silent, not "
           "wait")

    def edit_late(d: dict[str, Any]) -> None:
        at(d, agent="R", kind="wait").update(kind="silence", action="silence", name="silence",
                                             cost=0)

    caught(p, mutated(build(p, opening_robot()), edit_late), "R silence]",
           "silence is a move only at the speech opening")


def test_silence_at_the_opening() -> None:
    p = dataclasses.replace(speech_problem(starts="human"), after=("R silence",))
    policy = solved(p)
    ok(p, policy)
    # silence costs nothing, changes nothing and counts no passive move
    sem = _Semantics(speech_problem(starts="human"))
    es = sem.initial()
    assert es.opening
    st = sem.silence(es)
    assert st.cost == 0 and st.after is not None
    assert (st.after.worlds, st.after.passive, st.after.forced) == (es.worlds, 0, False)

    def edit(d: dict[str, Any]) -> None:
        d["after"] = ["R wait"]

    caught(dataclasses.replace(p, after=("R wait",)), mutated(policy, edit),
           "opening: after[0] 'R wait' is not a legal move",
           "the robot may only inform or stay silent")


def apart_opening(where: InformWhere) -> tuple[Problem, Policy]:
    """The human starts in the hall, back to the lab to use the item it wrongly believes it
    may not use; relevance "plan" sees its plan fail. The robot opens with a call."""
    p = problem(lab_domain(), init=["human_at(hall)", "secret(a)"],
                human=["go(hall, lab)", "use_it(a)"], beliefs=[([], ["secret(a)"])],
                communication=Communication(inform=where, speech=Speech.WITH_ACTION,
                                            relevance=Relevance.PLAN))
    hall, lab = ["human_at(hall)", "secret(a)"], ["human_at(lab)", "secret(a)"]
    root = N(None, "start", 4, hall, "R", cost=0, cop=False, diffs=[([], ["secret(a)"])],
             human=["go(hall, lab)", "use_it(a)"], kids=[
                 N("R", "inform(secret(a))", 3, hall, "H", cop=False,
                   human=["go(hall, lab)", "use_it(a)"], kids=[
                       N("H", "go(hall, lab)", 2, lab, "R", human=["use_it(a)"], kids=[
                           N("R", "wait", 1, lab, "H", human=["use_it(a)"], kids=[
                               N("H", "use(a)", 0, [*lab, "used(a)"], None)])])])])
    return p, build(p, root)


def test_an_opening_call_needs_inform_anywhere() -> None:
    ok(*apart_opening(InformWhere.ANYWHERE))
    caught(*apart_opening(InformWhere.COPRESENT), "branch []: node 0 (start)",
           "to_move is 'R', expected 'H'", "no speech opening, since no informing set exists "
           "in the initial state: inform is offered only while co-present")


# -- §7: objectives and values ------------------------------------------------------------------

def expected_problem(**weights: Fraction) -> Problem:
    return speech_problem(objective=Objective(kind=ObjectiveKind.EXPECTED, weights=weights))


def test_expected_values_with_weights() -> None:
    # by hand, with a pass weighing half as much as an action: after the robot's move, the
    # human uses the item (1) or passes and uses it after a wait (1 + 2 = 3):
    # (1 * 1 + 1/2 * 3) / (1 + 1/2) = 5/3; the root adds the move's 2: 11/3
    p = expected_problem(**{"pass": Fraction(1, 2)})
    v: list[Cost] = [Fraction(11, 3), Fraction(5, 3), 0, 2, 1, 0]
    policy = build(p, speaking_robot(v), objective={"kind": "expected"}, worst_case=5,
                   expected=Fraction(11, 3))
    ok(p, policy)
    # in JSON the values are floats: accepted within a small tolerance
    as_json = Policy.from_dict(policy.to_dict())
    assert isinstance(as_json.cost, float)
    ok(p, as_json)
    # a label weighs before an action name: use(a) three times as likely as anything else,
    # (3 * 1 + 1 * 3) / (3 + 1) = 3/2
    p3 = expected_problem(**{"use(a)": Fraction(3)})
    v3: list[Cost] = [Fraction(7, 2), Fraction(3, 2), 0, 2, 1, 0]
    ok(p3, build(p3, speaking_robot(v3), objective={"kind": "expected"}, expected=v3[0]))


def test_expected_value_mutations() -> None:
    p = expected_problem(**{"pass": Fraction(1, 2)})
    v: list[Cost] = [Fraction(11, 3), Fraction(5, 3), 0, 2, 1, 0]
    good = build(p, speaking_robot(v), objective={"kind": "expected"}, worst_case=5,
                 expected=Fraction(11, 3))
    # node values are the chosen objective's: the worst case is wrong here
    caught(p, build(p, speaking_robot([5, 3, 0, 2, 1, 0]), objective={"kind": "expected"}),
           "node 0 (start): value is 5, but its expected cost-to-go is 3.6666666666666665")
    # exact where exact: a Fraction a hair off is wrong, the float of 5/3 is fine
    off = [v[0], Fraction(5, 3) + Fraction(1, 10**12), *v[2:]]
    caught(p, build(p, speaking_robot(off), objective={"kind": "expected"}),
           "value is 5000000000003/3000000000000, but its expected cost-to-go is 1.66666")
    ok(p, build(p, speaking_robot([v[0], 5 / 3, *v[2:]]), objective={"kind": "expected"}))

    def edit(key: str, value: Any) -> Callable[[dict[str, Any]], None]:
        return lambda d: d.__setitem__(key, value)

    caught(p, mutated(good, edit("worst_case", 4)),
           "policy worst_case is 4, but the policy's worst-case cost is 5 (§7)")
    caught(p, mutated(good, edit("expected", 4)),
           "policy expected is 4, but the policy's expected cost is 3.666")
    caught(p, mutated(good, edit("cost", 5)), "policy cost is 5, but the root's value is 3.666")
    caught(p, mutated(good, edit("objective", {"kind": "worst-case"})),
           "policy objective kind is 'worst-case', but the problem's objective is 'expected'")
    caught(p, mutated(good, edit("objective", {"kind": "expected", "weights": {}})),
           "policy objective weights are {}, but the problem's are {'pass': 0.5}")


def test_worst_case_policies_report_their_expected_cost_too() -> None:
    p = speech_problem()
    ok(p, build(p, speaking_robot(), worst_case=5, expected=4))
    caught(p, build(p, speaking_robot(), worst_case=5, expected=5),
           "policy expected is 5, but the policy's expected cost is 4")
    caught(p, build(p, speaking_robot(), objective={"kind": "expected"}),
           "policy objective kind is 'expected', but the problem's objective is 'worst-case'")


def test_planned_policies_under_each_objective_validate() -> None:
    for kind in (ObjectiveKind.WORST_CASE, ObjectiveKind.EXPECTED):  # turns: not preferences
        p = speech_problem(starts="human", objective=Objective(kind=kind))
        policy = solved(p)
        assert policy.objective["kind"] == kind.value
        assert policy.worst_case is not None and policy.expected is not None
        assert policy.cost == (policy.worst_case if kind == ObjectiveKind.WORST_CASE
                               else policy.expected)
        ok(p, policy)
