"""Reproduce Table 1 of the paper: our figures beside the published and stored ones.

    .venv/bin/python benchmarks/table1.py [--repeat N] [--json FILE] [--only P1 ...]

Same table as ``ehatp bench table1``; timing lives here and in that command, never in the
unit tests.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ehatp.experiments.bench import format_table, run_table1


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", "-n", type=int, default=3,
                    help="runs per instance; the best time is kept (default 3)")
    ap.add_argument("--json", type=Path, help="also write the rows as JSON to this file")
    ap.add_argument("--only", action="append", metavar="NAME",
                    help="run just this instance (repeatable), e.g. --only P3")
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error("--repeat must be at least 1")

    def notify(inst: str, run: int, runs: int) -> None:
        if sys.stderr.isatty():  # a one-line status on a terminal, nothing in logs
            print(f"\r\033[Ksolving {inst} (run {run}/{runs})", end="", file=sys.stderr,
                  flush=True)

    rows = run_table1(args.repeat, notify, args.only)
    if not rows:
        ap.error(f"no Table 1 instance named {', '.join(args.only)}")
    if sys.stderr.isatty():
        print("\r\033[K", end="", file=sys.stderr, flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
    sys.stdout.write(format_table(rows))
    return 0 if rows and all(r["solved"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
