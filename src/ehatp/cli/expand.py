"""``ehatp expand``: a lifted policy (format version 3) as the version 2 graph over the real
objects (:func:`ehatp.run.expand.expand_policy`), for the tools that need every real state."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..errors import printable
from .common import command_app, die, expand_limit, load_policy, load_problem, user_errors

app = command_app()


@app.command("expand")
def expand_cmd(
    policy: Annotated[Path, typer.Argument(
        help="Policy JSON written by `ehatp solve`.", metavar="POLICY.json",
        show_default=False)],
    problem: Annotated[Path, typer.Option(
        "--problem", "-p", help="The problem file the policy was planned for.",
        metavar="PROBLEM.toml", show_default=False)],
    out: Annotated[Path, typer.Option(
        "--out", "-o", help="Where to write the version 2 policy (gzip-compressed if the "
                            "name ends in .gz).", show_default=False)],
    limit: Annotated[int, typer.Option(
        "--expand-limit", min=0, metavar="N",
        help="Stop, writing nothing, past N nodes over the real objects (0: no limit; a "
             "lifted policy can stand for hundreds of thousands).")] = 0,
) -> None:
    """Write the version 2 graph, over the real objects, of a lifted policy (format version 3).

    Each move is played by the problem's own semantics from the real start, so the graph is
    the one `ehatp solve --expand` writes. A version 1 or 2 policy is written as version 2.
    Exit 0 written; 1 stopped by --expand-limit (nothing written); 2 bad input (or a policy
    that does not fit the problem).
    """
    from ..errors import PolicyTooLarge
    from ..run.expand import expand_policy

    pol = load_policy(policy, problem, counts=False)
    prob = load_problem(problem)
    with user_errors(policy):
        try:
            real = expand_policy(prob, pol, max_nodes=expand_limit(limit))
        except PolicyTooLarge as e:
            typer.echo(printable(f"expand: {policy}: stopped, {e} (--expand-limit {limit}); "
                                 "nothing written"), err=True)
            raise typer.Exit(1) from None
    try:
        real.write(out)
    except OSError as e:
        die(f"{out}: cannot write the policy ({e.strerror or e}); choose another --out")
    typer.echo(f"{policy}: {len(pol.nodes):,} nodes -> {out}: {len(real.nodes):,} nodes "
               f"(format version {real.version}), {real.leaves:,} branches")
