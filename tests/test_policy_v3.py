"""Policy format version 3, the lifted policy (docs/policy-format.md, "Version 3"): over
canonical states the planner writes the canonical nodes and each move's renaming; the summary
figures are those of the policy over the real objects; the executor realises a branch lazily;
``--expand`` and ``ehatp expand`` write the version 2 graph; a finished search is never thrown
away."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

import ehatp
from ehatp import HIDDEN, Domain, HumanModel, Var
from ehatp.cli.app import app
from ehatp.errors import InputError
from ehatp.experiments.bench import GridPoint
from ehatp.formats.lifted import Renamings, expand
from ehatp.formats.policy import Policy
from ehatp.formats.problem_toml import loads
from ehatp.model.formula import exists
from ehatp.model.grounding import ground_problem
from ehatp.model.options import Passes
from ehatp.model.problem import Problem
from ehatp.run.executor import Executor
from ehatp.run.expand import expand_policy
from ehatp.run.walk import walk_policy
from ehatp.search import planner
from ehatp.search.interchangeable import detect
from ehatp.search.limits import LimitReached, SolveStatus
from ehatp.search.planner import solve

from .conftest import DATA, EXAMPLES, IPC_LIFTED, ROOT, Example
from .scenarios import problem as scenario

P4 = ROOT / "examples" / "cubes" / "p4.toml"


def grid(cubes: int, boxes: int, K: int) -> Problem:
    """A cube-grid instance as ``ehatp bench scaling`` builds it."""
    return loads(GridPoint("cubes", K, cubes, boxes).toml(), "grid.toml")


def figures(policy: Policy) -> tuple[object, ...]:
    return (policy.cost, policy.worst_case, policy.expected, policy.leaves,
            policy.communications, policy.optimal)


def both(p: Problem) -> tuple[Policy, Policy]:
    """The policy ``solve`` returns and the one it returns expanded (version 2)."""
    lifted, real = solve(p).policy, solve(p, expand=True).policy
    assert lifted is not None and real is not None
    return lifted, real


def invoke(*args: object) -> object:
    return CliRunner().invoke(app, [str(a) for a in args])


# -- what is written ----------------------------------------------------------------------------

@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_example_gives_the_same_cost_communications_and_leaves_in_v3_and_v2(
        example: Example) -> None:
    p = ehatp.load(example.path)
    lifted, real = both(p)
    assert real.version == 2 and real.symmetry is None
    assert figures(lifted) == figures(real)
    sym = detect(ground_problem(p))
    if sym is None:  # no interchangeable objects: version 2, exactly as without symmetry
        assert lifted.version == 2 and lifted.to_json() == real.to_json()
    else:
        assert lifted.version == 3 and lifted.symmetry is not None
        assert lifted.symmetry["objects"] == sym.objects
        assert len(lifted.nodes) <= len(real.nodes)


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_both_versions_walk_to_the_goal_on_every_branch(example: Example) -> None:
    p = ehatp.load(example.path)
    lifted, real = both(p)
    for policy in (lifted, real):
        report = walk_policy(p, policy)
        assert report.ok and report.branches == policy.leaves, report


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_a_v3_file_loads_back_identically_and_re_solving_gives_the_same_bytes(
        example: Example, tmp_path: Path) -> None:
    p = ehatp.load(example.path)
    first = solve(p).policy
    assert first is not None
    first.write(tmp_path / "p.json")
    back = Policy.load(tmp_path / "p.json")
    assert back == first and back.to_json() == first.to_json()
    again = solve(p).policy
    assert again is not None and again.to_json() == first.to_json()


def test_symmetry_off_writes_version_2() -> None:
    policy = solve(ehatp.load(P4), symmetry=False).policy
    assert policy is not None and policy.version == 2 and '"renaming"' not in policy.to_json()


def test_the_table_holds_integer_permutations_the_identity_first() -> None:
    policy = solve(ehatp.load(P4)).policy
    assert policy is not None and policy.symmetry is not None
    table = policy.symmetry
    n = len(table["objects"])
    assert table["renamings"][0] == list(range(n))
    assert all(sorted(r) == list(range(n)) for r in table["renamings"])
    used = {m.renaming for _, m in policy.edges()} | {table["root"]}
    assert used == set(range(len(table["renamings"])))  # the table lists what is used
    assert any(m.renaming for _, m in policy.edges())
    text = policy.to_json()
    assert '"renaming": 0' not in text  # the identity is not written on a move


@pytest.mark.parametrize(("cubes", "boxes", "K"), [
    (4, 2, 2), (5, 2, 4), (4, 3, 2), (6, 2, 2), (8, 2, 2),
    pytest.param(12, 2, 2, marks=pytest.mark.slow), pytest.param(6, 3, 4, marks=pytest.mark.slow),
])
def test_the_summary_figures_of_the_lifted_graph_are_those_of_the_real_one(
        cubes: int, boxes: int, K: int) -> None:
    p = grid(cubes, boxes, K)
    lifted, real = both(p)
    assert lifted.version == 3
    assert figures(lifted) == figures(real)
    assert lifted.tree_size() == real.tree_size()
    assert len(lifted.nodes) < len(real.nodes)


@pytest.mark.parametrize(("cubes", "boxes", "K"), [(4, 2, 2), (5, 2, 4), (4, 3, 2), (6, 2, 2)])
def test_on_the_cube_grid_the_lifted_policy_walks_and_validates(cubes: int, boxes: int,
                                                                K: int) -> None:
    p = grid(cubes, boxes, K)
    lifted, real = both(p)
    report = walk_policy(p, lifted)
    assert report.ok and report.branches == lifted.leaves, report
    assert ehatp.validate(p, lifted).ok
    assert ehatp.validate(p, real).ok


def test_the_12_cube_file_is_far_smaller_lifted(capsys: pytest.CaptureFixture[str]) -> None:
    p = grid(12, 2, 2)
    lifted, real = both(p)
    small, big = len(lifted.to_json()), len(real.to_json())
    with capsys.disabled():
        print(f"\n12 cubes / 2 boxes / K=2: version 3 {small:,} bytes, {len(lifted.nodes):,} "
              f"nodes; version 2 {big:,} bytes, {len(real.nodes):,} nodes")
    assert small * 8 < big
    assert figures(lifted) == figures(real)


# -- expanding ----------------------------------------------------------------------------------

@pytest.mark.parametrize("p", [pytest.param(ehatp.load(P4), id="p4"),
                               pytest.param(grid(5, 2, 4), id="grid-5-2-4"),
                               pytest.param(grid(4, 3, 2), id="grid-4-3-2")])
def test_expanding_a_lifted_policy_gives_the_planners_own_version_2(p: Problem) -> None:
    lifted, real = both(p)
    assert expand_policy(p, lifted).to_json() == real.to_json()
    assert expand_policy(p, real) is real  # version 2 is left alone


def test_expanding_by_text_alone_keeps_the_counts() -> None:
    p = grid(4, 3, 2)
    lifted, real = both(p)
    g = ground_problem(p)
    text = expand(lifted, g.atom_index, g.task_index)
    assert text.version == 2 and figures(text) == figures(real)
    assert expand(real) is real


def test_ehatp_expand_writes_what_solve_expand_writes(tmp_path: Path) -> None:
    lifted, real, out = tmp_path / "l.json", tmp_path / "r.json", tmp_path / "e.json"
    assert invoke("solve", P4, "--out", lifted).exit_code == 0  # type: ignore[attr-defined]
    assert invoke("solve", P4, "--out", real, "--expand").exit_code == 0  # type: ignore[attr-defined]
    assert json.loads(lifted.read_text())["version"] == 3
    assert json.loads(real.read_text())["version"] == 2
    r = invoke("expand", lifted, "--problem", P4, "--out", out)
    assert r.exit_code == 0, r.output  # type: ignore[attr-defined]
    assert out.read_bytes() == real.read_bytes()


def test_show_render_simulate_and_export_read_a_v3_file(tmp_path: Path) -> None:
    f = tmp_path / "p.json"
    assert invoke("solve", P4, "--out", f).exit_code == 0  # type: ignore[attr-defined]
    for args in (("show", f), ("show", f, "--problem", P4), ("render", f),
                 ("render", f, "--format", "html"), ("export", "bt", f, "--problem", P4),
                 ("validate", P4, f), ("simulate", P4, "--policy", f)):
        r = invoke(*args)
        assert r.exit_code == 0, (args, r.output)  # type: ignore[attr-defined]


# -- the executor realises lazily ---------------------------------------------------------------

def test_the_executor_follows_a_lifted_policy_without_expanding_it(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from ehatp.formats import lifted as lifted_module
    from ehatp.run import expand as expand_module

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("expanded")

    monkeypatch.setattr(lifted_module, "expand", refuse)
    monkeypatch.setattr(expand_module, "expand_policy", refuse)
    p = grid(5, 2, 4)
    policy = solve(p).policy
    assert policy is not None and policy.version == 3
    report = walk_policy(p, policy)
    assert report.ok and report.branches == policy.leaves


def test_the_executor_shows_the_real_objects() -> None:
    p = grid(4, 2, 2)
    lifted, real = both(p)
    a, b = Executor(p, lifted), Executor(p, real)
    while not b.done:  # the first branch, side by side
        assert a.node is not None and b.node is not None
        assert a.node.state == b.node.state
        assert [m.action for m in a.node.moves] == [m.action for m in b.node.moves]
        action = b.next_robot_action()
        if action is not None:
            assert a.robot_action_done(action.label).action == b.robot_action_done().action
        else:
            label = b.expected_human_actions()[-1].label
            a.observe_human_action(label)
            b.observe_human_action(label)
        assert a.state == b.state
    assert a.done and a.goal_reached


def test_renamings_compose_as_the_format_says() -> None:
    table = {"objects": ["a", "b", "c"], "classes": [["a", "b", "c"]],
             "renamings": [[0, 1, 2], [1, 0, 2], [0, 2, 1]], "root": 1}
    ren = Renamings(table)
    assert ren.root == (1, 0, 2)  # the inverse of the swap is the swap
    tau = ren.child(ren.root, 2)  # tau . inverse(renamings[2])
    assert tau == tuple(ren.root[j] for j in (0, 2, 1))
    assert tau == (1, 2, 0)  # a -> b, b -> c, c -> a
    assert ren.text(tau, "on(a, c) + place(b, box)") == "on(b, a) + place(c, box)"


# -- reading ------------------------------------------------------------------------------------

def test_versions_1_and_2_still_load() -> None:
    assert Policy.load(DATA / "p4-v1.json").version == 2
    policy = solve(ehatp.load(P4), expand=True).policy
    assert policy is not None
    assert Policy.from_dict(json.loads(policy.to_json())).version == 2


@pytest.mark.parametrize(("edit", "needle"), [
    (lambda d: d["symmetry"]["renamings"].append([0, 0, 1, 2]), "is not a permutation"),
    (lambda d: d["symmetry"].update(root=99), "symmetry.root 99"),
    (lambda d: d["nodes"][0]["moves"][0].update(renaming=99), "renaming"),
    (lambda d: d.pop("symmetry"), "missing field 'symmetry'"),
])
def test_a_broken_symmetry_table_is_one_line(tmp_path: Path, edit: object,
                                             needle: str) -> None:
    policy = solve(ehatp.load(P4)).policy
    assert policy is not None
    d = json.loads(policy.to_json())
    edit(d)  # type: ignore[operator]
    f = tmp_path / "bad.json"
    f.write_text(json.dumps(d))
    with pytest.raises(InputError, match=needle.replace("(", r"\(").replace("[", r"\[")):
        Policy.load(f)


# -- never throw away a finished search ---------------------------------------------------------

def test_a_limit_in_expansion_after_a_finished_search_returns_the_lifted_policy(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def stop(*args: object, **kwargs: object) -> None:
        raise LimitReached(SolveStatus.TIMEOUT, "time limit of 1 s reached, during expansion")

    monkeypatch.setattr(planner, "realise", stop)
    r = solve(grid(5, 2, 4), expand=True)
    assert r.status == SolveStatus.SOLVED and r.optimal
    assert r.policy is not None and r.policy.version == 3 and r.policy.optimal
    assert "during expansion" in r.reason and "lifted policy" in r.reason


def test_a_limit_in_writing_an_expansion_writes_the_lifted_policy(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from ehatp.cli.solve import _write
    from ehatp.search.limits import Budget

    r = solve(grid(5, 2, 4), expand=True)
    assert r.policy is not None and r.policy.version == 2 and r.lifted is not None
    budget = Budget()

    def out_of_time() -> None:
        raise LimitReached(SolveStatus.TIMEOUT, "time limit of 1 s reached, during writing")

    monkeypatch.setattr(budget, "check", out_of_time)
    out, written = _write(r, tmp_path / "p.json", budget)
    assert written and out.status == SolveStatus.SOLVED and out.optimal
    assert "after the search had finished" in out.reason
    assert Policy.load(tmp_path / "p.json").version == 3


def test_the_schema_accepts_every_examples_v3_policy_and_wants_its_table() -> None:
    jsonschema = pytest.importorskip("jsonschema")
    schema_file = ROOT / "src" / "ehatp" / "formats" / "policy.schema.json"
    schema = json.loads(schema_file.read_text(encoding="utf-8"))
    check = jsonschema.Draft202012Validator(schema)
    lifted = 0
    for example in EXAMPLES:
        policy = solve(ehatp.load(example.path)).policy
        assert policy is not None
        data = json.loads(policy.to_json())
        errors = [f"{list(e.absolute_path)}: {e.message}" for e in check.iter_errors(data)]
        assert errors == [], (example.name, errors[:3])
        if data["version"] == 3:
            lifted += 1
            bad = dict(data)
            del bad["symmetry"]
            assert list(check.iter_errors(bad))
    assert lifted


def spare_parts() -> Problem:
    """Three spare parts, all available; the human takes one (any), then fetches one, which
    needs an available part it has not taken, but believes none is available. The robot tells
    it one: the two parts left tie on everything but names (§5)."""
    d = Domain("spare-parts")
    item = d.type("item")
    i = Var("i", item)
    avail = d.predicate("avail", i, observability=HIDDEN)
    taken = d.predicate("taken", i)
    fetched = d.predicate("fetched")
    h = d.human
    take = h.action("take", i, pre=~taken(i), effects=[taken(i)])
    one = h.task("take_one")
    h.method(one, "any", params=[i], pre=~taken(i), subtasks=[take(i)])
    fetch = h.action("fetch", pre=exists(i, avail(i) & ~taken(i)), effects=[fetched()])
    get = h.task("get", done=fetched())
    h.method(get, "fetch", subtasks=[fetch()])
    parts = ["avail(a)", "avail(b)", "avail(c)"]
    return scenario(d, init=parts, human=["take_one", "get"],
                    objects={"item": ["a", "b", "c"]},
                    human_model=HumanModel(passes=Passes.IDLE), beliefs=[([], parts)])


def test_an_inform_chosen_by_name_at_a_renamed_node_is_written_over_the_real_objects(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # §3, §5: after take(a) the node stands for a renamed state, where the real rules choose
    # among the parts left by their real names; only the mapping back follows them
    p = spare_parts()
    policy = solve(p).policy
    assert policy is not None and policy.version == 2 and ehatp.validate(p, policy).ok
    assert policy.to_json() == solve(p, expand=True).policy.to_json()  # type: ignore[union-attr]
    monkeypatch.setattr(planner, "liftable", lambda *args: True)
    forced = solve(p).policy
    assert forced is not None and forced.version == 3
    assert not ehatp.validate(p, forced).ok  # what the check keeps from being written


# the imported IPC-2020 domains with interchangeable objects (conftest.IPC_LIFTED): their
# policies are written lifted (the others as version 2; docs/hddl.md, "Lifted policies"), and
# this is the test that walks them (tests/test_every_policy_runs.py walks the others)


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*deprecated - use:DeprecationWarning")
@pytest.mark.parametrize("name", IPC_LIFTED)
def test_an_imported_ipc_domain_gives_the_same_figures_lifted_and_expanded_and_both_validate(
        name: str) -> None:
    pytest.importorskip("unified_planning", reason="ehatp[hddl] (unified-planning) not installed")
    from ehatp.experiments import hddl_report
    from ehatp.formats import hddl

    shipped = {n: (d, p) for n, d, p in hddl_report.domains_shipped()}
    d, pf = shipped[name]
    p = hddl.import_hddl(d, pf, sidecar=hddl.Sidecar(expects="nothing")).problem()
    lifted, real = solve(p, timeout=120), solve(p, timeout=120, expand=True)
    assert lifted.policy is not None and real.policy is not None
    assert json.loads(lifted.policy.to_json())["version"] == 3
    assert json.loads(real.policy.to_json())["version"] == 2
    figures = ("cost", "communications", "leaves", "worst_case", "expected")
    assert ([getattr(lifted.policy, f) for f in figures]
            == [getattr(real.policy, f) for f in figures])
    assert ehatp.validate(p, lifted.policy).ok and ehatp.validate(p, real.policy).ok
    report = walk_policy(p, lifted.policy)
    assert report.ok and report.branches == lifted.policy.leaves, report.message
