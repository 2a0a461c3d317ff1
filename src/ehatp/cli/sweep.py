"""``ehatp sweep``: many problems, and a grid of variants of each, solved in parallel
(:mod:`ehatp.experiments.sweep` runs them; docs/sweep.md)."""

from __future__ import annotations

import importlib
import shutil
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from ..errors import InputError, printable
from ..experiments.pools import (
    ExecutorFailed,
    ExecutorKind,
    default_workers,
    open_pool,
    run_tasks,
)
from ..experiments.sweep import (
    Grid,
    Settings,
    check_grid,
    find_problems,
    make_tasks,
    overrides_text,
    plot,
    read_grid,
    read_rows,
    row_line,
    summary_table,
    write_csv,
)
from ..experiments.sweep_worker import Row, Task
from .common import EXIT_NO_POLICY, EXIT_OK, command_app, die, user_errors

EXIT_INTERRUPTED = 130

app = command_app()


def _stderr() -> Console | None:
    return Console(stderr=True) if sys.stderr.isatty() else None


@app.command("sweep")
def sweep_command(
    patterns: Annotated[list[str] | None, typer.Argument(
        help="Problem files or glob patterns (** is recursive; quote it), e.g. "
             "'examples/**/*.toml'.", metavar="PATTERN...", show_default=False)] = None,
    grid: Annotated[Path | None, typer.Option(
        "--grid", help="TOML file of overrides to try, each a list of values (problem.K = "
                       "[2, 3, 4]); every combination runs on every file.",
        metavar="GRID.toml", show_default=False)] = None,
    executor: Annotated[ExecutorKind, typer.Option(
        "--executor", help="Where instances run: local processes, a Dask or a Ray "
                           "cluster.")] = ExecutorKind.local,
    workers: Annotated[int | None, typer.Option(
        "--workers", "-j", min=1, help="Worker processes (local, or the Dask/Ray cluster "
                                       "started here; default: the cores).",
        show_default=False)] = None,
    address: Annotated[str | None, typer.Option(
        "--address", help="A running Dask scheduler (tcp://host:8786) or Ray cluster "
                          "(auto, ray://host:10001) to use.", show_default=False)] = None,
    memory: Annotated[float | None, typer.Option(
        "--memory", min=0.001, help="Memory an instance may take, in GB (its address space "
                                    "may grow by that much); beyond it, an error row.",
        metavar="GB", show_default=False)] = None,
    timeout: Annotated[float | None, typer.Option(
        "--timeout", min=0.0, help="Time limit per instance in seconds (default: the "
                                   "problem's limits.timeout); a worker still busy well after "
                                   "it is ended.", metavar="S", show_default=False)] = None,
    validate: Annotated[bool, typer.Option(
        "--validate", help="Check each policy with the independent validator.")] = False,
    policies: Annotated[Path | None, typer.Option(
        "--policies", help="Folder for the policies, one KEY.json per instance.",
        metavar="DIR", show_default=False)] = None,
    compress: Annotated[bool, typer.Option(
        "--compress", help="With --policies: write each policy gzip-compressed, "
                           "KEY.json.gz.")] = False,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Results, one JSON line per instance (default results.jsonl); "
                            "with --plot, the picture (default: RESULTS.png).",
        show_default=False)] = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Keep the rows already in --out and run only the missing "
                         "instances.")] = False,
    csv_out: Annotated[Path | None, typer.Option(
        "--csv", help="Also write the sweep's rows as CSV.", metavar="FILE",
        show_default=False)] = None,
    plot_in: Annotated[Path | None, typer.Option(
        "--plot", help="Instead of running, draw this results file (needs --x).",
        metavar="RESULTS.jsonl", show_default=False)] = None,
    x: Annotated[str | None, typer.Option(
        "--x", help="With --plot: the override on the x axis, e.g. problem.K.",
        metavar="KEY", show_default=False)] = None,
) -> None:
    """Solve many problems, and variants of them from a grid, in parallel: one JSON line per
    instance (status, statistics, costs, validation, time or error), a summary table at the
    end.

    A bad instance (unreadable, over --memory, still running past --timeout, crashing its
    worker) is an error row; the others complete. `--resume` runs only the instances without
    a row. `--plot RESULTS.jsonl --x problem.K` draws time, states and |W| against an
    override. Exit 0 when every instance ran, 1 if any is an error row or an invalid policy,
    2 on bad input. See docs/sweep.md.
    """
    if plot_in is not None:
        _plot(plot_in, x, out, bool(patterns))
    if x is not None:
        die("--x goes with --plot RESULTS.jsonl")
    if not patterns:
        die("give problem files or patterns to run (e.g. 'examples/**/*.toml'), or --plot "
            "RESULTS.jsonl; see 'ehatp sweep --help'")
    results = out if out is not None else Path("results.jsonl")
    files, grid_values = _inputs(patterns, grid, results, resume, memory, policies, csv_out)
    marks = results.with_name(f".{results.name}.marks")
    if compress and policies is None:
        die("--compress goes with --policies DIR (it compresses the policy files)")
    settings = Settings(timeout=timeout, memory_gb=memory, validate=validate,
                        policies=policies, compress=compress, marks=marks,
                        memory_mode="rlimit" if executor is ExecutorKind.local else "watch")
    tasks = make_tasks(files, grid_values, settings)
    ordered, new = _run_missing(tasks, results, marks, resume, executor, workers, address)
    _report(ordered, new, results, csv_out)
    bad = any(r.get("status") == "error" or r.get("valid") is False for r in ordered)
    raise typer.Exit(EXIT_NO_POLICY if bad else EXIT_OK)


def _plot(plot_in: Path, x: str | None, out: Path | None, patterns: bool) -> None:
    """``--plot RESULTS.jsonl --x KEY``: draw the results file instead of running; exit."""
    if patterns:
        die("give either problem files to run or --plot RESULTS.jsonl, not both")
    if x is None:
        die("--plot needs --x KEY, the override to draw along, e.g. --x problem.K")
    target = out if out is not None else plot_in.with_suffix(".png")
    with user_errors(plot_in):
        n_lines, n_points = plot(read_rows(plot_in), x, target)
    typer.echo(f"wrote {target} ({n_lines} line{'s' * (n_lines != 1)}, {n_points} "
               f"instances)")
    raise typer.Exit(EXIT_OK)


def _inputs(patterns: Sequence[str], grid: Path | None, results: Path, resume: bool,
            memory: float | None, policies: Path | None,
            csv_out: Path | None) -> tuple[list[Path], Grid | None]:
    """Return the problem files and the grid, checked, once the outputs can be written."""
    with user_errors(results):
        files = find_problems(patterns)
        grid_values = read_grid(grid) if grid is not None else None
        if grid_values is not None and grid is not None:
            check_grid(grid_values, grid, files)
        _check_setup(results, resume, memory, policies, csv_out)
    return files, grid_values


def _run_missing(tasks: list[Task], results: Path, marks: Path, resume: bool,
                 executor: ExecutorKind, workers: int | None,
                 address: str | None) -> tuple[list[Row], int]:
    """Run the tasks without a row in ``results`` (all of them unless ``resume``); return
    every task's row, in the tasks' order, and how many ran now."""
    done: dict[str, Row] = {}
    if resume and results.exists():
        with user_errors(results):
            done = {r["key"]: r for r in read_rows(results, repair=True)}
    todo = [t for t in tasks if t.key not in done]
    todo = list({t.key: t for t in todo}.values())  # the same instance twice runs once
    n = workers if workers is not None else default_workers()
    console = _stderr()
    if done:
        typer.echo(f"resuming: {len(tasks) - len(todo)} of {len(tasks)} instances already in "
                   f"{results}", err=True)
    rows = _run(todo, executor, min(n, max(1, len(todo))) if executor is ExecutorKind.local
                else n, address, results, marks, console, resume)
    rows_by_key = {**done, **{r["key"]: r for r in rows}}
    return [rows_by_key[t.key] for t in tasks if t.key in rows_by_key], len(rows)


def _check_setup(results: Path, resume: bool, memory: float | None, policies: Path | None,
                 csv_out: Path | None) -> None:
    if results.exists() and not resume:
        raise InputError(str(results), "", "already exists", "add --resume to run only the "
                         "instances it has no row for, or choose another --out")
    if results.is_dir():
        raise InputError(str(results), "", "is a folder", "give a file name with --out")
    if memory is not None:
        try:
            importlib.import_module("resource")
        except ImportError:
            raise InputError("--memory", "", "needs a POSIX system (RLIMIT_AS)",
                             "leave --memory out") from None
    for folder in (policies, results.parent, csv_out.parent if csv_out else None):
        if folder is None:
            continue
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(str(folder), "", f"cannot create the folder ({e.strerror or e})",
                             "choose another path") from None


def _run(todo: list[Task], kind: ExecutorKind, workers: int, address: str | None,
         results: Path, marks: Path, console: Console | None, resume: bool) -> list[Row]:
    rows: list[Row] = []
    if not todo:
        return rows
    progress = None
    with user_errors(f"--executor {kind.value}"):
        pool = open_pool(kind, workers, address)
    t0 = time.perf_counter()
    try:
        shutil.rmtree(marks, ignore_errors=True)
        marks.mkdir(parents=True, exist_ok=True)
        with results.open("a" if resume else "w", encoding="utf-8") as f:
            if console is not None:
                from rich.progress import Progress

                progress = Progress(console=console, transient=True)
                progress.start()
                bar = progress.add_task(f"sweep ({pool.name})", total=len(todo))

            def emit(row: Row) -> None:
                f.write(row_line(row))
                f.flush()
                rows.append(row)
                if progress is not None:
                    progress.update(bar, advance=1)

            run_tasks(todo, pool, emit)
    except KeyboardInterrupt:
        typer.echo(f"interrupted: {len(rows)} of {len(todo)} new rows are in {results}; run "
                   "the same command with --resume to go on", err=True)
        raise typer.Exit(EXIT_INTERRUPTED) from None
    except ExecutorFailed as e:
        die(f"the {kind.value} executor failed ({e}); {len(rows)} of {len(todo)} new rows are "
            f"in {results}; run the same command with --resume to go on", EXIT_NO_POLICY)
    except OSError as e:
        die(f"{results}: cannot write the results ({e.strerror or e}); choose another --out")
    finally:
        if progress is not None:
            progress.stop()
        pool.close()
        shutil.rmtree(marks, ignore_errors=True)
    rows_time = time.perf_counter() - t0
    typer.echo(f"{len(rows)} instance{'s' * (len(rows) != 1)} run in {rows_time:.1f} s on "
               f"{pool.name} ({workers} worker{'s' * (workers != 1)})"
               if kind is ExecutorKind.local or address is None else
               f"{len(rows)} instances run in {rows_time:.1f} s on {pool.name} ({address})",
               err=True)
    return rows


def _report(rows: Sequence[Row], new: int, results: Path, csv_out: Path | None) -> None:
    con = Console() if sys.stdout.isatty() else Console(width=160, no_color=True)
    if rows:
        con.print(summary_table(rows))
    counts: dict[str, int] = {}
    for r in rows:
        counts[str(r.get("status"))] = counts.get(str(r.get("status")), 0) + 1
    invalid = sum(r.get("valid") is False for r in rows)
    what = ", ".join(f"{v} {k}" for k, v in sorted(counts.items()))
    typer.echo(f"{len(rows)} rows ({new} new) in {results}: {what or 'none'}"
               + (f", {invalid} INVALID" if invalid else ""))
    errors = [r for r in rows if r.get("status") == "error"]
    for r in errors[:5]:
        over = overrides_text(r.get("overrides") or {})
        typer.echo(printable(f"  error: {r.get('instance')}{' [' + over + ']' if over else ''}: "
                             f"{r.get('error')}"))
    if len(errors) > 5:
        typer.echo(f"  ... and {len(errors) - 5} more error rows (status \"error\" in "
                   f"{results})")
    if csv_out is not None:
        try:
            write_csv(rows, csv_out)
        except OSError as e:
            die(f"{csv_out}: cannot write the CSV ({e.strerror or e}); choose another --csv")
        typer.echo(f"wrote {csv_out}")
