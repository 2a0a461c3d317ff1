"""``ehatp relabel``: one search of a preferences problem, its graph relabelled for each profile
asked (C11, docs/concurrent.md "Preferences"). A process cannot keep the explored graph for the
next one, so the command searches once and writes one policy per ``--profile``; from Python,
``ehatp.solve(problem, keep_graph=True).graph.relabel(name)`` relabels the kept graph as often as
wanted without searching again."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .common import EXIT_NO_POLICY, command_app, die, load_problem, user_errors

app = command_app()


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
) -> None:
    """Search a preferences problem once and write the policy each profile prefers, by
    relabelling the explored graph (no new search per profile).

    Each policy is byte-identical to the one `ehatp solve` writes with that profile chosen in
    the problem file. The graph lives in this process only: relabel more profiles by naming
    them all here, or from Python (`solve(..., keep_graph=True)`). Exit 0 written; 1 no policy;
    2 bad input.
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
    with user_errors(problem):
        result = solve(prob, keep_graph=True)
    if result.graph is None:
        typer.echo(f"{problem}: no policy ({result.status}): {result.reason}", err=True)
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
