"""HDDL import report: which HTN domains map to ehatp, solve and validate.

    .venv/bin/python benchmarks/hddl_report.py [--timeout S] [--max-states N] [--jobs N]
        [--only PATTERN ...] [--json FILE] [--expects nothing|plan]

Runs ``ehatp.experiments.hddl_report.check_domain`` on every HDDL domain unified-planning ships
with its tests (the IPC 2020 HTN track's, one problem each) and on the small ones of
tests/data/hddl:
import (the domain as the robot's HTN, the human with an empty agenda, everything observable,
always together; by default the robot alone, the human following no plan of it, and with
``--expects plan`` a human who knows the robot's model), solve within ``--timeout`` seconds
(grounding included), validate the policy. Each domain runs in a child process of its own.
Prints one line per domain (the stage it reached and, if it stopped short, why, in one line),
then how many map, solve and validate.
docs/hddl.md keeps the figures of a run.
"""

from __future__ import annotations

import argparse
import dataclasses
import fnmatch
import json
import multiprocessing
import sys
import time
from collections.abc import Iterator
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

# run the checkout this file lives in, whatever is installed (the child processes too)
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))

from ehatp.experiments import hddl_report  # noqa: E402
from ehatp.formats import hddl  # noqa: E402

OWN = ROOT / "tests" / "data" / "hddl"


def own_domains() -> list[tuple[str, Path, Path]]:
    """tests/data/hddl: NAME-domain.hddl with NAME-p1.hddl (and more problems)."""
    out = []
    for dom in sorted(OWN.glob("*-domain.hddl")):
        stem = dom.name.removesuffix("-domain.hddl")
        for prob in sorted(OWN.glob(f"{stem}-p*.hddl")):
            out.append((f"own/{stem}/{prob.stem.removeprefix(stem + '-')}", dom, prob))
    return out


def _child(conn: Connection, name: str, dom: Path, prob: Path, timeout: float,
           max_states: int, expects: str) -> None:
    """In a child: say when the domain imported, then send its row."""
    try:
        hddl.import_hddl(dom, prob).problem()
        conn.send(("imported", None))
        row = hddl_report.check_domain(name, dom, prob, timeout=timeout, max_states=max_states,
                                expects=expects)
    except Exception as e:  # noqa: BLE001 - a crash is a finding, reported like the others
        row = hddl_report.Row(name, "unmapped",
                              f"crash: {type(e).__name__}: {hddl_report.report_reason(e)}")
    conn.send(("row", row))


def run_all(todo: list[tuple[str, Path, Path]], timeout: float, max_states: int, jobs: int,
            expects: str = "nothing", grace: float = 180.0) -> Iterator[hddl_report.Row]:
    """Each domain in a child process of its own, ``jobs`` at a time, in order. A child
    still running ``grace`` seconds after its time limit (validating a policy takes as
    long as solving it, and is not limited) is killed, and its row says so."""
    ctx = multiprocessing.get_context("fork")
    pending = list(todo)
    running: list[tuple[str, Any, Connection, float, list[bool]]] = []
    done: dict[str, hddl_report.Row] = {}
    order = [n for n, _, _ in todo]
    nxt = 0
    while pending or running:
        while pending and len(running) < jobs:
            name, dom, prob = pending.pop(0)
            parent, child = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_child, args=(child, name, dom, prob, timeout,
                                                    max_states, expects))
            proc.start()
            child.close()
            running.append((name, proc, parent, time.monotonic(), [False]))
        time.sleep(0.05)
        for item in list(running):
            name, proc, conn, start, imported = item
            row = None
            while conn.poll():
                try:
                    kind, value = conn.recv()
                except EOFError:
                    break
                if kind == "imported":
                    imported[0] = True
                else:
                    row = value
            late = time.monotonic() - start > timeout + grace
            if row is None and (late or not proc.is_alive()):
                if proc.is_alive():
                    proc.kill()
                proc.join()
                row = hddl_report.Row(name, "mapped" if imported[0] else "unmapped",
                               f"still grounding or solving {time.monotonic() - start:.0f} s "
                               f"after starting (time limit {timeout:g} s): stopped"
                               if late else f"the child process died (exit {proc.exitcode})",
                               seconds=time.monotonic() - start)
            if row is not None:
                proc.join()
                running.remove(item)
                done[name] = row
        while nxt < len(order) and order[nxt] in done:
            yield done[order[nxt]]
            nxt += 1


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--timeout", type=float, default=60.0, metavar="S",
                    help="seconds to ground and solve one domain (default 60)")
    ap.add_argument("--max-states", type=int, default=1_000_000, metavar="N",
                    help="distinct states per domain (default 1,000,000)")
    ap.add_argument("--jobs", type=int, default=2, metavar="N", help="processes (default 2)")
    ap.add_argument("--only", action="append", metavar="PATTERN",
                    help="domains whose name matches (fnmatch, repeatable)")
    ap.add_argument("--json", metavar="FILE", help="also write the rows as JSON")
    ap.add_argument("--expects", choices=("nothing", "plan"), default="nothing",
                    help="what the human expects of the robot (the sidecar's [other] "
                         "expects): nothing, the robot alone (default); plan, a human who "
                         "knows the robot's model and follows its possible methods")
    args = ap.parse_args(argv)
    shipped = hddl_report.domains_shipped()
    if not shipped:
        print("unified-planning is not installed (pip install 'ehatp[hddl]'): only the "
              "domains of tests/data/hddl are run", file=sys.stderr)
    todo = [(f"ipc/{n}", d, p) for n, d, p in shipped] + own_domains()
    if args.only:
        todo = [t for t in todo if any(fnmatch.fnmatch(t[0], f"*{pat}*") for pat in args.only)]
    rows: list[hddl_report.Row] = []
    for row in run_all(todo, args.timeout, args.max_states, args.jobs, args.expects):
        rows.append(row)
        cost = f"cost {row.cost}, " if row.cost is not None else ""
        print(f"{row.name:44s} {row.stage:9s} {row.seconds:6.1f} s  {cost}"
              f"{row.states} states{'  ' + row.reason if row.reason else ''}", flush=True)
    for group in ("ipc/", "own/"):
        part = [r for r in rows if r.name.startswith(group)]
        if not part:
            continue
        mapped = sum(r.mapped for r in part)
        solved = sum(r.stage in ("solved", "validated") for r in part)
        valid = sum(r.stage == "validated" for r in part)
        print(f"{group[:-1]}: {len(part)} domains, {mapped} map, {solved} solve within "
              f"{args.timeout:g} s, {valid} validate")
    if args.json:
        Path(args.json).write_text(json.dumps([dataclasses.asdict(r) for r in rows],
                                              indent=1, default=str), encoding="utf-8")
    return 0 if all(r.stage != "solved" for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
