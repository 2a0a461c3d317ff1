"""``ehatp execute``: a policy run live, JSON lines on stdin and stdout, for a robot process
that runs ehatp as its subprocess (the protocol is :mod:`ehatp.run.execute`; docs/execution.md).

Exit codes: 0 the goal is reached; 1 the input ended before the goal, or replanning found no
policy; 2 bad input before the protocol starts (one ``error:`` line on stderr) or a policy that
turns out not to fit the problem (a ``policy-mismatch`` line); 3 internal error.
"""

from __future__ import annotations

import dataclasses
import json
import re
import sys
from pathlib import Path
from typing import Any, TextIO

import typer

from ..errors import ExecutionError, InputError, PolicyMismatch
from ..formats.policy_check import read_policy
from ..model.options import ObjectiveKind
from ..run.execute import EXIT_STOPPED, Emit, replans_folder, run
from ..run.executor import Executor
from .common import command_app, load_problem, memory_option, user_errors

app = command_app()

# what json.dumps leaves raw with ensure_ascii=False and a terminal may obey: DEL and the C1
# controls (U+009B is a one-character escape-sequence start on some terminals); inside JSON
# strings only, so \u escapes keep every line valid JSON
_RAW_CONTROL = re.compile("[\x7f-\x9f]")


def safe_json_lines(out: TextIO) -> Emit:
    """Return the emitter of the protocol's JSON lines on ``out`` (one line each, flushed):
    no control character is written raw, so an echoed input line cannot drive a terminal."""
    def emit(message: dict[str, Any]) -> None:
        text = json.dumps(message, ensure_ascii=False)
        out.write(_RAW_CONTROL.sub(lambda m: f"\\u{ord(m.group()):04x}", text) + "\n")
        out.flush()
    return emit



@app.command("execute")
def execute_cmd(
    problem: Path = typer.Argument(..., help="Problem TOML file.", show_default=False),
    policy: Path | None = typer.Option(
        None, "--policy", "-p", help="Policy JSON from `ehatp solve` (default: solve now).",
        show_default=False),
    replan: bool = typer.Option(
        False, "--replan", help="When the human does something the policy does not cover "
                                "but the human model allows, plan again from there."),
    save_replans: Path | None = typer.Option(
        None, "--save-replans", metavar="DIR", help="Write each replanned policy to "
        "DIR/replan-N.json (its `after` is the execution so far).", show_default=False),
    timeout: float | None = typer.Option(
        None, "--timeout", min=0.1, help="Seconds each planning may take (the first, without "
        "--policy, and every replan; default: the problem's limits.timeout).",
        show_default=False),
    max_memory: str | None = typer.Option(
        None, "--max-memory", help="Resident memory each planning may use, e.g. 2G (default: "
        "the problem's limits.max_memory).", show_default=False),
    decision_timeout: float | None = typer.Option(
        None, "--decision-timeout", min=0.0, metavar="SECONDS", help="Joint steps: how long "
        "the human has to start an action before the robot process reports a pass; carried "
        "in every waiting line (ehatp keeps no clock).", show_default=False),
    keep_graph: bool = typer.Option(
        True, "--keep-graph/--no-keep-graph", help="Preferences problems: keep the explored "
        'graph (searched at the start, also with --policy) so that a {"profile": NAME} line '
        "relabels it; --no-keep-graph: no search with --policy, profile lines refused."),
    recognition_latency: float | None = typer.Option(
        None, "--recognition-latency", min=0.0, metavar="SECONDS", help="Joint steps: how "
        "long after the human's action starts the robot process may report it; carried in "
        "every waiting line.", show_default=False),
) -> None:
    """Execute a policy live: JSON lines on stdin (what the human did, what the robot
    finished) and on stdout (what the robot should do, what the human believes, the goal,
    errors), for a robot process to run as a subprocess. See docs/execution.md.

    A preferences problem keeps its explored graph (searched once at the start, also with
    --policy; not with --no-keep-graph), so that a {"profile": NAME} line switches profile at
    a step's start without a new search.

    Exit code 0: goal reached; 1: the input ended first, or no policy after replanning;
    2: bad problem or policy."""
    memory = memory_option(max_memory)
    prob = load_problem(problem)
    if not prob.steps.concurrent and (decision_timeout is not None
                                      or recognition_latency is not None):
        with user_errors(problem):
            raise InputError(str(problem), "", "--decision-timeout and --recognition-latency "
                             "time joint steps, and this problem takes turns",
                             'leave them out, or set [steps] mode = "concurrent"')
    if timeout is not None or memory is not None:  # the first planning too (no --policy)
        limits = dataclasses.replace(
            prob.limits, timeout=prob.limits.timeout if timeout is None else timeout,
            max_memory=prob.limits.max_memory if memory is None else memory)
        prob = dataclasses.replace(prob, limits=limits)
    pol = None
    if policy is not None:
        with user_errors(policy):
            pol = read_policy(policy)
    where = str(policy) if policy is not None else str(problem)
    graph = None
    if keep_graph and prob.objective.kind == ObjectiveKind.PREFERENCES:  # C11: kept for
        # {"profile": NAME} lines
        from ..search.planner import solve  # as the executor loads it: when planning

        with user_errors(problem):
            result = solve(prob, keep_graph=True)
        graph = result.graph
        if pol is None:
            pol = result.policy
            if pol is None:
                typer.echo(json.dumps({"error": "no-policy", "message": f"{problem}: no policy "
                                       f"to execute: {result.reason or result.status}",
                                       "line": 0, "seq": 1}))
                raise typer.Exit(EXIT_STOPPED)
    with user_errors(where):
        try:
            ex = Executor(prob, pol)
        except PolicyMismatch as e:
            raise InputError(where, "", str(e), "give the policy solved for this problem"
                             ) from None
        except ExecutionError as e:
            typer.echo(json.dumps({"error": "no-policy", "message": str(e), "line": 0,
                                   "seq": 1}))
            raise typer.Exit(EXIT_STOPPED) from None
    if save_replans is not None:
        with user_errors(save_replans):
            replans_folder(save_replans)  # created, with its parents, if missing
    code = run(ex, sys.stdin, safe_json_lines(sys.stdout), replan=replan,
               source=str(policy) if policy is not None else "solved now",
               save=save_replans, timeout=timeout, max_memory=memory,
               decision_timeout=decision_timeout, recognition_latency=recognition_latency,
               graph=graph, relabel=keep_graph)
    raise typer.Exit(code)
