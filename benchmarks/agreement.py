"""Planner/validator agreement on random problems: solve, validate, execute, re-solve.

    .venv/bin/python benchmarks/agreement.py --n 10000 [--start SEED] [--jobs N] [--verbose]
        [--no-symmetry] [--world-classes] [--walk-cap N]
    .venv/bin/python benchmarks/agreement.py --show SEED      # print one seed's problem

Solves the random problems of seeds start..start+n-1 (``ehatp.experiments.randomgen``), validates
every policy the planner returns with the independent validator, executes it (walks it on every
branch, up to a cap, through the Executor: ``ehatp.run.walk``; the check is
``ehatp.experiments.agreement``), looks in its file for a human
node with two moves of one label (a branch on a choice the robot cannot see, docs/semantics.md
§3), and on one seed in ten solves again (and declared in reverse order), expecting
byte-identical policy JSON. A problem with preference profiles (``[objective] kind =
"preferences"``, docs/concurrent.md C11: half of those in joint steps) is solved keeping its
graph, relabelled for each of its profiles, and each policy compared with a fresh solve for
that profile (byte for byte), validated and executed. A search stopped by its limits is
counted apart (skipped). Prints every crash, disagreement, non-executable policy, hidden-choice
branch and relabelling that differs with its seed (and, in braces, the model options its
problem sets away from the defaults), then the counts and the time taken; exits 1 if there is
any of them. ``--no-symmetry`` solves without the symmetry
reduction (docs/semantics.md §3), whatever the problems say; ``--world-classes`` keeps the
human's worlds as classes (docs/semantics.md §3, "Worlds as classes") and solves each problem
again with them listed, expecting the same policy (its timings aside), states and ``|W|``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

# run the checkout this file lives in, whatever is installed
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "src"))

from ehatp.experiments import agreement, randomgen  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000, metavar="N",
                    help="number of random problems to solve (default 1000)")
    ap.add_argument("--start", type=int, default=0, metavar="SEED",
                    help="first seed (default 0); seeds start..start+N-1 are used")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, metavar="N",
                    help="worker processes (default: the number of CPUs)")
    ap.add_argument("--verbose", "-v", action="store_true",
                    help="one line per seed: outcome, planner status, time")
    ap.add_argument("--show", type=int, metavar="SEED",
                    help="print the problem of SEED and what checking it gives, then exit")
    ap.add_argument("--no-symmetry", action="store_true",
                    help="search without the symmetry reduction (docs/semantics.md §3)")
    ap.add_argument("--world-classes", action="store_true",
                    help="keep the human's worlds as classes (issue 17 §2), and expect the "
                         "policy solving with them listed gives")
    ap.add_argument("--walk-cap", type=int, default=agreement.WALK_CAP, metavar="N",
                    help="branches of a policy executed at most (default "
                         f"{agreement.WALK_CAP})")
    args = ap.parse_args(argv)
    if args.n < 1:
        ap.error("--n must be at least 1")
    if args.jobs < 1:
        ap.error("--jobs must be at least 1")
    if args.walk_cap < 1:
        ap.error("--walk-cap must be at least 1")
    symmetry = False if args.no_symmetry else None  # None: as each problem says

    if args.show is not None:
        return show(args.show, args.walk_cap, symmetry, args.world_classes)

    seeds = range(args.start, args.start + args.n)
    tty = sys.stderr.isatty()
    done = 0

    def progress(_: agreement.Outcome) -> None:
        nonlocal done
        done += 1
        if tty and (done % 50 == 0 or done == args.n):
            print(f"\r\033[K{done}/{args.n}", end="", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    outcomes = agreement.run(seeds, jobs=args.jobs, on_result=progress, walk_cap=args.walk_cap,
                             symmetry=symmetry, world_classes=args.world_classes)
    elapsed = time.perf_counter() - t0
    if tty:
        print("\r\033[K", end="", file=sys.stderr, flush=True)
    return report(outcomes, seeds, elapsed, args.jobs, args.walk_cap, args.verbose,
                  args.world_classes)


def show(seed: int, walk_cap: int, symmetry: bool | None, world_classes: bool = False) -> int:
    """Print the problem of ``seed`` and what checking it gives; return the exit code."""
    print(randomgen.draw(seed).describe())
    o = agreement.check(seed, determinism=True, walk_cap=walk_cap, symmetry=symmetry,
                        world_classes=world_classes)
    print(f"\n{o.kind} (planner: {o.status or '-'}) {o.detail}")
    if o.executed:
        print(f"executed: {o.branches} branch(es){' (capped)' if o.capped else ''}"
              + (f"; fails: {o.unexecutable}" if o.unexecutable else ", every one to the goal"))
    if o.hidden_choice:
        print(f"branches on a hidden choice: {o.hidden_choice}")
    if o.classes_differ:
        print(f"worlds as classes: {o.classes_differ}")
    if o.preferences:
        print(f"preference profiles: {o.relabelled} relabelled"
              + (f"; {o.relabel_differs}" if o.relabel_differs else
                 ", each the policy of a fresh solve, valid and executed"))
    return 1 if o.failed else 0


def report(outcomes: list[agreement.Outcome], seeds: range, elapsed: float, jobs: int,
           walk_cap: int, verbose: bool, classes: bool = False) -> int:
    """Print every failing seed (every seed when ``verbose``), then the counts; return the
    exit code."""
    for o in outcomes:
        if verbose or o.failed:
            det = " [determinism checked]" if o.checked_determinism else ""
            opts = f" {{{', '.join(o.options)}}}" if o.options else ""
            walked = (f", executed {o.branches} branch(es)" + (" (capped)" if o.capped else "")
                      if o.executed else "")
            print(f"seed {o.seed}: {o.kind} (planner: {o.status or '-'}, "
                  f"{o.seconds * 1000:.0f} ms{walked}){opts}{det}"
                  f"{': ' + o.detail if o.detail else ''}")
            if o.unexecutable:
                print(f"  non-executable: {o.unexecutable}")
            if o.hidden_choice:
                print(f"  branches on a hidden choice: {o.hidden_choice}")
            if o.relabel_differs:
                print(f"  relabelling: {o.relabel_differs}")
            if o.classes_differ:
                print(f"  worlds as classes: {o.classes_differ}")
    c = agreement.summary(outcomes)
    checked = sum(o.checked_determinism for o in outcomes)
    failures = sum(o.failed for o in outcomes)
    plain = sum(1 for o in outcomes if o.failed and not o.options)
    walk_time = sum(o.walk_seconds for o in outcomes)
    branches = sum(o.branches for o in outcomes)
    print(f"{len(seeds)} problems (seeds {seeds.start}..{seeds.stop - 1}) in {elapsed:.1f} s "
          f"on {jobs} job(s); determinism checked on {checked}")
    print(f"solved {c['solved']}, unsolvable {c['unsolvable']}, limit {c['limit']}, "
          f"crashes {c['crash']}, disagreements {c['disagreement']}, "
          f"nondeterministic {c['nondeterministic']}")
    print(f"executed {c['executed']} policies ({branches} branches, {c['capped']} stopped at "
          f"{walk_cap} branches; {walk_time:.1f} s of the workers' time), "
          f"non-executable {c['non-executable']}, "
          f"branches on a hidden choice {c['hidden-choice']}")
    solved_prefs = sum(1 for o in outcomes if o.preferences and o.kind == "solved")
    print(f"preference profiles: {c['preferences']} problems ({solved_prefs} solved), "
          f"{c['relabelled']} profiles relabelled and compared with a fresh solve, "
          f"relabellings that differ {c['relabel-differs']}")
    if any(o.classes_differ for o in outcomes) or classes:
        print(f"worlds as classes: policies that differ from the worlds listed "
              f"{c['classes-differ']}")
    print("OK: planner and validator agree, every policy executes" if not failures else
          f"FAIL: {failures} seed(s) with a crash, disagreement, nondeterminism, "
          f"non-executable policy, branch on a hidden choice, relabelling or classes that "
          f"differ "
          f"({plain} with every model option at its default)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
