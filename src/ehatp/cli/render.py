"""``ehatp render``: a policy as Graphviz DOT or SVG, or as the HTML explorer
(:mod:`ehatp.formats.render` draws it)."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import DotMissing, PolicyTooLarge, printable
from ..formats.lifted import EXPAND_LIMIT, expanded
from ..formats.policy_check import check_consistent, check_policy_problem, read_policy
from ..formats.render import DEFAULT_MAX_NODES, Format, render, static_facts
from .common import (
    EXPAND_LIMIT_HELP,
    command_app,
    die,
    expand_limit,
    load_problem,
    user_errors,
    write_output,
)

app = command_app()


@app.command("render")
def render_command(
    policy: Path = typer.Argument(..., help="Policy JSON written by `ehatp solve --out FILE`.",
                                  show_default=False),
    fmt: Format = typer.Option(Format.dot, "--format", "-f",
                               help="dot (text), svg (needs Graphviz) or html (explorer)."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Write here instead of stdout."),
    max_depth: int | None = typer.Option(None, "--max-depth", min=0,
                                         help="Fold everything below this depth."),
    max_nodes: int = typer.Option(DEFAULT_MAX_NODES, "--max-nodes", min=1,
                                  help="Node budget; bigger policies are collapsed."),
    share: bool | None = typer.Option(None, "--share/--no-share",
                                      help="Draw identical subtrees once "
                                           "[default: only when over --max-nodes]."),
    problem: Path | None = typer.Option(None, "--problem", "-p", metavar="PROBLEM.toml",
                                        help="Check that the policy was planned for this "
                                             "problem file; label moves as on its objects, and "
                                             "list its static facts in the explorer."),
    limit: int = typer.Option(EXPAND_LIMIT, "--expand-limit", min=0, metavar="N",
                              help=EXPAND_LIMIT_HELP),
) -> None:
    """Draw a policy as Graphviz DOT or SVG, or as a self-contained HTML explorer.

    The file is checked first (exit 2, one line, if it was edited into something else): its
    structure, that what it says agrees with its own graph (values, who moves, goals, worlds,
    the moves' text), and with --problem that it was planned for that problem. Whether every
    move is legal is `ehatp validate`'s.

    Written to a file (--out), one line on stderr says what: the file, the format, the
    policy's nodes, the size, and how the drawing was collapsed, if it was."""
    with user_errors(policy):
        pol = read_policy(policy)
    prob = None if problem is None else load_problem(problem)
    too_large = None  # past the limit a lifted policy is drawn realised as far as it is drawn
    with user_errors(policy):
        if prob is not None:
            check_policy_problem(pol, policy, prob)
        check_consistent(pol, str(policy))
        if prob is not None and pol.symmetry is not None:  # lifted: the problem's own labels
            from ..run.expand import expand_policy

            try:
                pol = expand_policy(prob, pol, max_nodes=expand_limit(limit))
            except PolicyTooLarge as e:
                too_large = e
    if too_large is None and pol.symmetry is not None:  # expanded once, here
        try:
            pol = expanded(pol, expand_limit(limit))
        except PolicyTooLarge as e:
            too_large = e
    with user_errors(policy):
        try:
            static = static_facts(prob) if prob is not None and fmt is Format.html else None
            text, notes = render(pol, fmt, max_depth=max_depth, max_nodes=max_nodes,
                                 share=share, static=static, too_large=too_large)
        except DotMissing as e:
            die(str(e))
    if notes and out is None:
        typer.echo(printable(f"render: {policy}: collapsed: {'; '.join(notes)}"), err=True)
    kind = {Format.dot: "Graphviz DOT", Format.svg: "SVG", Format.html: "HTML explorer"}[fmt]
    size = (f"{len(pol.nodes):,} policy nodes" if pol.symmetry is None
            else f"lifted, {len(pol.nodes):,} canonical nodes")
    what = f"{kind} of {pol.problem}, {size}"
    if notes:
        what += f" (collapsed: {'; '.join(notes)})"
    write_output(text, out, what, command="render")
