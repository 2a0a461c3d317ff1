"""``ehatp relabel --after`` / ``--after-from`` (C11, docs/concurrent.md "Relabelling"): the
execution so far given on the command line, one search, one policy per profile rooted at the
state the moves reach, each the file ``ehatp solve`` writes for the problem with ``[problem]
after`` set to those moves and that profile chosen.

The problem is :func:`tests.test_profile_switch.warmup` written as files (its domain a ``.py``
file beside the problem), with two profiles, ``hurry = (makespan, human_effort)`` and
``lazy_human = (human_effort, makespan)``. Every vector was derived by hand before the planner
was run (the derivation in each test's docstring, from the replies tests/test_profile_switch.py
derives)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import Result
from typer.testing import CliRunner

import ehatp
from ehatp.cli.app import app
from ehatp.formats.policy import Policy
from ehatp.run.walk import walk_policy

DOMAIN = (Path(__file__).parent / "data" / "warmup.py").read_text(encoding="utf-8")

PROBLEM = '''\
[problem]
name = "warmup"
starts = "human"
{after}
[domain]
name = "warm.py:domain"

[steps]
mode = "concurrent"

[objective]
kind = "preferences"
profile = "{profile}"

[objective.profiles]
hurry = ["makespan", "human_effort"]
lazy_human = ["human_effort", "makespan"]

[init]
true = []

[agenda]
robot = ["prep", "work"]
human = ["help(b)"]
'''

S1 = ["H pass", "R warm(b)"]
GRAB = [*S1, "H pass", "R grab(b)"]
PUT = [*S1, "H pass", "R put(a)"]
GOAL = [*S1, "H hput(b)", "R put(a)"]


def files(tmp_path: Path, profile: str = "hurry", after: list[str] | None = None,
          name: str = "warmup.toml") -> Path:
    """The problem file (``[problem] after`` set when ``after`` is given), its domain beside
    it."""
    (tmp_path / "warm.py").write_text(DOMAIN, encoding="utf-8")
    line = "" if after is None else f"after = {json.dumps(after)}\n"
    f = tmp_path / name
    f.write_text(PROBLEM.format(after=line, profile=profile), encoding="utf-8")
    return f


def run(*args: object) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args])


def after_args(moves: list[str]) -> list[str]:
    return [a for m in moves for a in ("--after", m)]


@pytest.mark.parametrize(("moves", "hurry", "lazy"), [
    (S1, [2, 1], [1, 1]),
    (GRAB, [2, 0], [0, 2]),
    (PUT, [1, 1], [1, 1]),
    (GOAL, [0, 0], [0, 0]),
])
def test_relabelling_after_a_history_writes_what_solve_writes_with_that_opening(
        tmp_path: Path, moves: list[str], hurry: list[int], lazy: list[int]) -> None:
    """By hand, the root vectors after each history (hurry: (makespan, human_effort); lazy:
    (human_effort, makespan)).

    S1 = after (pass, warm(b)), the only step at the start (``hput(b)`` needs ``b`` ready, so
    the human passes; the robot's one task first is ``prep``). At S1 the human may
    ``hput(b)``: the robot's reply is ``put(a)`` (``grab(b)`` would share ``b``'s resource),
    the goal in 1 step, human effort 1: (1, 1) for both. Or it passes: the robot puts ``a``,
    then the human must ``hput(b)`` (the robot is done, C5: no pass), the robot waiting —
    makespan 2, effort 1: hurry (2, 1), lazy (1, 2) — or grabs ``b``, then (pass, put(a)),
    (pass, drop(b)) — makespan 3, effort 0: hurry (3, 0), lazy (0, 3). The robot takes the
    least: hurry (2, 1) by ``put(a)``, lazy (0, 3) by ``grab(b)``; the human node the worst:
    hurry max{(1, 1), (2, 1)} = (2, 1), lazy max{(1, 1), (0, 3)} = (1, 1).
    GRAB = S1 then (pass, grab(b)): the two forced steps left, hurry (2, 0), lazy (0, 2).
    PUT = S1 then (pass, put(a)): (hput(b), wait) only, (1, 1) for both.
    GOAL = S1 then (hput(b), put(a)): the goal, nothing left, (0, 0).

    Each file is byte-identical to ``ehatp solve``'s on the problem file with ``[problem]
    after`` set to the moves and the profile chosen, validates (``ehatp validate``) and is
    walked through the Executor on every branch."""
    f = files(tmp_path)
    r = run("relabel", f, "--profile", "hurry", "--profile", "lazy_human",
            "--out", tmp_path / "r-{profile}.json", *after_args(moves))
    assert r.exit_code == 0, r.output
    assert r.stdout.splitlines() == [
        f"hurry: makespan {hurry[0]}, human_effort {hurry[1]} -> {tmp_path / 'r-hurry.json'}",
        f"lazy_human: human_effort {lazy[0]}, makespan {lazy[1]} -> "
        f"{tmp_path / 'r-lazy_human.json'}"]
    for profile, value in (("hurry", hurry), ("lazy_human", lazy)):
        g = files(tmp_path, profile, moves, name=f"{profile}.toml")
        s = run("solve", g, "--out", tmp_path / "fresh.json")
        assert s.exit_code == 0, s.output
        got = (tmp_path / f"r-{profile}.json").read_bytes()
        assert got == (tmp_path / "fresh.json").read_bytes(), profile
        v = run("validate", g, tmp_path / f"r-{profile}.json")
        assert v.exit_code == 0, v.output
        policy = Policy.read(tmp_path / f"r-{profile}.json")
        assert policy.after == moves and policy.objective["value"] == value
        assert policy.objective["profile"] == profile
        walked = walk_policy(ehatp.load(g), policy)
        assert walked.ok, str(walked)


def test_the_history_can_come_from_a_policy_file_then_more_moves(tmp_path: Path) -> None:
    """``--after-from`` a policy file reads its ``after`` (S1, a policy relabelled after
    (pass, warm(b))); ``--after`` moves follow it: S1 then (pass, grab(b)) is GRAB, hurry
    (2, 0) as derived above, and the same bytes as giving the four moves with ``--after``."""
    f = files(tmp_path)
    first = run("relabel", f, "--profile", "lazy_human", "--out", tmp_path / "s1.json",
                *after_args(S1))
    assert first.exit_code == 0, first.output
    assert Policy.read(tmp_path / "s1.json").after == S1
    r = run("relabel", f, "--profile", "hurry", "--out", tmp_path / "a.json",
            "--after-from", tmp_path / "s1.json", "--after", "H pass", "--after", "R grab(b)")
    assert r.exit_code == 0, r.output
    assert "hurry: makespan 2, human_effort 0" in r.stdout
    b = run("relabel", f, "--profile", "hurry", "--out", tmp_path / "b.json",
            *after_args(GRAB))
    assert b.exit_code == 0, b.output
    assert (tmp_path / "a.json").read_bytes() == (tmp_path / "b.json").read_bytes()


def play_log(tmp_path: Path, f: Path) -> Path:
    """A real ``ehatp play`` session of ``f`` (its policy solved for ``hurry``) whose
    participant passes twice: the robot warms ``b``, then (hurry, derived above) puts ``a``;
    the log as the server writes it."""
    from ehatp.play.files import load_setup, session_log
    from ehatp.play.session import PlaySession

    setup = load_setup(f, None)
    log = session_log(tmp_path, "abc")
    s = PlaySession(setup.problem, setup.policy, setup.source, session_id="abc", log=log)
    s.start()
    s.run_robot()
    for move in ("pass", "pass"):
        s.choose(move)
        s.run_robot()
    log.close()
    return Path(log.path)


def test_the_history_can_come_from_a_play_log(tmp_path: Path) -> None:
    """``--after-from`` an ``ehatp play`` log: its step records in order are PUT (the
    participant passed twice under ``hurry``: warm(b), then put(a)), so both profiles are at
    (1, 1) (derived above), and the files are those ``--after`` with PUT writes. A log of
    another problem file (its hash differs) is one line, exit 2."""
    f = files(tmp_path)
    log = play_log(tmp_path, f)
    steps = [json.loads(line) for line in log.read_text(encoding="utf-8").splitlines()]
    assert [f"{r['agent']} {r['move']}" for r in steps if r["type"] == "step"] == PUT
    r = run("relabel", f, "--profile", "hurry", "--profile", "lazy_human",
            "--out", tmp_path / "log-{profile}.json", "--after-from", log)
    assert r.exit_code == 0, r.output
    assert "hurry: makespan 1, human_effort 1" in r.stdout
    assert "lazy_human: human_effort 1, makespan 1" in r.stdout
    b = run("relabel", f, "--profile", "hurry", "--profile", "lazy_human",
            "--out", tmp_path / "arg-{profile}.json", *after_args(PUT))
    assert b.exit_code == 0, b.output
    for profile in ("hurry", "lazy_human"):
        assert (tmp_path / f"log-{profile}.json").read_bytes() == \
            (tmp_path / f"arg-{profile}.json").read_bytes()
    other = files(tmp_path, "lazy_human", name="other.toml")
    bad = run("relabel", other, "--profile", "hurry", "--out", tmp_path / "x.json",
              "--after-from", log)
    assert bad.exit_code == 2
    assert "the session played another problem file" in bad.stderr
    assert bad.stderr.count("\n") == 1
    assert not (tmp_path / "x.json").exists()


@pytest.mark.parametrize(("args", "says"), [
    (["--after", "H hput(b)"],  # b is not ready at the start: the human can only pass
     "--after 1: move 1 from the problem's start: 'hput(b)' is not a move of H here; "
     "options: pass; give a move possible at that point"),
    (["--after", "R warm(b)"], "'R warm(b)' names R, but it is H's turn"),
    ([*after_args(S1), "--after", "H pass", "--after", "R dance"],
     "--after 4: move 4 from the problem's start: 'dance' is not a move of R here; options: "
     "grab(b), put(a);"),
    ([*after_args(GOAL), "--after", "H pass"],  # a state past the goal: not in the graph
     "--after 5: the task is done after move 4 (a goal: the graph has no state past it)"),
    (["--profile", "slow", "--after", "H pass"], "no profile 'slow'; use one of hurry, "
     "lazy_human"),
    (["--after-from", "PROBLEM"], "not JSON"),
    (["--after-from", "NOFILE"], "cannot read"),
])
def test_a_history_that_cannot_be_played_is_one_line(
        tmp_path: Path, args: list[str], says: str) -> None:
    """A move not possible at that point (placed where it was given, with the moves that
    were possible), a state past the goal, an unknown profile, a file that holds no moves:
    one line ``place: problem; fix``, exit 2, nothing written."""
    f = files(tmp_path)
    args = [str(f) if a == "PROBLEM" else str(tmp_path / "none.json") if a == "NOFILE"
            else a for a in args]
    if "--profile" not in args:
        args = ["--profile", "hurry", *args]
    r = run("relabel", f, *args, "--out", tmp_path / "x.json")
    assert r.exit_code == 2, r.output
    assert says in r.stderr, r.stderr
    assert r.stderr.count("\n") == 1 and "; " in r.stderr
    assert not (tmp_path / "x.json").exists()


def test_a_problem_with_an_opening_needs_the_history_to_start_with_it(tmp_path: Path) -> None:
    """The moves are the execution from the problem's start, so a problem whose ``[problem]
    after`` is S1 takes S1 then more (GRAB: hurry (2, 0), derived above), and refuses moves
    that do not start with S1 (one line naming the opening). A problem that is not of kind
    preferences is refused as without ``--after``."""
    f = files(tmp_path, after=S1)
    r = run("relabel", f, "--profile", "hurry", "--out", tmp_path / "x.json",
            *after_args(GRAB))
    assert r.exit_code == 0, r.output
    assert "hurry: makespan 2, human_effort 0" in r.stdout
    bad = run("relabel", f, "--profile", "hurry", "--out", tmp_path / "y.json",
              "--after", "H pass")
    assert bad.exit_code == 2
    assert "must start with the problem's fixed opening" in bad.stderr
    assert bad.stderr.count("\n") == 1 and not (tmp_path / "y.json").exists()
    plain = tmp_path / "plain.toml"
    text = files(tmp_path).read_text(encoding="utf-8")
    plain.write_text(text[:text.index("[objective]")] + text[text.index("[init]"):],
                     encoding="utf-8")
    no = run("relabel", plain, "--profile", "hurry", "--out", tmp_path / "z.json",
             "--after", "H pass")
    assert no.exit_code == 2 and 'kind = "preferences"' in no.stderr
