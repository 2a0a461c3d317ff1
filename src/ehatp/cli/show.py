"""``ehatp show``: a policy as an indented tree and its branches' timelines
(:mod:`ehatp.formats.text` writes them)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from ..formats.lifted import EXPAND_LIMIT
from .common import EXPAND_LIMIT_HELP, command_app, expand_limit, load_policy, write_stdout

app = command_app()


@app.command("show")
def show_cmd(
    policy: Annotated[Path, typer.Argument(
        help="Policy JSON written by `ehatp solve`.", metavar="POLICY.json",
        show_default=False)],
    tree: Annotated[bool, typer.Option(
        "--tree/--no-tree", help="Print the policy tree.")] = True,
    timelines: Annotated[bool, typer.Option(
        "--timelines/--no-timelines",
        help="Print the branches' timelines (the first 100).")] = True,
    details: Annotated[bool, typer.Option(
        "--details", "-d", help="Under each tree node, list what the human is unsure about "
                                "and the K-counter.")] = False,
    problem: Annotated[Path | None, typer.Option(
        "--problem", "-p", help="Check that the policy was planned for this problem file.",
        metavar="PROBLEM.toml", show_default=False)] = None,
    limit: Annotated[int, typer.Option(
        "--expand-limit", min=0, metavar="N", help=EXPAND_LIMIT_HELP)] = EXPAND_LIMIT,
) -> None:
    """Print a policy as an indented tree and the timelines of its branches (the first 100).

    Tree: each line is one step (node number, agent, action, W = worlds the human entertains;
    marks apart, COMM for a communication, GOAL). Straight runs stay at one indent; the tree
    forks only where the human chooses. A node reached by several paths is printed once; the
    other moves into it end with "-> see node N".
    Timelines: turns while the agents are together,
    parallel lanes while they are apart. Colour on a terminal, plain text in a pipe.
    In joint steps ([steps] mode = "concurrent") a line of the tree and of a timeline is a
    step: the human's move, then the robot's reply (the robot's first with first = "robot");
    with preference profiles the header gives the profile and the root's vector, and the
    tree the vector beside each robot choice (docs/rendering.md).
    The file is checked first (exit 2, one line, if it was edited into something else): its
    structure, that what it says agrees with its own graph (values, who moves, goals, worlds,
    the moves' text), and with --problem that it was planned for that problem. Whether every
    move is legal is `ehatp validate`'s.
    """
    pol = load_policy(policy, problem, consistent=True)
    too_large = None  # then its branches are realised one at a time (policy_lines)
    if problem is not None and pol.symmetry is not None:  # lifted: its real labels
        from ..errors import PolicyTooLarge
        from ..run.expand import expand_policy
        from .common import load_problem, user_errors

        with user_errors(policy):
            try:
                pol = expand_policy(load_problem(problem), pol, max_nodes=expand_limit(limit))
            except PolicyTooLarge as e:
                too_large = e
    from ..formats.text import plain, policy_lines, print_rich

    lines = policy_lines(pol, tree=tree, timelines=timelines, details=details,
                         expand_limit=expand_limit(limit), too_large=too_large)
    if sys.stdout.isatty():
        from rich.console import Console

        print_rich(lines, Console())
    else:
        write_stdout(plain(lines))
