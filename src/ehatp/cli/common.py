"""What every command shares: how each run ends in one line and a documented exit code, how a
command module makes its typer app (:func:`command_app`), and reading the files commands take.

Exit codes: 0 ok, 1 no (valid) policy, 2 bad input (one line ``error: FILE:PLACE: problem;
fix``), 3 internal error (one line naming a file that holds the traceback, or the traceback on
screen with ``ehatp --debug``), 141 the reader of the output went away (``ehatp ... | head``:
no message, as a shell reports a command that SIGPIPE ended). Usage mistakes (an unknown
option, a missing argument) are bad input too, and also one line.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import os
import platform
import sys
import tempfile
import traceback
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import typer
from typer.core import TyperGroup
from typer.exceptions import TyperException

from .. import __version__
from ..errors import DomainError, EhatpError, InputError, printable
from ..formats.policy import Policy
from ..formats.policy_check import check_consistent, check_policy_problem, read_policy
from ..formats.problem_toml import load
from ..model.options import ObjectiveKind
from ..model.problem import Problem, parse_size

if TYPE_CHECKING:
    from rich.console import Console

EXIT_OK, EXIT_NO_POLICY, EXIT_BAD_INPUT, EXIT_INTERNAL = 0, 1, 2, 3
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE: what a shell reports for a tool a closed pipe ended
ARGV_KEY = "ehatp.argv"  # where the command line is kept for an internal-error report


def die(message: str, code: int = EXIT_BAD_INPUT) -> NoReturn:
    """One line on stderr, then exit; newlines are folded so the promise of one line holds,
    and control characters are written escaped (a name cannot send a terminal escape code)."""
    typer.echo(f"error: {printable(' '.join(message.split()))}", err=True)
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


# --- the files commands read -----------------------------------------------------------------


def load_problem(path: Path) -> Problem:
    with user_errors(path):
        return load(path)
    raise AssertionError  # unreachable: user_errors exits; keeps type checkers content


def load_policy(path: Path, problem: Path | None = None, *, counts: bool = True,
                consistent: bool = False) -> Policy:
    """The policy at ``path``, its structure checked (see
    :func:`~ehatp.formats.policy_check.read_policy`), with ``problem`` checked to be the one
    it was planned for, and (``consistent``) what it says checked against its own graph
    (:func:`~ehatp.formats.policy_check.check_consistent`); a mistake is one line, exit 2."""
    with user_errors(path):
        pol = read_policy(path, counts=counts)
    if problem is not None:
        prob = load_problem(problem)
        with user_errors(path):
            check_policy_problem(pol, path, prob)
    if consistent:
        with user_errors(path):
            check_consistent(pol, str(path))
    return pol


EXPAND_LIMIT_HELP = ("How many nodes over the real objects a lifted policy (format version 3) "
                     "may expand to here (0: no limit); past it, what needs the whole graph "
                     "is left out or refused, in one line.")


def expand_limit(n: int) -> int | None:
    """``--expand-limit N`` as the readers take it: None (no limit) for 0."""
    return n or None


def memory_option(text: str | None) -> int | None:
    """Return ``--max-memory TEXT`` in bytes (None when not given); a size that does not read
    is one line, exit 2."""
    if text is None:
        return None
    try:
        return parse_size(text)
    except ValueError as e:
        die(f"--max-memory {text}: {e}; write e.g. 2G, 512M or a number of bytes")


def with_objective(prob: Problem, kind: ObjectiveKind | None) -> Problem:
    """Print the problem's notes; ``--objective`` overrides its ``[objective] kind``."""
    if prob.notes:
        from ..formats.text import print_notes

        print_notes(prob)
    if kind is None:
        return prob
    return dataclasses.replace(prob, objective=dataclasses.replace(prob.objective, kind=kind))


def stderr_console() -> Console | None:
    """A console for live progress, or None when stderr is not a terminal (stay quiet)."""
    if not sys.stderr.isatty():
        return None
    from rich.console import Console

    return Console(stderr=True)


# --- one command, one module -----------------------------------------------------------------


def command_app(**settings: Any) -> typer.Typer:
    """The typer app of one command module (``ehatp/cli/<command>.py``), with the settings of
    ``ehatp`` itself: help in markdown, no shell-completion options. A module registers its
    command with ``@app.command("name")``; a group of commands (``bench``, ``export``) gives
    its ``name`` and ``help`` here. :data:`ehatp.cli.app.COMMANDS` lists the modules."""
    return typer.Typer(add_completion=False, pretty_exceptions_show_locals=False,
                       rich_markup_mode="markdown", **settings)


# --- the command group: usage mistakes and internal errors as one line -----------------------


class Commands(TyperGroup):
    """The ``ehatp`` command group. A usage mistake becomes one ``error:`` line (exit 2); an
    exception that is the program's fault one ``internal error:`` line (exit 3), its
    traceback in a file (or on screen with ``--debug``)."""

    # contexts are typed Any: typer's own Context type lives in a private module
    def make_context(self, info_name: str | None, args: list[str], parent: Any = None,
                     **extra: Any) -> Any:
        argv = list(args)  # parsing consumes the list
        with _pipe_closed(), _usage_errors():  # --help and --version write here
            ctx = super().make_context(info_name, args, parent, **extra)
        ctx.meta[ARGV_KEY] = argv
        return ctx

    def invoke(self, ctx: Any) -> Any:
        try:
            with _pipe_closed(), _usage_errors():
                return super().invoke(ctx)
        except (typer.Exit, typer.Abort, TyperException, EOFError, PipeClosed):
            raise  # the normal ways out (EOFError: typer's "Aborted!")
        except Exception as e:
            internal_error(e, ctx.meta.get(ARGV_KEY, []), bool(ctx.params.get("debug")))


class PipeClosed(Exception):
    """The reader of the output went away (``ehatp ... | head``): not a result and not a bug.
    Not an :class:`OSError`, so that typer does not turn it into exit code 1 ("no policy");
    :func:`ehatp.cli.app.main` ends the run quietly with :data:`EXIT_BROKEN_PIPE`."""


def is_broken_pipe(e: BaseException) -> bool:
    """Return whether ``e`` says the output's reader went away (EPIPE)."""
    return isinstance(e, BrokenPipeError) or isinstance(e, OSError) and e.errno == errno.EPIPE


@contextmanager
def _pipe_closed() -> Iterator[None]:
    try:
        yield
    except OSError as e:
        if not is_broken_pipe(e):
            raise
        raise PipeClosed() from None


def quiet_exit_broken_pipe() -> NoReturn:
    """End the run after the output's reader went away: point stdout and stderr at the null
    device (so the interpreter's last flush of what is still buffered cannot fail again and
    print "Exception ignored ... BrokenPipeError"), then exit with :data:`EXIT_BROKEN_PIPE`,
    saying nothing (there is no one to say it to, and ``| head`` is not a mistake)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    for stream in (sys.stdout, sys.stderr):
        # (a stream with no file descriptor, such as a test's capture, is left as it is)
        with contextlib.suppress(OSError, ValueError, AttributeError):
            os.dup2(devnull, stream.fileno())
    os.close(devnull)
    raise SystemExit(EXIT_BROKEN_PIPE)


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
    goes to a new file only the user can read (:func:`report_file`), or to the screen with
    ``--debug``."""
    what = f"{type(e).__name__}: {e}" if str(e) else type(e).__name__
    what = printable(" ".join(what.split()))
    tb = "".join(traceback.format_exception(e))
    if debug:
        typer.echo(printable(tb.rstrip("\n"), lines=True), err=True)
        typer.echo(f"internal error: {what}; traceback above", err=True)
        raise typer.Exit(EXIT_INTERNAL)
    report = (f"ehatp {__version__} internal error (Python {platform.python_version()}, "
              f"{sys.platform})\ncommand: ehatp {' '.join(argv)}\n\n{tb}")
    try:
        where = f"details in {report_file(report)}"
    except OSError:
        where = "run again with `ehatp --debug ...` to see the traceback"
    typer.echo(f"internal error: {what}; this is a bug in ehatp, not in your input; {where} "
               "(please report it)", err=True)
    raise typer.Exit(EXIT_INTERNAL)


def report_file(report: str) -> Path:
    """Return the path of a new file holding ``report``: made by :func:`tempfile.mkstemp` in
    the temporary folder, under a name no one can guess in advance and readable by the user
    alone (mode 0600), so that another user can neither plant it nor read it."""
    fd, name = tempfile.mkstemp(prefix="ehatp-internal-error-", suffix=".txt")
    with open(fd, "w", encoding="utf-8") as f:
        f.write(report)
    return Path(name)


def write_output(text: str, out: Path | None, what: str | None = None,
                 command: str | None = None) -> None:
    """Write a command's output to ``out``, or to stdout when it is None (control characters
    escaped when stdout is a terminal); a file that cannot be written is one line and exit 2.
    Written to a file, it says so in one line on stderr, as ``solve`` does: ``COMMAND: wrote
    p2.html: WHAT, 60.6 kB`` (:func:`wrote_line`)."""
    if out is None:
        write_stdout(printable(text, lines=True) if sys.stdout.isatty() else text)
        return
    data = text.encode("utf-8")
    try:
        out.write_bytes(data)
    except OSError as e:
        die(InputError(str(out), "", f"cannot write ({e.strerror or e})",
                       "check that the directory exists and is writable").line())
    typer.echo(wrote_line(out, len(data), what, command), err=True)


def wrote_line(out: Path | str, size: int, what: str | None = None,
               command: str | None = None) -> str:
    """Return the line a command says after writing ``size`` bytes to the file ``out``, e.g.
    ``render: wrote p2.html: HTML explorer of P2, 26 policy nodes, 60.6 kB``: the command (if
    given), the file, ``what`` it holds (if given), its size."""
    head = f"{command}: " if command else ""
    parts = [what, file_size(size)] if what else [file_size(size)]
    return printable(f"{head}wrote {out}: {', '.join(parts)}")


def file_size(size: int) -> str:
    """Return a size in bytes as people read it: ``812 bytes``, ``60.6 kB``, ``41.2 MB``
    (powers of 1000)."""
    if size < 1000:
        return f"{size} byte" + ("" if size == 1 else "s")
    for unit, scale in (("kB", 1e3), ("MB", 1e6)):
        if size < scale * 1000 - 50 * scale / 1000:
            return f"{size / scale:.1f} {unit}"
    return f"{size / 1e9:.1f} GB"


def write_stdout(text: str) -> None:
    """Write ``text`` to stdout whole, or raise :class:`BrokenPipeError` when the reader goes
    away first. Straight to the file descriptor, each partial write continued: Python's own
    buffered write of a large text into a pipe whose reader leaves mid-write drops the rest
    silently and reports success, which would end ``ehatp render ... | head`` with exit 0."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, ValueError, OSError):  # not a real file (a test's capture)
        sys.stdout.write(text)
        return
    sys.stdout.flush()
    data = memoryview(text.encode(sys.stdout.encoding or "utf-8", "replace"))
    while data:
        data = data[os.write(fd, data):]
