"""Property tests on random problems (``ehatp.experiments.randomgen``, seeds drawn by hypothesis):
the planner never crashes, every policy it returns passes the independent validator, executes to
the goal on every branch through the Executor and never branches on a choice the robot cannot
see, the result does not depend on declaration order, and solving twice gives byte-identical
JSON."""

from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ehatp
from ehatp.experiments import agreement, randomgen
from ehatp.formats.policy import Policy
from ehatp.run.walk import walk_policy

SETTINGS = settings(max_examples=120, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])
LIMITS = {"max_states": agreement.MAX_STATES, "timeout": 10}


@pytest.mark.slow  # 120 random problems
@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_policies_pass_the_validator_execute_and_do_not_depend_on_declaration_order(
        seed: int) -> None:
    p = randomgen.problem(seed)
    r = ehatp.solve(p, **LIMITS)  # type: ignore[arg-type]
    assert r.status in ("solved", "unsolvable"), r.reason
    if r.status == "unsolvable":
        assert r.reason.startswith("no policy exists")
        return
    assert r.policy is not None
    report = ehatp.validate(p, r.policy)
    assert report.ok, report.message
    read = Policy.from_dict(json.loads(r.policy.to_json()))  # as its file reads
    assert agreement.hidden_choices(read) == []
    walk = walk_policy(p, read, cap=agreement.WALK_CAP)
    assert walk.ok, walk.message
    assert walk.branches >= 1
    again = ehatp.solve(randomgen.problem(seed, reverse=True), **LIMITS)  # type: ignore[arg-type]
    assert again.policy is not None
    assert again.policy.to_json() == r.policy.to_json()
    assert ehatp.solve(p).policy.to_json() == r.policy.to_json()  # type: ignore[union-attr]
