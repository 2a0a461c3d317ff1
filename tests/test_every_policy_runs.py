"""Every policy the planner returns also runs: it executes to the goal on every branch through the
executor a robot uses (ehatp.run.walk, docs/simulation.md), and its behaviour tree ticks to the
goal in py_trees (docs/behaviour-trees.md). Planner and validator read the same rules, so they
can agree on a policy that a robot cannot follow; the executor is a third reader."""

from __future__ import annotations

import dataclasses

import pytest

import ehatp
from ehatp import Communication, Domain, HumanModel, Policy, Var
from ehatp.formats import bt
from ehatp.model.options import Intentions, Speech
from ehatp.model.problem import Problem
from ehatp.run.executor import Executor
from ehatp.run.walk import tick_py_trees, walk_policy

from .conftest import (
    EXAMPLES,
    IPC_LIFTED,
    IPC_VALIDATED,
    Example,
    every_example_by_branch,
    solved,
)
from .scenarios import problem as scenario
from .test_intentions import car_problem, shelf_problem


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_shipped_example_walks_to_the_goal_on_every_branch(example: Example) -> None:
    problem, policy = solved(example)
    report = walk_policy(problem, policy)
    assert report.ok, report.message
    assert not report.capped and report.branches == policy.leaves


@pytest.mark.parametrize("example", every_example_by_branch())
def test_every_shipped_example_s_behaviour_tree_ticks_to_the_goal(example: Example) -> None:
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    problem, policy = solved(example)
    report = tick_py_trees(problem, policy)
    assert report.ok, report.message
    assert not report.capped and report.branches == policy.leaves


def test_the_walk_stops_at_the_cap_and_says_so() -> None:
    problem, policy = solved("cubes/x1-4cubes-k2")
    assert policy.leaves > 3
    report = walk_policy(problem, policy, cap=3)
    assert report.ok and report.capped and report.branches == 3
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    ticked = tick_py_trees(problem, policy, cap=3)
    assert ticked.ok and ticked.capped and ticked.branches == 3


def test_a_policy_whose_leaf_is_no_goal_fails_the_walk_on_that_branch() -> None:
    problem, policy = solved("cubes/p2")
    d = policy.to_dict()
    # cut the policy after its first move: the node it reaches becomes a leaf
    first = d["nodes"][0]["moves"][0]
    d["nodes"][first["to"]]["moves"] = []
    report = walk_policy(problem, Policy.from_dict(d))
    assert not report.ok and report.branches == 1
    assert report.message.startswith(f"branch 1 (H {first['action']}): ")
    assert report.message.endswith(f"policy leaf {first['to']} is reached but the goal does not "
                                   "hold there")


def test_a_policy_that_does_not_fit_fails_the_walk_with_the_executor_s_error() -> None:
    problem, policy = solved("cubes/p2")
    d = policy.to_dict()
    second = d["nodes"][0]["moves"][1]
    d["nodes"][second["to"]]["worlds"] = 7
    report = walk_policy(problem, Policy.from_dict(d))
    assert not report.ok and report.branches >= 1
    assert "differ on worlds" in report.message
    assert f"(H {second['action']})" in report.message


def test_a_human_choice_covered_twice_under_one_label_fails_the_walk() -> None:
    # a robot that sees only the human's action cannot tell two such branches apart (§3)
    problem, policy = solved("cubes/p2")
    d = policy.to_dict()
    first, second = d["nodes"][0]["moves"][:2]
    second["action"] = first["action"]
    report = walk_policy(problem, Policy.from_dict(d))
    assert not report.ok and report.branches == 0
    assert report.message == (f"branch 1 (no move): policy node 0 covers H {first['action']} "
                              "more than once: a robot that sees only the action cannot tell "
                              "its branches apart")


def test_a_problem_with_a_fixed_opening_walks_from_where_the_opening_ends() -> None:
    problem, policy = solved("cubes/qualitative")
    assert problem.after
    report = walk_policy(problem, policy)
    assert report.ok and report.branches == policy.leaves
    other = dataclasses.replace(problem, after=())
    assert not walk_policy(other, policy).ok  # planned after the opening: it does not fit


# -- moves that share a label ------------------------------------------------------------------


def fetching() -> Problem:
    """The robot tidies by one of two methods that both start with ``fetch``: ``piling`` (then
    ``pile``, which needs what never holds) or ``shelving`` (then ``shelve``). After ``fetch``
    the two moves lead to different nodes; only shelving's reaches the goal."""
    d = Domain("fetching")
    fetched, shelved = d.predicate("fetched"), d.predicate("shelved")
    piled, steady = d.predicate("piled"), d.predicate("steady")
    r = d.robot
    fetch = r.action("fetch", pre=~fetched(), effects=[fetched()])
    pile = r.action("pile", pre=fetched() & steady(), effects=[piled()])
    shelve = r.action("shelve", pre=fetched(), effects=[shelved()])
    tidy = r.task("tidy")
    r.method(tidy, "piling", subtasks=[fetch(), pile()])
    r.method(tidy, "shelving", subtasks=[fetch(), shelve()])
    return scenario(d, init=[], robot=["tidy"], objects={}, starts="robot")


def test_a_robot_move_that_shares_its_label_is_followed_along_the_policy_s_edge() -> None:
    p = fetching()
    result = ehatp.solve(p)
    assert result.policy is not None
    policy = result.policy
    root = policy.root
    (edge,) = root.moves
    assert edge.action == "fetch"
    ex = Executor(p, policy)
    fetches = [m for m in ex.sem.moves(ex.state) if m.label == "fetch"]
    # one per method, piling's first: the first move with the label is the dead end
    rests = [m.child.robot_agenda if m.child else None for m in fetches]
    assert [ex.sem.net.names_of(r) for r in rests if r is not None] == [["pile"], ["shelve"]]
    assert ex.edge_move(root, edge) == fetches[1]
    step = ex.robot_action_done("fetch")
    assert step.node is not None and step.node.robot_agenda == ["shelve"]
    report = walk_policy(p, policy)
    assert report.ok and report.branches == policy.leaves, report.message
    bt.answers_of(p, policy)  # walks every node along the policy's edges too
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    ticked = tick_py_trees(p, policy)
    assert ticked.ok and ticked.branches == policy.leaves, ticked.message


# -- the moves of hidden intentions and of the new ways to talk ---------------------------------


def errand(**kw: object) -> Problem:
    """The robot sweeps (leaving no trace) while the human is out: back home, the human's worlds
    differ only in the robot's agenda (swept or not), which no ``inform`` can tell; with
    ``announce`` the robot says it has nothing left to do (docs/semantics.md §5)."""
    d = Domain("errand")
    Place = d.type("place")
    p, q = Var("p", Place), Var("q", Place)
    at = d.predicate("at", p)
    d.copresence = at("home")
    d.robot.action("sweep", pre=at("out"), effects=[])
    d.human.action("go", p, q, pre=at(p) & ~at(q), effects=[at(q), ~at(p)])
    return scenario(d, init=["at(home)"], robot=["sweep"],
                    human=["go(home, out)", "go(out, home)"], objects={"place": ["home", "out"]},
                    **kw)  # type: ignore[arg-type]


OPTIONS = {  # a problem, and a move kind (or label) its policy must use
    "visible intentions": (lambda: shelf_problem(
        human_model=HumanModel(intentions=Intentions.VISIBLE)), "grab [place(l)]"),
    "robot asks": (lambda: shelf_problem(communication=Communication(robot_asks=True)),
                   "answer"),
    "announce": (lambda: errand(communication=Communication(announce=True)), "announce"),
    "speech with an action": (lambda: car_problem(communication=Communication(
        speech=Speech.WITH_ACTION)), "inform(oil_ok) + refill"),
}


@pytest.mark.parametrize("case", list(OPTIONS))
def test_policies_that_ask_answer_announce_or_speak_with_an_action_walk_and_tick(
        case: str) -> None:
    make, uses = OPTIONS[case]
    p = make()
    result = ehatp.solve(p)
    assert result.policy is not None, result.reason
    policy = result.policy
    assert any(uses in (m.kind, m.action) for _, m in policy.edges())
    report = walk_policy(p, policy)
    assert report.ok and report.branches == policy.leaves, report.message
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    ticked = tick_py_trees(p, policy)
    assert ticked.ok and ticked.branches == policy.leaves, ticked.message


def explained(p: Problem, *human: str) -> list[str]:
    """The executor's explanation of every step of the branch where the human plays
    ``human``, in order (the robot plays the policy)."""
    result = ehatp.solve(p)
    assert result.policy is not None
    ex = Executor(p, result.policy)
    moves = list(human)
    out: list[str] = []
    while not ex.done:
        step = (ex.robot_action_done() if ex.next_robot_action() is not None
                else ex.observe_human_action(moves.pop(0)))
        out += [f"{step.action.agent} {step.action.label}", *ex.explain(step)]
    assert ex.goal_reached and not moves
    return out


def test_the_executor_explains_questions_answers_and_announcements() -> None:
    lines = explained(shelf_problem(communication=Communication(robot_asks=True)),
                      "grab", "answer(place(r))", "pass", "place(r)")
    assert "R ask(intention)" in lines and "R asks H what H is about to do" in lines
    assert "H answers R: place(r); R now knows H's intention" in lines
    assert any(x.startswith("R cannot tell which of 2 intentions H follows: ") for x in lines)
    lines = explained(errand(communication=Communication(announce=True)),
                      "go(home, out)", "go(out, home)")
    assert "R tells H what it is doing: nothing more (2 -> 1 world)" in lines


# -- the imported IPC-2020 domains (conftest.IPC_VALIDATED; the lifted ones: test_policy_v3) ---


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*deprecated - use:DeprecationWarning")
@pytest.mark.parametrize("name", [n for n in IPC_VALIDATED if n not in IPC_LIFTED])
def test_every_imported_ipc_domain_that_validates_walks_to_the_goal(name: str) -> None:
    pytest.importorskip("unified_planning", reason="ehatp[hddl] (unified-planning) not installed")
    from ehatp.experiments import hddl_report
    from ehatp.formats import hddl

    shipped = {n: (d, p) for n, d, p in hddl_report.domains_shipped()}
    d, pf = shipped[name]
    # as the report imports them (hddl_report.check_domain): the human expects nothing of the robot
    p = hddl.import_hddl(d, pf, sidecar=hddl.Sidecar(expects="nothing")).problem()
    result = ehatp.solve(p, timeout=120)
    assert result.policy is not None, result.reason
    assert ehatp.validate(p, result.policy).ok
    report = walk_policy(p, result.policy)
    assert report.ok and report.branches == result.policy.leaves, report.message
