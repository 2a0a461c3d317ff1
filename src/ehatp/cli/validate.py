"""``ehatp validate``: check a policy against a problem with the independent validator
(:mod:`ehatp.check.validator`)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from ..errors import printable
from ..model.options import ObjectiveKind
from .common import (
    EXIT_NO_POLICY,
    EXIT_OK,
    command_app,
    load_problem,
    memory_option,
    user_errors,
    with_objective,
)

app = command_app()


@app.command("validate")
def validate_cmd(
    ctx: typer.Context,
    problem: Annotated[Path, typer.Argument(
        help="Problem file (TOML).", metavar="PROBLEM.toml", show_default=False)],
    policy: Annotated[Path, typer.Argument(
        help="Policy JSON to check against the problem.", metavar="POLICY.json",
        show_default=False)],
    objective: Annotated[ObjectiveKind | None, typer.Option(
        "--objective", help="The objective the policy was planned for, if `solve --objective` "
                            "overrode the problem's.", show_default=False)] = None,
    timeout: Annotated[float | None, typer.Option(
        "--timeout", min=0.1, help="Seconds the check may take, reading the files included "
                                   "(default: the problem's limits.timeout, else none).",
        show_default=False)] = None,
    max_memory: Annotated[str | None, typer.Option(
        "--max-memory", help="Resident memory the check may use, e.g. 2G or 512M (default: "
                             "the problem's limits.max_memory, else none).",
        show_default=False)] = None,
) -> None:
    """Check a policy against a problem with the independent validator.

    Exit 0 only if the policy is valid; otherwise print the first violation and exit 1, or,
    when --timeout or --max-memory stops the check first, say so (no verdict) and exit 1
    (2 on unreadable input).
    """
    import ehatp  # the package-level validate(), so the validator loads only when needed

    from ..formats.policy_check import read_policy
    from ..search.limits import Budget, LimitReached
    from .limits import guarded

    t0 = time.perf_counter()
    memory = memory_option(max_memory)
    prob = with_objective(load_problem(problem), objective)  # as `solve --objective` planned
    budget = Budget(prob.limits.timeout if timeout is None else timeout,
                    prob.limits.max_memory if memory is None else memory, start=t0)
    budget.phase = "reading the policy"
    with guarded(ctx.obj, f"validate {policy}", budget.timeout, budget.max_memory, EXIT_NO_POLICY):
        try:
            with user_errors(policy):  # whether counts match is the validator's call
                pol = read_policy(policy, counts=False, check=budget.check)
            if pol.problem != prob.name:  # legal to check, but most likely the wrong files
                typer.echo(printable(f"note: {policy} was planned for {pol.problem!r}, not "
                                     f"{prob.name!r}"),
                           err=True)
            budget.phase = "validation"
            with user_errors(policy):
                report = ehatp.validate(prob, pol, check=budget.check)
        except (LimitReached, MemoryError) as e:
            stop = e if isinstance(e, LimitReached) else budget.out_of_memory()
            typer.secho(printable(f"not checked: {policy}: {stop.reason}; no verdict, raise "
                                  "--timeout or --max-memory"), fg="yellow", err=True)
            raise typer.Exit(EXIT_NO_POLICY) from None
    if report.ok:
        typer.secho(printable(f"valid: {policy} is a valid policy for {prob.name}"), fg="green")
        raise typer.Exit(EXIT_OK)
    typer.secho(printable(f"invalid: {report.message}"), fg="red")
    raise typer.Exit(EXIT_NO_POLICY)
