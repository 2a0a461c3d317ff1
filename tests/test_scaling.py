"""The scaling benchmark (``ehatp bench scaling``, ``benchmarks/scaling.py``): its grid, the
waypoint options that make longer trips, and a run of the smallest grid points. Nothing here
measures speed."""

from __future__ import annotations

import builtins
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import ehatp
from ehatp.cli.app import app
from ehatp.domains import cooking, cubes
from ehatp.experiments import bench
from ehatp.experiments.classes import count
from ehatp.formats.problem_toml import loads

ROOT = Path(__file__).resolve().parents[1]
runner = CliRunner()
SMALL = ["cubes-c3-b2-transparent-k2", "cubes-c3-b2-opaque-k2", "cooking-k2"]


def test_grid_names_are_unique_and_smallest_first() -> None:
    grid = bench.scaling_grid()
    names = [p.name for p in grid]
    assert len(names) == len(set(names))
    assert [p.size for p in grid] == sorted(p.size for p in grid)
    cube = [p for p in grid if p.family == "cubes" and p.reach == "fetched" and p.cubes <= 10]
    assert {p.cubes for p in cube} == set(range(3, 11))
    assert {p.boxes for p in cube} == {2, 3} and {p.K for p in cube} == {2, 4, 6, 8}
    assert {p.transparent for p in cube} == {True, False}
    assert {p.K for p in grid if p.family == "cooking"} == {2, 4, 6, 8}
    assert {"cubes-c12-b2-opaque-k2", "cubes-c10-b2-opaque-k2-any"} <= set(names)


def test_selection() -> None:
    assert all(p.size <= 3 for p in bench.select_points(3))
    assert [p.name for p in bench.select_points(3, ["cubes-c12-b2-*"])] == [
        "cubes-c12-b2-opaque-k2", "cubes-c12-b2-opaque-k4", "cubes-c12-b2-opaque-k8"]
    assert bench.select_points(None, ["nothing-like-this"]) == []


def test_the_large_points_are_opt_in() -> None:
    big = bench.select_points(5, big=True)
    names = [p.name for p in big]
    assert len(names) == len(set(names)) == 45
    assert {p.cubes for p in big} == {12, 16, 20, 24, 30}
    assert {p.boxes for p in big} == {2, 3, 4} and {p.K for p in big} == {2, 4, 8}
    # the targets are among them
    assert {"cubes-c20-b2-opaque-k2", "cubes-c30-b2-opaque-k2", "cubes-c20-b3-opaque-k4",
            "cubes-c16-b3-opaque-k8"} <= set(names)
    # never in the default grid, nor reached by --max-size; named, they run
    assert not set(names) & {p.name for p in bench.select_points(None)} - {
        "cubes-c12-b2-opaque-k2"}
    assert [p.name for p in bench.select_points(3, ["cubes-c30-b4-opaque-k8"])] == [
        "cubes-c30-b4-opaque-k8"]
    assert len({p.name for p in bench.scaling_grid(big=True)}) == len(
        bench.scaling_grid()) + 44


def test_the_largest_point_is_a_problem(tmp_path: Path) -> None:
    p = next(x for x in bench.big_points() if x.name == "cubes-c30-b4-opaque-k8")
    f = tmp_path / "big.toml"
    f.write_text(p.toml(), encoding="utf-8")
    prob = ehatp.load(f)
    assert prob.K == 8 and len(prob.objects["cube"]) == 30 and len(prob.objects["box"]) == 4


def test_phase_shares_add_up_by_phase() -> None:
    phases = {"before grounding": 0.01, "grounding": 0.09, "search": 0.5,
              "search (first worst-case pass)": 0.1, "values (worst case)": 0.05,
              "values (choices)": 0.05, "extraction": 0.15, "writing": 0.05}
    shares = bench.phase_shares(phases)
    assert shares is not None and list(shares) == list(bench.PHASES)
    assert shares["grounding"] == pytest.approx(0.1) and shares["search"] == pytest.approx(0.6)
    assert shares["values"] == pytest.approx(0.1) and sum(shares.values()) == pytest.approx(1)
    assert bench.format_shares(shares) == "10/60/10/15/5"
    # a phase of a name the benchmark does not know is shown after the five, not lost
    other = bench.phase_shares({"search": 1.0, "lifting": 1.0})
    assert other is not None and bench.format_shares(other) == "0/50/0/0/0 +lifting 50"
    assert bench.phase_shares(None) is None and bench.format_shares(None) == "-"
    assert bench.phase_group("expansion") == "extraction"


@pytest.mark.parametrize("name", ["cubes-c3-b2-opaque-k6", "cubes-c3-b2-transparent-k8",
                                  "cooking-k6", "cooking-k8"])
def test_long_trips_solve_and_validate(tmp_path: Path, name: str) -> None:
    p = next(x for x in bench.scaling_grid() if x.name == name)
    f = tmp_path / f"{name}.toml"
    f.write_text(p.toml(), encoding="utf-8")
    prob = ehatp.load(f)
    r = ehatp.solve(prob)
    assert r.status == "solved" and r.optimal and r.policy is not None
    assert ehatp.validate(prob, r.policy).ok


def test_waypoints_make_the_trip_longer(tmp_path: Path) -> None:
    from ehatp.epistemic.semantics import Semantics
    from ehatp.model.grounding import ground_problem

    # K=6 cubes: no turning, two places on the way; the human leaves for the first of them
    p = next(x for x in bench.scaling_grid() if x.name == "cubes-c3-b2-opaque-k6")
    f = tmp_path / "k6.toml"
    f.write_text(p.toml(), encoding="utf-8")
    sem = Semantics(ground_problem(ehatp.load(f)))
    labels = [m.label for m in sem.moves(sem.initial())]
    assert "move(mt, way1)" in labels and "move(mt, ot)" not in labels
    assert cubes.make_domain(waypoints=2).name == "cubes-way2"
    assert cooking.make_domain(waypoints=1).name == "cooking-way1"
    assert cubes.make_domain().name == "cubes"  # the default is unchanged


@pytest.mark.parametrize("bad", [-1, 1.5, True, "2"])
def test_bad_waypoints(bad: object) -> None:
    with pytest.raises(ValueError, match="waypoints"):
        cubes.make_domain(waypoints=bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="waypoints"):
        cooking.make_domain(waypoints=bad)  # type: ignore[arg-type]


def test_bench_scaling_runs_the_smallest_points(tmp_path: Path) -> None:
    out = tmp_path / "s.json"
    args = ["bench", "scaling", "--timeout", "60", "--json", str(out)]
    for name in SMALL:
        args += ["--only", name]
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.output
    rows = json.loads(out.read_text(encoding="utf-8"))
    assert [x["instance"] for x in rows] == [p.name for p in bench.select_points(None, SMALL)]
    for x in rows:
        assert x["status"] == "solved" and x["optimal"], x
        assert x["generated"] >= x["distinct"] > 0 and x["max_worlds"] >= 1
        assert x["peak_mb"] > 0 and x["time_s"] > 0 and x["states_per_s"] > 0
        assert x["policy_nodes"] > 0 and x["policy_bytes"] > 0
        assert x["cpu_s"] > 0  # the whole process's, start-up included
        # every count the solver reports, and the time of each phase of the solve
        assert x["stats"]["distinct"] == x["distinct"] and x["stats"]["atoms"] > 0
        assert {"grounding", "search", "extraction", "writing"} <= set(x["phases_s"])
        assert list(x["phase_shares"]) == list(bench.PHASES)
        assert sum(x["phase_shares"].values()) == pytest.approx(1)
        assert x["last_phase"] == "extraction"
    for name in SMALL:
        assert name in r.stdout
    assert "CPU s" in r.stdout and "phases % g/s/v/e/w" in r.stdout


def test_bench_scaling_without_symmetry_counts_every_renaming() -> None:
    name = "cubes-c3-b2-opaque-k2"
    counts = {}
    for flag in ([], ["--no-symmetry"]):
        r = runner.invoke(app, ["bench", "scaling", "--only", name, *flag, "--json", "-"])
        assert r.exit_code == 0, r.output
        (row,) = json.loads(r.stdout)
        assert row["status"] == "solved" and row["symmetry"] == (False if flag else None)
        counts[bool(flag)] = (row["distinct"], row["cost"])
    (distinct, cost), (distinct_all, cost_all) = counts[False], counts[True]
    assert distinct_all > distinct and cost_all == cost


def test_bench_scaling_stops_an_instance_at_its_timeout(tmp_path: Path) -> None:
    # without the symmetry reduction (docs/semantics.md §3) this search still has over
    # 180,000 states open after 5 s; with it, a fast core proves it optimal within 0.1 s
    r = runner.invoke(app, ["bench", "scaling", "--only", "cubes-c9-b3-opaque-k4",
                            "--no-symmetry", "--timeout", "0.1", "--json", "-"])
    assert r.exit_code == 0, r.output
    (row,) = json.loads(r.stdout)
    assert row["status"] == "timeout" and "time limit" in row["error"]
    assert row["last_phase"] is not None  # the phase the limit stopped


def test_bench_scaling_counts_the_worlds_as_classes_only_when_asked() -> None:
    # issue 17 §5: "|W| classes". The count is experiments.classes's (tested by hand in
    # test_classes.py), at the node with the most worlds of the same search the row timed;
    # cooking has no interchangeable objects, so nothing to count
    names = ["cubes-c8-b3-opaque-k8", "cooking-k2"]
    args = ["bench", "scaling", *[a for n in names for a in ("--only", n)]]
    r = runner.invoke(app, [*args, "--classes", "--json", "-"])
    assert r.exit_code == 0, r.output
    rows = {row["instance"]: row for row in json.loads(r.stdout)}
    cube = rows["cubes-c8-b3-opaque-k8"]
    point = bench.select_points(None, ["cubes-c8-b3-opaque-k8"])[0]
    (node,) = count(loads(point.toml(), "p.toml"), top=1).nodes
    assert cube["classes"] == {"worlds": node.worlds, "classes": node.classes,
                               "cells": list(node.cells)}
    assert cube["classes"]["worlds"] == cube["max_worlds"] > cube["classes"]["classes"] > 1
    assert rows["cooking-k2"]["classes"] is None
    table = runner.invoke(app, [*args, "--classes"]).stdout.splitlines()
    header = next(line for line in table if line.startswith("instance"))
    assert header.split().index("classes") == header.split().index("|W|") + 2
    line = next(line for line in table if line.startswith("cubes-c8-b3"))
    assert f"{node.classes:,} of {node.worlds:,} [" in line
    plain = runner.invoke(app, args)
    assert plain.exit_code == 0 and "classes" not in plain.stdout
    assert "classes" not in json.loads(runner.invoke(app, [*args, "--json", "-"]).stdout)[0]


def test_bench_scaling_unknown_instance_is_one_line() -> None:
    r = runner.invoke(app, ["bench", "scaling", "--only", "P9"])
    assert r.exit_code == 2 and "no grid instance" in r.stderr


def test_plot_is_skipped_without_matplotlib(monkeypatch: pytest.MonkeyPatch,
                                            tmp_path: Path) -> None:
    real = builtins.__import__

    def no_matplotlib(name: str, *args: Any, **kwargs: Any) -> Any:
        if name.startswith("matplotlib"):
            raise ImportError(name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    assert not bench.plot_scaling({"x": []}, str(tmp_path / "p.png"))
    assert not (tmp_path / "p.png").exists()


def test_plot_writes_an_image(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    rows = [{"instance": "a", "status": "solved", "distinct": 100, "time_s": 0.1,
             "peak_mb": 30.0}, {"instance": "b", "status": "solved", "distinct": 1000,
                                "time_s": 1.0, "peak_mb": 60.0}]
    f = tmp_path / "p.png"
    assert bench.plot_scaling({"before": rows, "after": rows}, str(f))
    assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_scaling_script_prints_the_table(tmp_path: Path) -> None:
    r = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "scaling.py"), "--only",
                        "cooking-k2", "--json", str(tmp_path / "s.json")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "cooking-k2" in r.stdout and "states/s" in r.stdout


# -- the search does less work, with the same results (docs/semantics.md §7, "Search") --------


@pytest.mark.parametrize("name", ["cubes/p1.toml", "cubes/p4.toml", "cubes/p6.toml",
                                  "cooking/cooking2.toml", "communication/late-fatal.toml",
                                  "sally-anne/inform.toml"])
def test_live_worst_case_values_are_knuths_after_every_expansion(
        monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    assert _check_live_values(monkeypatch, ehatp.load(ROOT / "examples" / name)) > 0


@pytest.mark.slow  # random problems, each searched with the live values checked
def test_live_values_on_random_problems(monkeypatch: pytest.MonkeyPatch) -> None:
    from ehatp.experiments import randomgen

    # every option varies on these (speech openings with their zero-cost silence included)
    checked = [_check_live_values(monkeypatch, randomgen.problem(seed), max_states=3000)
               for seed in range(100)]
    assert sum(1 for c in checked if c) >= 25


def _check_live_values(monkeypatch: pytest.MonkeyPatch, problem: ehatp.Problem,
                       max_states: int = 20_000) -> int:
    """Solve ``problem``, checking the kept-up-to-date values against a full pass after every
    expansion once the root is solved (every tenth after the first 300); how many expansions
    were checked."""
    from ehatp.search import values

    real = values.LiveWorst.expanded
    checked = 0

    seen = 0

    def expanded(self: values.LiveWorst, n: int) -> None:
        nonlocal checked, seen
        real(self, n)
        seen += 1
        if seen <= 300 or not seen % 10:
            full, _ = values.knuth(self.gr)
            assert self.value == full, n
            checked += 1

    monkeypatch.setattr(values.LiveWorst, "expanded", expanded)
    # without the symmetry reduction (docs/semantics.md §3), which leaves p4 too few states to
    # expand once its root is solved
    # the search by f keeps these values; the focused search keeps bounds (test_bounds.py)
    r = ehatp.solve(problem, max_states=max_states, symmetry=False, focus=False)
    assert r.status in ("solved", "unsolvable", "state-limit")
    if r.status == "solved" and problem.objective.kind == ehatp.ObjectiveKind.WORST_CASE:
        assert r.optimal
    return checked
