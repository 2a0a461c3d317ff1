"""``ehatp export``: a policy in another tool's format; ``export bt`` writes a behaviour tree
(:mod:`ehatp.formats.bt`)."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import InputError, PolicyTooLarge
from ..formats.bt import (
    BTFormat,
    NotExpressible,
    answers_of,
    from_policy,
    to_btcpp,
    to_py_trees_source,
)
from ..formats.lifted import EXPAND_LIMIT
from ..formats.policy_check import check_policy_problem, read_policy
from ..run.expand import expand_policy
from .common import (
    EXPAND_LIMIT_HELP,
    command_app,
    expand_limit,
    load_problem,
    user_errors,
    write_output,
)

app = command_app(name="export", help="Write a policy in another tool's format.",
                  no_args_is_help=True)


@app.command("bt")
def export_bt(
    policy: Path = typer.Argument(..., help="Policy JSON written by `ehatp solve --out FILE`.",
                                  show_default=False),
    fmt: BTFormat = typer.Option(BTFormat.btcpp4, "--format", "-f",
                                 help="btcpp4 (BehaviorTree.CPP v4 XML, opens in Groot) or "
                                      "py_trees (a Python module building the tree)."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Write here instead of stdout."),
    problem: Path | None = typer.Option(
        None, "--problem", "-p", metavar="PROBLEM.toml",
        help="The problem the policy was planned for: checked, and used to write the robot's "
             "answers (yes/no) to the human's questions.", show_default=False),
    limit: int = typer.Option(EXPAND_LIMIT, "--expand-limit", min=0, metavar="N",
                              help=EXPAND_LIMIT_HELP),
) -> None:
    """Write a policy as a behaviour tree: robot moves are action nodes, each human choice a
    wait for the human's action then a Fallback over what the human did, shared states
    SubTrees defined once, goals GoalReached. See docs/behaviour-trees.md."""
    with user_errors(policy):
        pol = read_policy(policy)
    answers = None
    too_large = ("raise --expand-limit (a behaviour tree holds every branch), or run the "
                 "policy with `ehatp execute`, which realises only the branch it follows")
    if problem is not None:
        prob = load_problem(problem)
        with user_errors(policy):
            check_policy_problem(pol, policy, prob)
            try:  # a lifted policy: its graph on the real objects
                pol = expand_policy(prob, pol, max_nodes=expand_limit(limit))
            except PolicyTooLarge as e:
                raise InputError(str(policy), "", str(e), too_large) from None
            answers = answers_of(prob, pol)
    with user_errors(policy):
        try:
            forest = from_policy(pol, answers, expand_limit(limit))
        except PolicyTooLarge as e:
            raise InputError(str(policy), "", str(e), too_large) from None
        except NotExpressible as e:
            raise InputError(str(policy), "", str(e), e.fix) from None
        except ValueError as e:
            raise InputError(str(policy), "", str(e), "give a policy written by ehatp solve"
                             ) from None
    text = to_btcpp(forest) if fmt is BTFormat.btcpp4 else to_py_trees_source(forest)
    kind = ("BehaviorTree.CPP v4 XML" if fmt is BTFormat.btcpp4
            else "py_trees module (Python)")
    write_output(text, out, f"{kind} of {pol.problem}, {len(pol.nodes)} policy nodes",
                 command="export bt")
