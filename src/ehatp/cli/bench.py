"""``ehatp bench``: the paper's Table 1 beside its figures, and how the planner scales
(:mod:`ehatp.experiments.bench` runs them)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from ..errors import printable
from ..model.problem import parse_size
from .common import EXIT_NO_POLICY, EXIT_OK, command_app, die, stderr_console, write_stdout

if TYPE_CHECKING:
    from rich.console import Console

app = command_app(name="bench", help="Re-run the paper's benchmarks and compare with its "
                                     "figures; measure how the planner scales.",
                  no_args_is_help=True)


def _write_rows(rows: object, json_out: Path) -> None:
    """A bench's rows as JSON, to ``json_out`` or to stdout for ``-``."""
    data = json.dumps(rows, indent=1) + "\n"
    if str(json_out) == "-":
        write_stdout(data)
        return
    try:
        json_out.write_text(data, encoding="utf-8")
    except OSError as e:
        die(f"{json_out}: cannot write ({e.strerror or e}); choose another --json file")


@app.command("table1")
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
    from ..experiments import bench as bench_mod

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
            write_stdout(bench_mod.format_table(rows))
    failed = [r for r in rows if not r["solved"]]
    for r in failed:
        typer.echo(f"not solved: {r['instance']}: {r['error']}", err=True)
    raise typer.Exit(EXIT_NO_POLICY if failed else EXIT_OK)


def _run_points(points: list[Any], timeout: float, memory: int, repeat: int,
                symmetry: bool | None, classes: bool,
                world_classes: bool = False) -> list[dict[str, Any]]:
    """Return the scaling rows of ``points``, each solved in a process of its own, and say on
    stderr one line per finished point (:func:`~ehatp.experiments.bench.progress_line`),
    whether stderr is a terminal or a pipe or a file, with a status line on a terminal saying
    which one is running."""
    from ..experiments import bench as bench_mod

    console = stderr_console()
    status = console.status("") if console is not None else None

    def notify(p: Any, i: int, n: int, run: int) -> None:
        if status is not None:
            status.update(f"solving {p.name} ({i + 1}/{n}, run {run + 1}/{repeat})")

    def done(row: dict[str, Any], i: int, n: int) -> None:
        line = printable(f"bench scaling: {bench_mod.progress_line(row, i, n)}")
        if console is not None:
            console.print(line, markup=False, highlight=False)  # above the status line
        else:
            typer.echo(line, err=True)  # a line at a time: `2>&1 | tee`, a CI log

    if status is not None:
        status.start()
    try:
        return bench_mod.run_scaling(points, timeout=timeout, max_memory=memory,
                                     repeat=repeat, notify=notify, symmetry=symmetry,
                                     done=done, classes=classes,
                                     world_classes=world_classes)
    finally:
        if status is not None:
            status.stop()


@app.command("scaling")
def bench_scaling(
    max_size: Annotated[int, typer.Option(
        "--max-size", min=1, help="Run the grid points up to this size (cubes, or places on "
                                  "the pantry trip for cooking).")] = 5,
    only: Annotated[list[str] | None, typer.Option(
        "--only", metavar="PATTERN",
        help="Run just the instances matching this name pattern, any size (repeatable), e.g. "
             "--only 'cubes-c9-*' --only cooking-k8.", show_default=False)] = None,
    big: Annotated[bool, typer.Option(
        "--big", help="Run the large points instead: 12-30 cubes, 2-4 opaque boxes, K=2, 4, 8 "
                      "(45 points, up to --timeout each).")] = False,
    no_symmetry: Annotated[bool, typer.Option(
        "--no-symmetry", help="Solve without the symmetry reduction (every renaming of "
                              "interchangeable objects its own state).")] = False,
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
    classes: Annotated[bool, typer.Option(
        "--classes", help="Also count the human's worlds as classes (the renamings of one "
                          "another under the swaps that fix the node) at the node with the "
                          "most worlds: a second search over canonical states, after the "
                          "timed figures and not in them, of at most --timeout.")] = False,
    world_classes: Annotated[bool, typer.Option(
        "--world-classes", help="Solve with the human's worlds kept as classes "
                                "(docs/semantics.md §3, \"Worlds as classes\").")] = False,
) -> None:
    """Solve a grid of generated problems, each in a fresh process, and show how time and
    memory grow: cubes 3-10 split over both tables, 2-3 boxes, transparent or opaque, trips of
    K=2-8; cooking with trips of K=2-8; and two larger cube instances (12 cubes; 10 cubes with
    human_reach "any"), run when --only names them or --max-size allows; --big runs the large
    points (12-30 cubes, 2-4 boxes, K=2-8) instead.

    Per instance: time (solve and the policy as JSON), the whole process's CPU time, states
    generated and distinct (canonical, with symmetry), states/s, |W|, peak resident memory,
    the policy's size (nodes, bytes) and the share of time in each phase (grounding, search,
    values, extraction, writing); with --classes, the |W| classes; with --world-classes the
    solves keep the human's worlds as classes. Exit 1 if an instance
    crashed (a stop at --timeout or --max-memory is a result, not a failure).
    """
    from ..experiments import bench as bench_mod

    memory = 0
    if max_memory is not None:
        try:
            memory = parse_size(max_memory)
        except ValueError as e:
            die(f"--max-memory {max_memory}: {e}; write e.g. 2G, 512M or a number of bytes")
    points = bench_mod.select_points(max_size, only, big)
    if not points:
        what = f"--only {' '.join(only)}" if only else f"--max-size {max_size}"
        die(f"{what}: no grid instance selected; names look like cubes-c6-b3-opaque-k8, "
            "cooking-k4")
    rows = _run_points(points, timeout, memory, repeat, False if no_symmetry else None, classes,
                       world_classes)
    if json_out is not None:
        _write_rows(rows, json_out)
    if str(json_out) != "-":
        write_stdout(bench_mod.format_scaling(rows))
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
