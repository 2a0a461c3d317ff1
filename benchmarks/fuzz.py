"""Fuzz every input file kind through the commands that read it: thousands of mutated cases.

    .venv/bin/python benchmarks/fuzz.py [--n 2000] [--kind KIND ...] [--seed S]

Each case is a mutated problem, policy (text or JSON value), sidecar, HDDL domain or `execute`
input (ehatp.experiments.fuzz, shared with tests/test_fuzz_inputs.py), run in this process.
Prints, per kind, how many cases ended with each exit code, and every case that did not end
with exit 0, 1 or 2 (exit 2 in one line), with the seed that reproduces it. Exit 1 if any.
"""

from __future__ import annotations

import argparse
import collections
import random
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(1, str(ROOT))  # tests.fuzzing: how a case is run, shared with the tests

from tests.fuzzing import run_case  # noqa: E402

import ehatp  # noqa: E402
from ehatp.experiments.fuzz import KINDS, Seeds, fuzz_case  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2000, help="cases in all (default 2000)")
    ap.add_argument("--kind", action="append", choices=KINDS, help="only these kinds")
    ap.add_argument("--seed", type=int, default=0, help="the first case's seed (default 0)")
    args = ap.parse_args(argv)
    kinds = args.kind or list(KINDS)
    hddl = ROOT / "tests" / "data" / "hddl"
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        problem = ROOT / "examples" / "cubes" / "p2.toml"
        result = ehatp.solve(ehatp.load(problem))
        assert result.policy is not None
        policy = folder / "seed-policy.json"
        result.policy.write(policy)
        seeds = Seeds(problem, policy, hddl / "transport-domain.hddl",
                      hddl / "transport-p1.hddl", hddl / "transport-sidecar.toml")
        codes: dict[str, collections.Counter[int]] = {k: collections.Counter() for k in kinds}
        bad: list[str] = []
        t0 = time.process_time()
        for i in range(args.n):
            seed = args.seed + i
            kind = kinds[i % len(kinds)]
            case = folder / f"case-{i}"
            case.mkdir()
            command, stdin = fuzz_case(kind, seeds, random.Random(seed), case)
            verdict = run_case(command, stdin)
            codes[kind][verdict.exit_code] += 1
            if not verdict.ok:
                bad.append(f"{kind} seed {seed}: ehatp {' '.join(command)}: {verdict.why}")
        cpu = time.process_time() - t0
    print(f"{args.n} cases, {cpu:.1f} s CPU")
    for kind in kinds:
        print(f"  {kind:12} " + ", ".join(f"exit {c}: {n}" for c, n in sorted(codes[kind].items())))
    print(f"{len(bad)} not ended with exit 0, 1 or 2 in one line")
    for line in bad[:50]:
        print("  " + line)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
