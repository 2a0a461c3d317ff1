"""``relevance = "plan"`` never solves fewer problems than ``"next"`` (docs/semantics.md §5):
where no informing set within the size bound fixes the rest of the human's plan, the sets that
fix its next step remain robot options. Checked on the random generator's problems
(``ehatp.experiments.randomgen``), each solved with relevance forced one way, then the other."""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ehatp.experiments import agreement, randomgen
from ehatp.model.options import Relevance
from ehatp.model.problem import Problem
from ehatp.search.planner import LIMITS, Result, solve

# seed 452: with informing sets of one atom, "plan" left it unsolved before issue 15 (the first
# such seed in 1,500, with this version of the generator)
FOUND = (452,)
SEEDS = (*range(150), *FOUND)


def _solve(p: Problem, relevance: Relevance, max_atoms: int | None = None) -> Result:
    c = replace(p.communication, relevance=relevance)
    if max_atoms is not None:
        c = replace(c, inform_max_atoms=max_atoms)
    return solve(replace(p, communication=c), max_states=agreement.MAX_STATES,
                 timeout=agreement.TIMEOUT)


def _plan_solves_what_next_solves(seed: int, max_atoms: int | None) -> bool | None:
    """None when the problem is not solved with "next" (or a limit stopped either search),
    else whether "plan" solves it too."""
    p = randomgen.problem(seed)
    nxt = _solve(p, Relevance.NEXT, max_atoms)
    if nxt.status != "solved":
        return None
    plan = _solve(p, Relevance.PLAN, max_atoms)
    if plan.status in LIMITS:
        return None
    return plan.status == "solved"


@pytest.mark.slow  # random problems, each solved twice
@pytest.mark.parametrize("max_atoms", [None, 1], ids=["informing sets as drawn",
                                                      "informing sets of one atom"])
def test_relevance_plan_solves_every_random_problem_that_relevance_next_solves(
        max_atoms: int | None) -> None:
    compared, fewer = 0, []
    for seed in SEEDS:
        same = _plan_solves_what_next_solves(seed, max_atoms)
        if same is None:
            continue
        compared += 1
        if not same:
            fewer.append(seed)
    assert not fewer, f"relevance plan leaves unsolved what next solves: seeds {fewer}"
    assert compared >= len(SEEDS) // 3, compared


@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_relevance_plan_never_solves_a_random_problem_that_relevance_next_solves_not(
        seed: int) -> None:
    assert _plan_solves_what_next_solves(seed, None) is not False
