"""A problem, a result and a policy print as one short line a notebook user can read
(issue 18: they were 1.3 kB and 14 kB dumps)."""

from __future__ import annotations

import ehatp

from .conftest import ROOT, solved

P2 = ROOT / "examples/cubes/p2.toml"


def test_a_problem_prints_its_name_domain_size_and_file() -> None:
    assert repr(ehatp.load(P2)) == ("Problem('P2', domain='cubes', objects=4, K=2, "
                                    f"source={str(P2)!r})")


def test_a_result_prints_its_status_and_policy_in_one_short_line() -> None:
    r = solved(P2).result
    text = repr(r)
    assert len(text) < 200 and "\n" not in text
    assert text.startswith("Result(status='solved', optimal=True, policy=Policy('P2', "
                           "domain='cubes', version=3, nodes=")
    assert "leaves=6, cost=13)" in text and "distinct=60" in text


def test_a_stopped_result_prints_why() -> None:
    r = ehatp.solve(ehatp.load(P2), max_states=3)
    assert repr(r).startswith("Result(status='state-limit', optimal=False, policy=None")
    assert "reason='state limit reached" in repr(r)
