"""``ehatp simulate``: one execution of a policy, step by step, with what each agent believes
(:mod:`ehatp.run.simulate` runs it; docs/simulation.md)."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import printable
from ..run.simulate import run
from .common import command_app, user_errors

app = command_app()


@app.command("simulate")
def simulate_cmd(
    problem: Path = typer.Argument(..., help="problem TOML file"),
    policy: Path | None = typer.Option(
        None, "--policy", "-p", help="policy JSON from `ehatp solve` (default: solve now)"),
    human: str = typer.Option(
        "first", "--human", help="how the human chooses: ask, random, first or script"),
    script: Path | None = typer.Option(
        None, "--script", "-s", help="human moves, one per line (implies --human script)"),
    seed: int = typer.Option(0, "--seed", help="seed of --human random"),
) -> None:
    """Step through an execution of the policy for PROBLEM, saying what each agent
    believes. Exit code 0: goal reached; 1: the human left the policy; 2: bad input."""
    with user_errors(problem):
        code = run(problem, policy_path=policy, human=human, script_path=script,
                   seed=seed, out=lambda s: typer.echo(printable(s, lines=True)))
    raise typer.Exit(code)
