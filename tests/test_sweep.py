"""``ehatp sweep``: rows equal separate solves, the grid, resume, isolation, executors, plot.

No timing assertions: times are recorded, never compared. The 512-variant grid is
``benchmarks/sweep_grid.py``.
"""

from __future__ import annotations

import csv
import gzip
import importlib.util
import json
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import ehatp
from ehatp.cli.app import app
from ehatp.experiments import pools, sweep
from ehatp.experiments.examples import examples_dir
from ehatp.formats.policy import Policy, num
from ehatp.formats.problem_toml import load

CUBES = examples_dir() / "cubes"
runner = CliRunner()
TIMES = ("time_s", "search_ms")

GRID = """\
problem.K = [2, 3]
communication.inform = ["copresent", "anywhere"]
"""

# more cubes than any example: solving it takes about 0.12 GB of address space (175,000
# states), so --memory 0.04 stops it part-way, long before --timeout would; the examples
# beside it need a few MB
BIG = """\
[problem]
name = "9cubes"
K = 8

[domain]
name = "cubes"
turn_before_move = true
human_reach = "fetched"

[objects]
cube = ["r", "y", "g", "b", "p", "q", "w", "v", "o"]
box = ["box1", "box2"]

[init]
true = [
  "at(R, mt)", "facing(R, mt)", "at(H, mt)", "facing(H, mt)",
  "handempty(R)", "handempty(H)", "empty(box1)", "empty(box2)",
  "on(r, mt)", "on(y, mt)", "on(g, mt)", "on(b, mt)", "on(p, mt)", "on(q, mt)",
  "origin(r, mt)", "origin(y, mt)", "origin(g, mt)", "origin(b, mt)", "origin(p, mt)",
  "origin(q, mt)",
  "on(w, ot)", "on(v, ot)", "on(o, ot)", "origin(w, ot)", "origin(v, ot)", "origin(o, ot)",
]

[agenda]
robot = ["organize"]
human = ["organize"]

[limits]
symmetry = false  # with it (docs/semantics.md §3) a few thousand states suffice
"""  # about 350 MB at its peak: more than the heap earlier tests may leave free in-process


def invoke(*args: str | Path) -> tuple[int, str, str]:
    r = runner.invoke(app, ["sweep", *map(str, args)])
    return r.exit_code, r.stdout, r.stderr


def rows_of(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]


def content(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Rows by key without their times (the only part that may differ between runs)."""
    return {r["key"]: {k: v for k, v in r.items() if k not in TIMES} for r in rows}


@pytest.fixture
def problems(tmp_path: Path) -> Path:
    """Three small cube problems in a folder of their own."""
    d = tmp_path / "problems"
    d.mkdir()
    for name in ("p1.toml", "p2.toml", "qualitative.toml"):
        (d / name).write_text((CUBES / name).read_text(encoding="utf-8"), encoding="utf-8")
    return d


@pytest.fixture
def grid(tmp_path: Path) -> Path:
    g = tmp_path / "grid.toml"
    g.write_text(GRID, encoding="utf-8")
    return g


@pytest.fixture
def local_rows(problems: Path, grid: Path, tmp_path: Path) -> list[dict[str, Any]]:
    out = tmp_path / "local.jsonl"
    code, _, err = invoke(problems / "*.toml", "--grid", grid, "--out", out, "--workers", "2")
    assert code == 0, err
    return rows_of(out)


# --- the grid and the overrides hook ---------------------------------------------------------


def test_the_pools_are_still_importable_from_the_sweep_module() -> None:
    """CHANGELOG.md names ``Pool``, ``sigterm_as_interrupt`` and the pools in
    ``ehatp.experiments.sweep``; they live in ``ehatp.experiments.pools`` now and the old
    names are the same objects."""
    for name in ("DaskPool", "ExecutorFailed", "ExecutorKind", "LocalPool", "Pool", "RayPool",
                 "WorkerLost", "default_workers", "open_pool", "run_tasks",
                 "sigterm_as_interrupt"):
        assert getattr(sweep, name) is getattr(pools, name), name
        assert name in sweep.__all__


def test_grid_is_a_cartesian_product(tmp_path: Path) -> None:
    g = tmp_path / "g.toml"
    g.write_text('problem.K = [2, 3, 4]\n[communication]\ninform = ["copresent", "anywhere"]\n'
                 "[domain]\nturn_before_move = [false, true]\n", encoding="utf-8")
    grid = sweep.read_grid(g)
    assert grid == {"problem.K": [2, 3, 4], "communication.inform": ["copresent", "anywhere"],
                    "domain.turn_before_move": [False, True]}
    combos = sweep.combinations(grid)
    assert len(combos) == 12 and len({json.dumps(c, sort_keys=True) for c in combos}) == 12
    assert combos[0] == {"problem.K": 2, "communication.inform": "copresent",
                         "domain.turn_before_move": False}
    assert sweep.combinations(None) == [{}]


def test_overrides_load_as_if_written_in_the_file(tmp_path: Path) -> None:
    text = (CUBES / "p2.toml").read_text(encoding="utf-8")
    edited = tmp_path / "p2.toml"
    edited.write_text(text.replace("K = 2", "K = 3").replace(
        "turn_before_move = false", "turn_before_move = true"), encoding="utf-8")
    over = load(CUBES / "p2.toml", {"problem.K": 3, "domain.turn_before_move": True,
                                    "costs.inform": 5})
    by_hand = load(edited)
    assert (over.K, over.costs.inform) == (3, 5)
    assert ehatp.solve(over).stats["distinct"] == ehatp.solve(by_hand).stats["distinct"]
    with pytest.raises(ehatp.InputError, match="K must be a whole number"):
        load(CUBES / "p2.toml", {"problem.K": -1})
    with pytest.raises(ehatp.InputError, match="problem.K is not a table"):
        load(CUBES / "p2.toml", {"problem.K.x": 1})


def test_key_follows_what_decides_the_result(tmp_path: Path) -> None:
    text = (CUBES / "p1.toml").read_text(encoding="utf-8")
    p = CUBES / "p1.toml"
    k = sweep.instance_key(text, p, {"problem.K": 2, "costs.inform": 1})
    assert k == sweep.instance_key(text, tmp_path / "elsewhere.toml",
                                   {"costs.inform": 1, "problem.K": 2})  # order, place: same
    assert k != sweep.instance_key(text, p, {"problem.K": 3, "costs.inform": 1})
    assert k != sweep.instance_key(text + "\n# edited\n", p, {"problem.K": 2, "costs.inform": 1})
    # a domain file beside the problem is part of it
    (tmp_path / "dom.py").write_text("# v1\n", encoding="utf-8")
    with_file = 'goal = []\n[domain]\nname = "dom.py:make"\n'
    k1 = sweep.instance_key(with_file, tmp_path / "x.toml", {})
    (tmp_path / "dom.py").write_text("# v2\n", encoding="utf-8")
    assert sweep.instance_key(with_file, tmp_path / "x.toml", {}) != k1


# --- rows ------------------------------------------------------------------------------------


def test_rows_equal_separate_solves(local_rows: list[dict[str, Any]], problems: Path) -> None:
    assert len(local_rows) == 3 * 4
    for r in local_rows:
        assert list(r)[:len(sweep.ROW_KEYS)] == list(sweep.ROW_KEYS)
        prob = load(problems / Path(r["instance"]).name, r["overrides"])
        res = ehatp.solve(prob)
        pol = res.policy
        assert pol is not None and r["status"] == res.status == "solved"
        assert r["problem"] == prob.name and r["optimal"] == res.optimal
        assert (r["cost"], r["worst_case"], r["expected"], r["communications"], r["leaves"]) \
            == (num(pol.cost), num(pol.worst_case or 0), num(pol.expected or 0),
                pol.communications, pol.leaves)
        same = {k: v for k, v in res.stats.items()
                if k not in ("time_ms", "cost", "worst_case", "expected", "communications",
                             "leaves")}
        assert r["stats"] == same
        assert r["error"] is None and r["valid"] is None  # not asked to validate
        assert r["version"] == ehatp.__version__
    # each row records its overrides; the grid's four combinations per file
    assert {json.dumps(r["overrides"], sort_keys=True) for r in local_rows} == {
        json.dumps({"problem.K": k, "communication.inform": i}, sort_keys=True)
        for k in (2, 3) for i in ("copresent", "anywhere")}


def test_policies_validation_and_csv(problems: Path, tmp_path: Path) -> None:
    out, pols, table = tmp_path / "r.jsonl", tmp_path / "pols", tmp_path / "r.csv"
    code, stdout, err = invoke(problems / "p*.toml", "--validate", "--policies", pols,
                               "--out", out, "--csv", table)
    assert code == 0, err
    rows = rows_of(out)
    assert len(rows) == 2 and all(r["valid"] is True for r in rows)
    for r in rows:
        f = Path(r["policy"])
        assert f.parent == pols.resolve() and f.name == f"{r['key']}.json"
        pol = Policy.load(f)
        assert num(pol.cost) == r["cost"]
        assert ehatp.validate(load(problems / Path(r["instance"]).name), pol).ok
    with table.open(encoding="utf-8") as fh:
        lines = list(csv.DictReader(fh))
    # the CSV follows the files' order (the JSON lines, the order they finished in)
    assert [line["key"] for line in lines] == [r["key"] for r in
                                               sorted(rows, key=lambda r: r["instance"])]
    assert {"instance", "status", "cost", "stats.distinct", "stats.max_worlds"} <= set(lines[0])
    assert "2 rows (2 new)" in stdout and "2 solved" in stdout


def test_compressed_policies_hold_the_same_json_and_compress_needs_a_folder(
        problems: Path, tmp_path: Path) -> None:
    plain, packed = tmp_path / "plain", tmp_path / "packed"
    assert invoke(problems / "p*.toml", "--policies", plain, "--out", tmp_path / "a.jsonl")[0] == 0
    code, _, err = invoke(problems / "p*.toml", "--policies", packed, "--compress",
                          "--out", tmp_path / "b.jsonl")
    assert code == 0, err
    rows = rows_of(tmp_path / "b.jsonl")
    assert len(rows) == 2
    for r in rows:
        f = Path(r["policy"])
        assert f.name == f"{r['key']}.json.gz"
        assert gzip.decompress(f.read_bytes()) == (plain / f"{r['key']}.json").read_bytes()
        pol = Policy.load(f)
        assert ehatp.validate(load(problems / Path(r["instance"]).name), pol).ok
    code, _, err = invoke(problems / "p*.toml", "--compress", "--out", tmp_path / "c.jsonl")
    assert code == 2 and "--compress goes with --policies" in err


def test_resume_runs_only_missing_rows(problems: Path, grid: Path, tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    assert invoke(problems / "*.toml", "--grid", grid, "--out", out)[0] == 0
    full = rows_of(out)
    lines = out.read_text(encoding="utf-8").splitlines(keepends=True)
    # a run stopped mid-way: 7 whole rows and half of the 8th
    out.write_text("".join(lines[:7]) + lines[7][:40], encoding="utf-8")
    code, stdout, err = invoke(problems / "*.toml", "--grid", grid, "--out", out, "--resume")
    assert code == 0, err
    resumed = rows_of(out)
    assert len(resumed) == 12  # 7 kept + 5 solved now: the cut line was run again
    assert "12 rows (5 new)" in stdout and "7 of 12 instances already" in err
    assert content(resumed) == content(full)
    # nothing left to do: no new line
    code, stdout, _ = invoke(problems / "*.toml", "--grid", grid, "--out", out, "--resume")
    assert code == 0 and len(rows_of(out)) == 12 and "(0 new)" in stdout
    # without --resume an existing results file is not overwritten
    code, _, err = invoke(problems / "*.toml", "--out", out)
    assert code == 2 and "add --resume" in err and len(rows_of(out)) == 12


@pytest.mark.slow
def test_a_memory_hungry_instance_is_an_error_row(problems: Path, tmp_path: Path) -> None:
    (problems / "big.toml").write_text(BIG, encoding="utf-8")
    out = tmp_path / "r.jsonl"
    code, stdout, _ = invoke(problems / "*.toml", "--memory", "0.04", "--timeout", "120",
                             "--out", out, "--workers", "2")
    assert code == 1  # an error row
    rows = {Path(r["instance"]).name: r for r in rows_of(out)}
    assert set(rows) == {"big.toml", "p1.toml", "p2.toml", "qualitative.toml"}
    big = rows.pop("big.toml")
    assert (big["status"], big["error_kind"]) == ("error", "memory"), big
    assert "--memory budget of 0.04 GB" in big["error"] and big["problem"] == "9cubes"
    assert all(r["status"] == "solved" for r in rows.values())
    assert "error: " in stdout and "big.toml" in stdout


RUNAWAY = """\
import ehatp
from ehatp.domains.cubes import make_domain


@ehatp.domain_factory
def make(hang: bool = False, **options):
    while hang:  # outside solve, so no time limit of its own stops it
        pass
    return make_domain(**options)
"""


@pytest.mark.slow
def test_a_runaway_worker_is_ended_and_reported(problems: Path, tmp_path: Path) -> None:
    (problems / "runaway.py").write_text(RUNAWAY, encoding="utf-8")
    text = (problems / "p1.toml").read_text(encoding="utf-8")
    (problems / "runaway.toml").write_text(text.replace(
        'name = "cubes"', 'name = "runaway.py:make"\nhang = true'), encoding="utf-8")
    marks = tmp_path / "marks"
    marks.mkdir()
    tasks = sweep.make_tasks(sweep.find_problems([str(problems / "*.toml")]), None,
                             sweep.Settings(timeout=1, kill_after=2, marks=marks))
    rows: list[dict[str, Any]] = []
    pool = pools.LocalPool(2)
    try:
        pools.run_tasks(tasks, pool, rows.append)
    finally:
        pool.close()
    by_name = {Path(r["instance"]).name: r for r in rows}
    assert len(rows) == 4 and set(by_name) == {"p1.toml", "p2.toml", "qualitative.toml",
                                               "runaway.toml"}
    stuck = by_name.pop("runaway.toml")
    assert (stuck["status"], stuck["error_kind"]) == ("error", "killed"), stuck
    assert stuck["error"] == ("still running 2 s after it started (--timeout 1 s): its worker "
                              "process was ended")
    assert all(r["status"] == "solved" for r in by_name.values())


def test_an_instance_with_a_bad_file_is_an_error_row(problems: Path, tmp_path: Path) -> None:
    (problems / "broken.toml").write_text("[problem]\nK = 'x'\n", encoding="utf-8")
    out = tmp_path / "r.jsonl"
    code, stdout, _ = invoke(problems / "*.toml", "--out", out)
    assert code == 1
    rows = {Path(r["instance"]).name: r for r in rows_of(out)}
    assert rows["broken.toml"]["error_kind"] == "input"
    assert "broken.toml" in rows["broken.toml"]["error"]
    assert sum(r["status"] == "solved" for r in rows.values()) == 3


# --- bad input: one line, exit 2 -------------------------------------------------------------


@pytest.mark.parametrize(("grid_text", "says"), [
    ("problem.K = [2, -1]", "problem.K = -1 is refused: K must be a whole number"),
    ("problem.KK = [1]", "unknown key 'KK'"),
    ("problem.K = 3", "must be a list of the values to try"),
    ("problem.K = []", "lists no value"),
    ("nonsense.K = [1]", "'nonsense' is not a table of a problem file"),
    ("domain.bogus = [1]", "bad domain options"),
    ('communication.inform = ["nowhere"]', "unknown value 'nowhere'"),
    ("problem.K = [", "not valid TOML"),
])
def test_bad_grid_is_one_line(problems: Path, tmp_path: Path, grid_text: str,
                              says: str) -> None:
    g = tmp_path / "g.toml"
    g.write_text(grid_text + "\n", encoding="utf-8")
    out = tmp_path / "r.jsonl"
    code, stdout, err = invoke(problems / "*.toml", "--grid", g, "--out", out)
    assert code == 2 and stdout == ""
    assert err.count("\n") == 1 and err.startswith(f"error: {g}") and says in err, err
    assert not out.exists()


@pytest.mark.parametrize(("args", "says"), [
    (["nothing/*.toml"], "nothing/*.toml: no file matches"),
    (["P", "--address", "tcp://127.0.0.1:1"], "the local executor takes no address"),
    (["P", "--executor", "spark"], "'spark' is not one of"),
    (["P", "--x", "K"], "--x goes with --plot"),
    ([], "give problem files or patterns"),
    (["P", "--plot", "r.jsonl", "--x", "K"], "not both"),
    (["--plot", "r.jsonl"], "--plot needs --x"),
])
def test_bad_command_line_is_one_line(problems: Path, args: list[str], says: str) -> None:
    argv = [str(problems / "p1.toml") if a == "P" else a for a in args]
    code, stdout, err = invoke(*argv)
    assert code == 2 and stdout == "" and err.count("\n") == 1 and says in err, err


def _hide(monkeypatch: pytest.MonkeyPatch, *names: str) -> None:
    """Make ``import NAME`` fail as if NAME were not installed."""
    for name in names:
        monkeypatch.setitem(sys.modules, name, None)


def test_missing_extras_say_what_to_install(problems: Path, tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch,
                                            local_rows: list[dict[str, Any]]) -> None:
    _hide(monkeypatch, "distributed", "ray", "matplotlib", "matplotlib.figure")
    for kind, extra in (("dask", "ehatp[dask]"), ("ray", "ehatp[ray]")):
        code, _, err = invoke(problems / "p1.toml", "--executor", kind, "--out",
                              tmp_path / f"{kind}.jsonl")
        assert code == 2 and err.count("\n") == 1 and f"pip install '{extra}'" in err, err
    results = tmp_path / "rows.jsonl"
    results.write_text("".join(json.dumps(r) + "\n" for r in local_rows), encoding="utf-8")
    code, _, err = invoke("--plot", results, "--x", "K")
    assert code == 2 and err.count("\n") == 1 and "pip install 'ehatp[plot]'" in err, err


# --- the plot --------------------------------------------------------------------------------


def test_plot(local_rows: list[dict[str, Any]], tmp_path: Path) -> None:
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (ehatp[plot])")
    results = tmp_path / "rows.jsonl"
    results.write_text("".join(json.dumps(r) + "\n" for r in local_rows), encoding="utf-8")
    code, stdout, err = invoke("--plot", results, "--x", "K")  # short for problem.K
    assert code == 0, err
    png = results.with_suffix(".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "6 lines, 12 instances" in stdout  # 3 files x 2 inform values, 2 K each
    code, _, err = invoke("--plot", results, "--x", "inform", "--out", tmp_path / "i.svg")
    assert code == 0 and (tmp_path / "i.svg").exists(), err
    code, _, err = invoke("--plot", results, "--x", "nothing")
    assert code == 2 and "use one of: problem.K, communication.inform" in err


def plot_rows(series: int) -> list[dict[str, Any]]:
    """Rows of a sweep over problem.K = 2, 3, 4 and ``series`` values of domain.v: few
    states, few worlds, all whole numbers close together (where matplotlib would put ticks
    at 2.25, 5.5, ...)."""
    return [{"key": f"{k}-{v}", "instance": "p.toml", "overrides": {"problem.K": k,
             "domain.v": v}, "status": "solved", "time_s": 0.01 * k,
             "stats": {"distinct": 5 + k % 2 + v % 2, "max_worlds": 1 + k % 2}}
            for k in (2, 3, 4) for v in range(series)]


def ticks(axis: Any) -> list[float]:
    low, high = sorted(axis.get_view_interval())
    return [t for t in axis.get_ticklocs() if low <= t <= high]


@pytest.mark.parametrize(("series", "outside"), [(3, False), (24, True)])
def test_plot_names_every_line_and_counts_in_whole_numbers(series: int, outside: bool) -> None:
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (ehatp[plot])")
    fig, n_lines, n_points = sweep.figure(plot_rows(series), "K")
    assert (n_lines, n_points) == (series, 3 * series)
    fig.draw_without_rendering()
    time_ax, states_ax, worlds_ax = fig.axes
    legend = fig.legends[0] if outside else time_ax.get_legend()
    assert legend is not None and len(fig.legends) == int(outside)
    assert [t.get_text() for t in legend.get_texts()] == [f"v={v}" for v in range(series)]
    for ax in (time_ax, states_ax, worlds_ax):
        assert ticks(ax.xaxis) and all(t == int(t) for t in ticks(ax.xaxis))  # K
    for ax in (states_ax, worlds_ax):
        assert ticks(ax.yaxis) and all(t == int(t) for t in ticks(ax.yaxis))
    assert any(t != int(t) for t in ticks(time_ax.yaxis))  # seconds are not counted
    if outside:  # ten colours, then the same colours dashed
        styles = {(line.get_color(), line.get_linestyle()) for line in time_ax.get_lines()}
        assert len(styles) == series


# --- other executors -------------------------------------------------------------------------


@pytest.fixture
def dask_cluster() -> Iterator[Any]:
    distributed = pytest.importorskip("distributed",
                                      reason="dask.distributed is not installed (ehatp[dask])")
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                       dashboard_address=None)
    try:
        yield cluster
    finally:
        cluster.close()


@pytest.mark.slow
def test_dask_watches_the_memory_budget(dask_cluster: Any, problems: Path,
                                        tmp_path: Path) -> None:
    # the workers are threads of this process: a kernel limit would hit the scheduler and
    # pytest too, so the budget is watched and only the hungry instance's thread stops
    (problems / "big.toml").write_text(BIG, encoding="utf-8")
    out = tmp_path / "dask.jsonl"
    code, _, _ = invoke(problems / "*.toml", "--executor", "dask", "--memory", "0.04",
                        "--timeout", "120", "--address", dask_cluster.scheduler_address,
                        "--out", out)
    assert code == 1
    rows = {Path(r["instance"]).name: r for r in rows_of(out)}
    assert (rows["big.toml"]["status"], rows["big.toml"]["error_kind"]) == ("error", "memory")
    assert [r["status"] for n, r in sorted(rows.items()) if n != "big.toml"] == ["solved"] * 3


@pytest.mark.slow
def test_dask_gives_the_same_rows(dask_cluster: Any, problems: Path, grid: Path,
                                  tmp_path: Path, local_rows: list[dict[str, Any]]) -> None:
    out = tmp_path / "dask.jsonl"
    code, _, err = invoke(problems / "*.toml", "--grid", grid, "--executor", "dask",
                          "--address", dask_cluster.scheduler_address, "--out", out)
    assert code == 0, err
    assert content(rows_of(out)) == content(local_rows)


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("ray") is None,
                    reason="ray is not installed (ehatp[ray])")
def test_ray_gives_the_same_rows(problems: Path, grid: Path, tmp_path: Path,
                                 local_rows: list[dict[str, Any]]) -> None:
    out = tmp_path / "ray.jsonl"
    code, _, err = invoke(problems / "*.toml", "--grid", grid, "--executor", "ray",
                          "--workers", "2", "--out", out)
    assert code == 0, err
    assert content(rows_of(out)) == content(local_rows)
