"""A 512-variant grid of the cube problems through ``ehatp sweep``: run, resume, compare executors.

    .venv/bin/python benchmarks/sweep_grid.py [--workers N] [--executors local dask ray]

Two Table 1 problems (P2, P4) times a grid of eight two-valued overrides (K, who starts, where
the robot may inform, speech, asking, the pass rule, the objective, the cost of informing) is
512 instances. The script runs them with the real command (``ehatp sweep``) on each executor
asked for, then checks that

* every executor gives the same rows (all but the times),
* ``--resume`` on a complete results file runs nothing and adds no line,
* ``--resume`` after a run cut short (the file cut to 400 rows and half a line) runs exactly
  the 112 missing instances,

and prints the wall time of each step. Exit 1 if a check fails. Timing lives here, never in
the unit tests.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from ehatp.experiments.examples import examples_dir

GRID = """\
# 2^8 = 256 combinations per problem file
problem.K = [2, 3]
problem.starts = ["human", "robot"]
communication.inform = ["copresent", "anywhere"]
communication.speech = ["turn", "with-action"]
communication.ask = [true, false]
human.passes = ["fair", "prototype"]
objective.kind = ["worst-case", "expected"]
costs.inform = [1, 5]
"""
FILES = ("p2.toml", "p4.toml")
CUT = 400


def ehatp(*args: str | Path) -> tuple[int, float, str, str]:
    """Run ``ehatp`` (the console script beside this Python); exit code, seconds, output."""
    script = Path(sys.executable).with_name("ehatp")
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "ehatp.cli"]
    t0 = time.perf_counter()
    p = subprocess.run([*cmd, *map(str, args)], capture_output=True, text=True)
    return p.returncode, time.perf_counter() - t0, p.stdout, p.stderr


def rows(path: Path) -> dict[str, dict[str, Any]]:
    """Rows by key, without their times."""
    out = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        r = json.loads(line)
        out[r["key"]] = {k: v for k, v in r.items() if k not in ("time_s", "search_ms")}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", "-j", type=int, default=os.cpu_count() or 1,
                    help="workers per executor (default: the cores)")
    ap.add_argument("--executors", nargs="+", default=["local", "dask"],
                    choices=["local", "dask", "ray"], help="default: local dask")
    args = ap.parse_args(argv)
    failures: list[str] = []

    def check(ok: bool, what: str) -> None:
        print(f"  {'ok' if ok else 'FAILED'}: {what}")
        if not ok:
            failures.append(what)

    with tempfile.TemporaryDirectory(prefix="ehatp-sweep-grid-") as tmp:
        d = Path(tmp)
        grid = d / "grid.toml"
        grid.write_text(GRID, encoding="utf-8")
        problems = [examples_dir() / "cubes" / f for f in FILES]
        common = [*problems, "--grid", grid, "--workers", str(args.workers)]
        first: dict[str, dict[str, Any]] | None = None
        for ex in args.executors:
            module = {"dask": "distributed", "ray": "ray"}.get(ex)
            if module is not None and importlib.util.find_spec(module) is None:
                print(f"{ex}: skipped, not installed (pip install 'ehatp[{ex}]')")
                continue
            out = d / f"{ex}.jsonl"
            code, secs, _, err = ehatp("sweep", *common, "--executor", ex, "--out", out)
            got = rows(out) if out.exists() else {}
            print(f"{ex}: 512 instances in {secs:.1f} s (exit {code}, {args.workers} workers)")
            check(code == 0 and len(got) == 512, f"{ex}: 512 rows, exit 0 ({err.strip()[-200:]})")
            solved = sum(r["status"] == "solved" for r in got.values())
            print(f"  {solved} solved, {len(got) - solved} other")
            if first is None:
                first = got
            else:
                check(got == first, f"{ex}: the same rows as {args.executors[0]}")
            if ex != args.executors[0]:
                continue
            # resume a complete file: nothing runs, no line is added
            before = out.read_bytes()
            code, secs, stdout, _ = ehatp("sweep", *common, "--executor", ex, "--out", out,
                                          "--resume")
            print(f"{ex}: --resume with all 512 rows done: {secs:.1f} s")
            check(code == 0 and out.read_bytes() == before and "(0 new)" in stdout,
                  "--resume on a complete file runs nothing")
            # a run cut short: 400 rows and half of the next line
            lines = before.decode("utf-8").splitlines(keepends=True)
            out.write_text("".join(lines[:CUT]) + lines[CUT][:50], encoding="utf-8")
            code, secs, stdout, _ = ehatp("sweep", *common, "--executor", ex, "--out", out,
                                          "--resume")
            print(f"{ex}: --resume after {CUT} rows: {secs:.1f} s")
            check(code == 0 and f"({512 - CUT} new)" in stdout and rows(out) == first,
                  f"--resume runs the {512 - CUT} missing instances and gives the same rows")
    print("all checks passed" if not failures else f"{len(failures)} check(s) FAILED")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
