"""Switching preference profile in the middle of an execution (C11, docs/concurrent.md
"Relabelling"): the kept graph relabelled from the current state, against a fresh solve of the
execution so far.

    .venv/bin/python benchmarks/profile_switch.py [--cap N] [--random N]

For each of Table 1's nine instances and the 10-cube shared stack, in joint steps with three
profiles (``hurry``: makespan, human_effort; ``lazy_human``: human_effort, makespan;
``end``: human_end, makespan): solve under ``hurry`` keeping the graph, walk the policy through
the Executor, and at every step start met (up to ``--cap``) switch to each other profile twice
over, alternating: ``Executor.switch_profile`` on the kept graph, and ``ehatp.solve`` of
``executor.as_problem()`` with that profile. Prints, per instance, the distinct states of the
kept graph, the switches made, the mean CPU milliseconds of each way, the peak of Python
allocations of each (tracemalloc, one switch and one solve at the first step start, measured
apart from the timings), and how many switched policies differ from the fresh solve's (node by
node; the search statistics aside); then the process's maximum resident set size. Every
switched policy is validated (as the problem played so far) and walked on every branch from the
switch. With ``--random N``, the same on the random problems of seeds 0..N-1 that have
preference profiles (``ehatp.experiments.randomgen``, as ``benchmarks/agreement.py`` draws
them; its state and time limits), from each solved one's chosen profile to each other, at up
to 10 step starts. Exits 1 when one differs, is invalid or does not run.
"""

from __future__ import annotations

import argparse
import dataclasses
import resource
import sys
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

# run the checkout this file lives in, whatever is installed
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "src"))

import ehatp  # noqa: E402
from ehatp import StepMode, Steps  # noqa: E402
from ehatp.model.options import Metric, Objective, ObjectiveKind  # noqa: E402
from ehatp.run.executor import Executor  # noqa: E402
from ehatp.run.walk import (
    positions,  # noqa: E402
    walk_from,  # noqa: E402
)

ROOT = Path(__file__).resolve().parent.parent / "examples"
INSTANCES = [("P1", "cubes/p1"), ("P2", "cubes/p2"), ("P3", "cubes/p3"), ("P4", "cubes/p4"),
             ("P5", "cubes/p5"), ("P6", "cubes/p6"), ("Cooking 1", "cooking/cooking1"),
             ("Cooking 2", "cooking/cooking2"), ("Cooking 3", "cooking/cooking3"),
             ("stack10", "concurrent/stack10")]
PROFILES = {"hurry": (Metric.MAKESPAN, Metric.HUMAN_EFFORT),
            "lazy_human": (Metric.HUMAN_EFFORT, Metric.MAKESPAN),
            "end": (Metric.HUMAN_END, Metric.MAKESPAN)}


def step_starts(problem: ehatp.Problem, policy: ehatp.Policy, cap: int) -> list[Executor]:
    """Executors at the step starts of ``policy`` (past the opening, before the goal), every
    branch walked depth first, at most ``cap``."""
    return positions(Executor(problem, policy), cap=cap, step_starts=True)


def same(a: ehatp.Policy, b: ehatp.Policy) -> bool:
    """Whether two policies are the same but for the search's statistics."""
    da, db = a.to_dict(), b.to_dict()
    da.pop("stats", None)
    db.pop("stats", None)
    return da == db


def peak(work: Callable[..., Any], *args: Any) -> int:
    """The peak of Python allocations (bytes) while ``work(*args)`` runs."""
    tracemalloc.start()
    try:
        work(*args)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def random_problems(n: int) -> int:
    """Switch profile at the step starts of the random problems with profiles of seeds
    0..n-1; print the counts; return how many switches differ from a fresh solve."""
    from ehatp.experiments.agreement import MAX_STATES, TIMEOUT, WALK_CAP
    from ehatp.experiments.randomgen import build, draw
    from ehatp.search.limits import SolveStatus

    limits: dict[str, Any] = {"max_states": MAX_STATES, "timeout": TIMEOUT}
    with_profiles = solved = switches = compared = differ = 0
    t_switch = t_fresh = 0.0
    for seed in range(n):
        spec = draw(seed)
        if dict(spec.settings).get("objective.kind") != ObjectiveKind.PREFERENCES:
            continue
        with_profiles += 1
        p = build(spec)
        kept = ehatp.solve(p, keep_graph=True, **limits)
        if kept.policy is None or kept.graph is None:
            continue
        solved += 1
        for ex in step_starts(p, kept.policy, 10):
            for new in sorted(p.objective.profiles):
                if new == p.objective.profile:
                    continue
                other = ex.copy()
                t0 = time.process_time()
                policy = other.switch_profile(kept.graph, new)
                t1 = time.process_time()
                fresh = ehatp.solve(other.as_problem(), **limits)
                t2 = time.process_time()
                switches += 1
                if fresh.status in (SolveStatus.TIMEOUT, SolveStatus.STATE_LIMIT):
                    continue
                compared += 1
                t_switch += t1 - t0
                t_fresh += t2 - t1
                ok = (fresh.policy is not None and same(policy, fresh.policy)
                      and ehatp.validate(other.problem, policy).ok
                      and walk_from(other, cap=WALK_CAP).ok)
                if not ok:
                    differ += 1
                    print(f"seed {seed}: the switch to {new} after {len(other.history)} moves "
                          "differs from a fresh solve, or is invalid, or does not run")
    m = max(compared, 1)
    print(f"random seeds 0..{n - 1}: {with_profiles} with profiles, {solved} solved; "
          f"{switches} switches, {compared} compared with a fresh solve (the others stopped "
          f"at a limit), {differ} differ; mean CPU ms: switch {t_switch / m * 1000:.2f}, "
          f"fresh solve {t_fresh / m * 1000:.2f}")
    return differ


def main(argv: list[str] | None = None) -> int:
    """Print the table; return 1 on any failure."""
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--cap", type=int, default=40, help="step starts per instance, at most")
    ap.add_argument("--random", type=int, default=0, metavar="N",
                    help="also the random problems with profiles of seeds 0..N-1")
    args = ap.parse_args(argv)
    print("| inst | distinct | switches | switch ms | fresh solve ms | switch peak KB | "
          "solve peak KB | differ |")
    print("|---|---|---|---|---|---|---|---|")
    bad = 0
    for label, name in INSTANCES:
        p = ehatp.load(ROOT / f"{name}.toml")
        p = dataclasses.replace(p, steps=Steps(StepMode.CONCURRENT, first=p.steps.first),
                                objective=Objective(ObjectiveKind.PREFERENCES,
                                                    profile="hurry", profiles=PROFILES))
        kept = ehatp.solve(p, keep_graph=True)
        if kept.policy is None or kept.graph is None:
            print(f"| {label} | no policy: {kept.reason} |")
            bad += 1
            continue
        starts = step_starts(p, kept.policy, args.cap)
        t_switch = t_fresh = 0.0
        switches = differ = 0
        for ex in starts:
            for new in PROFILES:
                if new == "hurry":
                    continue
                for _ in range(2):  # alternating, twice over
                    other = ex.copy()
                    t0 = time.process_time()
                    policy = other.switch_profile(kept.graph, new)
                    t1 = time.process_time()
                    fresh = ehatp.solve(other.as_problem()).policy
                    t2 = time.process_time()
                    t_switch += t1 - t0
                    t_fresh += t2 - t1
                    switches += 1
                ok = (fresh is not None and same(policy, fresh)
                      and ehatp.validate(other.problem, policy).ok and walk_from(other).ok)
                differ += not ok
        bad += differ
        p_switch = peak(starts[0].copy().switch_profile, kept.graph, "lazy_human")
        moved = starts[0].copy()
        moved.switch_profile(kept.graph, "lazy_human")
        p_fresh = peak(ehatp.solve, moved.as_problem())
        n = max(switches, 1)
        print(f"| {label} | {kept.stats['distinct']} | {switches} | "
              f"{t_switch / n * 1000:.2f} | {t_fresh / n * 1000:.2f} | "
              f"{p_switch / 1024:.0f} | {p_fresh / 1024:.0f} | {differ} |")
    if args.random:
        bad += random_problems(args.random)
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kB on Linux
    print(f"\nmax RSS of the process: {rss_mb:.0f} MB")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
