"""The HDDL report (``benchmarks/hddl_report.py``, docs/hddl.md): how far each HDDL domain gets
-- imported, solved, validated -- as the robot's HTN beside a human with an empty agenda."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..check.validator import validate
from ..errors import DomainError, HddlMissing, HddlUnsupported
from ..formats.hddl import import_hddl
from ..formats.hddl_sidecar import Sidecar
from ..search.planner import solve


def report_reason(e: BaseException) -> str:
    """One line for a report: what stopped a domain."""
    text = " ".join(str(e).split())
    return text if len(text) <= 160 else text[:159] + "…"


@dataclass
class Row:
    """One domain of the report: how far it got (``stage``: "unmapped", "mapped" -- not
    solved within the limits --, "solved" -- but the validator rejects the policy -- or
    "validated") and why it stopped there (one line), with what was measured."""

    name: str
    stage: str
    reason: str = ""
    status: str = ""  # the planner's
    cost: object = None
    states: int = 0
    seconds: float = 0.0

    @property
    def mapped(self) -> bool:
        return self.stage != "unmapped"


def check_domain(name: str, domain_file: str | Path, problem_file: str | Path, *,
                 timeout: float = 60.0, max_states: int = 1_000_000,
                 expects: str = "nothing") -> Row:
    """Import, solve and validate one HDDL domain and problem as the robot's HTN, the human
    with an empty agenda, everything observable, always together: the report's row.
    ``expects`` (the sidecar's ``[other] expects``): "nothing", the robot alone (the human
    sees its actions and follows no plan of it), or "plan", a human who knows the robot's
    model and follows which methods it may be using (every world it entertains, §4)."""
    t0 = time.perf_counter()

    def row(stage: str, reason: str = "", **kw: Any) -> Row:
        return Row(name, stage, reason, seconds=time.perf_counter() - t0, **kw)

    try:
        problem = import_hddl(domain_file, problem_file,
                              sidecar=Sidecar(expects=expects)).problem()
    except (HddlUnsupported, HddlMissing) as e:
        return row("unmapped", report_reason(e))
    except DomainError as e:
        return row("unmapped", f"ehatp refuses the domain: {report_reason(e)}")
    try:
        r = solve(problem, timeout=timeout, max_states=max_states)
    except DomainError as e:
        return row("unmapped", report_reason(e))
    if r.policy is None:
        return row("mapped", report_reason(Exception(r.reason or r.status)), status=r.status,
                   states=int(r.stats.get("distinct", 0)))
    v = validate(problem, r.policy)
    return row("validated" if v.ok else "solved", "" if v.ok else report_reason(
        Exception(v.message)), status=r.status, cost=r.policy.cost,
        states=int(r.stats.get("distinct", 0)))


def domains_shipped() -> list[tuple[str, Path, Path]]:
    """The HDDL domains unified-planning ships with its tests (the IPC 2020 HTN track's, one
    problem each): (name, domain file, problem file), sorted by name; [] without it."""
    try:
        import unified_planning
    except ImportError:
        return []
    root = Path(unified_planning.__file__).parent / "test" / "hddl"
    out = []
    for d in sorted(root.glob("*")):
        dom = d / "domain.hddl"
        probs = sorted(p for p in d.glob("*.hddl") if p.name != "domain.hddl")
        if dom.is_file() and probs:
            out.append((d.name, dom, probs[0]))
    return out


__all__ = ["Row", "check_domain", "domains_shipped", "report_reason"]
