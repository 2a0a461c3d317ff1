"""The HTML explorer of a lifted policy (format version 3, issue 17 §1): the page embeds the
lifted policy as it is and realises its tree in the page, a branch when it is unfolded
(``explorer/explorer-lifted.js``). Every answer here is derived from the Python expansion
(:func:`~ehatp.formats.lifted.expanded`, the version 2 graph) or by hand, never from the page's
own code: unfolding the lazy page must show, node by node, what the expansion holds and what
the eager page of the expansion shows."""

from __future__ import annotations

import json
from html import escape as html_escape
from pathlib import Path
from typing import Any

import pytest

import ehatp
from ehatp.experiments import bench
from ehatp.experiments.examples import examples_dir
from ehatp.formats.lifted import Renamings, expanded
from ehatp.formats.policy import COMM_KINDS, PathStep, Policy, PolicyMove, PolicyNode, timeline
from ehatp.formats.render import Explorer, _asset, explorer_script, notebook_html, to_html

from .test_render import (  # noqa: F401  (browser is a fixture)
    SMALLEST_TEXT,
    browser,
    embedded,
    open_page,
)

CUBES = examples_dir() / "cubes"
Path_ = tuple[int, ...]  # a path of move indices from the root


def bench_policy(tmp_path: Path, name: str) -> Policy:
    """The bench point ``name`` solved with its own options (symmetry on: lifted)."""
    point = bench.select_points(None, [name], False)[0]
    toml = tmp_path / f"{name}.toml"
    toml.write_text(point.toml(), encoding="utf-8")
    policy = ehatp.solve(ehatp.load(toml)).policy
    assert policy is not None and policy.symmetry is not None
    return policy


def example_policy(name: str) -> Policy:
    policy = ehatp.solve(ehatp.load(CUBES / f"{name}.toml")).policy
    assert policy is not None and policy.symmetry is not None  # the default: lifted
    return policy


# --------------------------------------------------------------------------- a lifted twins


def _node(i: int, state: list[str], moves: list[PolicyMove], value: int,
          human: list[str] | None = None) -> PolicyNode:
    return PolicyNode(id=i, copresent=True, k=0, worlds=1, divergence=[],
                      world_diffs=[{"true": [], "false": []}], state=state, robot_agenda=[],
                      human_agenda=human or [], to_move="H" if moves else None, value=value,
                      goal=not moves, moves=moves)


def _h(action: str, to: int, renaming: int = 0) -> PolicyMove:
    name = action.split("(")[0]
    return PolicyMove("H", "pass" if action == "pass" else "action", action, name,
                      [], 1, to, renaming=renaming)


def lifted_twins() -> Policy:
    """A lifted policy whose moves read the same: two boxes, swapped by renaming 1, which is
    also the root's (``symmetry.root = 1``), so the real root is canonical node 0 with the
    boxes swapped. Canonical node 0 offers ``pick(w)`` to node 1 twice (the second through
    renaming 1) and ``pass`` to node 2, which offers ``wave`` to node 3 twice (the second
    through renaming 1); node 3's human agenda names box1, the first of two hypotheses
    (the robot cannot tell ``fill(box1)`` from ``idle``)."""
    nodes = [
        _node(0, ["at(w, ot)", "empty(box1)"],
              [_h("pick(w)", 1), _h("pick(w)", 1, 1), _h("pass", 2)], 2),
        _node(1, ["holding(H, w)", "in(r, box1)"], [], 0),
        _node(2, ["at(w, ot)"], [_h("wave", 3), _h("wave", 3, 1)], 1),
        _node(3, ["at(w, ot)"], [], 0, human=["fill(box1)"]),
    ]
    nodes[3].hypotheses = [["fill(box1)"], ["idle"]]
    return Policy("twins", "synthetic", {"robot": "R", "human": "H"}, 2,
                  {"inform": 1, "ask": 1, "wait": 1, "pass": 1, "actions": {}}, nodes, 2, 0, 4,
                  worst_case=2,
                  symmetry={"objects": ["box1", "box2"], "classes": [["box1", "box2"]],
                            "renamings": [[0, 1], [1, 0]], "root": 1})


def test_the_lifted_twins_expand_as_derived_by_hand() -> None:
    """By hand: the root's renaming is the swap (the inverse of renamings[1]), so the real
    root holds ``empty(box2)``; the first ``pick(w)`` keeps the swap (``in(r, box2)``), the
    second composes it with the inverse of the swap, the identity (``in(r, box1)``); after
    ``pass`` the first ``wave`` leads to the hypotheses ``fill(box2)`` / ``idle``, the second
    to ``fill(box1)`` / ``idle``: six real nodes. (The page test below leans on this.)"""
    e = expanded(lifted_twins())
    root = e.nodes[0]
    assert root.state == ["at(w, ot)", "empty(box2)"]
    assert [e.nodes[m.to].state for m in root.moves[:2]] == [
        ["holding(H, w)", "in(r, box2)"], ["holding(H, w)", "in(r, box1)"]]
    after = e.nodes[root.moves[2].to]
    assert [e.nodes[m.to].human_agenda for m in after.moves] == [["fill(box2)"], ["fill(box1)"]]
    assert [e.nodes[m.to].hypotheses for m in after.moves] == [
        [["fill(box2)"], ["idle"]], [["fill(box1)"], ["idle"]]]
    assert len(e.nodes) == 6 and e.leaves == 4


# --------------------------------------------------------------------------- the page


def test_a_lifted_page_embeds_the_lifted_policy_not_its_expansion(tmp_path: Path) -> None:
    """The page of 12 cubes / 2 boxes / K=2 carries the 252 canonical nodes as they are (the
    policy data is the lifted file's JSON) and is the size of the lifted file plus the page's
    own code; the page of its expansion (thousands of real nodes) is many times larger."""
    policy = bench_policy(tmp_path, "cubes-c12-b2-opaque-k2")
    page = to_html(policy, expand_limit=0)
    assert embedded(page, "policy-data") == json.loads(json.dumps(policy.to_dict()))
    assert explorer_script(True) in page and _asset("explorer-eager.js") not in page
    own = len(_asset("explorer.html")) + len(_asset("explorer.css")) + len(explorer_script(True))
    lifted = len(json.dumps(policy.to_dict(), ensure_ascii=False, separators=(",", ":")))
    assert len(page) < 1.05 * lifted + own
    e = expanded(policy)
    assert len(e.nodes) > 10 * len(policy.nodes)
    assert len(to_html(e)) > 20 * len(page)  # 10.6 MB against 258 kB


def test_a_version_2_page_is_the_eager_explorer_as_before() -> None:
    """A policy over real states is drawn by the eager model (explorer-eager.js, after the
    shared explorer.js) with its graph embedded, as before lifted pages existed."""
    e = expanded(example_policy("p2"))
    page = to_html(e)
    assert explorer_script(False) in page and _asset("explorer-lifted.js") not in page
    assert embedded(page, "policy-data") == json.loads(json.dumps(e.to_dict()))


def test_the_notebook_shows_the_lazy_page_of_a_lifted_policy_past_the_limit() -> None:
    policy = example_policy("p2")
    html = notebook_html(policy, expand_limit=0)
    assert html_escape(to_html(policy, expand_limit=0), quote=True) in html
    assert html_escape(_asset("explorer-lifted.js"), quote=True) in html
    # within the limit (26 real nodes), the page of the expansion, as `ehatp render` draws it
    assert Explorer(policy)._repr_html_() == notebook_html(policy) == notebook_html(
        expanded(policy))


def test_a_lifted_page_survives_hostile_strings() -> None:
    policy = lifted_twins()
    policy.problem = "</script><script>alert(1)</script> see https://example.org/x.js"
    page = to_html(policy, expand_limit=0)
    assert page.count("</script>") == 3  # policy data, config, code
    assert "https:" not in page
    assert embedded(page, "policy-data")["problem"] == policy.problem


# --------------------------------------------------------------------------- in Chromium

# what the details panel, the selected box and the timeline show (the same ids on both pages)
READ = """
const $ = (id) => document.getElementById(id);
const t = (id) => $(id).textContent;
const steps = [];
let end = "";
for (const c of $("timeline").children) {
  if (c.classList.contains("tl-step")) {
    steps.push({agent: c.getAttribute("data-agent"), action: c.lastChild.textContent});
  } else if (c.classList.contains("tl-parallel")) {
    const lanes = {};
    for (const l of c.querySelectorAll(".tl-lane")) {
      lanes[l.getAttribute("data-agent")] = [...l.querySelectorAll(".tl-step")]
        .map((s) => s.lastChild.textContent);
    }
    steps.push({parallel: lanes});
  } else if (c.classList.contains("tl-end")) {
    end = c.textContent;
  }
}
const box = document.querySelector("#nodes g.node.selected");
return {
  action: t("fact-action"), agent: t("fact-agent"), cost: t("fact-cost"),
  value: t("fact-value"), copresent: t("fact-copresent"), k: t("fact-k"),
  worlds: t("fact-worlds"), to_move: t("fact-to-move"),
  differs: $("fact-differs").hidden ? "" : t("fact-differs"),
  rows: [...document.querySelectorAll("#world-table tr")]
    .map((tr) => [...tr.children].map((c) => c.textContent)),
  truth: [...document.querySelectorAll("#designated-world li")].map((li) => li.textContent),
  agendas: [...document.querySelectorAll("#agendas dd")].map((d) => d.textContent),
  steps, end,
  label: box ? box.querySelector("text").textContent : null,
  sub: box ? box.querySelector("text.sub").textContent : null,
};
"""
# a click as the visitor makes it (dispatched: the box may be outside the visible pane)
CLICK = """
const e = document.querySelector(arguments[0]);
if (!e) return false;
e.dispatchEvent(new MouseEvent("click", {bubbles: true}));
return true;
"""
UNFOLD = """
const t = document.querySelector(`.toggle[data-toggle-path="${arguments[0]}"]`);
if (!t) return false;
if (t.getAttribute("aria-label") === "expand") {
  t.dispatchEvent(new MouseEvent("click", {bubbles: true}));
}
return true;
"""
GOTO = """
const b = document.createElement("button");
b.setAttribute("data-goto", arguments[0]);
document.body.appendChild(b);
b.click();
b.remove();
"""
READ_LIGHT = """
return {
  worlds: document.getElementById("fact-worlds").textContent,
  rows: document.querySelectorAll("#world-table tr").length,
  truth: [...document.querySelectorAll("#designated-world li")].map((li) => li.textContent),
  agendas: [...document.querySelectorAll("#agendas dd")].map((d) => d.textContent),
};
"""
NODE_LEVEL = ("value", "copresent", "k", "worlds", "to_move", "rows", "truth", "agendas")


def dotted(path: Path_) -> str:
    return ".".join(map(str, path))


def reach(driver: Any, path: Path_) -> dict[str, Any]:
    """Unfold the lazy page down ``path`` by its toggles, click the box there, read it."""
    for i in range(len(path)):
        assert driver.execute_script(UNFOLD, dotted(path[:i])), path[:i]
    assert driver.execute_script(CLICK, f'#nodes g.node[data-path="{dotted(path)}"]'), path
    out: dict[str, Any] = driver.execute_script(READ)
    return out


def num(x: Any) -> str:
    """A cost as the page's String(number) prints it."""
    return str(int(x)) if float(x).is_integer() else repr(float(x))


def plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def truncate(s: str, n: int) -> str:
    return s[:n - 1] + "…" if len(s) > n else s


def told_apart(e: Policy, group: list[PolicyMove]) -> list[str]:
    """What tells sibling moves that read the same apart (docs/rendering.md, "Moves that read
    the same"): the literals told, else the human's agendas at the next node, else the
    robot's, else the facts true there and not at every sibling's (first three)."""
    told = [", ".join(m.told) for m in group]
    if len(set(told)) > 1:
        return [f"says {t}" if t else "says nothing" for t in told]
    nxt = [e.nodes[m.to] for m in group]
    human = [" | ".join(", ".join(a) or "nothing"
                        for a in (n.hypotheses if n.hypotheses and len(n.hypotheses) > 1
                                  else [n.human_agenda])) for n in nxt]
    if len(set(human)) > 1:
        return [f"human: {a}" for a in human]
    robot = [", ".join(n.robot_agenda) or "nothing" for n in nxt]
    if len(set(robot)) > 1:
        return [f"robot: {a}" for a in robot]
    common = set.intersection(*(set(n.state) for n in nxt))
    every = set().union(*(n.state for n in nxt))
    out = []
    for n in nxt:
        facts = [a for a in n.state if a not in common] + \
            [f"not {a}" for a in sorted(every - set(n.state))]
        out.append(", ".join(facts[:3]) + (", …" if len(facts) > 3 else "") if facts
                   else f"→ node {n.id}")
    return out


def expected(e: Policy, path: Path_) -> dict[str, Any]:
    """What a page must show at ``path``, from the expansion ``e``: the move into the node,
    the node's facts and worlds, and the branch through it continued along first moves."""
    steps = [PathStep(None, e.nodes[0])]
    parent = None
    for j in path:
        parent = steps[-1].node
        m = parent.moves[j]
        steps.append(PathStep(m, e.nodes[m.to]))
    n, m = steps[-1].node, steps[-1].move
    branch = list(steps)
    while branch[-1].node.moves:
        m2 = branch[-1].node.moves[0]
        branch.append(PathStep(m2, e.nodes[m2.to]))
    sibling = None
    if m is not None and parent is not None:
        group = [x for x in parent.moves if (x.agent, x.action) == (m.agent, m.action)]
        if len(group) > 1:
            k = next(i for i, x in enumerate(group) if x is m)
            sibling = (k + 1, len(group), told_apart(e, group)[k])
    cols = sorted({a for d in n.world_diffs for a in [*d["true"], *d["false"]]})
    truth = set(n.state)
    rows = [["world", *cols], ["truth (designated)", *("T" if a in truth else "F" for a in cols)]]
    for i, d in enumerate(n.world_diffs):
        same = not d["true"] and not d["false"]
        rows.append([f"world {i + 1}" + (" (= truth)" if same else ""),
                     *("T" if a in d["true"] else "F" if a in d["false"]
                       else "T" if a in truth else "F" for a in cols)])
    role = {e.agents["robot"]: "robot", e.agents["human"]: "human"}
    tag = f" ({sibling[0]}/{sibling[1]})" if sibling else ""
    if sibling:
        sub = truncate(sibling[2], 28)
    else:
        sub = " · ".join([plural(n.worlds, "world"), f"k={n.k}/{e.K}",
                          *([] if n.copresent else ["apart"]), *(["goal"] if n.goal else [])])
    leaf = branch[-1].node
    cost = sum(float(s.move.cost) for s in branch[1:] if s.move is not None)
    return {
        "action": "start" if m is None else m.action + (
            f" (communication: {m.kind})" if m.kind in COMM_KINDS else ""),
        "agent": "nobody (initial state)" if m is None else f"{m.agent} ({role[m.agent]})",
        "cost": "0" if m is None else num(m.cost), "value": num(n.value),
        "copresent": "together" if n.copresent
        else "apart (the human does not see the robot's actions)",
        "k": f"{n.k} of K = {e.K} robot turns unseen by the human",
        "worlds": str(n.worlds), "to_move": n.to_move or "nobody (goal reached)",
        "differs": "" if sibling is None or m is None
        else f'move {sibling[0]} of {sibling[1]} that read "{m.agent}: {m.action}"; '
             f"this one: {sibling[2]}",
        "rows": rows, "truth": list(n.state),
        "agendas": [", ".join(n.robot_agenda) or "—", ", ".join(n.human_agenda) or "—"],
        "steps": timeline(e, branch)["steps"],
        "end": f"goal reached (branch cost {num(cost)})" if leaf.goal and len(branch) > 1
        else "the initial state is the goal" if len(branch) == 1 else "",
        "label": "start" if m is None
        else truncate(f"{m.agent}: {m.action}", 24 - len(tag)) + tag,
        "sub": sub,
    }


def tree_paths(e: Policy, *, depth: int | None = None, width: int | None = None) -> list[Path_]:
    """Paths of the tree unfolding, depth-first: all of them, or down to ``depth`` through
    the first ``width`` moves of each node."""
    out: list[Path_] = []
    stack: list[tuple[Path_, int]] = [((), 0)]
    while stack:
        path, i = stack.pop()
        out.append(path)
        if depth is not None and len(path) >= depth:
            continue
        moves = e.nodes[i].moves[:width]
        for j in reversed(range(len(moves))):
            stack.append(((*path, j), moves[j].to))
    return out


def real_node(e: Policy, path: Path_) -> int:
    i = 0
    for j in path:
        i = e.nodes[i].moves[j].to
    return i


def walk_and_compare(browser: Any, tmp_path: Path, policy: Policy,  # noqa: F811
                     paths: list[Path_]) -> int:
    """Open the lazy page of ``policy`` and the eager page of its expansion; for each path,
    the lazy page must show what the expansion holds, and the node's facts and worlds as the
    eager page shows them for that real node. Returns the number of items realised through
    a renaming other than the identity (so that the walk tested some renaming)."""
    e = expanded(policy)
    lazy, eager = tmp_path / "lazy.html", tmp_path / "eager.html"
    lazy.write_text(to_html(policy, expand_limit=0), encoding="utf-8")
    eager.write_text(to_html(e), encoding="utf-8")
    open_page(browser, eager)
    shown_eager: dict[int, dict[str, Any]] = {}
    for path in paths:
        i = real_node(e, path)
        if i not in shown_eager:
            browser.execute_script(GOTO, str(i))
            shown_eager[i] = browser.execute_script(READ)
    open_page(browser, lazy)
    from selenium.webdriver.common.by import By

    facts = browser.find_element(By.ID, "policy-facts").text
    assert facts.startswith(f"{e.leaves} branch{'' if e.leaves == 1 else 'es'} · "
                            f"{plural(e.communications, 'communication')} · K = {e.K} · ")
    ren = Renamings(policy.symmetry or {})
    renamed = 0
    for path in paths:
        shown = reach(browser, path)
        assert shown == expected(e, path), path
        page = shown_eager[real_node(e, path)]
        assert {k: shown[k] for k in NODE_LEVEL} == {k: page[k] for k in NODE_LEVEL}, path
        tau, n = ren.root, 0
        for j in path:
            m = policy.nodes[n].moves[j]
            tau, n = ren.child(tau, m.renaming), m.to
        renamed += bool(ren.names(tau))
    logs = [x for x in browser.get_log("browser") if x["level"] == "SEVERE"]
    assert not logs, logs
    return renamed


@pytest.mark.slow  # a real Chromium
@pytest.mark.parametrize("name", ["p2", "p4", "x2-4cubes-k4"])
def test_unfolding_a_lifted_example_shows_its_expansion_node_by_node(
        name: str, tmp_path: Path, browser: Any) -> None:  # noqa: F811
    """Every item of the tree (every branch to its leaf), reached by unfolding."""
    policy = example_policy(name)
    paths = tree_paths(expanded(policy))
    assert len(paths) == policy.tree_size()
    assert walk_and_compare(browser, tmp_path, policy, paths) > 0


@pytest.mark.slow  # a real Chromium
def test_unfolding_a_lifted_cubes_point_shows_its_expansion_a_few_levels_down(
        tmp_path: Path, browser: Any) -> None:  # noqa: F811
    """8 cubes / 3 boxes / K=8 (230 canonical nodes, thousands of real ones, up to dozens
    of worlds): seven levels through the first two moves of each node, and the first branch
    to its leaf."""
    policy = bench_policy(tmp_path, "cubes-c8-b3-opaque-k8")
    e = expanded(policy)
    first: Path_ = ()
    while e.nodes[real_node(e, first)].moves:
        first = (*first, 0)
    paths = [*tree_paths(e, depth=7, width=2), first]
    assert walk_and_compare(browser, tmp_path, policy, paths) > 0


@pytest.mark.slow  # a real Chromium
def test_moves_that_read_the_same_are_told_apart_through_renamings(
        tmp_path: Path, browser: Any) -> None:  # noqa: F811
    """The lifted twins: the two ``pick(w)`` read the same and are told apart by the boxes
    their renamings give (derived by hand in test_the_lifted_twins_expand_as_derived_by_hand:
    the first leads to ``in(r, box2)``, the second to ``in(r, box1)``), the two ``wave`` by
    the human's agendas ``fill(box2) | idle`` / ``fill(box1) | idle``."""
    policy = lifted_twins()
    assert walk_and_compare(browser, tmp_path, policy, tree_paths(expanded(policy))) > 0
    assert reach(browser, (0,))["differs"].endswith("this one: in(r, box2), not in(r, box1)")
    assert reach(browser, (1,))["label"] == "H: pick(w) (2/2)"
    assert reach(browser, (2, 1))["differs"].endswith("this one: human: fill(box1) | idle")
    from selenium.webdriver.common.by import By

    assert [o.text for o in browser.find_elements(By.CSS_SELECTOR, "#branch-select option")] == [
        "branch 1: H: pick(w) (1/2) (leaf c1)", "branch 2: H: pick(w) (2/2) (leaf c1)",
        "branch 3: H: wave (1/2) (leaf c3)", "branch 4: H: wave (2/2) (leaf c3)"]


@pytest.mark.slow  # a real Chromium
def test_a_link_to_a_path_selects_that_branch_on_load(tmp_path: Path,
                                                      browser: Any) -> None:  # noqa: F811
    policy = example_policy("p4")
    e = expanded(policy)
    path = tree_paths(e)[-1]  # the last item depth-first: a leaf of the last branch
    page = tmp_path / "p4.html"
    page.write_text(to_html(policy, expand_limit=0), encoding="utf-8")
    browser.get(page.as_uri() + f"#path={dotted(path)}")
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(browser, 20).until(lambda d: d.execute_script(
        "return document.body.getAttribute('data-ready')") == "true")
    assert browser.execute_script(READ) == expected(e, path)


@pytest.mark.slow  # a real Chromium, and a 7 s search
def test_the_k8_page_of_20_cubes_opens_and_unfolds(tmp_path: Path,
                                                   browser: Any) -> None:  # noqa: F811
    """20 cubes / 3 boxes / K=8: 780 canonical nodes, more than 520,000 real ones (its
    expansion did not finish in 10 minutes). The page carries the lifted file and opens; its
    header counts are the lifted file's (a renaming keeps them: docs/policy-format.md), and
    the first branch, unfolded to its leaf, shows the facts and agendas that the Python
    realisation (:class:`~ehatp.formats.lifted.Renamings`) gives along it."""
    from selenium.webdriver.common.by import By

    policy = bench_policy(tmp_path, "cubes-c20-b3-opaque-k8")
    page = to_html(policy, expand_limit=0)
    lifted = len(json.dumps(policy.to_dict(), ensure_ascii=False, separators=(",", ":")))
    assert len(page) < 1.05 * lifted + 200_000
    out = tmp_path / "k8.html"
    out.write_text(page, encoding="utf-8")
    open_page(browser, out)  # waits for the page to be drawn (at most 20 s)
    # it opens readable, the root in view (as an eager page does: tests/test_render.py)
    least, shown = browser.execute_script(SMALLEST_TEXT)
    assert shown > 0 and least >= 10, (least, shown)
    assert browser.execute_script(
        "const r = document.querySelector('[data-path=\"\"]').getBoundingClientRect(), "
        "p = document.getElementById('tree').getBoundingClientRect(); return r.top >= p.top "
        "&& r.bottom <= p.bottom && r.left >= p.left && r.right <= p.right;")
    facts = browser.find_element(By.ID, "policy-facts").text
    assert facts.startswith(f"{policy.leaves} branches · "
                            f"{plural(policy.communications, 'communication')} · K = 8 · ")
    assert f"{len(policy.nodes)} canonical nodes" in facts
    # the first branch realised in Python: 201 moves to its leaf
    ren = Renamings(policy.symmetry or {})
    tau, n = ren.root, 0
    branch = [PathStep(None, ren.node(tau, policy.nodes[n]))]
    while policy.nodes[n].moves:
        m = policy.nodes[n].moves[0]
        real = ren.move(tau, m)
        tau, n = ren.child(tau, m.renaming), m.to
        branch.append(PathStep(real, ren.node(tau, policy.nodes[n])))
    assert len(branch) > 100 and branch[-1].node.goal
    # at open the root is selected and the timeline is the first branch, to its leaf
    shown = browser.execute_script(READ)
    assert shown["steps"] == timeline(policy, branch)["steps"]
    cost = sum(float(s.move.cost) for s in branch[1:] if s.move is not None)
    assert shown["end"] == f"goal reached (branch cost {num(cost)})"
    # unfolded by hand down the first 17 moves (to a node of 5,036 worlds)
    for depth, step in enumerate(branch[:18]):
        path = (0,) * depth
        if path:  # its ancestors are unfolded already: the walk came down through them
            assert browser.execute_script(UNFOLD, dotted(path[:-1])), path
        assert browser.execute_script(CLICK, f'#nodes g.node[data-path="{dotted(path)}"]')
        shown = browser.execute_script(READ_LIGHT)  # the table has up to 5,036 rows: counted
        view = step.node
        assert shown["truth"] == view.state and shown["worlds"] == str(view.worlds)
        assert shown["agendas"] == [", ".join(view.robot_agenda) or "—",
                                    ", ".join(view.human_agenda) or "—"]
        assert shown["rows"] == view.worlds + 2
    assert max(s.node.worlds for s in branch[:18]) > 5000


def first_paths(policy: Policy) -> dict[int, Path_]:
    """The first path (depth-first, moves in order) to each canonical node."""
    out: dict[int, Path_] = {}
    stack: list[tuple[int, Path_]] = [(0, ())]
    while stack:
        n, path = stack.pop()
        if n in out:
            continue
        out[n] = path
        moves = policy.nodes[n].moves
        stack.extend((moves[j].to, (*path, j)) for j in reversed(range(len(moves))))
    return out


@pytest.mark.slow  # a real Chromium
def test_expand_all_stops_at_its_budget_and_the_lists_lead_to_real_moves(
        tmp_path: Path, browser: Any) -> None:  # noqa: F811
    """8 cubes / 3 boxes / K=8 (25,091 items in its tree unfolding): "expand all" draws at
    most 3,000 boxes and says so. P4: each communication of the canonical graph is listed
    once, as the expansion has it at the first path to its node, and leads there; the branch
    list gives every branch, depth-first, with the move into its leaf, and leads to it."""
    from selenium.webdriver.common.by import By

    policy = bench_policy(tmp_path, "cubes-c8-b3-opaque-k8")
    e = expanded(policy)
    page = tmp_path / "c8.html"
    page.write_text(to_html(policy, expand_limit=0), encoding="utf-8")
    open_page(browser, page)
    assert browser.find_element(By.ID, "node-count").text.endswith(
        f" of {policy.tree_size():,} tree items shown")
    browser.find_element(By.ID, "expand-all").click()
    drawn = len(browser.find_elements(By.CSS_SELECTOR, "#nodes g.node"))
    assert 2000 < drawn <= 3000
    assert "expand all stops at 3,000" in browser.find_element(By.ID, "node-count").text
    browser.find_element(By.ID, "collapse-all").click()
    assert len(browser.find_elements(By.CSS_SELECTOR, "#nodes g.node")) <= 1 + len(
        policy.nodes[0].moves)
    # P4: two communications and several leaves
    policy = example_policy("p4")
    e = expanded(policy)
    page = tmp_path / "p4.html"
    page.write_text(to_html(policy, expand_limit=0), encoding="utf-8")
    open_page(browser, page)
    paths = first_paths(policy)
    comms = [(*paths[i], j) for i, n in enumerate(policy.nodes)
             for j, m in enumerate(n.moves) if m.kind in COMM_KINDS]
    assert comms
    buttons = browser.find_elements(By.CSS_SELECTOR, "#comm-list [data-goto]")
    assert [b.get_attribute("data-goto") for b in buttons] == [dotted(p) for p in comms]
    for path, b in zip(comms, buttons, strict=True):
        assert b.text.endswith(expected(e, path)["label"])
    for path in comms:
        browser.execute_script(CLICK, f'#comm-list [data-goto="{dotted(path)}"]')
        assert browser.execute_script(READ) == expected(e, path)
    leaves = [p for p in tree_paths(e) if not e.nodes[real_node(e, p)].moves]
    assert len(leaves) == e.leaves > 1
    options = browser.find_elements(By.CSS_SELECTOR, "#branch-select option")
    assert [o.get_attribute("value") for o in options] == [dotted(p) for p in leaves]
    for k, (path, o) in enumerate(zip(leaves, options, strict=True)):
        assert o.text.startswith(f"branch {k + 1}: {expected(e, path)['label']} (leaf c")
    from selenium.webdriver.support.ui import Select

    Select(browser.find_element(By.ID, "branch-select")).select_by_value(dotted(leaves[-1]))
    assert browser.execute_script(READ) == expected(e, leaves[-1])
    errors = [x for x in browser.get_log("browser") if x["level"] == "SEVERE"]
    assert errors == []
