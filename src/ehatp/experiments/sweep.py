"""Solve many problem files, and a grid of variants of each, in parallel (``ehatp sweep``,
:mod:`ehatp.cli.sweep`): the grid, the instances and their keys, the results file, its summary,
CSV and plot.

One JSON line per instance, written as results arrive; ``--resume`` skips the instances whose
key (sha256 of the problem text, the overrides, a domain file beside the problem and the ehatp
version) already has a row. Instances run on a local process pool, a Dask cluster or a Ray
cluster (:mod:`ehatp.experiments.pools`); each is isolated (``--memory``, ``--timeout`` and a
watchdog), so a runaway one becomes an error row while the rest complete. ``--plot`` draws a
results file. See ``docs/sweep.md``; the workers' side is
:mod:`ehatp.experiments.sweep_worker`.
"""

from __future__ import annotations

import csv
import glob
import hashlib
import importlib
import itertools
import json
import os
import socket
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from datetime import date, datetime
from datetime import time as dtime
from pathlib import Path
from typing import Any

from rich.table import Table

from .. import __version__
from ..errors import InputError
from ..formats.problem_toml import loads
from .pools import (
    DaskPool,
    ExecutorFailed,
    ExecutorKind,
    LocalPool,
    Pool,
    RayPool,
    WorkerLost,
    default_workers,
    open_pool,
    run_tasks,
    sigterm_as_interrupt,
)
from .sweep_worker import ROW_KEYS, Row, Task

Grid = dict[str, list[Any]]

# the first part of a grid key: a problem file's tables (and its top-level goal)
GRID_TABLES = ("problem", "domain", "objects", "init", "beliefs", "agenda", "costs", "limits",
               "human", "communication", "objective", "options", "goal")
PLOT_EXTRA = "pip install 'ehatp[plot]'"


# --- the grid --------------------------------------------------------------------------------


def read_grid(path: Path) -> Grid:
    """The grid file as ``{"problem.K": [2, 3, 4], ...}`` (dotted keys, lists of values, in the
    file's order); :class:`InputError` naming the key on a mistake."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(str(path), "", f"cannot read the grid ({getattr(e, 'strerror', e)})",
                         "give a grid TOML file (see docs/sweep.md)") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(str(path), "", f"not valid TOML: {e}", "fix the TOML syntax") from None
    except RecursionError:
        raise InputError(str(path), "", "nested too deeply", "write table.key = [values]") \
            from None
    grid: Grid = {}
    _flatten(path, data, (), grid)
    if not grid:
        raise InputError(str(path), "", "the grid has no keys",
                         'write e.g. problem.K = [2, 3, 4] (see docs/sweep.md)')
    return grid


def _flatten(path: Path, t: Mapping[str, Any], at: tuple[str, ...], grid: Grid) -> None:
    for k, v in t.items():
        keys = (*at, k)
        dotted = ".".join(keys)
        if "." in k or not k:
            raise InputError(str(path), dotted, f"the key {k!r} is empty or has a dot in it",
                             "override keys made of plain names only")
        if not at and k not in GRID_TABLES:
            raise InputError(str(path), dotted, f"{k!r} is not a table of a problem file",
                             f"start each key with one of {', '.join(GRID_TABLES)}")
        if isinstance(v, dict):
            _flatten(path, v, keys, grid)
            continue
        if len(keys) < 2 and k != "goal":
            raise InputError(str(path), dotted, f"{dotted} is a table, not a key in it",
                             f"write {dotted}.KEY = [values]")
        if not isinstance(v, list):
            raise InputError(str(path), dotted, f"{dotted} must be a list of the values to try, "
                             f"got {v!r:.40}", f"write {dotted} = [{_toml(v)}]")
        if not v:
            raise InputError(str(path), dotted, f"{dotted} lists no value",
                             "give at least one value to try")
        for x in _leaves(v):
            if isinstance(x, datetime | date | dtime):
                raise InputError(str(path), dotted, f"a date or time ({x}) is no problem value",
                                 "give numbers, strings, booleans, lists or tables")
        grid[dotted] = v


def _leaves(v: Any) -> Iterable[Any]:
    if isinstance(v, list):
        for x in v:
            yield from _leaves(x)
    elif isinstance(v, dict):
        for x in v.values():
            yield from _leaves(x)
    else:
        yield v


def _toml(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return json.dumps(v, ensure_ascii=False, default=str)


def combinations(grid: Grid | None) -> list[dict[str, Any]]:
    """The grid's cartesian product, the last key varying fastest (one empty combination for
    no grid)."""
    if not grid:
        return [{}]
    keys = list(grid)
    return [dict(zip(keys, values, strict=True)) for values in itertools.product(*grid.values())]


def check_grid(grid: Grid, grid_path: Path, files: Sequence[Path]) -> None:
    """Try each grid value alone on the first problem that loads as written, so a bad key or
    value is one line naming the grid (values that fail only together, or only on another
    problem, become error rows). This runs in this process, so problems whose domain is
    registered or installed are tried before those naming a ``file.py`` of their own."""
    for f in sorted(files, key=_names_a_domain_file):
        try:
            text = f.read_text(encoding="utf-8")
            loads(text, f)
        except Exception:  # its own error row will say why
            continue
        for key, values in grid.items():
            for v in values:
                try:
                    loads(text, f, {key: v})
                except InputError as e:
                    raise InputError(str(grid_path), key, f"{key} = {_toml(v)} is refused: "
                                     f"{e.problem} (tried on {f})", e.fix) from None
                except Exception as e:  # a domain factory's own failure
                    raise InputError(str(grid_path), key, f"{key} = {_toml(v)} is refused: "
                                     f"{type(e).__name__}: {e} (tried on {f})",
                                     "give a value the problem accepts") from None
        return


def _names_a_domain_file(f: Path) -> bool:
    try:
        dom = tomllib.loads(f.read_text(encoding="utf-8")).get("domain", {})
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError):
        return True
    name = dom.get("name") if isinstance(dom, dict) else None
    return not isinstance(name, str) or ".py:" in name


# --- instances -------------------------------------------------------------------------------


def find_problems(patterns: Sequence[str]) -> list[Path]:
    """The files the patterns match (``**`` recursive), each once, sorted within a pattern;
    :class:`InputError` for a pattern that matches no file."""
    out: list[Path] = []
    seen: set[Path] = set()
    for pat in patterns:
        found = ([Path(pat)] if Path(pat).is_file() else  # a name with [ or * in it
                 sorted(Path(m) for m in glob.glob(pat, recursive=True) if Path(m).is_file()))
        if not found:
            raise InputError(pat, "", "no file matches", "check the path; quote patterns with "
                             "** so that the shell leaves them to ehatp")
        for f in found:
            if f.resolve() not in seen:
                seen.add(f.resolve())
                out.append(f)
    return out


def instance_key(text: str, path: Path, overrides: Mapping[str, Any]) -> str:
    """sha256 of what decides an instance's result: the problem text, the overrides, the text
    of a domain ``file.py`` it names (if any) and the ehatp version."""
    payload = {"problem": text, "overrides": overrides, "ehatp": __version__,
               "domain_file": _domain_file_text(text, path, overrides)}
    blob = json.dumps(payload, sort_keys=True, ensure_ascii=False, default=str)
    return hashlib.sha256(blob.encode("utf-8")).hexdigest()


def _domain_file_text(text: str, path: Path, overrides: Mapping[str, Any]) -> str | None:
    name = overrides.get("domain.name")
    if name is None:
        try:
            dom = tomllib.loads(text).get("domain", {})
        except (tomllib.TOMLDecodeError, RecursionError):
            return None
        name = dom.get("name") if isinstance(dom, dict) else None
    if not isinstance(name, str) or ".py:" not in name:
        return None
    try:
        return (path.parent / name.rpartition(":")[0]).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError, ValueError):
        return None


@dataclass(frozen=True)
class Settings:
    """What every task of a sweep shares."""

    timeout: float | None = None
    memory_gb: float | None = None
    memory_mode: str = "rlimit"  # "watch" where workers share their process (Dask, Ray)
    kill_after: float | None = None  # None: sweep_worker.kill_after(timeout)
    validate: bool = False
    policies: Path | None = None
    compress: bool = False  # the policies gzip-compressed: KEY.json.gz
    marks: Path | None = None


def make_tasks(files: Sequence[Path], grid: Grid | None, settings: Settings) -> list[Task]:
    """One task per file and grid combination, files outermost. A file that cannot be read
    still gets its tasks: the worker's row reports the error."""
    combos = combinations(grid)
    tasks: list[Task] = []
    here = (os.getpid(), socket.gethostname())
    for f in files:
        try:
            text = f.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            text = ""  # loads() says the file is empty; the row's error is about reading it
        for combo in combos:
            tasks.append(Task(
                key=instance_key(text, f, combo), instance=str(f), path=str(f.resolve()),
                text=text, overrides=combo, timeout=settings.timeout,
                memory_gb=settings.memory_gb, memory_mode=settings.memory_mode,
                kill_after=settings.kill_after,
                validate=settings.validate,
                policies=None if settings.policies is None else str(settings.policies.resolve()),
                compress=settings.compress,
                marks=None if settings.marks is None else str(settings.marks.resolve()),
                driver_pid=here[0], driver_host=here[1]))
    return tasks


# --- the results file ------------------------------------------------------------------------


def read_rows(path: Path, *, repair: bool = False) -> list[Row]:
    """The rows of a results file. A last line cut short (the run was stopped while writing
    it) is ignored, and with ``repair`` cut from the file so appending starts on a new line;
    any other line that is not a row is an :class:`InputError`."""
    try:
        data = path.read_bytes()
    except OSError as e:
        raise InputError(str(path), "", f"cannot read the results ({e.strerror or e})",
                         "give a results file written by ehatp sweep --out") from None
    end = data.rfind(b"\n") + 1
    if repair and end < len(data):
        with path.open("r+b") as f:
            f.truncate(end)
    rows: list[Row] = []
    for i, line in enumerate(data[:end].decode("utf-8", "replace").splitlines(), 1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
        except (ValueError, RecursionError):
            row = None
        if not isinstance(row, dict) or not isinstance(row.get("key"), str):
            raise InputError(str(path), str(i), "not a row written by ehatp sweep",
                             "remove that line, or give another --out") from None
        rows.append(row)
    return rows


def row_line(row: Row) -> str:
    """A row as one JSON line (the keys in :data:`ROW_KEYS` order, as the worker made it)."""
    return json.dumps(row, ensure_ascii=False, default=str) + "\n"


# --- the summary and the CSV -----------------------------------------------------------------


def overrides_text(overrides: Mapping[str, Any]) -> str:
    return " ".join(f"{k}={_toml(v)}" for k, v in overrides.items())


def _n(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, int) and not isinstance(v, bool):
        return f"{v:,}"
    return str(v)


def summary_table(rows: Sequence[Row], *, per_row_up_to: int = 30) -> Table:
    """One line per row for a small sweep, else one line per problem file."""
    if len(rows) <= per_row_up_to:
        t = Table(title="ehatp sweep", title_justify="left")
        over = any(r.get("overrides") for r in rows)
        for col in ("instance", *(["overrides"] if over else []), "status", "cost", "distinct",
                    "|W|", "time s"):
            t.add_column(col, justify="right" if col in ("cost", "distinct", "|W|", "time s")
                         else "left")
        for r in rows:
            st = r.get("stats") or {}
            status = str(r.get("status") or "")
            if r.get("error_kind"):
                status += f" ({r['error_kind']})"
            if r.get("valid") is False:
                status += " INVALID"
            t.add_row(str(r.get("instance")),
                      *([overrides_text(r.get("overrides") or {})] if over else []),
                      status, _n(r.get("cost")), _n(st.get("distinct")),
                      _n(st.get("max_worlds")), _n(r.get("time_s")),
                      style="red" if r.get("status") == "error" else None)
        return t
    t = Table(title="ehatp sweep, by problem file", title_justify="left")
    for col in ("instance", "runs", "solved", "other", "errors", "cost", "max distinct",
                "max |W|", "time s"):
        t.add_column(col, justify="left" if col in ("instance", "other") else "right")
    by_file: dict[str, list[Row]] = {}
    for r in rows:
        by_file.setdefault(str(r.get("instance")), []).append(r)
    for inst, rs in by_file.items():
        costs = [r["cost"] for r in rs if isinstance(r.get("cost"), int | float)]
        stats = [r.get("stats") or {} for r in rs]
        others: dict[str, int] = {}
        for r in rs:
            if r.get("status") not in ("solved", "error"):
                others[str(r.get("status"))] = others.get(str(r.get("status")), 0) + 1
        errors = sum(r.get("status") == "error" for r in rs)
        t.add_row(inst, str(len(rs)), str(sum(r.get("status") == "solved" for r in rs)),
                  " ".join(f"{k} {v}" for k, v in sorted(others.items())), str(errors),
                  f"{_n(min(costs))}–{_n(max(costs))}" if costs else "",
                  _n(max((s.get("distinct") or 0 for s in stats), default=0)),
                  _n(max((s.get("max_worlds") or 0 for s in stats), default=0)),
                  _n(round(sum(r.get("time_s") or 0 for r in rs), 2)),
                  style="red" if errors else None)
    return t


def write_csv(rows: Sequence[Row], path: Path) -> None:
    """The rows as CSV: one column per override and per statistic (``stats.NAME``)."""
    over: list[str] = []
    stats: list[str] = []
    for r in rows:
        over += [k for k in (r.get("overrides") or {}) if k not in over]
        stats += [k for k in (r.get("stats") or {}) if k not in stats]
    main = [k for k in ROW_KEYS if k not in ("overrides", "stats")]
    extra = sorted({k for r in rows for k in r} - set(ROW_KEYS) - {"traceback"})
    cols = ["instance", *over, *[k for k in main if k != "instance"],
            *[f"stats.{k}" for k in stats], *extra]
    with path.open("w", encoding="utf-8", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for r in rows:
            o, st = r.get("overrides") or {}, r.get("stats") or {}
            line = []
            for c in cols:
                if c in over:
                    v = o.get(c)
                elif c.startswith("stats."):
                    v = st.get(c[6:])
                else:
                    v = r.get(c)
                line.append("" if v is None else _toml(v) if isinstance(v, list | dict)
                            else str(v).lower() if isinstance(v, bool) else str(v))
            w.writerow(line)


# --- the plot --------------------------------------------------------------------------------


def plot_key(rows: Sequence[Row], x: str) -> str:
    """The override ``x`` names: exactly, or by its last part(s) if that is unambiguous."""
    keys: list[str] = []
    for r in rows:
        keys += [k for k in (r.get("overrides") or {}) if k not in keys]
    if x in keys:
        return x
    hits = [k for k in keys if k.endswith("." + x)]
    if len(hits) == 1:
        return hits[0]
    have = ", ".join(keys) if keys else "none (the sweep had no --grid)"
    raise InputError(f"--x {x}", "", "no override of that name in the results"
                     if not hits else f"ambiguous: {', '.join(hits)}", f"use one of: {have}")


def plot(rows: Sequence[Row], x: str, out: Path) -> tuple[int, int]:
    """Draw time, distinct states and |W| against the override ``x`` into ``out`` (see
    :func:`figure`); return (lines, points)."""
    fig, n_lines, n_points = figure(rows, x)
    try:
        fig.savefig(out)
    except (OSError, ValueError) as e:
        raise InputError(str(out), "", f"cannot write the plot ({e})",
                         "choose another --out (.png, .svg or .pdf)") from None
    return n_lines, n_points


LEGEND_INSIDE = 6  # more series than this: the legend goes beside the panels
LINE_STYLES = ("-", "--", ":", "-.")


def figure(rows: Sequence[Row], x: str) -> tuple[Any, int, int]:
    """Return a matplotlib figure of time, distinct states and |W| against the override
    ``x``, one line per combination of the other overrides (and problem file), with how many
    lines and points it has. A legend names the lines (inside the first panel for a few,
    beside the panels for more; colours repeat every ten lines, each time with another line
    style); whole-number axes (``x`` when every value is whole, the counts) have whole-number
    ticks."""
    try:
        figure_mod = importlib.import_module("matplotlib.figure")
        ticker = importlib.import_module("matplotlib.ticker")
    except ImportError:
        raise InputError("--plot", "", "drawing needs matplotlib, which is not installed",
                         PLOT_EXTRA) from None
    key = plot_key(rows, x)
    usable = [r for r in rows if key in (r.get("overrides") or {}) and r.get("status") != "error"
              and isinstance(r.get("stats"), dict)]
    if not usable:
        raise InputError(f"--x {x}", "", f"no row with {key} has statistics (all errors?)",
                         "plot a sweep whose instances ran")
    xs_all = [r["overrides"][key] for r in usable]
    numeric = all(isinstance(v, int | float) and not isinstance(v, bool) for v in xs_all)
    whole_x = numeric and all(float(v).is_integer() for v in xs_all)
    cats: list[Any] = []
    for v in xs_all:
        if v not in cats:
            cats.append(v)

    def pos(v: Any) -> float:
        return float(v) if numeric else float(cats.index(v))

    lines: dict[str, list[Row]] = {}
    files = {r.get("instance") for r in usable}
    for r in usable:
        rest = {k: v for k, v in r["overrides"].items() if k != key}
        label = " ".join([Path(str(r.get("instance"))).stem] if len(files) > 1 else [])
        label = " ".join(p for p in (label, " ".join(f"{k.rsplit('.', 1)[-1]}={_toml(v)}"
                                                      for k, v in rest.items())) if p)
        lines.setdefault(label or "all", []).append(r)
    metrics = (("time_s", "time (s)", False), ("distinct", "distinct states", True),
               ("max_worlds", "|W|", True))
    outside = len(lines) > LEGEND_INSIDE
    columns = 1 + (len(lines) - 1) // 30
    # beside the panels, the legend widens the figure rather than narrow them (inches for
    # the "small" font)
    width = 15 + (0.07 * max(map(len, lines)) + 0.5) * columns if outside else 15
    height = max(4.8, 0.2 * min(len(lines), 30) + 0.8) if outside else 4.8
    fig = figure_mod.Figure(figsize=(width, height), layout="constrained")
    axes = fig.subplots(1, 3)
    for ax, (m, title, count) in zip(axes, metrics, strict=True):
        values: list[float] = []
        for i, (label, rs) in enumerate(lines.items()):
            pts = sorted((pos(r["overrides"][key]),
                          r.get(m) if m == "time_s" else r["stats"].get(m),
                          r.get("status") == "solved") for r in rs)
            pts = [p for p in pts if isinstance(p[1], int | float)]
            if not pts:
                continue
            values += [float(p[1]) for p in pts if p[1] is not None]
            (line,) = ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o",
                              label=label, color=f"C{i % 10}",
                              linestyle=LINE_STYLES[i // 10 % len(LINE_STYLES)])
            unsolved = [p for p in pts if not p[2]]
            if unsolved:
                ax.plot([p[0] for p in unsolved], [p[1] for p in unsolved], "x",
                        color=line.get_color(), markersize=10)
        positive = [v for v in values if v > 0]
        if positive and max(positive) / min(positive) > 100:
            ax.set_yscale("log")
        elif count:
            ax.yaxis.set_major_locator(ticker.MaxNLocator(integer=True))
        ax.set_title(title)
        ax.set_xlabel(key)
        if not numeric:
            ax.set_xticks(range(len(cats)), [_toml(c) for c in cats])
        elif whole_x:
            ax.xaxis.set_major_locator(ticker.MaxNLocator(integer=True))
        ax.grid(True, alpha=0.3)
    if outside:
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside right upper", fontsize="small", ncols=columns)
    elif len(lines) > 1:
        axes[0].legend(fontsize="small")
    fig.suptitle(f"ehatp sweep: against {key} (x: not solved)")
    return fig, len(lines), len(usable)


# the pools live in .pools; CHANGELOG.md names them here, so they stay importable from here
__all__ = ["GRID_TABLES", "LEGEND_INSIDE", "LINE_STYLES", "PLOT_EXTRA", "ROW_KEYS", "DaskPool",
           "ExecutorFailed", "ExecutorKind", "Grid", "LocalPool", "Pool", "RayPool", "Row",
           "Settings", "Task", "WorkerLost", "check_grid", "combinations", "default_workers",
           "figure", "find_problems", "instance_key", "make_tasks", "open_pool",
           "overrides_text", "plot", "plot_key", "read_grid", "read_rows", "row_line",
           "run_tasks", "sigterm_as_interrupt", "summary_table", "write_csv"]
