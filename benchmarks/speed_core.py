"""Where symmetry does not help (issue 17 §4): two checkouts side by side, run by run.

    .venv/bin/python benchmarks/speed_core.py --versus DIR [--after PATH] [--repeat N]
        [--only NAME ...] [--validate] [--keep DIR] [--converted]

Targets: ``cubes-c8-b2-opaque-k2`` and ``cubes-c6-b3-opaque-k8`` solved with ``--no-symmetry``,
and the IPC 2020 HTN track's two largest, ``to-Woodworking`` and ``to-Entertainment`` (HDDL, the
robot alone, as ``benchmarks/hddl_report.py`` imports them; needs unified-planning). With
``--converted`` each checkout converts them once, untimed, with its own ``ehatp import-hddl``,
and the timed process reads the problem TOML, as ``ehatp solve`` does: the HDDL reader
(unified-planning's, about 1.3 s of imports and parsing) is then not timed. Every run
is a fresh process (``python -c``, the checkout's ``src`` first on ``sys.path``): import,
ground, solve, write the policy JSON, and with ``--validate`` validate it too. ``DIR`` (another
checkout, e.g. a ``git worktree`` of an older commit) and this one alternate run by run, so that
a shared machine's drift falls on both alike. ``--after PATH`` times ``PATH`` (a directory that
holds the ``ehatp`` package, such as the compiled core installed with ``pip install --no-deps
--target PATH``, docs/compiled.md) instead of this checkout's ``src``; the row says which core
ran.

Prints, per target and checkout, the medians of the whole process's CPU time (user + system,
start-up included) and its peak resident memory (``ru_maxrss`` of the child), the states,
and whether the two policies' JSON are byte-identical (their SHA-256), and without their
``stats`` (a search that counts other states writes other counts). ``--keep DIR`` writes
the policies there. Timing lives here, never in the unit tests.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent

CHILD = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
target, out, validate, converted = sys.argv[2], sys.argv[3], sys.argv[4] == "1", sys.argv[5]
if converted:  # the problem TOML ehatp import-hddl wrote, read as ehatp solve reads it
    import ehatp
    problem = ehatp.load(converted)
    kw = {}
elif target in ("woodworking", "entertainment"):
    from ehatp.experiments.hddl_report import domains_shipped
    from ehatp.formats.hddl import import_hddl
    from ehatp.formats.hddl_sidecar import Sidecar
    ipc = "to-" + target.capitalize()
    _, dom, prob = next(d for d in domains_shipped() if d[0].endswith(ipc))
    problem = import_hddl(dom, prob, sidecar=Sidecar(expects="nothing")).problem()
    kw = {}
else:
    import ehatp
    from ehatp.experiments import bench
    point = bench.select_points(None, [target], False)[0]
    path = out + ".toml"
    with open(path, "w", encoding="utf-8") as f:
        f.write(point.toml())
    problem = ehatp.load(path)
    kw = {"symmetry": False}
from ehatp.search import andor
from ehatp.search.planner import solve
r = solve(problem, timeout=3600, **kw)
text = r.policy.to_json() if r.policy is not None else ""
with open(out, "w", encoding="utf-8") as f:
    f.write(text)
ok = None
if validate and r.policy is not None:
    from ehatp.check.validator import validate as check
    ok = check(problem, r.policy).ok
from importlib.machinery import EXTENSION_SUFFIXES
core = "compiled" if andor.__file__.endswith(tuple(EXTENSION_SUFFIXES)) else "pure"
print(json.dumps({"core": core, "status": r.status, "distinct": r.stats.get("distinct"),
                  "cost": None if r.policy is None else str(r.policy.cost), "valid": ok}))
"""

TARGETS = {"cubes-c8-b2-opaque-k2": "cubes-c8-b2-opaque-k2 --no-symmetry",
           "cubes-c6-b3-opaque-k8": "cubes-c6-b3-opaque-k8 --no-symmetry",
           "woodworking": "IPC 2020 to-Woodworking, the robot alone",
           "entertainment": "IPC 2020 to-Entertainment, the robot alone"}


CONVERT = r"""
import sys
sys.path.insert(0, sys.argv[1])
from ehatp.cli.app import main
from ehatp.experiments.hddl_report import domains_shipped
target, side, out = sys.argv[2:5]
_, dom, prob = next(d for d in domains_shipped() if d[0].endswith("to-" + target.capitalize()))
sys.argv = ["ehatp", "import-hddl", str(dom), str(prob), "--sidecar", side, "--out", out]
main()
"""


def convert(src: str, target: str, where: Path) -> Path:
    """Convert an IPC target once with ``src``'s own ``ehatp import-hddl`` (untimed, a fresh
    process; the robot alone, expecting nothing of it, as ``hddl_report.py`` reads it) into
    ``where``; return the problem TOML it wrote."""
    where.mkdir(parents=True, exist_ok=True)
    side = where / "sidecar.toml"
    side.write_text('[other]\nexpects = "nothing"\n', encoding="utf-8")
    module = where / f"{target}.py"
    proc = subprocess.run([sys.executable, "-c", CONVERT, src, target, str(side), str(module)],
                          capture_output=True, text=True, cwd=where)
    if proc.returncode != 0:
        raise SystemExit(f"import-hddl of {target} with {src} failed:\n{proc.stderr}")
    return module.with_suffix(".toml")


def run(src: str, target: str, out: Path, validate: bool,
        converted: Path | None = None) -> dict[str, Any]:
    """One fresh process: its row (CPU s, peak MB, what it printed, the policy's hash)."""
    proc = subprocess.Popen(
        [sys.executable, "-c", CHILD, src, target, str(out), "1" if validate else "0",
         str(converted) if converted else ""],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        cwd=converted.parent if converted else None)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    stdout = proc.stdout.read() if proc.stdout else ""
    stderr = proc.stderr.read() if proc.stderr else ""
    if proc.returncode != 0:
        raise SystemExit(f"{target} with {src} failed (exit {proc.returncode}):\n{stderr}")
    row: dict[str, Any] = json.loads(stdout.strip().splitlines()[-1])
    row["cpu_s"] = usage.ru_utime + usage.ru_stime
    row["peak_mb"] = usage.ru_maxrss / 1024
    row["sha256"] = hashlib.sha256(out.read_bytes()).hexdigest()
    text = out.read_text(encoding="utf-8")
    policy = json.loads(text) if text else {}
    policy.pop("stats", None)  # the states counted differ between two searches
    row["sha256_policy"] = hashlib.sha256(json.dumps(policy, sort_keys=True).encode()).hexdigest()
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--versus", required=True, metavar="DIR",
                    help="the other checkout (its src/ is timed)")
    ap.add_argument("--after", metavar="PATH",
                    help="time PATH (holding the ehatp package, e.g. the compiled core "
                         "installed with pip --target) instead of this checkout's src")
    ap.add_argument("--repeat", "-n", type=int, default=3, metavar="N",
                    help="runs per target and checkout; medians (default 3)")
    ap.add_argument("--only", action="append", choices=sorted(TARGETS), metavar="NAME",
                    help=f"one of {', '.join(TARGETS)} (repeatable; default all)")
    ap.add_argument("--validate", action="store_true", help="validate each policy too")
    ap.add_argument("--keep", type=Path, metavar="DIR", help="write the policies there")
    ap.add_argument("--converted", action="store_true",
                    help="IPC targets: convert the HDDL once per checkout with its own "
                         "import-hddl (untimed) and time solving the problem TOML, as "
                         "'ehatp solve' does, without the HDDL reader")
    args = ap.parse_args(argv)
    srcs = {"before": str(Path(args.versus).resolve() / "src"),
            "after": str(Path(args.after).resolve() if args.after else ROOT / "src")}
    keep = args.keep or Path(tempfile.mkdtemp(prefix="speed-core-"))
    keep.mkdir(parents=True, exist_ok=True)
    print("target                                    | checkout | CPU s (runs)        | "
          "peak MB | states  | cost | valid | core")
    same = True
    for target in args.only or list(TARGETS):
        rows: dict[str, list[dict[str, Any]]] = {"before": [], "after": []}
        ipc = args.converted and target in ("woodworking", "entertainment")
        converted = {label: convert(src, target, keep / f"{target}-{label}") if ipc else None
                     for label, src in srcs.items()}
        for _ in range(args.repeat):
            for label, src in srcs.items():
                rows[label].append(run(src, target, keep / f"{target}-{label}.json",
                                       args.validate, converted[label]))
        cpu = {k: statistics.median(r["cpu_s"] for r in v) for k, v in rows.items()}
        for label, rs in rows.items():
            runs = " ".join(f"{r['cpu_s']:.2f}" for r in rs)
            print(f"{TARGETS[target][:41]:41s} | {label:8s} | {cpu[label]:6.2f} ({runs}) | "
                  f"{statistics.median(r['peak_mb'] for r in rs):7.0f} | "
                  f"{rs[-1]['distinct']:7,} | {rs[-1]['cost']:>4} | {rs[-1]['valid']} | "
                  f"{rs[-1]['core']}")
        hashes = {r["sha256"] for rs in rows.values() for r in rs}
        policies = {r["sha256_policy"] for rs in rows.values() for r in rs}
        same = same and len(policies) == 1
        print(f"  speed-up {cpu['before'] / cpu['after']:.2f}x; policy JSON "
              f"{'byte-identical' if len(hashes) == 1 else 'DIFFERS'} "
              f"({len(hashes)} distinct hash{'es' if len(hashes) > 1 else ''}); without its "
              f"stats (the states counted) {'identical' if len(policies) == 1 else 'DIFFERS'}",
              flush=True)
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
