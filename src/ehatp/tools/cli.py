"""The ``ehatp`` command line: solve, show, validate, bench (render and simulate plug in).

Exit codes: 0 success, 1 no policy (or an invalid one, or an unsolved benchmark row), 2 bad
input, 3 internal error. Bad input is always one line on stderr, ``FILE:PLACE: problem; fix``,
never a traceback; an internal error is one line naming the file that holds the traceback
(``ehatp --debug`` shows it instead). See ``common.py``.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from .. import __version__
from ..model.options import ObjectiveKind
from ..model.problem import Problem, load, parse_size
from ..policy_format import Policy
from .common import (
    EXIT_NO_POLICY,
    EXIT_OK,
    Commands,
    check_policy_problem,
    die,
    read_policy,
    user_errors,
)

# rich, the search and the bench tables load when a command needs them (start-up time)
if TYPE_CHECKING:
    from rich.console import Console
    from rich.live import Live
    from rich.text import Text

    from ..search.andor import Stats
    from ..search.planner import Result

app = typer.Typer(
    name="ehatp",
    cls=Commands,  # usage mistakes and internal errors end in one line too
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
    rich_markup_mode="markdown",  # reflows docstring paragraphs in --help
)
bench_app = typer.Typer(help="Re-run the paper's benchmarks and compare with its figures; "
                             "measure how the planner scales.", no_args_is_help=True)
app.add_typer(bench_app, name="bench")

SHOW_PROGRESS_AFTER_S = 0.5  # quick solves never flash a progress line


def load_problem(path: Path) -> Problem:
    with user_errors(path):
        return load(path)
    raise AssertionError  # unreachable: user_errors exits; keeps type checkers content


def load_policy(path: Path, problem: Path | None = None, *, counts: bool = True) -> Policy:
    """The policy at ``path``, its structure checked (see ``common.read_policy``), and with
    ``problem`` checked to be the one it was planned for; a mistake is one line, exit 2."""
    with user_errors(path):
        pol = read_policy(path, counts=counts)
    if problem is not None:
        prob = load_problem(problem)
        with user_errors(path):
            check_policy_problem(pol, path, prob)
    return pol


def stderr_console() -> Console | None:
    """A console for live progress, or None when stderr is not a terminal (stay quiet)."""
    if not sys.stderr.isatty():
        return None
    from rich.console import Console

    return Console(stderr=True)


# --- progress --------------------------------------------------------------------------------


class LiveProgress:
    """Progress on the terminal through every phase of ``solve`` (grounding, search with its
    states/s, worlds and frontier, values, extraction, writing), cleared when done."""

    def __init__(self, console: Console, label: str) -> None:
        self.console, self.label = console, label
        self.live: Live | None = None

    def __call__(self, stats: Stats, frontier: int) -> None:
        if stats.time_s < SHOW_PROGRESS_AFTER_S:
            return
        text = self.render(stats, frontier)
        if self.live is None:
            from rich.live import Live

            self.live = Live(text, console=self.console, transient=True, refresh_per_second=4,
                             redirect_stdout=False, redirect_stderr=False)
            self.live.start()
        else:
            self.live.update(text)

    def render(self, stats: Stats, frontier: int) -> Text:
        from rich.text import Text

        if stats.phase == "grounding":
            return Text.assemble((f"{self.label} ", "bold"), "grounding the problem · ",
                                 f"{stats.time_s:.1f} s")
        if stats.phase != "search":
            return Text.assemble((f"{self.label} ", "bold"), (stats.phase, "cyan"),
                                 f" · {stats.distinct:,} distinct states · {stats.time_s:.1f} s")
        rate = stats.generated / stats.time_s if stats.time_s else 0.0
        return Text.assemble(
            (f"{self.label} ", "bold"),
            f"{stats.generated:,} states ({stats.distinct:,} distinct) · ",
            (f"{rate:,.0f} states/s", "cyan"),
            f" · |W| ≤ {stats.max_worlds} · frontier {frontier:,} · {stats.time_s:.1f} s")

    def close(self) -> None:
        if self.live is not None:
            self.live.stop()
            self.live = None


# --- version and top level -------------------------------------------------------------------


def _version(value: bool) -> None:
    if value:
        typer.echo(f"ehatp {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[bool, typer.Option(
        "--version", callback=_version, is_eager=True,
        help="Print the version and exit.")] = False,
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


# --- solve -----------------------------------------------------------------------------------


def solve(problem: Problem, **kwargs: Any) -> Result:
    """:func:`ehatp.solve`; the search loads on first use, not when the program starts."""
    from ..search.planner import solve as planner_solve

    return planner_solve(problem, **kwargs)


def with_objective(prob: Problem, kind: ObjectiveKind | None) -> Problem:
    """Print the problem's notes; ``--objective`` overrides its ``[objective] kind``."""
    if prob.notes:
        from .show import print_notes

        print_notes(prob)
    if kind is None:
        return prob
    return dataclasses.replace(prob, objective=dataclasses.replace(prob.objective, kind=kind))


@app.command("solve")
def solve_cmd(
    problem: Annotated[Path, typer.Argument(
        help="Problem file (TOML), e.g. examples/cubes/p1.toml.", metavar="PROBLEM.toml",
        show_default=False)],
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Where to write the policy JSON (default: PROBLEM-NAME.policy.json "
                            "in the current directory).", show_default=False)] = None,
    timeout: Annotated[float | None, typer.Option(
        "--timeout", min=0.0, help="Stop after this many seconds, whatever the work under "
                                   "way: search, values, extraction or writing (default: the "
                                   "problem's limits.timeout, else none).",
        show_default=False)] = None,
    max_memory: Annotated[str | None, typer.Option(
        "--max-memory", metavar="SIZE", help="Stop before the process uses more resident "
                                             "memory than this, e.g. 2G or 512M (default: the "
                                             "problem's limits.max_memory, else none).",
        show_default=False)] = None,
    max_states: Annotated[int | None, typer.Option(
        "--max-states", min=1, help="Stop after this many distinct states (default: the "
                                    "problem's limits.max_states).",
        show_default=False)] = None,
    max_depth: Annotated[int | None, typer.Option(
        "--max-depth", min=1, help="Treat states deeper than this as dead ends (default: the "
                                   "problem's limits.max_depth).",
        show_default=False)] = None,
    objective: Annotated[ObjectiveKind | None, typer.Option(
        "--objective", help="What to minimise: the worst case over the human's choices or the "
                            "expected cost (default: the problem's [objective] kind, else "
                            "worst-case).", show_default=False)] = None,
    no_symmetry: Annotated[bool, typer.Option(
        "--no-symmetry", help="Search every state, not one per renaming of interchangeable "
                              "objects (default: the problem's limits.symmetry, else on; "
                              "docs/semantics.md §3).")] = False,
) -> None:
    """Plan a robot policy, optimal under the problem's objective, and write it as JSON.

    Prints a summary: solved or why not, states generated/distinct, the largest number of
    worlds the human entertains (|W|), leaves, the policy's worst-case and expected cost (and
    which one was minimised), communications and time.
    Exit 0 solved; 1 no policy exists or a limit stopped the work (one line says which; the
    best policy found so far, if any, is still written, marked not optimal); 2 bad input.
    """
    t0 = time.perf_counter()
    from ..search.limits import Budget, LimitReached

    memory: int | None = None
    if max_memory is not None:
        try:
            memory = parse_size(max_memory)
        except ValueError as e:
            die(f"--max-memory {max_memory}: {e}; write e.g. 2G, 512M or a number of bytes")
    prob = with_objective(load_problem(problem), objective)
    limits = prob.limits
    budget = Budget(limits.timeout if timeout is None else timeout,
                    limits.max_memory if memory is None else memory, start=t0)
    console = stderr_console()
    live = LiveProgress(console, prob.name) if console is not None else None
    result: Result | None = None
    target = out if out is not None else Path(f"{problem.stem}.policy.json")
    written = False
    try:
        with user_errors(problem):
            result = solve(prob, max_states=max_states, max_depth=max_depth, progress=live,
                           budget=budget, symmetry=False if no_symmetry else None)
        if result.policy is not None:
            budget.phase = "writing"
            try:
                # the text is made (under the limits) before the file is touched
                result.policy.write(target, check=budget.check)
                written = True
            except OSError as e:
                die(f"{target}: cannot write the policy ({e.strerror or e}); choose another "
                    "--out")
            except (LimitReached, MemoryError) as e:
                stop = e if isinstance(e, LimitReached) else budget.out_of_memory()
                result = dataclasses.replace(result, status=stop.status, policy=None,
                                             reason=stop.reason, optimal=False)
    finally:
        if live is not None:
            live.close()
    assert result is not None
    wall_ms = (time.perf_counter() - t0) * 1000
    _summary(prob, result, wall_ms, target if written else None)
    raise typer.Exit(EXIT_OK if result.status == "solved" else EXIT_NO_POLICY)


def _summary(prob: Problem, result: Result, wall_ms: float, written: Path | None) -> None:
    st = result.stats
    if result.status == "solved" and result.optimal:
        typer.secho(f"{prob.name}: solved (optimal policy found)", fg="green", bold=True)
    elif result.status == "solved":
        typer.secho(f"{prob.name}: solved, {result.reason}", fg="yellow", bold=True)
    elif result.status == "unsolvable":
        typer.secho(f"{prob.name}: {result.reason}", fg="red", bold=True)
    else:
        typer.secho(f"{prob.name}: stopped early, {result.reason}; partial statistics:",
                    fg="yellow", bold=True)
    rows: list[tuple[str, Any]] = [
        ("states", f"{st.get('generated', 0):,} generated, {st.get('distinct', 0):,} distinct, "
                   f"{st.get('expanded', 0):,} expanded"),
        ("|W|", f"{st.get('max_worlds', 0)} (most worlds the human entertains at once)"),
    ]
    pol = result.policy
    if pol is not None:
        from .show import cost_lines

        rows += [("leaves", pol.leaves), *cost_lines(pol),
                 ("communications", pol.communications)]
    rows.append(("time", f"{st.get('time_ms', 0):,} ms search, {wall_ms:,.1f} ms in all"))
    if written is not None:
        note = ("" if result.optimal else " (NOT proven optimal)" if result.status == "solved"
                else " (best found so far, NOT proven optimal)")
        rows.append(("policy", f"written to {written}{note}"))
    elif result.status != "unsolvable":
        rows.append(("policy", "none found before the work stopped"))
    for k, v in rows:
        typer.echo(f"  {k:<15} {v}")


# --- show ------------------------------------------------------------------------------------


@app.command("show")
def show_cmd(
    policy: Annotated[Path, typer.Argument(
        help="Policy JSON written by `ehatp solve`.", metavar="POLICY.json",
        show_default=False)],
    tree: Annotated[bool, typer.Option(
        "--tree/--no-tree", help="Print the policy tree.")] = True,
    timelines: Annotated[bool, typer.Option(
        "--timelines/--no-timelines",
        help="Print the branches' timelines (the first 100).")] = True,
    details: Annotated[bool, typer.Option(
        "--details", "-d", help="Under each tree node, list what the human is unsure about "
                                "and the K-counter.")] = False,
    problem: Annotated[Path | None, typer.Option(
        "--problem", "-p", help="Check that the policy was planned for this problem file.",
        metavar="PROBLEM.toml", show_default=False)] = None,
) -> None:
    """Print a policy as an indented tree and the timelines of its branches (the first 100).

    Tree: each line is one step (node number, agent, action, W = worlds the human entertains;
    marks apart, COMM for a communication, GOAL). Straight runs stay at one indent; the tree
    forks only where the human chooses. A node reached by several paths is printed once; the
    other moves into it end with "-> see node N".
    Timelines: turns while the agents are together,
    parallel lanes while they are apart. Colour on a terminal, plain text in a pipe.
    The file's structure is checked first (exit 2 if it was edited into something else).
    """
    pol = load_policy(policy, problem)
    from .show import plain, policy_lines, print_rich

    lines = policy_lines(pol, tree=tree, timelines=timelines, details=details)
    if sys.stdout.isatty():
        from rich.console import Console

        print_rich(lines, Console())
    else:
        typer.echo(plain(lines), nl=False)


# --- validate --------------------------------------------------------------------------------


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
        typer.echo(f"note: {policy} was planned for {pol.problem!r}, not {prob.name!r}",
                   err=True)
    with user_errors(policy):
        report = ehatp.validate(prob, pol)
    if report.ok:
        typer.secho(f"valid: {policy} is a valid policy for {prob.name}", fg="green")
        raise typer.Exit(EXIT_OK)
    typer.secho(f"invalid: {report.message}", fg="red")
    raise typer.Exit(EXIT_NO_POLICY)


# --- bench -----------------------------------------------------------------------------------


def _write_rows(rows: object, json_out: Path) -> None:
    """A bench's rows as JSON, to ``json_out`` or to stdout for ``-``."""
    data = json.dumps(rows, indent=1) + "\n"
    if str(json_out) == "-":
        typer.echo(data, nl=False)
        return
    try:
        json_out.write_text(data, encoding="utf-8")
    except OSError as e:
        die(f"{json_out}: cannot write ({e.strerror or e}); choose another --json file")


@bench_app.command("table1")
def bench_table1(
    json_out: Annotated[Path | None, typer.Option(
        "--json", help="Also write the rows as JSON to this file ('-' for stdout, which then "
                       "replaces the table).", show_default=False)] = None,
    repeat: Annotated[int, typer.Option(
        "--repeat", "-n", min=1, help="Runs per instance; the best time is kept.")] = 3,
    only: Annotated[list[str] | None, typer.Option(
        "--only", metavar="NAME",
        help="Run just this instance (repeatable), e.g. --only P3 --only 'Cooking 1'.",
        show_default=False)] = None,
) -> None:
    """Solve the nine Table 1 instances (P1-P6, Cooking 1-3) and compare with the paper.

    Shows our states, |W|, leaves and time (measured now) beside the paper's, and, labelled as
    stored figures, the published times and the authors' prototype without tree copying
    (measured side by side on 2026-11-22). Exit 1 if an instance is missing or not solved.
    """
    from . import bench as bench_mod

    if only:
        known = {bench_mod.instance_key(r.instance) for r in bench_mod.TABLE1}
        unknown = [o for o in only if bench_mod.instance_key(o) not in known]
        if unknown:
            names = ", ".join(r.instance for r in bench_mod.TABLE1)
            die(f"--only {unknown[0]}: no such Table 1 instance; use one of {names}")
    console = stderr_console()
    status = console.status("") if console is not None else None

    def notify(inst: str, run: int, runs: int) -> None:
        if status is not None:
            status.update(f"solving {inst} (run {run}/{runs})")

    if status is not None:
        status.start()
    try:
        rows = bench_mod.run_table1(repeat, notify, only)
    finally:
        if status is not None:
            status.stop()
    if json_out is not None:
        _write_rows(rows, json_out)
    if str(json_out) != "-":
        from rich.console import Console

        con = Console() if sys.stdout.isatty() else None
        table = bench_mod.rich_table(rows)
        # a crushed table is worse than a wrapped plain one on a narrow terminal
        if con is not None and _fits(con, table):
            con.print(table)
        else:
            typer.echo(bench_mod.format_table(rows), nl=False)
    failed = [r for r in rows if not r["solved"]]
    for r in failed:
        typer.echo(f"not solved: {r['instance']}: {r['error']}", err=True)
    raise typer.Exit(EXIT_NO_POLICY if failed else EXIT_OK)


@bench_app.command("scaling")
def bench_scaling(
    max_size: Annotated[int, typer.Option(
        "--max-size", min=1, help="Run the grid points up to this size (cubes, or places on "
                                  "the pantry trip for cooking).")] = 5,
    only: Annotated[list[str] | None, typer.Option(
        "--only", metavar="PATTERN",
        help="Run just the instances matching this name pattern, any size (repeatable), e.g. "
             "--only 'cubes-c9-*' --only cooking-k8.", show_default=False)] = None,
    timeout: Annotated[float, typer.Option(
        "--timeout", min=0.1, help="Seconds each instance may take (it is stopped then, and "
                                   "reported as such).")] = 60.0,
    max_memory: Annotated[str | None, typer.Option(
        "--max-memory", metavar="SIZE", help="Resident memory each instance may use, e.g. 2G.",
        show_default=False)] = None,
    repeat: Annotated[int, typer.Option(
        "--repeat", "-n", min=1, help="Runs per instance; times and peaks are medians.")] = 1,
    json_out: Annotated[Path | None, typer.Option(
        "--json", help="Also write the rows as JSON to this file ('-' for stdout, which then "
                       "replaces the table).", show_default=False)] = None,
    plot: Annotated[Path | None, typer.Option(
        "--plot", metavar="FILE.png", help="Also plot time and memory against the number of "
                                           "distinct states (needs ehatp[plot]).",
        show_default=False)] = None,
) -> None:
    """Solve a grid of generated problems, each in a fresh process, and show how time and
    memory grow: cubes 3-10 split over both tables, 2-3 boxes, transparent or opaque, trips of
    K=2-8; cooking with trips of K=2-8; and two larger cube instances (12 cubes; 10 cubes with
    human_reach "any"), run when --only names them or --max-size allows.

    Per instance: time (solve and the policy as JSON), states generated and distinct,
    states/s, |W|, peak resident memory, and the policy's size (nodes, bytes). Exit 1 if an
    instance crashed (a stop at --timeout or --max-memory is a result, not a failure).
    """
    from . import bench as bench_mod

    memory = 0
    if max_memory is not None:
        try:
            memory = parse_size(max_memory)
        except ValueError as e:
            die(f"--max-memory {max_memory}: {e}; write e.g. 2G, 512M or a number of bytes")
    points = bench_mod.select_points(max_size, only)
    if not points:
        what = f"--only {' '.join(only)}" if only else f"--max-size {max_size}"
        die(f"{what}: no grid instance selected; names look like cubes-c6-b3-opaque-k8, "
            "cooking-k4")
    console = stderr_console()
    status = console.status("") if console is not None else None

    def notify(p: Any, i: int, n: int, run: int) -> None:
        if status is not None:
            status.update(f"solving {p.name} ({i + 1}/{n}, run {run + 1}/{repeat})")

    if status is not None:
        status.start()
    try:
        rows = bench_mod.run_scaling(points, timeout=timeout, max_memory=memory,
                                     repeat=repeat, notify=notify)
    finally:
        if status is not None:
            status.stop()
    if json_out is not None:
        _write_rows(rows, json_out)
    if str(json_out) != "-":
        typer.echo(bench_mod.format_scaling(rows), nl=False)
    if plot is not None and not bench_mod.plot_scaling({"this run": rows}, str(plot)):
        typer.echo("note: --plot skipped: matplotlib is not installed "
                   "(pip install 'ehatp[plot]')", err=True)
    crashed = [r for r in rows if r["status"] in ("crashed", "killed")]
    for r in crashed:
        typer.echo(f"failed: {r['instance']}: {r['error']}", err=True)
    raise typer.Exit(EXIT_NO_POLICY if crashed else EXIT_OK)


def _fits(con: Console, table: Any) -> bool:
    # measure against a huge width: measuring against the console's own width always fits
    return con.measure(table, options=con.options.update_width(10_000)).maximum <= con.width


# --- entry point -----------------------------------------------------------------------------


def main() -> None:
    """Console entry point (``ehatp``)."""
    app(prog_name="ehatp")


# Other commands live in their own modules and add themselves; imported last so they may
# import helpers from this module without a circular-import failure.
from . import bt, execute, hddl, render, simulate, sweep  # noqa: E402

render.register(app)
simulate.register(app)
execute.register(app)
bt.register(app)
sweep.register(app)
hddl.register(app)

if __name__ == "__main__":
    main()
