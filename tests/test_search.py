"""Search limits, timelines and the policy file."""

from __future__ import annotations

import json
from pathlib import Path

import ehatp
from ehatp import Policy

from .conftest import EXAMPLES_DIR, big_problem, example

CUBES = EXAMPLES_DIR / "cubes"


def test_state_limit_stops_cleanly_with_partial_statistics() -> None:
    r = ehatp.solve(ehatp.load(CUBES / "p6.toml"), max_states=50)
    assert r.status == "state-limit" and r.policy is None and not r.optimal
    assert r.stats["distinct"] == 50 and r.stats["expanded"] > 0
    assert "state limit" in r.reason


def test_time_limit_stops_cleanly(tmp_path: Path) -> None:
    r = ehatp.solve(ehatp.load(big_problem(tmp_path)), timeout=0.0)
    assert r.status == "timeout" and "time limit" in r.reason
    assert r.stats["distinct"] >= 1 and "expanded" in r.stats


def test_a_problem_stopped_by_the_depth_limit_reports_the_limit_not_no_policy() -> None:
    # §6 (revised): P2's policies need 13 moves; cut at 4 nothing is proven unsolvable
    r = ehatp.solve(ehatp.load(CUBES / "p2.toml"), max_depth=4)
    assert r.status == "depth-limit" and r.policy is None
    assert "depth limit" in r.reason and "no policy exists" not in r.reason
    assert ehatp.solve(ehatp.load(CUBES / "p2.toml"), max_depth=13).status == "solved"


def test_timelines_put_parallel_lanes_between_separation_and_reunion() -> None:
    r = ehatp.solve(ehatp.load(CUBES / "p2.toml"))
    assert r.policy is not None
    tl = r.policy.timelines()
    assert len(tl) == r.policy.leaves
    first = tl[0]["steps"]
    assert first[0] == {"agent": "H", "action": "move(mt, ot)"}
    assert first[1] == {"parallel": {"R": ["pick(r)", "wait"],
                                     "H": ["pick(w)", "move(ot, mt)"]}}
    assert all("agent" in s for s in first[2:])


def test_policy_json_round_trips_and_is_versioned(tmp_path: Path) -> None:
    r = ehatp.solve(ehatp.load(CUBES / "qualitative.toml"))
    assert r.policy is not None
    f = tmp_path / "p.json"
    r.policy.write(f)
    data = json.loads(f.read_text())
    assert data["format"] == "ehatp-policy" and data["version"] == 2
    assert Policy.read(f).to_json() == f.read_text()
    node = data["nodes"][0]
    assert node["worlds"] == 2 and node["divergence"] == [
        "not empty(box1)", "empty(box2)", "in(r, box1)", "not in(r, box2)"]
    def canon(x: object) -> str:
        return json.dumps(x, sort_keys=True)

    assert sorted(map(canon, node["world_diffs"])) == sorted(map(canon, [
        {"true": [], "false": []},
        {"true": ["empty(box1)", "in(r, box2)"], "false": ["empty(box2)", "in(r, box1)"]}]))


def test_statistics_are_reported() -> None:
    r = ehatp.solve(ehatp.load(CUBES / "p4.toml"))
    for key in ("generated", "distinct", "expanded", "max_worlds", "time_ms", "cost",
                "communications", "leaves"):
        assert key in r.stats
    assert r.stats["max_worlds"] == example("cubes/p4").worlds == 7
    assert r.stats["generated"] >= r.stats["distinct"]
