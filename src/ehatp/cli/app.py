"""The ``ehatp`` command line: the typer app, its own options (``--version``, ``--debug``), and
:data:`COMMANDS`, the table of its commands.

One command, one module: ``ehatp/cli/<module>.py`` makes its app with
:func:`~ehatp.cli.common.command_app` and registers the command on it with
``@app.command("name")`` (a group -- ``bench``, ``export`` -- names itself there and registers
its subcommands). The module parses the options and calls the logic, which lives in
:mod:`ehatp.formats`, :mod:`ehatp.run` and :mod:`ehatp.experiments`. A command's module is
imported only when the command runs: ``ehatp --help`` lists the commands from :data:`COMMANDS`
and imports none of them.

Exit codes: 0 success, 1 no policy (or an invalid one, or an unsolved benchmark row), 2 bad
input, 3 internal error, 141 the output's reader went away (``ehatp ... | head``; quiet). Bad
input is always one line on stderr, ``FILE:PLACE: problem; fix``, never a traceback; an
internal error is one line naming the file that holds the traceback (``ehatp --debug`` shows it
instead). See :mod:`ehatp.cli.common`.
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Annotated, Any, NamedTuple

import typer
from typer.core import TyperCommand

from .. import __version__
from .common import Commands, PipeClosed, is_broken_pipe, quiet_exit_broken_pipe
from .limits import STANDALONE


class Entry(NamedTuple):
    """A command of ``ehatp``: the module under ``ehatp.cli`` that defines it, and the first
    paragraph of its help, which ``ehatp --help`` lists (tests/test_architecture.py checks it
    is the module's own)."""

    module: str
    help: str


# in the order of `ehatp --help`
COMMANDS: dict[str, Entry] = {
    "solve": Entry("solve", "Plan a robot policy, optimal under the problem's objective, and "
                            "write it as JSON."),
    "show": Entry("show", "Print a policy as an indented tree and the timelines of its branches "
                          "(the first 100)."),
    "validate": Entry("validate", "Check a policy against a problem with the independent "
                                  "validator."),
    "render": Entry("render", "Draw a policy as Graphviz DOT or SVG, or as a self-contained HTML "
                              "explorer."),
    "simulate": Entry("simulate", "Step through an execution of the policy for PROBLEM, saying "
                                  "what each agent believes. Exit code 0: goal reached; 1: the "
                                  "human left the policy; 2: bad input."),
    "execute": Entry("execute", "Execute a policy live: JSON lines on stdin (what the human did, "
                                "what the robot finished) and on stdout (what the robot should "
                                "do, what the human believes, the goal, errors), for a robot "
                                "process to run as a subprocess. See docs/execution.md."),
    "play": Entry("play", "Play the human against the robot's policy in a browser: the participant's page shows only what the human perceives, an experimenter's page shows the truth and the policy, and every session is logged as JSON lines. See docs/play.md."),  # noqa: E501
    "sweep": Entry("sweep", "Solve many problems, and variants of them from a grid, in parallel: "
                            "one JSON line per instance (status, statistics, costs, validation, "
                            "time or error), a summary table at the end."),
    "import-hddl": Entry("import_hddl", "Import an HDDL domain and problem as one agent's task "
                                        "model: writes a Python domain module and a problem "
                                        "TOML that `ehatp solve` reads (docs/hddl.md). Exit 2 "
                                        "when the HDDL uses something ehatp cannot express (the "
                                        "line says what)."),
    "bench": Entry("bench", "Re-run the paper's benchmarks and compare with its figures; "
                            "measure how the planner scales."),
    "export": Entry("export", "Write a policy in another tool's format."),
    "expand": Entry("expand", "Write the version 2 graph, over the real objects, of a lifted "
                              "policy (format version 3)."),
    "relabel": Entry("relabel", "Search a preferences problem once and write the policy each "
                                "profile prefers, by relabelling the explored graph (no new "
                                "search per profile)."),
}


def load_command(name: str) -> Any:
    """The click command (or group) of ``ehatp NAME``, its module imported now."""
    module = importlib.import_module(f"{__package__}.{COMMANDS[name].module}")
    command_app: typer.Typer = module.app
    if command_app.info.name:  # a group names itself
        return typer.main.get_group(command_app)
    return typer.main.get_command(command_app)


class _Listed(TyperCommand):
    """A command as ``ehatp --help`` lists it, before its module is imported."""


class LazyCommands(Commands):
    """The ``ehatp`` group: :data:`COMMANDS` as placeholders, each replaced by the real command
    when it is the one to run (or to show the help of)."""

    def __init__(self, **attrs: Any) -> None:
        super().__init__(**attrs)
        for name, entry in COMMANDS.items():
            self.commands.setdefault(name, _Listed(name=name, help=entry.help))

    def resolve_command(self, ctx: Any, args: list[str]) -> Any:
        name, command, rest = super().resolve_command(ctx, args)
        if isinstance(command, _Listed) and name is not None:
            command = self.commands[name] = load_command(name)
        return name, command, rest


app = typer.Typer(
    name="ehatp",
    cls=LazyCommands,  # usage mistakes and internal errors end in one line too
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
    rich_markup_mode="markdown",  # reflows docstring paragraphs in --help
)


def compiled_modules() -> list[str]:
    """The modules of ehatp that run compiled (docs/compiled.md): those with an extension
    module (``andor.cpython-311-x86_64-linux-gnu.so``) beside their source, which Python
    imports in its place. Empty for the pure Python core (``pip install .``)."""
    from importlib.machinery import EXTENSION_SUFFIXES
    from pathlib import Path

    import ehatp

    root = Path(ehatp.__file__).parent
    out = set()
    for f in root.rglob("*"):
        # the longest suffix first: "andor.cpython-311-x86_64-linux-gnu.so" before ".so"
        suffix = next((s for s in EXTENSION_SUFFIXES if f.name.endswith(s)), None)
        if suffix is not None:
            out.add(".".join(("ehatp", *f.relative_to(root).parent.parts,
                              f.name[:-len(suffix)])))
    return sorted(out)


def _version(value: bool) -> None:
    if value:
        n = len(compiled_modules())
        typer.echo(f"ehatp {__version__}" + (f" (compiled core: {n} modules)" if n else ""))
        raise typer.Exit()


def _core(value: bool) -> None:
    if value:
        mods = compiled_modules()
        typer.echo("\n".join(["compiled core:", *mods]) if mods else "pure Python core")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[bool, typer.Option(
        "--version", callback=_version, is_eager=True,
        help="Print the version and exit (it says \"compiled core\" when ehatp was installed "
             "with its compiled core, docs/compiled.md).")] = False,
    core: Annotated[bool, typer.Option(
        "--core", callback=_core, is_eager=True,
        help="Print which core runs, \"pure Python core\" or \"compiled core:\" and the "
             "modules compiled, and exit.")] = False,
    debug: Annotated[bool, typer.Option(
        "--debug", help="On an internal error, print the traceback instead of writing it to "
                        "a file.")] = False,
) -> None:
    """Epistemic Human-Aware Task Planner: plan robot policies that account for what the human
    sees, believes and may be told.

    Typical use: `ehatp solve problem.toml --out policy.json`, then `ehatp show policy.json`
    and `ehatp validate problem.toml policy.json`. Exit codes: 0 ok, 1 no (valid) policy,
    2 bad input, 3 internal error (a bug: the line names a file with the details).
    """


def main() -> None:
    """Run ``ehatp`` (the console entry point) and exit with its code. When the output's reader
    goes away (``ehatp solve ... | head``), at any point -- a command's output, ``--help``, the
    last flush of stdout -- the run ends quietly with exit code 141
    (:data:`~ehatp.cli.common.EXIT_BROKEN_PIPE`, what a shell reports for a tool SIGPIPE
    ended), never 1, which means "no policy"."""
    before = _stdout_identity()
    try:
        try:
            app(prog_name="ehatp", obj=STANDALONE)  # the backstop may end this process
        except SystemExit as e:
            sys.stdout.flush()  # the buffered rest, here rather than at interpreter exit
            if e.code == 1 and before != _stdout_identity() == _devnull_identity():
                # rich (typer's help, a live display) met the broken pipe itself: it pointed
                # stdout at the null device and exits 1, which here would mean "no policy"
                quiet_exit_broken_pipe()
            raise
        sys.stdout.flush()
    except PipeClosed:
        quiet_exit_broken_pipe()
    except OSError as e:
        if not is_broken_pipe(e):
            raise
        quiet_exit_broken_pipe()


def _stdout_identity() -> tuple[int, int] | None:
    """Return the device and inode file descriptor 1 refers to (None if it has none)."""
    try:
        st = os.fstat(1)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def _devnull_identity() -> tuple[int, int]:
    """Return the device and inode of the null device."""
    st = os.stat(os.devnull)
    return st.st_dev, st.st_ino

__all__ = ["COMMANDS", "Entry", "LazyCommands", "app", "load_command", "main"]


if __name__ == "__main__":
    main()
