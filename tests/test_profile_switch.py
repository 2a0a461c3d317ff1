"""Switching preference profile in the middle of an execution (C11, docs/concurrent.md
"Relabelling"): a robot that learns the human's preferences during the task relabels the kept
graph from where it is, without a new search, and follows the new profile's policy from the
current state on. Every figure was derived by hand from the rules before the planner was run;
the derivation is in each test's docstring."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
from pathlib import Path
from typing import Any

import pytest

import ehatp
from ehatp import Problem
from ehatp.errors import ExecutionError
from ehatp.formats.policy import Policy
from ehatp.model.options import Estimate
from ehatp.run.executor import Executor
from ehatp.run.walk import positions, walk_from, walk_policy
from ehatp.search import planner
from ehatp.search.planner import Result

from .test_concurrent import JOINT, chores, two_hands
from .test_execute import lines, session
from .test_preferences import PROFILES, helper, p2, prefer

WARMUP = Path(__file__).parent / "data" / "warmup.py"  # the domain


def warmup() -> Problem:
    """:func:`tests.test_preferences.helper` after a first step: the robot must first warm
    ``b`` (``warm(b)``, its task ``prep``, before ``work``), and the human can put ``b`` only
    once it is warm (``hput(x)`` needs ``ready(x)``). Always co-present, the human first."""
    spec = importlib.util.spec_from_file_location("warmup_domain", WARMUP)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    d = module.domain
    return Problem(name="warmup", domain=d, objects={}, init=frozenset(),
                   robot_agenda=(("prep", ()), ("work", ())),
                   human_agenda=(("help", ("b",)),), steps=JOINT)


def kept(p: Problem) -> Result:
    """``p`` solved with its graph kept; the policy validated and walked."""
    r = ehatp.solve(p, keep_graph=True)
    assert r.policy is not None and r.graph is not None, r.reason
    assert ehatp.validate(p, r.policy).ok
    assert walk_policy(p, r.policy).ok
    return r


def play(ex: Executor, *humans: str) -> list[str]:
    """Play whole steps: each human move given, then the robot's reply; return the replies."""
    out = []
    for h in humans:
        ex.observe_human_action(h)
        action = ex.next_robot_action()
        assert action is not None
        out.append(action.label)
        ex.robot_action_done(action.label)
    return out


def shape(policy: Policy, start: int = 0) -> list[dict[str, Any]]:
    """The sub-policy from node ``start``, node by node in a depth-first order of its own (ids
    renumbered, each move's target by the new number), each node with its vector: two policies
    are the same from two nodes when their shapes are equal."""
    vectors = policy.objective.get("vectors")
    order: list[int] = []
    seen: set[int] = set()
    stack = [start]
    while stack:
        n = stack.pop()
        if n in seen:
            continue
        seen.add(n)
        order.append(n)
        stack.extend(reversed(policy.nodes[n].children))
    number = {n: i for i, n in enumerate(order)}
    out = []
    for n in order:
        d = policy.nodes[n].to_dict()
        d.pop("id")
        for m in d["moves"]:
            m["to"] = number[m["to"]]
        d["vector"] = None if vectors is None else vectors[n]
        out.append(d)
    return out


def state_nodes(p: Problem, policy: Policy) -> dict[Any, int]:
    """Each epistemic state an executor of ``policy`` tracks, and the policy node it is at:
    every branch walked (how a test finds a state's node in a fresh solve's policy)."""
    out: dict[Any, int] = {}
    start = Executor(p, policy)
    start.replay_opening()
    stack = [start]
    while stack:
        ex = stack.pop()
        assert ex.node is not None
        out[ex.state] = ex.node.id
        if ex.done:
            continue
        if ex.next_robot_action() is not None:
            ex.robot_action_done()
            stack.append(ex)
            continue
        for label in [m.action for m in ex.node.moves]:
            other = ex.copy()
            other.observe_human_action(label)
            stack.append(other)
    return out


def check_switch(ex: Executor, policy: Policy) -> None:
    """The relabelled ``policy`` ex now follows: rooted at the current state, its opening the
    history; valid as a policy of ``ex.problem`` (the execution so far with the new profile:
    ``as_problem()``), node by node the policy a fresh solve of that problem gives, and every
    branch from the switch reaches the goal through the executor."""
    assert ex.policy is policy
    assert policy.after == [s.played for s in ex.history] == list(ex.problem.after)
    assert ex.as_problem().after == ex.problem.after
    report = ehatp.validate(ex.problem, policy)
    assert report.ok, report.message
    fresh = ehatp.solve(ex.as_problem()).policy
    assert fresh is not None
    assert shape(policy) == shape(fresh)
    assert policy.objective == fresh.objective
    walked = walk_from(ex)
    assert walked.ok, str(walked)
    assert walk_policy(ex.problem, policy).ok


def test_after_a_switch_at_a_step_start_the_robot_replies_as_the_new_profile(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """By hand, on :func:`warmup`. Root: ``hput(b)`` needs ``ready(b)``, so the human has
    nothing it could do and passes (C5); the robot's only reply is ``warm(b)`` ((pass, wait)
    is no step; the human's one world is the truth: nothing to inform). That step is forced
    under every profile, and leads to S1, the helper's root (tests/test_preferences.py) with
    ``b`` warm: ``hput(b)`` -> ``put(a)`` (1 step); pass -> ``hurry`` puts ``a`` (then
    ``(hput(b), wait)``), ``lazy_human`` grabs ``b`` (then ``(pass, put(a))``, ``(pass,
    drop(b))``).
    Executed under ``hurry``: (pass, warm(b)), then the switch to ``lazy_human`` at S1 (a
    decision node). The human passes: the robot now grabs ``b`` (``hurry`` would put ``a``),
    then puts ``a`` and drops ``b`` on the next two passes (switching back to ``hurry``
    after the grab changes nothing: from there both profiles do the same): the goal in 4
    steps. The
    relabelled policy from S1 has ``lazy_human``'s vector (human_effort, makespan) at S1:
    max{(1, 1) by hput(b), (0, 3) by pass} = (1, 1), and S1 is in ``lazy_human``'s policy
    from the root (after its forced first step), so it is that policy's sub-policy there."""
    r = kept(prefer(warmup(), "hurry"))
    assert r.policy is not None and r.graph is not None
    ex = Executor(r.graph.problem, r.policy)
    assert play(ex, "pass") == ["warm(b)"]

    def no_search(*args: object, **kwargs: object) -> None:
        raise AssertionError("switching profile searched again")

    with monkeypatch.context() as m:  # relabelled on the kept graph: no new search
        m.setattr(planner, "search", no_search)
        policy = ex.switch_profile(r, "lazy_human")
    assert policy.objective["profile"] == "lazy_human" == ex.problem.objective.profile
    assert policy.objective["value"] == [1, 1]
    assert [s.played for s in ex.history] == ["H pass", "R warm(b)"]  # the history is kept
    check_switch(ex, policy)
    lazy = kept(prefer(warmup(), "lazy_human")).policy
    assert lazy is not None
    at = state_nodes(prefer(warmup(), "lazy_human"), lazy)[ex.state]
    assert shape(policy) == shape(lazy, at)
    assert play(ex, "pass") == ["grab(b)"]
    # and back: from S2 (b held) the human can only pass, the robot puts a, then drops b,
    # whatever the profile: hurry's (makespan, human_effort) from there is (2, 0)
    back = ex.switch_profile(r, "hurry")
    assert back.objective["value"] == [2, 0] and ex.problem.objective.profile == "hurry"
    check_switch(ex, back)
    assert play(ex, "pass", "pass") == ["put(a)", "drop(b)"]
    assert ex.done and ex.goal_reached and len(ex.history) == 8


@pytest.mark.parametrize(("first", "then", "humans", "replies", "vector", "nodes"), [
    # lazy grabs b after the pass; hurry, from the root, puts a there: held(b) is none of
    # its states. From S2 (b held) the human can only pass; the robot puts a, then drops b:
    # hurry's (makespan, human_effort) = (2, 0); 5 nodes (decision, reply, decision, reply,
    # goal)
    ("lazy_human", "hurry", ("pass",), ["grab(b)"], [2, 0], 5),
    # hurry puts a after the pass; lazy, from the root, grabs b there. From S2' (a placed)
    # the robot is done, so the human may not pass (C5): (hput(b), wait); lazy's
    # (human_effort, makespan) = (1, 1); 3 nodes
    ("hurry", "lazy_human", ("pass",), ["put(a)"], [1, 1], 3),
])
def test_a_switch_from_a_state_the_new_profile_never_reaches_plans_from_it(
        first: str, then: str, humans: tuple[str, ...], replies: list[str],
        vector: list[int], nodes: int) -> None:
    """By hand, on :func:`warmup` (the derivation of the test above): after the forced
    (pass, warm(b)) and one more step under the first profile, the state is not in the
    second profile's policy from the root, so relabelling from the root would not do; the
    policy relabelled from the state is the one a fresh solve of the execution so far gives
    (figures in the parameters' comments), validated as that problem and walked to the goal on
    every branch from the switch."""
    r = kept(prefer(warmup(), first))
    assert r.policy is not None and r.graph is not None
    ex = Executor(r.graph.problem, r.policy)
    assert play(ex, "pass", *humans) == ["warm(b)", *replies]
    other = kept(prefer(warmup(), then)).policy
    assert other is not None
    assert ex.state not in state_nodes(prefer(warmup(), then), other)
    policy = ex.switch_profile(r.graph, then)
    assert (policy.objective["value"], len(policy.nodes)) == (vector, nodes)
    check_switch(ex, policy)


ROBOT_FIRST = dataclasses.replace(JOINT, first=ehatp.StepFirst.ROBOT)
PROBLEMS = {"e1": lambda: chores(JOINT), "e2": lambda: two_hands(JOINT), "helper": helper,
            "warmup": warmup, "e2-robot-first": lambda: two_hands(ROBOT_FIRST),
            "warmup-robot-first": lambda: dataclasses.replace(warmup(), steps=ROBOT_FIRST)}


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_switching_at_every_step_start_gives_the_fresh_solve_from_there(name: str) -> None:
    """C11, on every step start (decision node: the human's, or the robot's when it decides
    first) of every profile's policy, to every profile, both estimates (a switch in the middle
    of a step is refused): the policy relabelled there is valid for the execution so far
    with the new profile, the one its fresh solve gives node by node, and every branch from
    the switch reaches the goal; where the new profile's own policy from the root reaches
    that state, it is that policy's sub-policy there, node by node."""
    switches = 0
    for estimate in Estimate:
        for old in PROFILES:
            p = prefer(PROBLEMS[name](), old, estimate)
            r = kept(p)
            assert r.policy is not None
            fresh = {new: kept(prefer(PROBLEMS[name](), new, estimate)).policy
                     for new in PROFILES}
            where = {new: state_nodes(prefer(PROBLEMS[name](), new, estimate), pol)
                     for new, pol in fresh.items() if pol is not None}
            for ex in positions(Executor(p, r.policy)):
                for new in PROFILES:
                    other = ex.copy()
                    if ex.state.pending:  # mid-step: refused
                        with pytest.raises(ExecutionError, match="middle of a step"):
                            other.switch_profile(r, new)
                        continue
                    policy = other.switch_profile(r, new)
                    check_switch(other, policy)
                    switches += 1
                    at = where[new].get(other.state)
                    if at is not None:
                        pol = fresh[new]
                        assert pol is not None
                        assert shape(policy) == shape(pol, at)
    assert switches >= 2 * len(PROFILES) ** 2


def test_a_switch_is_refused_in_one_clear_error_where_it_cannot_be_made() -> None:
    """Each refusal is one :class:`ExecutionError` naming the reason, and nothing changes:
    in the middle of a step (the human passed, the robot's reply is due); an unknown profile
    (the known ones named); a problem without preference profiles; no graph kept; during
    the fixed opening; once the task is done; a state the kept graph does not hold (the graph
    of the problem played from S1, :func:`warmup`'s second step, holds no root S0); the graph
    of another problem; a graph whose problem lacks the profile."""
    p = prefer(warmup(), "hurry")
    r = kept(p)
    assert r.policy is not None and r.graph is not None
    ex = Executor(p, r.policy)

    def refused(says: str, on: Executor, graph: Any = r, profile: str = "lazy_human") -> None:
        before = (on.policy, on.problem, on.node, list(on.history))
        with pytest.raises(ExecutionError, match=says) as e:
            on.switch_profile(graph, profile)
        assert "\n" not in str(e.value)
        assert (on.policy, on.problem, on.node, list(on.history)) == before

    refused("no profile 'shy': the problem names effort, end, hurry, lazy_human, quiet",
            ex, profile="shy")
    ex.observe_human_action("pass")
    refused("in the middle of a step", ex)
    plain = ehatp.solve(warmup(), keep_graph=True)
    assert plain.policy is not None and plain.graph is None
    refused('kind is "worst-case", not "preferences"', Executor(warmup(), plain.policy))
    refused("no explored graph was kept", Executor(p, r.policy),
            graph=ehatp.solve(p))
    later = dataclasses.replace(p, after=("H pass", "R warm(b)"))
    r1 = kept(later)
    assert r1.policy is not None
    refused("opening is still being played", Executor(later, r1.policy))
    refused("not in the kept graph .* plan again from here", Executor(p, r.policy), graph=r1)
    done = Executor(p, r.policy)
    play(done, "pass", "hput(b)")
    assert done.done
    refused("the task is done", done)
    refused("the kept graph is of problem 'helper', not of this execution's 'warmup'",
            Executor(p, r.policy), graph=kept(prefer(helper(), "hurry")))
    fewer = dataclasses.replace(p, objective=dataclasses.replace(
        p.objective, profiles={"hurry": PROFILES["hurry"]}))
    refused("cannot switch to profile 'lazy_human': no profile 'lazy_human': the problem "
            "names hurry", Executor(p, r.policy), graph=kept(fewer))


def test_a_profile_line_switches_the_execution_over_the_protocol(tmp_path: Any) -> None:
    """``{"profile": NAME}`` in ``ehatp execute`` (docs/execution.md), on :func:`warmup`
    under ``hurry`` (the derivation above): after (pass, warm(b)) the line switches to
    ``lazy_human``: a ``switched`` line (after 2 moves; the vector (1, 1) of the policy from
    S1; its worst-case cost 3, the pass branch's 3 steps; 9 nodes: S1, the reply to
    ``hput(b)``, its goal, the reply to the pass, S2 (b held), its reply, S3, its reply and
    its goal, another node than the first goal: the true state is the same, but after
    ``drop(b)`` the human's agenda still holds ``help(b)``, done but not consumed, since only
    the human's own moves progress it, §1), then the waiting line again; the human passes
    and the robot grabs
    ``b``; the goal after 8 moves. Refused as ``bad-request``: a profile that is not a
    string, one the problem does not name; as ``wrong-turn``: in the middle of a step. With
    ``--save-replans`` the relabelled policy is written (``profile-1.json``): a valid policy
    of the problem played up to the switch with ``lazy_human`` chosen."""
    p = prefer(warmup(), "hurry")
    r = kept(p)
    assert r.policy is not None
    code, out = session(Executor(p, r.policy), lines(
        {"human": "pass"}, {"profile": "lazy_human"}, {"robot_done": "warm(b)"},
        {"profile": 3}, {"profile": "shy"}, {"profile": "lazy_human"}, {"human": "pass"},
        {"robot_done": "grab(b)"}, {"human": "pass"}, {"robot_done": True},
        {"human": "pass"}, {"robot_done": True}), graph=r.graph, save=tmp_path)
    errors = [(m["error"], m["line"]) for m in out if "error" in m]
    assert errors == [("wrong-turn", 2), ("bad-request", 4), ("bad-request", 5)]
    [switched] = [m["switched"] for m in out if "switched" in m]
    written = Policy.read(switched.pop("policy"))  # --save-replans: profile-1.json
    after = dataclasses.replace(prefer(warmup(), "lazy_human"), after=("H pass", "R warm(b)"))
    assert written.after == ["H pass", "R warm(b)"] and ehatp.validate(after, written).ok
    assert switched == {"profile": "lazy_human", "after": 2, "cost": 3, "nodes": 9,
                        "metrics": ["human_effort", "makespan"], "value": [1, 1]}
    assert [m["robot"]["action"] for m in out if "robot" in m] == [
        "warm(b)", "grab(b)", "put(a)", "drop(b)"]
    assert code == 0 and out[-1] == {"goal": True, "steps": 8, "cost": 4}


def test_a_profile_line_on_a_problem_without_profiles_is_a_bad_request() -> None:
    r = ehatp.solve(warmup())
    assert r.policy is not None
    _, out = session(Executor(warmup(), r.policy), lines({"profile": "hurry"}))
    [err] = [m for m in out if "error" in m and m["error"] != "end-of-input"]
    assert err["error"] == "bad-request" and "no preference profiles" in err["message"]


def test_ehatp_execute_keeps_the_graph_of_a_preferences_problem(tmp_path: Any) -> None:
    """``ehatp execute`` on Table 1 P2 in joint steps with profiles: a ``profile`` line at
    the first step start switches (a ``switched`` line, then the waiting line again), an
    unknown one is one ``bad-request`` line."""
    from .test_execute import ehatp_cli, numbered

    f = p2(tmp_path)
    got = ehatp_cli("execute", f, stdin=lines({"profile": "nobody"},
                                              {"profile": "lazy_human"}))
    out = numbered(got.stdout)
    assert got.returncode == 1, got.stderr
    kinds = [next(iter(m)) for m in out]
    assert kinds[:3] == ["start", "beliefs", "waiting"]
    assert out[3]["error"] == "bad-request" and "early, hurry, lazy_human" in out[3]["message"]
    assert out[4]["switched"]["profile"] == "lazy_human" and out[4]["switched"]["after"] == 0
    assert "waiting" in out[5] and out[6]["error"] == "end-of-input"


def test_ehatp_execute_with_a_policy_and_no_keep_graph_searches_nothing(
        tmp_path: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    """``--no-keep-graph`` with ``--policy``: the policy is followed with no search at the
    start (the planner, patched to fail, is never called), and a ``profile`` line is one
    ``no-relabel`` error saying why; without the flag the same command searches once."""
    from typer.testing import CliRunner

    from ehatp.cli.app import app

    f = p2(tmp_path)
    pol = tmp_path / "p.json"
    ehatp.solve(ehatp.load(f)).policy.write(pol)

    calls: list[bool] = []

    def no_search(*args: Any, **kw: Any) -> Any:
        calls.append(kw.get("keep_graph", False))
        raise AssertionError("searched")

    monkeypatch.setattr(planner, "solve", no_search)
    got = CliRunner().invoke(app, ["execute", str(f), "--policy", str(pol), "--no-keep-graph"],
                             input=lines({"profile": "lazy_human"}))
    out = [json.loads(x) for x in got.stdout.splitlines()]
    assert got.exit_code == 1, got.output
    assert [next(iter(m)) for m in out][:3] == ["start", "beliefs", "waiting"]
    assert out[3]["error"] == "no-relabel" and "--no-keep-graph" in out[3]["message"]
    assert calls == []
    CliRunner().invoke(app, ["execute", str(f), "--policy", str(pol)],
                       input=lines({"profile": "lazy_human"}))
    assert calls == [True]


def test_a_replan_keeps_its_own_graph_for_the_next_profile_line() -> None:
    """On :func:`warmup` under ``hurry``: the robot's ``warm(b)`` fails (it did not happen),
    so execute plans again from the same state (the reply node after the human's pass: its
    only reply is ``warm(b)`` again) and keeps that search's graph; once the step is done, a
    ``profile`` line relabels the new graph: ``lazy_human`` from S1, (1, 1), and the robot
    grabs ``b`` on the human's pass."""
    from ehatp.run.execute import Session

    p = prefer(warmup(), "hurry")
    r = kept(p)
    assert r.policy is not None
    out: list[dict[str, Any]] = []
    s = Session(Executor(p, r.policy), out.append, replan=False, graph=r.graph)
    s.start("test")
    for i, msg in enumerate(({"human": "pass"}, {"robot_failed": "warm(b)"},
                             {"robot_done": "warm(b)"}, {"profile": "lazy_human"},
                             {"human": "pass"}), 1):
        s.handle(lines(msg), i)
    assert s.graph is not None and s.graph is not r.graph
    assert s.graph.problem.after == ("H pass",)  # planned from the reply node
    assert [m["replanned"]["outcome"] for m in out if "replanned" in m] == [None]
    [switched] = [m["switched"] for m in out if "switched" in m]
    assert (switched["after"], switched["value"]) == (2, [1, 1])
    assert [m["robot"]["action"] for m in out if "robot" in m] == [
        "warm(b)", "warm(b)", "grab(b)"]
    assert not [m for m in out if "error" in m]


def test_relabelling_from_the_moves_alone_needs_no_executor() -> None:
    """``Relabeler.relabel(profile, after=moves)`` replays the moves through the search's
    semantics and relabels from the state they reach: on :func:`warmup`, after (pass,
    warm(b)), (pass, grab(b)) ``hurry`` from S2 is (pass, put(a)), (pass, drop(b)): vector
    (2, 0), 5 nodes (derived above), the executor's switch there node for node. Moves that
    cannot be played, that reach another state than ``at``, or ``at`` without them, are one
    ``ValueError`` each."""
    p = prefer(warmup(), "lazy_human")
    r = kept(p)
    assert r.policy is not None and r.graph is not None
    moves = ("H pass", "R warm(b)", "H pass", "R grab(b)")
    policy = r.graph.relabel("hurry", after=moves)
    assert (policy.objective["value"], len(policy.nodes)) == ([2, 0], 5)
    assert policy.after == list(moves)
    later = dataclasses.replace(prefer(warmup(), "hurry"), after=moves)
    assert ehatp.validate(later, policy).ok and walk_policy(later, policy).ok
    ex = Executor(p, r.policy)
    play(ex, "pass", "pass")
    assert shape(ex.switch_profile(r, "hurry")) == shape(policy)
    with pytest.raises(ValueError, match=r"move 2, 'R put\(a\)'"):
        r.graph.relabel("hurry", after=("H pass", "R put(a)"))
    with pytest.raises(ValueError, match="do not reach the state given"):
        r.graph.relabel("hurry", at=ex.state, after=moves[:2])
    with pytest.raises(ValueError, match="needs after="):
        r.graph.relabel("hurry", at=ex.state)
