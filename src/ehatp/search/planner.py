"""``solve``: ground a problem, search it, and return the policy with its statistics."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from ..model.grounding import ground_problem
from ..model.options import Intentions
from ..model.problem import Problem
from ..policy_format import Policy
from . import symmetry as _symmetry
from .andor import Progress, Stats, search
from .diagnose import diagnose
from .limits import Budget, LimitReached
from .policy import explain_failure, extract, realise


@dataclass
class Result:
    # "solved" | "unsolvable" | "timeout" | "state-limit" | "memory-limit" | "depth-limit"
    status: str
    policy: Policy | None
    stats: dict[str, Any] = field(default_factory=dict)
    reason: str = ""
    optimal: bool = False

    @property
    def solved(self) -> bool:
        return self.policy is not None


LIMITS = ("timeout", "state-limit", "memory-limit", "depth-limit")


def solve(problem: Problem, *, timeout: float | None = None, max_states: int | None = None,
          max_depth: int | None = None, progress: Progress | None = None,
          max_memory: int | None = None, budget: Budget | None = None,
          symmetry: bool | None = None) -> Result:
    """Plan a robot policy for ``problem``, optimal under ``problem.objective``
    (docs/semantics.md §7: worst-case by default, or expected cost).

    Limits default to the problem's ``[limits]``; ``timeout`` (seconds) and ``max_memory``
    (bytes of resident memory) bound the whole call — grounding, search, values and
    extraction — or pass a ``budget`` (:class:`~ehatp.search.limits.Budget`) shared with the
    caller's own work, such as writing the policy. When a limit stops the work the result
    carries partial statistics, and the best policy found so far if there is one (``optimal``
    False); ``reason`` says which limit. ``progress(stats, frontier)`` is called about 20 times
    a second, ``stats.phase`` naming the work under way.

    ``symmetry`` (default: ``[limits] symmetry``) searches over canonical states, the policy
    mapped back to the real objects (docs/semantics.md §3, "Symmetry"); when the reduction
    cannot be trusted for this problem (a decision taken by name or index order, or a move
    that does not map back) the problem is solved again without it.
    """
    limits = problem.limits
    if budget is None:
        budget = Budget(limits.timeout if timeout is None else timeout,
                        limits.max_memory if max_memory is None else max_memory)
    live = Stats()
    if progress is not None and budget.on_poll is None:
        def poll(b: Budget) -> None:
            live.time_s, live.phase = b.elapsed(), b.phase
            progress(live, live.frontier)
        budget.on_poll = poll
    budget.phase = "grounding"
    try:
        grounded = ground_problem(problem, check=budget.check)
    except LimitReached as e:
        return Result(e.status, None, {**live.as_dict(), "time_ms": round(budget.elapsed()
                                                                          * 1000, 1)},
                      e.reason)
    except MemoryError:
        oom = budget.out_of_memory()
        return Result(oom.status, None, live.as_dict(), oom.reason)
    if symmetry is None:
        symmetry = (problem.limits.symmetry if _symmetry.OVERRIDE is None
                    else _symmetry.OVERRIDE)
    out = search(grounded, max_states=max_states, max_depth=max_depth, budget=budget,
                 stats=live, symmetry=symmetry)
    if out.status == "symmetry-unsafe":
        _restart(live)
        out = search(grounded, max_states=max_states, max_depth=max_depth, budget=budget,
                     stats=live)
    stats: dict[str, Any] = out.stats.as_dict()
    stats["atoms"] = len(grounded.atoms)
    status, reason, optimal = out.status, out.reason, out.optimal
    policy = None
    if out.values is not None and out.values.value[out.root] != float("inf"):
        public = {k: v for k, v in stats.items() if k != "time_ms"}
        budget.phase = "extraction"
        try:
            budget.check()
            graph, root, values = out.graph, out.root, out.values
            if graph.sym is not None:
                real = realise(graph, root, values, check=budget.check)
                if isinstance(real, str):  # not expected: solve without symmetry
                    _restart(live)
                    return solve(problem, max_states=max_states, max_depth=max_depth,
                                 budget=budget, symmetry=False)
                graph, root, values = real
            policy = extract(graph, root, values, problem_name=problem.name,
                             optimal=optimal, stats=public, check=budget.check)
            budget.check()
        except LimitReached as e:
            status, reason, optimal, policy = e.status, e.reason, False, None
        except MemoryError:
            oom = budget.out_of_memory()
            status, reason, optimal, policy = oom.status, oom.reason, False, None
        if policy is not None:
            stats.update(cost=policy.cost, communications=policy.communications,
                         leaves=policy.leaves, worst_case=policy.worst_case,
                         expected=policy.expected)
    if status == "unsolvable":
        # name the goal literals or agendas that fail everywhere; a line of play that dies
        # is only the fallback (it is one of many, and may look arbitrary)
        graph, root = out.graph, out.root
        hidden = ""
        if any(len(es.human_agendas) > 1 for es in graph.states):
            hidden = _hidden_choice(problem, budget, max_states, max_depth)
        reason = "no policy exists: " + hidden + diagnose(grounded, graph,
                                                          lambda: explain_failure(graph, root))
    elif status == "solved" and not optimal:  # §7: expected cost on a graph with cycles
        reason = ("not proven optimal: the solvable graph has cycles, so choices inside them "
                  "were restricted to those of the worst-case pass")
    budget.phase = "done"
    return Result(status, policy, stats, reason, optimal)


def _hidden_choice(problem: Problem, budget: Budget, max_states: int | None,
                   max_depth: int | None) -> str:
    """docs/semantics.md §3-§4: when a robot that saw the human's method choices would have
    a policy, the choice it cannot see is the reason there is none: return it in words
    (the first human move of that policy whose label had to name the intention), else ""."""
    seen = replace(problem, human=replace(problem.human, intentions=Intentions.VISIBLE))
    try:
        other = solve(seen, max_states=max_states, max_depth=max_depth, budget=budget)
    except LimitReached:
        return ""
    if other.policy is None:
        return ""
    for node in other.policy.nodes:
        told = [m.action for m in node.moves if m.action.endswith("]") and " [" in m.action]
        if told:
            act = told[0].partition(" [")[0]
            means = " or ".join(t.partition(" [")[2][:-1] for t in told
                                if t.partition(" [")[0] == act)
            h = problem.domain.human_name
            return (f"the robot cannot see which method {h} chose when it does {act} (for "
                    f"{means}); with [human] intentions = \"visible\", or a question "
                    f"([communication] robot_asks = true), a policy exists (worst case "
                    f"{other.policy.worst_case}); ")
    return ""


def _restart(live: Stats) -> None:
    """Statistics start again for a search without symmetry."""
    fresh = Stats()
    for k in ("generated", "distinct", "expanded", "max_worlds", "frontier"):
        setattr(live, k, getattr(fresh, k))
