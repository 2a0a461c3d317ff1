"""Readers of a lifted policy too large to expand (issue 17 §1: ``show``, ``render`` and
``export bt`` realise what they print, not the whole graph over the real objects).

A lifted policy's canonical nodes can stand for very many real ones: at 16 cubes / 2 boxes /
K=2, 413 canonical nodes stand for 795,237, which took 196 s to expand. Past ``--expand-limit``
(:data:`~ehatp.formats.lifted.EXPAND_LIMIT` by default) ``show`` prints the header and the
first timelines, each branch realised on its own; ``render`` draws the top of the policy,
realised breadth-first as far as it is drawn; ``export bt``, which needs every branch, refuses
in one line. The answers below come from the full expansion
(:func:`~ehatp.formats.lifted.expanded`, with no limit), which the limited readers must agree
with wherever they show something."""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import pytest
from typer.testing import CliRunner

import ehatp
from ehatp.cli.app import app
from ehatp.errors import PolicyTooLarge
from ehatp.experiments import bench
from ehatp.formats import lifted
from ehatp.formats.lifted import expand, expanded, real_branches
from ehatp.formats.policy import Policy, PolicyMove, PolicyNode
from ehatp.formats.render import lifted_view, plan_view

runner = CliRunner()


def invoke(*args: str | Path) -> tuple[int, str]:
    r = runner.invoke(app, [str(a) for a in args])
    return r.exit_code, r.output


@pytest.fixture(scope="module")
def c8(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Policy]:
    """8 cubes / 2 boxes / K=2 with symmetry: 131 canonical nodes standing for 817 real
    ones and 2,304 branches (the figures the first test checks); the problem file beside it
    as ``c8.toml``."""
    d = tmp_path_factory.mktemp("c8")
    problem = d / "c8.toml"
    problem.write_text(bench.select_points(None, ["cubes-c8-b2-opaque-k2"], False)[0].toml(),
                       encoding="utf-8")
    out = d / "c8.json"
    assert invoke("solve", problem, "--out", out)[0] == 0
    return out, ehatp.Policy.load(out)


def test_the_expansion_stops_past_its_limit_and_says_how_large_the_lifted_policy_is(
        c8: tuple[Path, Policy]) -> None:
    _, pol = c8
    whole = expanded(pol)
    assert (len(pol.nodes), len(whole.nodes), whole.leaves) == (131, 817, 2304)
    assert len(expand(pol, max_nodes=817).nodes) == 817  # exactly at the limit: whole
    with pytest.raises(PolicyTooLarge) as e:
        expand(pol, max_nodes=816)
    assert (e.value.limit, e.value.canonical) == (816, 131)
    assert str(e.value) == ("the lifted policy (131 canonical nodes) stands for more than 816 "
                            "nodes over the real objects")


def _content(step_node: PolicyNode) -> dict[str, object]:
    d = step_node.to_dict()
    del d["id"]
    for m in d["moves"]:
        del m["to"]
        m.pop("renaming", None)
    return d


def _move(m: PolicyMove | None) -> dict[str, object] | None:
    if m is None:
        return None
    d = m.to_dict()
    del d["to"]
    d.pop("renaming", None)
    return d


def test_branches_realised_one_at_a_time_are_those_of_the_expansion(
        c8: tuple[Path, Policy]) -> None:
    _, pol = c8
    lazy = list(real_branches(pol))
    whole = list(expanded(pol).iter_branches())
    assert len(lazy) == len(whole) == 2304
    for a, b in zip(lazy, whole, strict=True):
        assert [_move(s.move) for s in a] == [_move(s.move) for s in b]
        assert [_content(s.node) for s in a] == [_content(s.node) for s in b]


def _timelines(text: str) -> list[str]:
    """The timelines of ``ehatp show``'s output, leaf numbers left out (the limited show
    numbers leaves by their canonical nodes)."""
    body = text[text.index("Timelines ("):]
    return [re.sub(r"leaf #\d+", "leaf", line) for line in body.splitlines()[1:]]


def test_show_past_the_limit_prints_the_header_and_the_same_timelines_without_the_tree(
        c8: tuple[Path, Policy]) -> None:
    path, _ = c8
    code, full = invoke("show", path, "--expand-limit", 0)
    assert code == 0 and "graph: 817 nodes" in full
    code, limited = invoke("show", path, "--expand-limit", 100)
    assert code == 0
    assert "graph: lifted, 131 canonical nodes" in limited
    assert "more than 100 nodes over the real objects" in limited
    assert "not printed: the lifted policy (131 canonical nodes)" in limited
    assert "→ see node" not in limited.split("Timelines")[0]  # no tree lines
    # the first 100 branches of 2,304, step for step as the expansion's show prints them
    assert _timelines(limited)[-1].startswith("... and 2204 more branches: `ehatp simulate`")
    assert _timelines(limited)[:-1] == _timelines(full)[:-1]


def test_show_past_the_limit_realises_a_bounded_number_of_nodes(
        c8: tuple[Path, Policy], monkeypatch: pytest.MonkeyPatch) -> None:
    # the work is the limit's worth of the expansion plus the branches printed, however large
    # the policy over the real objects: count the canonical nodes seen through a renaming
    path, _ = c8
    calls = Counter[str]()
    real = lifted.Renamings.node

    def node(self: lifted.Renamings, tau: lifted.Perm, n: PolicyNode) -> PolicyNode:
        calls["node"] += 1
        return real(self, tau, n)

    monkeypatch.setattr(lifted.Renamings, "node", node)
    assert invoke("show", path, "--expand-limit", 50, "--no-timelines")[0] == 0
    # the expansion's walk stops at its 51st node: each node realised pushes its children,
    # each popped once (at most 4 moves a node here)
    assert calls["node"] <= 51 * 5


def _labels(dot: str) -> Counter[str]:
    """The drawn policy nodes' labels (what a node shows; ids and tooltips left out, and the
    count of tree copies a node stands for, ``(×k)``, which only the expansion knows)."""
    return Counter(re.sub(r"\\n\(×\d+\)$", "", x)
                   for x in re.findall(r'^\tn\d+ \[label="([^"]*)"', dot, re.M))


def test_render_past_the_limit_draws_the_same_nodes_realised_as_far_as_it_draws(
        c8: tuple[Path, Policy]) -> None:
    path, pol = c8
    code, whole = invoke("render", path, "--expand-limit", 0, "--max-nodes", 10_000,
                         "--no-share")
    assert code == 0
    code, lazy = invoke("render", path, "--expand-limit", 100, "--max-nodes", 10_000)
    assert code == 0
    # everything fits the budget: the same 817 nodes with the same labels
    assert sum(_labels(whole).values()) == 817
    assert _labels(lazy) == _labels(whole)
    assert "131 canonical nodes, 817 drawn" in lazy
    # within the default budget: the top of the policy, the rest folded into stubs that
    # count canonical nodes
    code, top = invoke("render", path, "--expand-limit", 100)
    assert code == 0
    drawn = _labels(top)
    assert sum(drawn.values()) <= 400
    assert not drawn - _labels(whole)
    assert "more below (" in top and "canonical nodes)" in top
    assert "node budget 400 reached" in top


def test_the_lazy_drawing_walks_breadth_first_as_the_expanded_one_does(
        c8: tuple[Path, Policy]) -> None:
    # the breadth-first walk of plan_view over the expansion (no merging of identical
    # subgraphs) and of lifted_view over the lifted policy draw the same nodes in the same
    # order, whatever the budget
    _, pol = c8
    whole = expanded(pol)
    too_large = PolicyTooLarge(1, len(pol.nodes))
    for budget in (1, 7, 60, 400):
        eager = plan_view(whole, max_nodes=budget, share=False)
        drawn, lazy = lifted_view(pol, too_large, max_nodes=budget)
        assert [_content(whole.nodes[i]) for i in eager.nodes] == [
            _content(drawn.nodes[i]) for i in lazy.nodes]
        assert len(eager.edges) == len(lazy.edges)
        # the same nodes folded, by their place in the walk
        assert sorted(eager.nodes.index(i) for i in eager.folded) == sorted(
            lazy.nodes.index(i) for i in lazy.folded)


def test_export_bt_past_the_limit_is_one_line_with_the_fix(
        c8: tuple[Path, Policy], tmp_path: Path) -> None:
    path, _ = c8
    code, out = invoke("export", "bt", path, "--expand-limit", 100)
    line = out.strip()
    assert code == 2 and "\n" not in line
    assert line.startswith(f"error: {path}: the lifted policy (131 canonical nodes) stands for "
                           "more than 100 nodes over the real objects; raise --expand-limit")
    code, out = invoke("export", "bt", path, "--expand-limit", 0, "--out", tmp_path / "t.xml")
    assert code == 0, out


def test_a_policy_within_the_limit_is_shown_and_drawn_as_before(
        c8: tuple[Path, Policy]) -> None:
    path, pol = c8
    assert invoke("show", path)[1] == invoke("show", path, "--expand-limit", 0)[1]
    assert invoke("render", path)[1] == invoke("render", path, "--expand-limit", 0)[1]
    assert pol.symmetry is not None  # lifted, and within the default limit (817 real nodes)


def test_expand_stops_at_its_limit_writing_nothing_and_without_one_writes_the_graph(
        c8: tuple[Path, Policy], tmp_path: Path) -> None:
    path, _ = c8
    problem, out = path.with_name("c8.toml"), tmp_path / "c8-real.json"
    r = runner.invoke(app, ["expand", str(path), "--problem", str(problem), "--out", str(out),
                            "--expand-limit", "100"])
    assert r.exit_code == 1 and not out.exists()
    assert r.stderr.strip() == (f"expand: {path}: stopped, the lifted policy (131 canonical "
                                "nodes) stands for more than 100 nodes over the real objects "
                                "(--expand-limit 100); nothing written")
    r = runner.invoke(app, ["expand", str(path), "--problem", str(problem), "--out", str(out)])
    # played by the problem's semantics, a real node is a real epistemic state: 562 of them,
    # as many as the policy of the search without symmetry has (the text-only expansion keeps
    # two canonical nodes apart even where they map to one real state: 817)
    assert r.exit_code == 0 and len(Policy.load(out).nodes) == 562


def test_show_with_its_problem_past_the_limit_prints_the_same_timelines(
        c8: tuple[Path, Policy]) -> None:
    # --problem expands by the problem's semantics (562 real nodes here); past the limit the
    # branches are realised from the file as without --problem, the same moves step for step
    path, _ = c8
    problem = path.with_name("c8.toml")
    code, full = invoke("show", path, "--problem", problem, "--expand-limit", 0)
    assert code == 0 and "graph: 562 nodes" in full
    code, limited = invoke("show", path, "--problem", problem, "--expand-limit", 100)
    assert code == 0 and "more than 100 nodes over the real objects" in limited
    assert _timelines(limited)[:-1] == _timelines(full)[:-1]
