"""Objectives for joint action (C11, docs/concurrent.md "Preferences"): named lexicographic
profiles over per-branch metrics, worst-case or optimistic, and relabelling a kept graph for
another profile. Every figure was derived by hand from the rules before the planner was run;
the derivation is in each test's docstring."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

import ehatp
from ehatp import Domain, InputError, Problem, Var
from ehatp.formats.policy import Policy
from ehatp.model.options import Estimate, Metric, Objective, ObjectiveKind
from ehatp.search.planner import relabel

from .conftest import EXAMPLES_DIR as EXAMPLES
from .test_concurrent import JOINT, chores, drawer, replies, solved, two_hands

PROFILES = {
    "lazy_human": (Metric.HUMAN_EFFORT, Metric.MAKESPAN),
    "hurry": (Metric.MAKESPAN, Metric.HUMAN_EFFORT),
    "end": (Metric.HUMAN_END, Metric.MAKESPAN),
    "effort": (Metric.EFFORT, Metric.COMMUNICATIONS),
    "quiet": (Metric.COMMUNICATIONS, Metric.MAKESPAN),
}


def relabelled_as_fresh(p: Problem, profiles: dict[str, tuple[str, ...]],
                        estimate: Estimate, seed: int) -> dict[str, Policy] | None:
    """C11: ``p`` with ``kind = "preferences"`` over ``profiles`` (the first chosen), solved
    once with its graph kept, then relabelled for each profile: each policy valid for the
    problem with that profile chosen and the JSON of a fresh solve of it (``seed`` names the
    problem in a failure). Return the policies by profile, or None when ``p`` has none."""
    q = dataclasses.replace(p, objective=Objective(
        ObjectiveKind.PREFERENCES, profile=next(iter(profiles)), profiles=profiles,
        estimate=estimate))
    kept = ehatp.solve(q, keep_graph=True, max_states=20000)
    if kept.policy is None:
        return None
    out = {}
    for name in profiles:
        mine = dataclasses.replace(q, objective=q.objective.with_profile(name))
        policy = relabel(kept, name)
        report = ehatp.validate(mine, policy)
        assert report.ok, (seed, name, report.message)
        fresh = ehatp.solve(mine, max_states=20000).policy
        assert fresh is not None
        assert "".join(fresh.iter_json()) == "".join(policy.iter_json()), (seed, name)
        out[name] = policy
    return out


def prefer(p: Problem, profile: str, estimate: Estimate = Estimate.WORST_CASE) -> Problem:
    """``p`` with ``[objective] kind = "preferences"`` and ``profile`` chosen."""
    return dataclasses.replace(p, objective=Objective(
        ObjectiveKind.PREFERENCES, profile=profile, profiles=PROFILES, estimate=estimate))


def helper() -> Problem:
    """Two things, ``a`` and ``b``, always co-present, the human first. The robot's task
    ``work`` has two methods: ``share``, put ``a`` (one action), or ``all``, grab ``b``, put
    ``a``, drop ``b`` in its place (three actions: ``b`` is placed by the robot). The human's
    task is to have ``b`` placed (done once it is): ``hput(b)``, only while ``b`` is on the
    table (neither placed nor held)."""
    d = Domain("helper", robot="R", human="H")
    thing = d.type("thing")
    x = Var("x", thing)
    a, b = d.constant("a", thing), d.constant("b", thing)
    placed, held = d.predicate("placed", x), d.predicate("held", x)
    put = d.robot.action("put", x, pre=~placed(x), effects=[placed(x)], resources=[x])
    grab = d.robot.action("grab", x, pre=~placed(x) & ~held(x), effects=[held(x)],
                          resources=[x])
    drop = d.robot.action("drop", x, pre=held(x), effects=[~held(x), placed(x)],
                          resources=[x])
    work = d.robot.task("work")
    d.robot.method(work, "share", subtasks=[put(a)])
    d.robot.method(work, "all", subtasks=[grab(b), put(a), drop(b)])
    hput = d.human.action("hput", x, pre=~placed(x) & ~held(x), effects=[placed(x)],
                          resources=[x])
    task = d.human.task("help", x, done=placed(x))
    d.human.method(task, "put", subtasks=[hput(x)])
    return Problem(name="helper", domain=d, objects={}, init=frozenset(),
                   robot_agenda=(("work", ()),), human_agenda=(("help", ("b",)),),
                   steps=JOINT)


def run(p: Problem) -> tuple[Policy, list[object]]:
    """Solve ``p`` (validated, walked), and return the policy and its root vector."""
    policy = solved(p)
    return policy, policy.objective["value"]


def test_two_profiles_choose_different_replies_when_the_human_passes() -> None:
    """By hand, on :func:`helper`. Root (the human decides first, C4): ``hput(b)``, or pass
    (co-present, the robot has a real action, C5).
    - ``hput(b)``: ``grab(b)`` is no reply (not applicable after it, C3 a), so ``put(a)``
      (``share``) ends it: 1 step; human_effort 1, makespan 1, human_end 1.
    - ``pass``: (pass, wait) is no step, so the robot puts ``a`` (``share``) or grabs ``b``
      (``all``).
      - ``share``: the robot is done, so the human may not pass (C5): (hput(b), wait), 2
        steps; human_effort 1, makespan 2, human_end 2 (its action is in step 2).
      - ``all``: ``b`` is held, so the human, blocked, passes; (pass, put(a)), (pass,
        drop(b)): 3 steps; human_effort 0, makespan 3, human_end 0.
    ``lazy_human`` (human_effort, makespan), worst case: share (1, 2) against all (0, 3): the
    robot grabs ``b``; the root is max{(1, 1), (0, 3)} = (1, 1). ``hurry`` (makespan,
    human_effort): share (2, 1) against all (3, 0): it puts ``a``; the root is max{(1, 1),
    (2, 1)} = (2, 1). ``end`` (human_end, makespan): share (2, 2) against all (0, 3): it grabs
    ``b``; root (1, 1). The default objective (worst case 2 against 3) puts ``a``.
    Optimistic (the best branch): ``lazy_human`` grabs (root min{(1, 1), (0, 3)} = (0, 3));
    ``hurry`` puts (root min{(1, 1), (2, 1)} = (1, 1))."""
    grab = {("hput(b)",): "put(a)", ("pass",): "grab(b)", ("pass", "pass"): "put(a)",
            ("pass", "pass", "pass"): "drop(b)"}
    put = {("hput(b)",): "put(a)", ("pass",): "put(a)", ("pass", "hput(b)"): "wait"}
    assert replies(solved(helper())) == put
    for profile, estimate, want, value in (
            ("lazy_human", Estimate.WORST_CASE, grab, [1, 1]),
            ("hurry", Estimate.WORST_CASE, put, [2, 1]),
            ("end", Estimate.WORST_CASE, grab, [1, 1]),
            ("lazy_human", Estimate.OPTIMISTIC, grab, [0, 3]),
            ("hurry", Estimate.OPTIMISTIC, put, [1, 1])):
        policy, got = run(prefer(helper(), profile, estimate))
        assert (profile, replies(policy), got) == (profile, want, value)
        assert policy.objective["profile"] == profile
        assert policy.objective["estimate"] == str(estimate)


def test_e2_lazy_human_and_makespan() -> None:
    """E2 (one cube, two hands) by hand. Root: ``pick(c)``, or pass.
    - ``pick(c)``: the robot can only wait (C3), then the human places: 2 steps, both the
      human's: human_effort 2, makespan 2.
    - ``pass``: the robot picks ((pass, wait) is no step), the human, blocked, passes, the
      robot places: 2 steps, human_effort 0.
    ``lazy_human``: the robot picks when the human passes (its only reply); the worst branch
    is the human's own pick: (2, 2); optimistic, the pass branch: (0, 2). ``hurry``
    (makespan, human_effort): (2, 2) worst, (2, 0) optimistic. Every profile keeps E2's
    compliant replies (pick -> wait, pass -> pick): the makespan profile ties with the lazy
    one."""
    want = {("pick(c)",): "wait", ("pick(c)", "place(c)"): "wait", ("pass",): "pick(c)",
            ("pass", "pass"): "place(c)"}
    for profile, estimate, value in (("lazy_human", Estimate.WORST_CASE, [2, 2]),
                                     ("lazy_human", Estimate.OPTIMISTIC, [0, 2]),
                                     ("hurry", Estimate.WORST_CASE, [2, 2]),
                                     ("hurry", Estimate.OPTIMISTIC, [2, 0])):
        policy, got = run(prefer(two_hands(JOINT), profile, estimate))
        assert (replies(policy), got) == (want, value)


def test_e1_and_e3_vectors() -> None:
    """E1 (two chores) by hand: ``put(b)`` -> (put(b), put(a)), 1 step, the human acting in
    it; ``pass`` -> (pass, put(a)), (put(b), wait): 2 steps, the human acting in step 2.
    ``end`` (human_end, makespan): worst (2, 2); ``lazy_human``: worst (1, 2) (the human acts
    once on each branch; the longer branch is the worse); ``effort`` (both agents' actions,
    communications): 2 on each branch: (2, 0).
    E3 with a human who cannot ask (spec figures, tests/test_concurrent.py): holding costs 4
    steps and no communication, moving at once 4 steps and an inform. ``quiet``
    (communications, makespan): the robot holds, (0, 4)."""
    assert run(prefer(chores(JOINT), "end"))[1] == [2, 2]
    assert run(prefer(chores(JOINT), "lazy_human"))[1] == [1, 2]
    assert run(prefer(chores(JOINT), "effort"))[1] == [2, 0]
    policy, value = run(prefer(drawer(JOINT, ask=False), "quiet"))
    assert value == [0, 4] and replies(policy)[("leave",)] == "wait"


def same_bytes(a: Policy, b: Policy, tmp_path: Path) -> bool:
    a.write(tmp_path / "a.json")
    b.write(tmp_path / "b.json")
    return (tmp_path / "a.json").read_bytes() == (tmp_path / "b.json").read_bytes()


PROBLEMS = {"e1": lambda: chores(JOINT), "e2": lambda: two_hands(JOINT),
            "e3": lambda: drawer(JOINT), "e3-no-ask": lambda: drawer(JOINT, ask=False),
            "helper": helper}


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_relabelling_gives_the_fresh_solve_byte_for_byte(name: str, tmp_path: Path) -> None:
    """C11: one search, relabelled for every profile and both estimates, gives exactly the
    policy a fresh solve with that profile writes."""
    for estimate in Estimate:
        kept = ehatp.solve(prefer(PROBLEMS[name](), "hurry", estimate), keep_graph=True)
        assert kept.graph is not None
        for profile in PROFILES:
            fresh = ehatp.solve(prefer(PROBLEMS[name](), profile, estimate)).policy
            assert fresh is not None
            assert same_bytes(relabel(kept, profile), fresh, tmp_path), (profile, estimate)


PREFS = """
[steps]
mode = "concurrent"

[objective]
kind = "preferences"
profile = "hurry"

[objective.profiles]
hurry = ["makespan", "communications"]
lazy_human = ["human_effort", "makespan"]
early = ["human_end", "effort"]
"""


def p2(tmp_path: Path, extra: str = PREFS) -> Path:
    f = tmp_path / "p2.toml"
    text = (EXAMPLES / "cubes" / "p2.toml").read_text(encoding="utf-8") + extra
    f.write_text(text, encoding="utf-8")
    return f


def test_table1_p2_in_joint_steps_relabels_byte_for_byte(tmp_path: Path) -> None:
    """Table 1 P2 in joint steps: ``ehatp relabel`` (one search) writes for each profile the
    file ``ehatp solve`` writes with that profile chosen; each is valid."""
    from typer.testing import CliRunner

    from ehatp.cli.app import app

    f = p2(tmp_path)
    out = CliRunner().invoke(app, ["relabel", str(f), "--profile", "hurry", "--profile",
                                   "lazy_human", "--profile", "early",
                                   "--out", str(tmp_path / "r-{profile}.json")])
    assert out.exit_code == 0, out.output
    for name in ("hurry", "lazy_human", "early"):
        g = tmp_path / f"{name}.toml"
        g.write_text(f.read_text(encoding="utf-8").replace('profile = "hurry"',
                                                           f'profile = "{name}"'),
                     encoding="utf-8")
        problem = ehatp.load(g)
        fresh = ehatp.solve(problem).policy
        assert fresh is not None
        fresh.write(tmp_path / "fresh.json")
        got = (tmp_path / f"r-{name}.json").read_bytes()
        assert got == (tmp_path / "fresh.json").read_bytes(), name
        assert ehatp.validate(ehatp.load(f), Policy.read(tmp_path / f"r-{name}.json")).ok
        assert json.loads(got)["objective"]["profile"] == name


def test_the_validator_recomputes_the_vectors(tmp_path: Path) -> None:
    """A recorded vector changed by hand is caught, naming the node and the metrics."""
    problem = prefer(helper(), "lazy_human")
    policy = solved(problem)
    policy.objective["vectors"][1] = [7, 7]
    report = ehatp.validate(problem, policy)
    assert not report.ok and "human_effort/makespan" in report.message
    assert "C11" in report.message


@pytest.mark.parametrize(("extra", "says"), [
    ('\n[objective]\nkind = "preferences"\nprofile = "a"\n[objective.profiles]\n'
     'a = ["makespan"]\n', 'joint steps only'),
    (PREFS.replace('"communications"]', '"speed"]'), "unknown metric 'speed'"),
    (PREFS.replace('profile = "hurry"', 'profile = "slow"'), "[objective] profile"),
    (PREFS.replace('hurry = ["makespan", "communications"]', 'hurry = []'),
     "[objective.profiles] hurry"),
    (PREFS.replace('profile = "hurry"', 'profile = "hurry"\nestimate = "rosy"'),
     "[objective] estimate"),
    ('\n[objective]\nprofile = "a"\n', "read only with kind"),
])
def test_bad_preferences_are_one_line(tmp_path: Path, extra: str, says: str) -> None:
    """Bad input is one line naming the file and the place, with the fix."""
    with pytest.raises(InputError) as e:
        ehatp.load(p2(tmp_path, extra))
    line = e.value.line()
    assert "\n" not in line and says in line and line.startswith(str(tmp_path / "p2.toml"))
    assert "; " in line


def test_preferences_in_turns_from_python_are_refused() -> None:
    """From Python too, preferences ask for joint steps (one line, C11)."""
    p = dataclasses.replace(prefer(helper(), "hurry"), steps=ehatp.Steps())
    with pytest.raises(InputError, match="joint steps only"):
        ehatp.solve(p)


TABLE1 = ["cubes/p1", "cubes/p2", "cubes/p3", "cubes/p4", "cubes/p5", "cubes/p6",
          "cooking/cooking1", "cooking/cooking2", "cooking/cooking3"]


@pytest.mark.parametrize("name", [
    pytest.param(n, marks=() if n in ("cubes/p2", "cooking/cooking1") else pytest.mark.slow)
    for n in TABLE1])
def test_table1_in_joint_steps_relabels_exactly(name: str) -> None:
    """Table 1 in joint steps, both estimates: one search relabelled for three profiles gives,
    for each, exactly the policy a fresh solve writes (the same JSON text), valid, proven
    optimal (the solvable graphs are acyclic). Root vectors for P2 (checked by reading the
    policies, not derived by hand): ``hurry`` (makespan, communications) worst (6, 0),
    optimistic (4, 0); ``lazy_human`` (4, 6) and (4, 4)."""
    profiles = {"hurry": (Metric.MAKESPAN, Metric.COMMUNICATIONS),
                "lazy_human": (Metric.HUMAN_EFFORT, Metric.MAKESPAN),
                "early": (Metric.HUMAN_END, Metric.EFFORT)}
    p = dataclasses.replace(ehatp.load(EXAMPLES / f"{name}.toml"),
                            steps=ehatp.Steps(ehatp.StepMode.CONCURRENT))
    got = {}
    for estimate in Estimate:
        q = dataclasses.replace(p, objective=Objective(
            ObjectiveKind.PREFERENCES, profile="hurry", profiles=profiles, estimate=estimate))
        kept = ehatp.solve(q, keep_graph=True)
        assert kept.graph is not None and kept.optimal
        for profile in profiles:
            mine = dataclasses.replace(q, objective=q.objective.with_profile(profile))
            fresh = ehatp.solve(mine).policy
            assert fresh is not None
            policy = relabel(kept, profile)
            assert "".join(policy.iter_json()) == "".join(fresh.iter_json())
            assert ehatp.validate(mine, policy).ok
            got[profile, str(estimate)] = policy.objective["value"]
    if name == "cubes/p2":
        assert got["hurry", "worst-case"] == [6, 0] and got["hurry", "optimistic"] == [4, 0]
        assert got["lazy_human", "worst-case"] == [4, 6]
        assert got["lazy_human", "optimistic"] == [4, 4]


def test_relabel_command_mistakes_are_one_line(tmp_path: Path) -> None:
    """``ehatp relabel``: an unknown profile, several profiles with one ``--out`` file, a
    problem without preferences: one line each, exit 2, nothing written."""
    from typer.testing import CliRunner

    from ehatp.cli.app import app

    f = p2(tmp_path)
    runner = CliRunner()
    for args, says in (
            (["--profile", "slow", "--out", "x.json"], "no profile 'slow'"),
            (["--profile", "hurry", "--profile", "early", "--out", "x.json"], "{profile}")):
        r = runner.invoke(app, ["relabel", str(f), *args])
        assert r.exit_code == 2 and says in r.stderr and r.stderr.count("\n") == 1, r.output
    r = runner.invoke(app, ["relabel", str(EXAMPLES / "cubes" / "p2.toml"), "--profile", "a",
                            "--out", str(tmp_path / "x.json")])
    assert r.exit_code == 2 and 'kind = "preferences"' in r.stderr
    assert not (tmp_path / "x.json").exists()


def test_e2_with_the_robot_first() -> None:
    """E2 with ``[steps] first = "robot"`` (C4) by hand. The robot decides first: ``pick(c)``
    — the human, who saw it start, cannot pick too and may not wait idle beside it, so it
    passes; then (place(c), pass): 2 steps, human_effort 0, human_end 0; or ``wait`` — beside
    a wait the human may not pass, so it picks, then places: 2 steps, human_effort 2.
    ``lazy_human`` (human_effort, makespan): pick, (0, 2); ``end`` (human_end, makespan):
    pick, (0, 2); ``hurry`` (makespan, human_effort): pick, (2, 0)."""
    first = dataclasses.replace(JOINT, first=ehatp.StepFirst.ROBOT)
    for profile, value in (("lazy_human", [0, 2]), ("end", [0, 2]), ("hurry", [2, 0])):
        policy, got = run(prefer(two_hands(first), profile))
        assert got == value
        assert policy.root.moves[0].action == "pick(c)"


def test_random_joint_problems_relabel_exactly_and_validate() -> None:
    """The agreement benchmark's random problems (``ehatp.experiments.randomgen``) that are in
    joint steps, seeds 0-599: each under three random profiles of random metrics and a random
    estimate, solved once, relabelled for each profile: the same JSON as a fresh solve, and
    valid. (Seeds 0-9,999 the same way, once by hand: 1,165 joint problems, 510 solved, 0
    invalid, 0 different, 0 crashes.)"""
    import random

    from ehatp.experiments.randomgen import problem

    solved_n = 0
    for seed in range(600):
        p = problem(seed)
        if not p.steps.concurrent:
            continue
        rng = random.Random(seed)
        metrics = list(Metric)
        profiles = {f"p{i}": tuple(rng.sample(metrics, rng.randint(1, len(metrics))))
                    for i in range(3)}
        if relabelled_as_fresh(p, profiles, rng.choice(list(Estimate)), seed) is not None:
            solved_n += 1
    assert solved_n > 10
