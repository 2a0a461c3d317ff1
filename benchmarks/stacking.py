"""The shared stacking domain in joint steps (docs/domains/stacking.md): solve, validate and walk
one problem, and print what it took.

    .venv/bin/python benchmarks/stacking.py [examples/concurrent/stack10.toml]

Prints the states the search generated and kept (distinct), the makespan (worst case, in
steps), the policy's leaves, the CPU seconds of the solve, of the validation and of the walk
through the Executor on every branch, and the process's maximum resident set size. Exits 1 when
there is no policy, it is invalid or it does not run, or when the whole took over 60 s of CPU or
2 GB (issue 20's bound).
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

# run the checkout this file lives in, whatever is installed
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "src"))

import ehatp  # noqa: E402
from ehatp.run.walk import walk_policy  # noqa: E402

DEFAULT = Path(__file__).resolve().parent.parent / "examples" / "concurrent" / "stack10.toml"
CPU_LIMIT_S, RSS_LIMIT_MB = 60.0, 2048.0


def main(argv: list[str] | None = None) -> int:
    """Print the figures; return 1 on any failure or past the bound."""
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("problem", nargs="?", type=Path, default=DEFAULT)
    args = ap.parse_args(argv)
    problem = ehatp.load(args.problem)
    t0 = time.process_time()
    result = ehatp.solve(problem)
    t1 = time.process_time()
    if result.policy is None:
        print(f"{args.problem}: no policy ({result.reason})")
        return 1
    report = ehatp.validate(problem, result.policy)
    t2 = time.process_time()
    walked = walk_policy(problem, result.policy)
    t3 = time.process_time()
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kB on Linux
    p, s = result.policy, result.stats
    print(f"{problem.name}: generated {s['generated']}, distinct {s['distinct']}, "
          f"makespan {p.cost}, communications {p.communications}, leaves {p.leaves}, "
          f"|W| {s['max_worlds']}")
    print(f"CPU s: solve {t1 - t0:.2f}, validate {t2 - t1:.2f}, walk {t3 - t2:.2f}, "
          f"all {t3 - t0:.2f}; max RSS {rss_mb:.0f} MB")
    print(f"valid {report.ok}, runs on every branch {walked.ok} ({walked.branches} branches)")
    ok = report.ok and walked.ok and t3 - t0 <= CPU_LIMIT_S and rss_mb <= RSS_LIMIT_MB
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
