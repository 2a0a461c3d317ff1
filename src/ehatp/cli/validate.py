"""``ehatp validate``: check a policy against a problem with the independent validator
(:mod:`ehatp.check.validator`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..errors import printable
from ..model.options import ObjectiveKind
from .common import (
    EXIT_NO_POLICY,
    EXIT_OK,
    command_app,
    load_policy,
    load_problem,
    user_errors,
    with_objective,
)

app = command_app()


@app.command("validate")
def validate_cmd(
    problem: Annotated[Path, typer.Argument(
        help="Problem file (TOML).", metavar="PROBLEM.toml", show_default=False)],
    policy: Annotated[Path, typer.Argument(
        help="Policy JSON to check against the problem.", metavar="POLICY.json",
        show_default=False)],
    objective: Annotated[ObjectiveKind | None, typer.Option(
        "--objective", help="The objective the policy was planned for, if `solve --objective` "
                            "overrode the problem's.", show_default=False)] = None,
) -> None:
    """Check a policy against a problem with the independent validator.

    Exit 0 only if the policy is valid; otherwise print the first violation and exit 1
    (2 on unreadable input).
    """
    import ehatp  # the package-level validate(), so the validator loads only when needed

    prob = with_objective(load_problem(problem), objective)  # as `solve --objective` planned
    pol = load_policy(policy, counts=False)  # whether counts match is the validator's call
    if pol.problem != prob.name:  # legal to check, but most likely the wrong pair of files
        typer.echo(printable(f"note: {policy} was planned for {pol.problem!r}, not "
                             f"{prob.name!r}"),
                   err=True)
    with user_errors(policy):
        report = ehatp.validate(prob, pol)
    if report.ok:
        typer.secho(printable(f"valid: {policy} is a valid policy for {prob.name}"), fg="green")
        raise typer.Exit(EXIT_OK)
    typer.secho(printable(f"invalid: {report.message}"), fg="red")
    raise typer.Exit(EXIT_NO_POLICY)
