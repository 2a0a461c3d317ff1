"""How time and memory grow with the problem: the scaling grid, one fresh process per instance.

    .venv/bin/python benchmarks/scaling.py [--max-size N] [--only PATTERN ...] [--big]
        [--no-symmetry] [--timeout S] [--max-memory SIZE] [--repeat N] [--json FILE]
        [--plot FILE.png] [--baseline FILE.json] [--src DIR] [--versus DIR]
        [--world-classes] [--versus-listed] [--report classes [--top N] [--every]]

Same grid and table as ``ehatp bench scaling`` (``ehatp.experiments.bench``). ``--src DIR`` times
another checkout's ``src`` directory with this checkout's grid (how docs/benchmarks.md measured
"before"); ``--versus DIR`` runs every instance with both, alternately (``DIR`` first, then
this checkout, run after run) so that a noisy machine's drift falls on both alike, and prints
and plots the two side by side; ``--baseline FILE.json`` adds an earlier run's rows to the
plot. ``--report classes`` solves each instance once (the search alone) and reports, for its
``--top N`` nodes with the most worlds, how many classes the human's worlds form under the
swaps of objects that leave the node unchanged (``ehatp.experiments.classes``; issue 17 §2);
``--every`` also sums the worlds and the classes over every node of the search.
``--world-classes`` solves with the human's worlds kept as classes (docs/semantics.md §3,
"Worlds as classes"); ``--versus-listed`` runs every instance both ways, alternately (worlds
listed, then as classes, run after run), and prints the two side by side. Timing
lives here and in that command, never in the unit tests.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path
from typing import Any

# run the checkout this file lives in, whatever is installed (the child processes too)
SRC = str(Path(__file__).resolve().parent.parent / "src")
sys.path.insert(0, SRC)

from ehatp.experiments import bench  # noqa: E402
from ehatp.model.problem import parse_size  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-size", type=int, default=5, metavar="N",
                    help="grid points up to this size (default 5)")
    ap.add_argument("--only", action="append", metavar="PATTERN",
                    help="instances whose name matches (repeatable), any size")
    ap.add_argument("--big", action="store_true",
                    help="the large points instead (12-30 cubes, 2-4 boxes, K=2, 4, 8)")
    ap.add_argument("--no-symmetry", action="store_true",
                    help="solve without the symmetry reduction")
    ap.add_argument("--timeout", type=float, default=60.0, metavar="S",
                    help="seconds per instance (default 60)")
    ap.add_argument("--max-memory", metavar="SIZE", help="resident memory per instance, e.g. 2G")
    ap.add_argument("--repeat", "-n", type=int, default=1, metavar="N",
                    help="runs per instance; times and peaks are medians (default 1)")
    ap.add_argument("--json", type=Path, help="also write the rows as JSON to this file")
    ap.add_argument("--plot", type=Path, metavar="FILE.png", help="plot time and memory")
    ap.add_argument("--baseline", type=Path, action="append", metavar="FILE.json",
                    help="an earlier run's JSON to plot beside this one (label: file stem)")
    ap.add_argument("--src", metavar="DIR", help="time the ehatp package under DIR instead")
    ap.add_argument("--versus", metavar="DIR",
                    help="also time the ehatp package under DIR, alternating run by run")
    ap.add_argument("--report", choices=["classes"],
                    help="classes: count the human's worlds as classes instead of timing")
    ap.add_argument("--world-classes", action="store_true",
                    help="solve with the human's worlds kept as classes (docs/semantics.md "
                         "§3, \"Worlds as classes\")")
    ap.add_argument("--versus-listed", action="store_true",
                    help="alternate, point by point and run by run, solving with the worlds "
                         "listed and with them kept as classes (this checkout)")
    ap.add_argument("--top", type=int, default=5, metavar="N",
                    help="--report classes: the nodes with the most worlds counted (default 5)")
    ap.add_argument("--every", action="store_true",
                    help="--report classes: also sum worlds and classes over every node (slow)")
    args = ap.parse_args(argv)
    args.src = args.src or SRC
    if args.repeat < 1:
        ap.error("--repeat must be at least 1")
    try:
        memory = parse_size(args.max_memory) if args.max_memory else 0
    except ValueError as e:
        ap.error(f"--max-memory: {e}")
    points = bench.select_points(args.max_size, args.only, args.big)
    symmetry = False if args.no_symmetry else None
    if not points:
        ap.error("no grid instance selected")
    if args.report == "classes":
        return report_classes(points, args.src, args.timeout, args.top, args.every, args.json)

    def notify(p: bench.GridPoint, i: int, n: int, run: int) -> None:
        if sys.stderr.isatty():
            print(f"\r\033[Ksolving {p.name} ({i + 1}/{n}, run {run + 1}/{args.repeat})",
                  end="", file=sys.stderr, flush=True)

    if args.versus_listed:  # one point at a time, listed and classes alternating run by run
        series = {"worlds listed": [], "world classes": []}
        for i, p in enumerate(points):
            for r in range(args.repeat):
                notify(p, i, len(points), r)
                for label, kept in (("worlds listed", False), ("world classes", True)):
                    series[label] += bench.run_scaling([p], timeout=args.timeout,
                                                       max_memory=memory, src=args.src,
                                                       symmetry=symmetry, world_classes=kept)
        series = {k: _medians(v) for k, v in series.items()}
    elif args.versus is None:
        series = {"ehatp": bench.run_scaling(points, timeout=args.timeout, max_memory=memory,
                                             repeat=args.repeat, src=args.src, notify=notify,
                                             symmetry=symmetry,
                                             world_classes=args.world_classes)}
    else:  # one point at a time, the two versions alternating run by run
        series = {"versus": [], "this checkout": []}
        for i, p in enumerate(points):
            for r in range(args.repeat):
                notify(p, i, len(points), r)
                for label, src in (("versus", args.versus), ("this checkout", args.src)):
                    series[label] += bench.run_scaling([p], timeout=args.timeout,
                                                       max_memory=memory, src=src,
                                                       symmetry=symmetry,
                                                       world_classes=args.world_classes)
        series = {k: _medians(v) for k, v in series.items()}
    if sys.stderr.isatty():
        print("\r\033[K", end="", file=sys.stderr, flush=True)
    data: Any = series.get("ehatp", series)
    if args.json is not None:
        args.json.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    for label, rows in series.items():
        if args.versus_listed:
            print(f"== {label}")
        elif args.versus is not None:
            print(f"== {label}: {args.versus if label == 'versus' else args.src}")
        sys.stdout.write(bench.format_scaling(rows))
    if args.plot is not None:
        shown = {f.stem: json.loads(f.read_text(encoding="utf-8")) for f in args.baseline or []}
        shown.update(series)
        if not bench.plot_scaling(shown, str(args.plot)):
            print("note: --plot skipped: matplotlib is not installed (pip install 'ehatp[plot]')",
                  file=sys.stderr)
    return 1 if any(r["status"] in ("crashed", "killed") for rows in series.values()
                    for r in rows) else 0


# the child of --report classes: count the classes of one instance, one JSON line
_CLASSES_CHILD = r"""
import dataclasses, json, sys
import ehatp
from ehatp.experiments.classes import count
report = count(ehatp.load(sys.argv[1]), top=int(sys.argv[2]), timeout=float(sys.argv[3]),
               every=sys.argv[4] == "every")
print(json.dumps(dataclasses.asdict(report)))
"""


def report_classes(points: list[bench.GridPoint], src: str, timeout: float, top: int,
                   every: bool, out: Path | None) -> int:
    """Print, per point, the classes of its ``top`` nodes with the most worlds (one fresh
    process each): ``|W| -> classes`` with the cells (sizes of the sets of objects whose
    swaps fix the node), and the time the count took beside the node's canonical form."""
    import os
    import subprocess
    import tempfile

    rows = []
    env = dict(os.environ, PYTHONPATH=src + os.pathsep + os.environ.get("PYTHONPATH", ""))
    print("The human's worlds as classes under the swaps that fix a node (issue 17 §2): "
          "|W| -> classes [cells]\n(count ms: finding them, a measurement; canon ms: the "
          "node's canonical form, as the search computes it)\n")
    for p in points:
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, f"{p.name}.toml")
            Path(path).write_text(p.toml(), encoding="utf-8")
            proc = subprocess.run([sys.executable, "-c", _CLASSES_CHILD, path, str(top),
                                   str(timeout), "every" if every else "top"],
                                  capture_output=True, text=True, env=env,
                                  timeout=timeout * 3 + (600 if every else 60))
        if proc.returncode != 0 or not proc.stdout.strip():
            err = (proc.stderr.strip().splitlines() or [f"exit {proc.returncode}"])[-1]
            print(f"{p.name}: crashed ({err})")
            rows.append({"instance": p.name, "status": "crashed", "error": err})
            continue
        row = {"instance": p.name, **json.loads(proc.stdout.strip().splitlines()[-1])}
        rows.append(row)
        print(f"{p.name}: {row['status']}, {row['distinct']:,} canonical states, "
              f"largest |W| {row['max_worlds']:,}")
        for n in row["nodes"]:
            cells = ", ".join(str(c) for c in n["cells"])
            print(f"  {n['worlds']:>6,} -> {n['classes']:>5,}  ({n['worlds'] / n['classes']:.1f}x)"
                  f"  cells [{cells}]  count {n['count_ms']:.1f} ms, canon {n['canon_ms']:.1f} ms")
        if row.get("total_worlds") is not None:
            w, c = row["total_worlds"], row["total_classes"]
            print(f"  every node: {w:,} worlds -> {c:,} classes ({w / max(c, 1):.1f}x)")
    if out is not None:
        out.write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
    return 1 if any(r["status"] == "crashed" for r in rows) else 0


def _medians(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per instance: the last run's, with the medians of time, states/s and peak."""
    by: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        by.setdefault(r["instance"], []).append(r)
    out = []
    for runs in by.values():
        row = dict(runs[-1], runs=len(runs))
        for k in bench.MEDIAN_KEYS:
            xs = [x[k] for x in runs if x.get(k) is not None]
            row[k] = statistics.median(xs) if xs else None
        out.append(row)
    return out


if __name__ == "__main__":
    sys.exit(main())
