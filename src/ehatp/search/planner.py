"""``solve``: ground a problem, search it, and return the policy with its statistics."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..model.grounding import ground_problem
from ..model.problem import Problem
from ..policy_format import Policy
from .andor import Progress, search
from .diagnose import diagnose
from .policy import explain_failure, extract


@dataclass
class Result:
    status: str  # "solved" | "unsolvable" | "timeout" | "state-limit"
    policy: Policy | None
    stats: dict[str, Any] = field(default_factory=dict)
    reason: str = ""
    optimal: bool = False

    @property
    def solved(self) -> bool:
        return self.policy is not None


def solve(problem: Problem, *, timeout: float | None = None, max_states: int | None = None,
          max_depth: int | None = None, progress: Progress | None = None) -> Result:
    """Plan a robot policy for ``problem``, optimal under ``problem.objective``
    (docs/semantics.md §7: worst-case by default, or expected cost).

    Limits default to the problem's ``[limits]``. When a limit stops the search the result
    carries partial statistics, and the best policy found so far if there is one
    (``optimal`` False).
    """
    grounded = ground_problem(problem)
    out = search(grounded, timeout=timeout, max_states=max_states, max_depth=max_depth,
                 progress=progress)
    stats: dict[str, Any] = out.stats.as_dict()
    stats["atoms"] = len(grounded.atoms)
    policy = None
    if out.values is not None and out.values.value[out.root] != float("inf"):
        public = {k: v for k, v in stats.items() if k != "time_ms"}
        policy = extract(out.graph, out.root, out.values, problem_name=problem.name,
                         optimal=out.optimal, stats=public)
        stats.update(cost=policy.cost, communications=policy.communications,
                     leaves=policy.leaves, worst_case=policy.worst_case,
                     expected=policy.expected)
    reason = ""
    if out.status == "unsolvable":
        # name the goal literals or agendas that fail everywhere; a line of play that dies
        # is only the fallback (it is one of many, and may look arbitrary)
        graph, root = out.graph, out.root
        reason = "no policy exists: " + diagnose(grounded, graph,
                                                 lambda: explain_failure(graph, root))
    elif out.status == "timeout":
        reason = f"time limit reached after {out.stats.time_s:.1f} s"
    elif out.status == "state-limit":
        reason = f"state limit reached ({out.stats.distinct} distinct states)"
    elif not out.optimal:  # §7: expected cost on a solvable graph with cycles
        reason = ("not proven optimal: the solvable graph has cycles, so choices inside them "
                  "were restricted to those of the worst-case pass")
    return Result(out.status, policy, stats, reason, out.optimal)
