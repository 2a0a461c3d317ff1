"""What every command shares: how each run ends in one line and a documented exit code.

Exit codes: 0 ok, 1 no (valid) policy, 2 bad input (one line ``error: FILE:PLACE: problem;
fix``), 3 internal error (one line naming a file that holds the traceback, or the traceback on
screen with ``ehatp --debug``). Usage mistakes (an unknown option, a missing argument) are bad
input too, and also one line.
"""

from __future__ import annotations

import hashlib
import json
import math
import platform
import sys
import tempfile
import traceback
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from fractions import Fraction
from pathlib import Path
from typing import Any, NoReturn

import typer
from typer.core import TyperGroup
from typer.exceptions import TyperException

from .. import __version__
from ..errors import EhatpError, InputError
from ..model.domain import DomainError
from ..model.problem import Problem
from ..policy_format import POLICY_FIX, Policy, malformed

EXIT_OK, EXIT_NO_POLICY, EXIT_BAD_INPUT, EXIT_INTERNAL = 0, 1, 2, 3
ARGV_KEY = "ehatp.argv"  # where the command line is kept for an internal-error report


def die(message: str, code: int = EXIT_BAD_INPUT) -> NoReturn:
    """One line on stderr, then exit; newlines are folded so the promise of one line holds."""
    typer.echo(f"error: {' '.join(message.split())}", err=True)
    raise typer.Exit(code)


@contextmanager
def user_errors(file: Path | str) -> Iterator[None]:
    """Turn the errors a user can cause with ``file`` into one line and exit code 2."""
    try:
        yield
    except InputError as e:
        die(e.line())
    except DomainError as e:
        die(f"{file}: the domain is malformed: {e}; fix the domain definition")
    except EhatpError as e:
        die(f"{file}: {e}")


# --- policy files ----------------------------------------------------------------------------


def read_policy(path: Path | str, *, counts: bool = True) -> Policy:
    """Read and check a policy file (version 2, or 1 turned into a graph): :meth:`Policy.load`,
    then the type of every field the tools read and (``counts``) whether the header's counts
    and the moves' agents match the graph, so a hand-edited or truncated file is one
    :class:`InputError` line instead of a wrong display or a crash. (``validate`` leaves the
    counts to the validator.)"""
    try:
        policy = Policy.load(path)
    except (AttributeError, TypeError, KeyError, ValueError, IndexError, RecursionError) as e:
        # the format reader trusts the JSON's shapes; anything it trips on is the file's fault
        place, what = _shape(path) or ("", f"malformed policy ({type(e).__name__}: {e})")
        raise InputError(str(path), place, what, POLICY_FIX) from None
    check_policy(policy, str(path), counts=counts)
    return policy


def _shape(path: Path | str) -> tuple[str, str] | None:
    """Where a policy's JSON has the wrong shape for its reader, in the file's own terms."""
    try:
        raw = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    return malformed(raw)


_NODE_FIELDS: dict[str, tuple[str, str]] = {
    # field: (kind of value, how to say it)
    "copresent": ("bool", "true or false"), "k": ("int", "a whole number"),
    "worlds": ("int", "a whole number"), "divergence": ("strs", "a list of strings"),
    "state": ("strs", "a list of strings"), "robot_agenda": ("strs", "a list of strings"),
    "human_agenda": ("strs", "a list of strings"), "value": ("num", "a number"),
    "goal": ("bool", "true or false"), "to_move": ("str?", "a string or null"),
}
_MOVE_FIELDS: dict[str, tuple[str, str]] = {
    "agent": ("str", "a string"), "kind": ("str", "a string"), "action": ("str", "a string"),
    "name": ("str", "a string"), "args": ("strs", "a list of strings"),
    "cost": ("num", "a number"), "told": ("strs", "a list of strings"),
}
_TOP_FIELDS: dict[str, tuple[str, str]] = {
    "problem": ("str", "a string"), "domain": ("str", "a string"), "K": ("int", "a whole number"),
    "cost": ("num", "a number"), "communications": ("int", "a whole number"),
    "leaves": ("int", "a whole number"), "optimal": ("bool", "true or false"),
    "after": ("strs", "a list of strings"), "stats": ("dict", "an object"),
    "costs": ("dict", "an object"),
}


def _is(kind: str, v: Any) -> bool:
    if kind == "str":
        return isinstance(v, str)
    if kind == "str?":
        return v is None or isinstance(v, str)
    if kind == "strs":
        return isinstance(v, list) and all(isinstance(x, str) for x in v)
    if kind == "bool":
        return isinstance(v, bool)
    if kind == "int":
        return isinstance(v, int) and not isinstance(v, bool) and v >= 0
    if kind == "num":
        return (isinstance(v, int | Fraction) and not isinstance(v, bool)
                or isinstance(v, float) and math.isfinite(v))
    return isinstance(v, dict)


def check_policy(policy: Policy, name: str, *, counts: bool = True) -> None:
    """The structure :func:`read_policy` checks (see there); raise :class:`InputError`."""
    fix = POLICY_FIX + " (it looks edited by hand or cut short)"
    for f, (kind, say) in _TOP_FIELDS.items():
        if not _is(kind, getattr(policy, f)):
            raise InputError(name, f, f"{f} must be {say}, got {getattr(policy, f)!r:.40}", fix)
    agents = policy.agents
    if not all(isinstance(agents[a], str) and agents[a] for a in ("robot", "human")):
        raise InputError(name, "agents", "agents must name the robot and the human", fix)
    for i, node in enumerate(policy.nodes):
        for f, (kind, say) in _NODE_FIELDS.items():
            v = getattr(node, f)
            if not _is(kind, v):
                raise InputError(name, f"nodes[{i}].{f}", f"must be {say}, got {v!r:.40}", fix)
        for j, move in enumerate(node.moves):
            for f, (kind, say) in _MOVE_FIELDS.items():
                v = getattr(move, f)
                if not _is(kind, v):
                    raise InputError(name, f"nodes[{i}].moves[{j}].{f}",
                                     f"must be {say}, got {v!r:.40}", fix)
    if not counts:
        return
    for node in policy.nodes:
        for j, move in enumerate(node.moves):
            if move.agent not in agents.values():
                raise InputError(name, f"nodes[{node.id}].moves[{j}].agent",
                                 f"every move is the robot's or the human's "
                                 f"({agents['robot']}, {agents['human']}), not "
                                 f"{move.agent!r:.40}", fix)
    # counted over the graph: linear, however many branches share its nodes
    leaves = policy.count_branches()
    if leaves != policy.leaves:
        raise InputError(name, "leaves", f"says {policy.leaves}, but the policy has {leaves} "
                         "branches", fix)
    comms = policy.count_communications()
    if comms != policy.communications:
        raise InputError(name, "communications",
                         f"says {policy.communications}, but the policy has {comms}", fix)


def check_policy_problem(policy: Policy, policy_path: Path | str, problem: Problem) -> None:
    """Raise :class:`InputError` unless ``policy`` was planned for ``problem`` (same problem
    name, domain, agents and K)."""
    d = problem.domain
    pairs = [("problem", policy.problem, problem.name), ("domain", policy.domain, d.name),
             ("robot", policy.agents["robot"], d.robot_name),
             ("human", policy.agents["human"], d.human_name), ("K", policy.K, problem.K)]
    for what, have, want in pairs:
        if have != want:
            raise InputError(str(policy_path), what, f"planned for {what} {have!r}, but "
                             f"{problem.source} has {want!r}",
                             f"give the policy solved for that problem (ehatp solve "
                             f"{problem.source} --out {policy_path})")


# --- the command group: usage mistakes and internal errors as one line -----------------------


class Commands(TyperGroup):
    """The ``ehatp`` command group. A usage mistake becomes one ``error:`` line (exit 2); an
    exception that is the program's fault one ``internal error:`` line (exit 3), its
    traceback in a file (or on screen with ``--debug``)."""

    # contexts are typed Any: typer's own Context type lives in a private module
    def make_context(self, info_name: str | None, args: list[str], parent: Any = None,
                     **extra: Any) -> Any:
        argv = list(args)  # parsing consumes the list
        with _usage_errors():
            ctx = super().make_context(info_name, args, parent, **extra)
        ctx.meta[ARGV_KEY] = argv
        return ctx

    def invoke(self, ctx: Any) -> Any:
        try:
            with _usage_errors():
                return super().invoke(ctx)
        except (typer.Exit, typer.Abort, TyperException, EOFError):
            raise  # the normal ways out (EOFError: typer's "Aborted!")
        except BrokenPipeError:
            raise  # the reader went away (e.g. `| head`): typer exits quietly
        except Exception as e:
            internal_error(e, ctx.meta.get(ARGV_KEY, []), bool(ctx.params.get("debug")))


@contextmanager
def _usage_errors() -> Iterator[None]:
    try:
        yield
    except TyperException as e:
        if type(e).__name__ == "NoArgsIsHelpError":  # `ehatp` alone: the help was printed
            raise
        ctx = getattr(e, "ctx", None)
        see = f"; see '{ctx.command_path} --help'" if ctx is not None else ""
        message = e.format_message().rstrip(".")
        die(f"{message}{see}", getattr(e, "exit_code", EXIT_BAD_INPUT))


def internal_error(e: BaseException, argv: Sequence[str], debug: bool) -> NoReturn:
    """Report an exception that is the program's fault: one line, exit code 3. The traceback
    goes to a file named after its content (the same failure reuses one file), or to the
    screen with ``--debug``."""
    what = f"{type(e).__name__}: {e}" if str(e) else type(e).__name__
    what = " ".join(what.split())
    tb = "".join(traceback.format_exception(e))
    if debug:
        typer.echo(tb.rstrip("\n"), err=True)
        typer.echo(f"internal error: {what}; traceback above", err=True)
        raise typer.Exit(EXIT_INTERNAL)
    report = (f"ehatp {__version__} internal error (Python {platform.python_version()}, "
              f"{sys.platform})\ncommand: ehatp {' '.join(argv)}\n\n{tb}")
    digest = hashlib.sha256(tb.encode()).hexdigest()[:12]
    path = Path(tempfile.gettempdir()) / f"ehatp-internal-error-{digest}.txt"
    try:
        path.write_text(report, encoding="utf-8")
        where = f"details in {path}"
    except OSError:
        where = "run again with `ehatp --debug ...` to see the traceback"
    typer.echo(f"internal error: {what}; this is a bug in ehatp, not in your input; {where} "
               "(please report it)", err=True)
    raise typer.Exit(EXIT_INTERNAL)


def write_output(text: str, out: Path | None) -> None:
    """Write a command's output to ``out``, or to stdout when it is None; a file that cannot
    be written is one line and exit 2."""
    if out is None:
        sys.stdout.write(text)
        return
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as e:
        die(InputError(str(out), "", f"cannot write ({e.strerror or e})",
                       "check that the directory exists and is writable").line())
