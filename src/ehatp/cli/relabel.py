"""``ehatp relabel``: one search of a preferences problem, its graph relabelled for each profile
asked (C11, docs/concurrent.md "Preferences"). A process cannot keep the explored graph for the
next one, so the command searches once and writes one policy per ``--profile``; from Python,
``ehatp.solve(problem, keep_graph=True).graph.relabel(name)`` relabels the kept graph as often as
wanted without searching again.

With ``--after`` / ``--after-from`` (the execution so far: moves, a policy file's ``after``, or
an ``ehatp play`` log) the one search is the problem's played up to there (its ``[problem]
after`` set to those moves), so each policy is rooted at the state they reach and is the file
``ehatp solve`` writes for that problem with the profile chosen."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import Annotated, Any

import typer

from ..model.problem import Problem
from .common import EXIT_NO_POLICY, command_app, die, load_problem, user_errors

app = command_app()

_LOG_FIX = "give an `ehatp play` log or a policy file whose \"after\" lists the moves"


@app.command("relabel")
def relabel_cmd(
    problem: Annotated[Path, typer.Argument(
        help='Problem TOML with [objective] kind = "preferences".', metavar="PROBLEM.toml",
        show_default=False)],
    profile: Annotated[list[str], typer.Option(
        "--profile", help="A profile of [objective.profiles]; repeat for several.",
        show_default=False)],
    out: Annotated[str, typer.Option(
        "--out", "-o", help="Where to write the policy; with several --profile, a path "
                            "holding {profile}, replaced by each name.",
        show_default=False)],
    after: Annotated[list[str] | None, typer.Option(
        "--after", help='A move played from the problem\'s start, as [problem] after writes '
                        'it ("H pick(c1)", "R wait"); repeat in order. After --after-from\'s '
                        "moves when both are given.", show_default=False)] = None,
    after_from: Annotated[Path | None, typer.Option(
        "--after-from", help='The moves played so far, read from a policy file\'s "after" '
                             "(ehatp execute --save-replans, ehatp relabel --after) or an "
                             "ehatp play log (its step records).", show_default=False)] = None,
) -> None:
    """Search a preferences problem once and write the policy each profile prefers, by
    relabelling the explored graph (no new search per profile).

    Each policy is byte-identical to the one `ehatp solve` writes with that profile chosen in
    the problem file. With `--after MOVE ...` or `--after-from FILE` (the execution so far,
    from the problem's start, its own `[problem] after` first) each policy starts where those
    moves lead: the file `ehatp solve` writes with `[problem] after` set to them. The graph
    lives in this process only: relabel more profiles by naming them all here, or from Python
    (`solve(..., keep_graph=True)`). Exit 0 written; 1 no policy; 2 bad input.
    """
    from ..model.options import ObjectiveKind
    from ..search.planner import solve

    prob = load_problem(problem)
    obj = prob.objective
    if obj.kind != ObjectiveKind.PREFERENCES:
        die(f'{problem}:[objective] kind: relabelling needs kind = "preferences"; add it with '
            "[objective.profiles]")
    for name in profile:
        if name not in obj.profiles:
            die(f"{problem}:[objective.profiles]: no profile {name!r}; use one of "
                + ", ".join(sorted(obj.profiles)))
    if len(set(profile)) > 1 and "{profile}" not in out:
        die(f"--out {out}: several profiles need a path holding {{profile}}; write e.g. "
            "--out 'policy-{profile}.json'")
    played = after_from is not None or bool(after)
    if played:
        prob = _played(problem, prob, after_from, list(after or ()))
    with user_errors(problem):
        result = solve(prob, keep_graph=True)
    if result.graph is None:
        where = f" after {len(prob.after)} moves" if played else ""
        typer.echo(f"{problem}: no policy{where} ({result.status}): {result.reason}", err=True)
        raise typer.Exit(EXIT_NO_POLICY)
    for name in dict.fromkeys(profile):
        policy = result.graph.relabel(name)
        target = Path(out.replace("{profile}", name))
        try:
            policy.write(target)
        except OSError as e:
            die(f"{target}: cannot write the policy ({e.strerror or e}); choose another --out")
        value = ", ".join(f"{m} {v}" for m, v in zip(policy.objective["metrics"],
                                                     policy.objective["value"], strict=True))
        typer.echo(f"{name}: {value} -> {target}")


def _played(path: Path, prob: Problem, after_from: Path | None,
            after: list[str]) -> Problem:
    """Return ``prob`` played up to the moves given, ``--after-from``'s then ``--after``'s (its
    ``[problem] after`` set to them, C11 "Relabelling": the policy starts there). The moves
    must start with the problem's own fixed opening, and :func:`_replay` checks each."""
    moves: list[tuple[tuple[str, str], str]] = []
    if after_from is not None:
        moves += _moves_of_file(path, after_from)
    moves += [((f"--after {i + 1}", ""), m) for i, m in enumerate(after)]
    opening = list(prob.after)
    if [m for _, m in moves[:len(opening)]] != opening:
        first = _where(moves[0][0]) if moves else "--after"
        die(f"{first}: the moves must start with the problem's fixed opening ({path}:"
            f"[problem] after = {opening}); give the whole execution from the problem's start")
    _replay(prob, moves)
    labels = [m for _, m in moves]
    return dataclasses.replace(prob, after=tuple(labels))


def _where(place: tuple[str, str]) -> str:
    """``file:place``, or ``file`` alone (``--after 2``)."""
    return f"{place[0]}:{place[1]}" if place[1] else place[0]


def _replay(prob: Problem, moves: list[tuple[tuple[str, str], str]]) -> None:
    """Play ``moves`` from ``prob``'s initial state through the search's own semantics (the
    rules of docs/semantics.md §4, or C1-C12 in joint steps), as the search replays ``[problem]
    after``: each must be a move possible at that point and not one that fails, and none may
    follow a goal (§6: a goal is a leaf of the graph, nothing is explored past it). A bad one is
    one line naming where it was given (``--after 2``, ``log.jsonl:line 14``), exit 2."""
    from ..epistemic.concurrent import semantics_for
    from ..model.grounding import ground_problem

    with user_errors(prob.source):
        sem = semantics_for(ground_problem(prob))
    es = sem.initial()
    for i, (where, label) in enumerate(moves):
        if sem.is_goal(es):
            die(f"{_where(where)}: the task is done after move {i} (a goal: the graph has no "
                f"state past it), so {label!r} cannot be played; give the moves up to the goal")
        try:
            es = sem.follow(es, label).child  # type: ignore[assignment]  # None: follow raises
        except ValueError as e:
            die(f"{_where(where)}: move {i + 1} from the problem's start: {e}; give a move "
                "possible at that point")


def _moves_of_file(problem: Path, f: Path) -> list[tuple[tuple[str, str], str]]:
    """The moves ``f`` holds, each with its place: a policy file's ``after`` (a JSON object;
    ``ehatp execute --save-replans`` files hold the history there), or an ``ehatp play`` log
    (JSON lines, a ``start`` record first): its ``step`` records in order, ``agent`` then
    ``move``; the log's problem must be ``problem`` (its hash). One line, exit 2, otherwise."""
    try:
        text = f.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        die(f"{f}: cannot read ({getattr(e, 'strerror', None) or e}); {_LOG_FIX}")
    lines = text.splitlines()
    first = next((i for i, ln in enumerate(lines) if ln.strip()), None)
    if first is None:
        die(f"{f}: empty; {_LOG_FIX}")
    try:
        head: Any = json.loads(lines[first])
    except json.JSONDecodeError:
        head = None
    if isinstance(head, dict) and head.get("type") == "start":
        return _moves_of_log(problem, f, lines, head)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        die(f"{f}:{e.lineno}:{e.colno}: not JSON ({e.msg}); {_LOG_FIX}")
    after = data.get("after") if isinstance(data, dict) else None
    if not isinstance(after, list) or not all(isinstance(m, str) for m in after):
        die(f'{f}: no "after" list of moves (neither a policy file nor an `ehatp play` log); '
            f"{_LOG_FIX}")
    return [((str(f), f"after[{i}]"), m) for i, m in enumerate(after)]


def _moves_of_log(problem: Path, f: Path, lines: list[str],
                  start: dict[str, Any]) -> list[tuple[tuple[str, str], str]]:
    """The moves of an ``ehatp play`` log (docs/play.md, "The log"): each ``step`` record's
    ``agent`` and ``move``, placed by line; a last line cut short by a crash is left out, as
    ``ehatp play --replay`` does."""
    try:
        mine = "sha256:" + hashlib.sha256(problem.read_bytes()).hexdigest()
    except OSError as e:  # read a moment ago: not expected, but one line all the same
        die(f"{problem}: cannot read ({e.strerror or e}); give a problem TOML file")
    if start.get("problem_hash") != mine:
        die(f"{f}: the session played another problem file (its hash {start.get('problem_hash')}"
            f", {problem}'s {mine}); give the session's problem file as PROBLEM")
    out = []
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
        except json.JSONDecodeError as e:
            if n == len(lines):
                break
            die(f"{f}:line {n}: not JSON ({e.msg}); {_LOG_FIX}")
        if not isinstance(rec, dict) or rec.get("type") != "step":
            continue
        agent, move = rec.get("agent"), rec.get("move")
        if not isinstance(agent, str) or not isinstance(move, str):
            die(f'{f}:line {n}: a step record without "agent" and "move"; {_LOG_FIX}')
        played = rec.get("played")  # the move as [problem] after writes it (since 0.3)
        out.append(((str(f), f"line {n}"),
                    played if isinstance(played, str) else f"{agent} {move}"))
    return out
