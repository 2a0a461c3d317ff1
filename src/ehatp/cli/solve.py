"""``ehatp solve``: plan a robot policy for a problem file and write it as JSON, with live
progress on a terminal and a summary of what was found."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from ..errors import InputError, printable
from ..model.options import ObjectiveKind
from ..model.problem import Problem
from ..search.limits import SolveStatus
from .common import (
    EXIT_NO_POLICY,
    EXIT_OK,
    command_app,
    die,
    load_problem,
    memory_option,
    stderr_console,
    user_errors,
    with_objective,
)

# rich and the search load when the command runs them (start-up time)
if TYPE_CHECKING:
    from rich.console import Console
    from rich.live import Live
    from rich.text import Text

    from ..search.andor import Stats
    from ..search.limits import Budget
    from ..search.planner import Result

app = command_app()

SHOW_PROGRESS_AFTER_S = 0.5  # quick solves never flash a progress line


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


def solve(problem: Problem, **kwargs: Any) -> Result:
    """:func:`ehatp.solve`; the search loads on first use, not when the program starts."""
    from ..search.planner import solve as planner_solve

    return planner_solve(problem, **kwargs)


@app.command("solve")
def solve_cmd(
    ctx: typer.Context,
    problem: Annotated[Path, typer.Argument(
        help="Problem file (TOML), e.g. examples/cubes/p1.toml.", metavar="PROBLEM.toml",
        show_default=False)],
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Where to write the policy JSON, gzip-compressed if the name "
                            "ends in .gz (default: PROBLEM-NAME.policy.json in the current "
                            "directory).", show_default=False)] = None,
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
    expand: Annotated[bool, typer.Option(
        "--expand", help="Write the policy over the real objects (format version 2) even when "
                         "the search ran over canonical states, where the lifted policy "
                         "(version 3) is written by default (docs/policy-format.md).")] = False,
    no_focus: Annotated[bool, typer.Option(
        "--no-focus", help="Expand every state whose g + h is at most the optimum, as 0.2 "
                           "did, not only the best partial policy's tips: the same policy, "
                           "more states (docs/semantics.md §7, \"Search\").")] = False,
    world_classes: Annotated[bool, typer.Option(
        "--world-classes", help="Keep the human's worlds as classes of renamings of one "
                                "another (with the symmetry reduction): the same policy, less "
                                "memory, faster where worlds multiply (docs/semantics.md §3, "
                                "\"Worlds as classes\").")] = False,
) -> None:
    """Plan a robot policy, optimal under the problem's objective, and write it as JSON.

    Prints a summary: solved or why not, states generated/distinct, the largest number of
    worlds the human entertains (|W|), leaves, the policy's worst-case and expected cost (and
    which one was minimised), communications, under preferences the chosen profile's vector
    (C11), and time.
    Exit 0 solved; 1 no policy exists or a limit stopped the work (one line says which; the
    best policy found so far, if any, is still written, marked not optimal); 2 bad input.
    """
    t0 = time.perf_counter()
    from ..search.limits import Budget

    memory = memory_option(max_memory)
    prob = with_objective(load_problem(problem), objective)
    if world_classes and (no_symmetry or not prob.limits.symmetry):
        with user_errors(problem):
            raise InputError(str(problem), "", "--world-classes keeps worlds as classes of "
                             "renamings, which needs the symmetry reduction, and it is off",
                             "leave out --no-symmetry (and set [limits] symmetry = true)")
    limits = prob.limits
    budget = Budget(limits.timeout if timeout is None else timeout,
                    limits.max_memory if memory is None else memory, start=t0)
    console = stderr_console()
    live = LiveProgress(console, printable(prob.name)) if console is not None else None
    target = out if out is not None else Path(f"{problem.stem}.policy.json")
    from .limits import guarded

    try:
        with guarded(ctx.obj, f"solve {problem}", budget.timeout, budget.max_memory,
                     EXIT_NO_POLICY):
            with user_errors(problem):
                result = solve(prob, max_states=max_states, max_depth=max_depth,
                               progress=live, budget=budget,
                               symmetry=False if no_symmetry else None, expand=expand,
                               focus=not no_focus, world_classes=world_classes)
            result, written = _write(result, target, budget)
    finally:
        if live is not None:
            live.close()
    wall_ms = (time.perf_counter() - t0) * 1000
    _summary(prob, result, wall_ms, target if written else None)
    raise typer.Exit(EXIT_OK if result.status == SolveStatus.SOLVED else EXIT_NO_POLICY)


def _write(result: Result, target: Path, budget: Budget) -> tuple[Result, bool]:
    """Write the policy found, if any, to ``target`` under the limits; return the result and
    whether the file was written. A limit reached while writing stops the work as it would the
    search, except after a finished search: then what it proved is written past the limit,
    the lifted policy (format version 3, small as the search) when there is one, and the
    result says which phase was cut."""
    from ..search.limits import LimitReached

    if result.policy is None:
        return result, False
    budget.phase = "writing"
    try:
        # the text is made (under the limits) before the file is touched
        result.policy.write(target, check=budget.check)
    except OSError as e:
        die(f"{target}: cannot write the policy ({e.strerror or e}); choose another --out")
    except (LimitReached, MemoryError) as e:
        stop = e if isinstance(e, LimitReached) else budget.out_of_memory()
        kept = result.lifted if result.lifted is not None else result.policy
        if result.status == SolveStatus.SOLVED and kept.symmetry is not None:
            try:
                kept.write(target)
            except OSError as err:
                die(f"{target}: cannot write the policy ({err.strerror or err}); choose "
                    "another --out")
            except MemoryError:
                pass
            else:
                what = ("the lifted policy (format version 3) is written instead"
                        if kept is not result.policy else "it was written past the limit")
                return dataclasses.replace(
                    result, policy=kept, lifted=None,
                    reason=f"{stop.reason}, after the search had finished: {what}"), True
        return dataclasses.replace(result, status=stop.status, policy=None, reason=stop.reason,
                                   optimal=False), False
    return result, True


def _summary(prob: Problem, result: Result, wall_ms: float, written: Path | None) -> None:
    st = result.stats
    # a problem built in Python may hold any name, and a reason quotes the domain's names
    name, reason = printable(prob.name), printable(str(result.reason))
    if result.status == SolveStatus.SOLVED and result.optimal and result.reason:
        typer.secho(f"{name}: solved (optimal policy found); {reason}",
                    fg="yellow", bold=True)
    elif result.status == SolveStatus.SOLVED and result.optimal:
        typer.secho(f"{name}: solved (optimal policy found)", fg="green", bold=True)
    elif result.status == SolveStatus.SOLVED:
        typer.secho(f"{name}: solved, {reason}", fg="yellow", bold=True)
    elif result.status == SolveStatus.UNSOLVABLE:
        typer.secho(f"{name}: {reason}", fg="red", bold=True)
    else:
        typer.secho(f"{name}: stopped early, {reason}; partial statistics:",
                    fg="yellow", bold=True)
    rows: list[tuple[str, Any]] = [
        ("states", f"{st.get('generated', 0):,} generated, {st.get('distinct', 0):,} distinct, "
                   f"{st.get('expanded', 0):,} expanded"),
        ("|W|", f"{st.get('max_worlds', 0)} (most worlds the human entertains at once)"),
    ]
    pol = result.policy
    if pol is not None:
        from ..formats.text import cost_lines

        rows += [("leaves", pol.leaves), *cost_lines(pol),
                 ("communications", pol.communications)]
        obj = pol.objective
        if obj.get("kind") == "preferences":  # C11: the chosen profile's root vector
            rows.append(("profile", f"{obj.get('profile')} ({obj.get('estimate')}): "
                         + ", ".join(f"{m} {v}" for m, v in zip(obj.get("metrics", []),
                                                                obj.get("value", []),
                                                                strict=False))))
    rows.append(("time", f"{st.get('time_ms', 0):,} ms search, {wall_ms:,.1f} ms in all"))
    if written is not None:
        solved = result.status == SolveStatus.SOLVED
        note = ("" if result.optimal else " (NOT proven optimal)" if solved
                else " (best found so far, NOT proven optimal)")
        if pol is not None and pol.symmetry is not None:
            note += (f", lifted: {len(pol.nodes):,} canonical nodes (format version 3; "
                     "--expand writes version 2)")
        rows.append(("policy", f"written to {written}{note}"))
    elif result.status != SolveStatus.UNSOLVABLE:
        rows.append(("policy", "none found before the work stopped"))
    for k, v in rows:
        typer.echo(printable(f"  {k:<15} {v}"))
