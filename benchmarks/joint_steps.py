"""Table 1's nine instances in turns and in joint, compliant steps (docs/concurrent.md).

    .venv/bin/python benchmarks/joint_steps.py [--repeat N] [--witness whole|start]
        [--first human|robot]

For each instance: the turn-taking policy's worst case, communications and |W| beside the
joint-step policy's makespan (worst case, in steps), communications and |W|, the distinct states
the joint search met, and its time (best of N, solve only); every joint policy is validated and
walked on every branch through the Executor. Prints a Markdown table (docs/benchmarks.md,
"Joint steps"); exits 1 when a joint policy is missing, invalid, does not run, or has a makespan
above the turn-taking worst case.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

# run the checkout this file lives in, whatever is installed
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "src"))

import ehatp  # noqa: E402
from ehatp import StepFirst, StepMode, Steps, Witness  # noqa: E402
from ehatp.run.walk import walk_policy  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent / "examples"
TABLE1 = [("P1", "cubes/p1"), ("P2", "cubes/p2"), ("P3", "cubes/p3"), ("P4", "cubes/p4"),
          ("P5", "cubes/p5"), ("P6", "cubes/p6"), ("Cooking 1", "cooking/cooking1"),
          ("Cooking 2", "cooking/cooking2"), ("Cooking 3", "cooking/cooking3")]


def main(argv: list[str] | None = None) -> int:
    """Print the table; return 1 on any failure."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs per instance (best kept)")
    ap.add_argument("--witness", choices=[w.value for w in Witness], default="whole")
    ap.add_argument("--first", choices=[f.value for f in StepFirst], default="human")
    args = ap.parse_args(argv)
    steps = Steps(StepMode.CONCURRENT, first=StepFirst(args.first),
                  witness=Witness(args.witness))
    print("| inst | turns: cost | comm | \\|W\\| | steps: makespan | comm | \\|W\\| | distinct "
          "| ms |")
    print("|---|---|---|---|---|---|---|---|---|")
    bad = 0
    for label, name in TABLE1:
        p = ehatp.load(ROOT / f"{name}.toml")
        turns = ehatp.solve(p)
        joint_p = dataclasses.replace(p, steps=steps)
        best = float("inf")
        result = None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            result = ehatp.solve(joint_p)
            best = min(best, time.perf_counter() - t0)
        assert result is not None and turns.policy is not None
        pol = result.policy
        ok = (pol is not None and ehatp.validate(joint_p, pol).ok
              and walk_policy(joint_p, pol).ok and pol.cost <= turns.policy.cost)
        bad += not ok
        st, tt = result.stats, turns.stats
        print(f"| {label} | {turns.policy.cost} | {turns.policy.communications} | "
              f"{tt['max_worlds']} | {pol.cost if pol else '-'} | "
              f"{pol.communications if pol else '-'} | {st.get('max_worlds')} | "
              f"{st.get('distinct')} | {best * 1000:.1f} |" + ("" if ok else " FAILED"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
