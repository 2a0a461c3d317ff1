"""`ehatp render`: DOT/SVG drawings, collapsing, and the offline HTML explorer in a real browser."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import graphviz
import pytest
import typer
from typer.testing import CliRunner

from ehatp.cli.app import app
from ehatp.formats import render as rd
from ehatp.formats.policy import Policy, PolicyMove, PolicyNode

from .conftest import CUBES_TABLE1, DATA, solved_v2

V1 = DATA / "p4-v1.json"  # written by format version 1
NAMES = [e.stem for e in CUBES_TABLE1]  # p1 ... p6
NODE_STMT = re.compile(r"^\s*n(\d+) \[", re.M)
EDGE_STMT = re.compile(r"^\s*n(\d+) -> n(\d+)", re.M)


@pytest.fixture(scope="module")
def policy_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("policies")
    files = {}
    for name in NAMES:
        path = out / f"{name}.json"
        solved_v2(f"cubes/{name}").policy.write(path)
        files[name] = path
    return files


def cli() -> typer.Typer:
    return app  # the real command line: `render` is one of its commands


def run(*args: str) -> Any:
    return CliRunner().invoke(cli(), ["render", *map(str, args)])


# --------------------------------------------------------------------------- DOT


@pytest.mark.parametrize("name", NAMES)
def test_dot_has_one_node_per_policy_node(policy_files: dict[str, Path], name: str) -> None:
    policy = Policy.read(policy_files[name])
    text, notes = rd.render(policy_files[name], rd.Format.dot)
    assert notes == []  # every shipped example fits the default budget
    graphviz.Source(text)  # accepted by the graphviz package
    ids = [int(i) for i in NODE_STMT.findall(text)]
    assert sorted(ids) == list(range(len(policy.nodes)))
    edges = {(int(a), int(b)) for a, b in EDGE_STMT.findall(text)}
    assert edges == {(n.id, c) for n in policy.nodes for c in n.children}
    assert "collapsed" not in text
    if shutil.which("dot"):
        # let Graphviz itself parse it: `plain` output lists one `node` line per node
        plain = subprocess.run(["dot", "-Tplain"], input=text, capture_output=True, text=True,
                               check=True).stdout
        assert sum(line.startswith("node ") for line in plain.splitlines()) == len(policy.nodes)


def test_dot_styles_tell_kinds_apart(policy_files: dict[str, Path]) -> None:
    policy = Policy.read(policy_files["p4"])
    text, _ = rd.render(policy_files["p4"], rd.Format.dot)
    lines = {int(m.group(1)): m.string[m.start():m.string.index("\n", m.start())]
             for m in NODE_STMT.finditer(text)}
    into: dict[int, list[Any]] = {}
    for _, m in policy.edges():
        into.setdefault(m.to, []).append(m)
    human = policy.agents["human"]
    seen = set()
    labelled = 0
    for n in policy.nodes:
        line = lines[n.id]
        assert f"{n.worlds} world" in line  # every node shows how many worlds
        assert f"k={n.k}/{policy.K}" in line  # the unseen-turn counter against K
        assert ("peripheries=2" in line) == n.goal
        if n.id == 0:
            continue
        entered = into[n.id]
        kinds = {m.kind for m in entered}
        if kinds <= {"inform", "ask"}:
            assert "shape=hexagon" in line
            seen.add("comm")
        elif kinds == {"action"}:
            assert ("shape=ellipse" if entered[0].agent == human else "shape=box") in line
            seen.add(entered[0].agent)
        if len({m.action for m in entered}) == 1:
            assert entered[0].action in line  # one way in: the node shows the move
        else:  # several: each edge shows its own
            labelled += 1
            for m in entered:
                assert re.search(rf"-> n{n.id} \[label=\"{re.escape(m.action)}\"", text)
    assert seen == {"comm", *policy.agents.values()}
    assert labelled  # P4: both of the human's questions lead to one state


def test_shared_nodes_are_drawn_once_with_an_edge_per_parent(
        policy_files: dict[str, Path]) -> None:
    policy = Policy.read(policy_files["p4"])
    view = rd.plan_view(policy, max_nodes=None, share=False)
    assert sorted(view.nodes) == list(range(len(policy.nodes))) and not view.notes
    parents: dict[int, set[int]] = {}
    for a, b, _ in view.edges:
        parents.setdefault(b, set()).add(a)
    assert max(len(p) for p in parents.values()) > 1
    # a shared node says how many copies the tree unfolding would hold
    copies = policy.path_counts()
    assert view.stands_for == {i: c for i, c in enumerate(copies) if c > 1}
    text = rd.to_dot(policy, view).source
    for i, c in view.stands_for.items():
        assert re.search(rf"^\s*n{i} \[label=\"[^\"]*\(×{c}\)", text, re.M)


def test_share_identical_subgraphs() -> None:
    # a version 1 file holds the tree unfolding: its copies are identical subtrees
    policy = Policy.load(V1)
    hashes = rd.subgraph_hashes(policy)
    view = rd.plan_view(policy, max_nodes=None, share=True)
    assert len(view.nodes) == len(set(hashes)) < len(policy.nodes)
    # every policy node is drawn through a node with the very same subgraph
    assert {hashes[i] for i in view.nodes} == set(hashes)
    assert any("identical subgraphs" in note for note in view.notes)
    assert any(k > 1 for k in view.stands_for.values())
    text = rd.to_dot(policy, view).source
    assert len(NODE_STMT.findall(text)) == len(view.nodes)
    assert "collapsed: identical subgraphs" in text  # the note is in the graph label
    # a shared node has several parents
    parents: dict[int, int] = {}
    for _, b, _ in view.edges:
        parents[b] = parents.get(b, 0) + 1
    assert max(parents.values()) > 1


def test_over_budget_collapses_and_says_so() -> None:
    result = run(V1, "--max-nodes", "40")
    assert result.exit_code == 0, result.output
    assert "collapsed: identical subgraphs" in result.stderr
    assert "collapsed: identical subgraphs" in result.stdout
    assert len(NODE_STMT.findall(result.stdout)) <= 40


def _hidden_below(policy: Policy, view: rd.View) -> dict[int, set[int]]:
    drawn = set(view.nodes)
    out: dict[int, set[int]] = {}
    for i in view.folded:
        seen: set[int] = set()
        stack = [i]
        while stack:
            for c in policy.nodes[stack.pop()].children:
                if c not in seen and c not in drawn:
                    seen.add(c)
                    stack.append(c)
        out[i] = seen
    return out


def test_depth_cap_folds_into_stubs(policy_files: dict[str, Path]) -> None:
    policy = Policy.read(policy_files["p3"])
    view = rd.plan_view(policy, max_depth=3, max_nodes=None, share=False)
    assert view.folded and any("depth 3" in note for note in view.notes)
    # each stub counts the nodes below it that are not drawn; together they are the rest
    hidden = _hidden_below(policy, view)
    assert view.folded == {i: len(s) for i, s in hidden.items()}
    assert set(view.nodes) | set().union(*hidden.values()) == set(range(len(policy.nodes)))
    text = rd.to_dot(policy, view).source
    assert len(re.findall(r"^\s*more\d+ \[", text, re.M)) == len(view.folded)
    result = run(policy_files["p3"], "--max-depth", "3")
    assert result.exit_code == 0 and "cut at depth 3" in result.stderr


def test_node_budget_keeps_siblings_together(policy_files: dict[str, Path]) -> None:
    policy = Policy.read(policy_files["p6"])
    view = rd.plan_view(policy, max_nodes=25, share=False)
    assert len(view.nodes) <= 25
    hidden = _hidden_below(policy, view)
    assert set(view.nodes) | set().union(*hidden.values()) == set(range(len(policy.nodes)))
    drawn = set(view.nodes)
    edges = {(a, b) for a, b, _ in view.edges}
    for i in drawn:
        kids = set(policy.nodes[i].children)
        # every child drawn with its edge, or none of its edges and a stub
        assert {(i, k) for k in kids} <= edges or (i in view.folded and not {
            (i, k) for k in kids} & edges)


# --------------------------------------------------------------------------- SVG and errors


def test_svg_through_dot(policy_files: dict[str, Path], tmp_path: Path) -> None:
    if not shutil.which("dot"):
        pytest.skip("Graphviz's dot is not installed")
    out = tmp_path / "p2.svg"
    result = run(policy_files["p2"], "--format", "svg", "--out", out)
    assert result.exit_code == 0, result.output
    svg = out.read_text(encoding="utf-8")
    assert "<svg" in svg and 'id="policy_node_0"' in svg


def test_svg_without_dot_says_how_to_install(policy_files: dict[str, Path],
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(rd.shutil, "which", lambda _name: None)
    result = run(policy_files["p2"], "--format", "svg")
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "install Graphviz" in lines[0]


def test_bad_input_is_one_line_exit_2(tmp_path: Path) -> None:
    missing = tmp_path / "nope.json"
    broken = tmp_path / "broken.json"
    broken.write_text("{not json", encoding="utf-8")
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"format": "something-else"}), encoding="utf-8")
    for path, what in [(missing, "no such file"), (broken, "not valid JSON"),
                       (other, "not an ehatp policy")]:
        result = run(path)
        assert result.exit_code == 2
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1, lines
        assert str(path) in lines[0] and what in lines[0] and "ehatp solve" in lines[0]


def test_cyclic_moves_are_rejected(policy_files: dict[str, Path], tmp_path: Path) -> None:
    data = json.loads(policy_files["p1"].read_text(encoding="utf-8"))
    back = dict(data["nodes"][1]["moves"][0])
    node = data["nodes"][back["to"]]
    node["moves"].append({**back, "to": 1})  # back up to node 1
    bad = tmp_path / "cyclic.json"
    bad.write_text(json.dumps(data), encoding="utf-8")
    result = run(bad)
    assert result.exit_code == 2 and "cycle through node" in result.stderr
    data["nodes"][1]["moves"].append({**back, "to": 0})  # into the root
    bad.write_text(json.dumps(data), encoding="utf-8")
    result = run(bad)
    assert result.exit_code == 2 and "moves[1].to" in result.stderr


# --------------------------------------------------------------------------- HTML


FETCHING = [
    re.compile(r"https?:", re.I),  # simplest: no absolute URL at all
    re.compile(r"<\w[^>]*\s(src|href|srcset|action|formaction|poster|data)\s*=", re.I),
    re.compile(r"\.(src|href)\s*=|setAttribute\(\s*[\"'](src|href)", re.I),
    re.compile(r"url\s*\(", re.I),
    re.compile(r"@import|\bimport\s*\(|\bimport\s+[\w{*'\"]", re.I),
    re.compile(r"\bfetch\s*\(|XMLHttpRequest|WebSocket|EventSource|sendBeacon", re.I),
    re.compile(r"<(link|iframe|img|object|embed|base)\b", re.I),
]


def embedded(html: str, element_id: str) -> Any:
    m = re.search(rf'<script type="application/json" id="{element_id}">(.*?)</script>', html,
                  re.S)
    assert m, element_id
    return json.loads(m.group(1))


@pytest.mark.parametrize("name", ["p2", "p4"])
def test_html_is_self_contained(policy_files: dict[str, Path], name: str) -> None:
    html, _ = rd.render(policy_files[name], rd.Format.html)
    for pattern in FETCHING:
        assert not pattern.search(html), pattern.pattern
    assert embedded(html, "policy-data") == json.loads(policy_files[name].read_text("utf-8"))
    assert "Content-Security-Policy" in html and "default-src 'none'" in html


def test_html_survives_hostile_strings(policy_files: dict[str, Path], tmp_path: Path) -> None:
    data = json.loads(policy_files["p1"].read_text(encoding="utf-8"))
    data["problem"] = "</script><script>alert(1)</script> see https://example.org/x.js"
    path = tmp_path / "hostile.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    html, _ = rd.render(path, rd.Format.html)
    assert html.count("</script>") == 3  # policy data, config, code
    assert not re.search(r"https?:", html)
    assert embedded(html, "policy-data")["problem"] == data["problem"]


def test_explorer_assets_are_package_data() -> None:
    # the wheel ships src/ehatp as a whole, so the explorer files only need to sit in it
    here = Path(rd.__file__).parent / "explorer"
    assert {p.name for p in here.iterdir()} >= {"explorer.html", "explorer.css", "explorer.js",
                                                "explorer-eager.js", "explorer-lifted.js"}


# --------------------------------------------------------------------------- real browser


def _chromium() -> tuple[str, str]:
    browser = next((p for p in map(shutil.which, ["chromium", "chromium-browser"]) if p), None)
    driver = shutil.which("chromedriver") or (
        "/usr/bin/chromedriver" if Path("/usr/bin/chromedriver").exists() else None)
    if browser is None or driver is None:
        pytest.skip("chromium and chromedriver are not installed "
                    "(apt-get install chromium chromium-driver)")
    return browser, driver


@pytest.fixture
def browser(monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    binary, driver_path = _chromium()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    monkeypatch.setenv("SE_OFFLINE", "true")  # Selenium Manager must not download anything
    options = webdriver.ChromeOptions()
    options.binary_location = binary
    profile = tempfile.mkdtemp(prefix="ehatp-chromium-")
    for arg in ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                "--no-first-run", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--window-size=1400,1000",
                f"--user-data-dir={profile}"]:
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(executable_path=driver_path), options=options)
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def first_moves(policy: Policy) -> dict[int, Any]:
    """The move by which the depth-first walk first reaches each node (the explorer draws a
    node there, and a reference to it at every other move into it)."""
    out: dict[int, Any] = {}
    stack: list[tuple[Any, int]] = [(None, 0)]
    while stack:
        move, i = stack.pop()
        if i in out:
            continue
        out[i] = move
        stack.extend((m, m.to) for m in reversed(policy.nodes[i].moves))
    return out


def open_page(browser: Any, page: Path) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    browser.get(page.as_uri())
    WebDriverWait(browser, 20).until(
        lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-ready") == "true")


# the smallest text drawn in the tree, in screen pixels: font size times the drawing's scale
SMALLEST_TEXT = """
  let least = Infinity, shown = 0;
  const pane = document.getElementById("tree").getBoundingClientRect();
  for (const t of document.querySelectorAll("#tree text")) {
    const r = t.getBoundingClientRect();
    if (r.right < pane.left || r.left > pane.right || r.bottom < pane.top || r.top > pane.bottom)
      continue;
    shown++;
    least = Math.min(least, parseFloat(getComputedStyle(t).fontSize) * t.getScreenCTM().a);
  }
  return [least, shown];
"""


@pytest.mark.slow  # a real Chromium
def test_click_node_and_read_world_table(policy_files: dict[str, Path], tmp_path: Path,
                                         browser: Any) -> None:
    from selenium.webdriver.common.by import By

    policy = Policy.read(policy_files["p4"])
    page = tmp_path / "p4.html"
    assert run(policy_files["p4"], "--format", "html", "--out", page).exit_code == 0
    open_page(browser, page)
    assert len(browser.find_elements(By.CSS_SELECTOR, "[data-node-id]")) == len(policy.nodes)
    browser.find_element(By.ID, "fit").click()  # the whole tree in view, to click anywhere
    # every other move into a shared node is a reference to its first copy
    refs = browser.find_elements(By.CSS_SELECTOR, "[data-ref-id]")
    moves = sum(len(n.moves) for n in policy.nodes)
    assert len(refs) == moves - (len(policy.nodes) - 1) > 0

    # a node where the human cannot tell several worlds apart
    node = max(policy.nodes, key=lambda n: (n.worlds, -n.id))
    assert node.worlds > 1
    browser.find_element(By.CSS_SELECTOR, f'[data-node-id="{node.id}"]').click()
    table = browser.find_element(By.ID, "world-table")
    atoms = [th.get_attribute("data-atom")
             for th in table.find_elements(By.CSS_SELECTOR, "thead th[data-atom]")]
    expected_atoms = sorted({a for d in node.world_diffs for a in d["true"] + d["false"]})
    assert atoms == expected_atoms
    rows = table.find_elements(By.CSS_SELECTOR, "tbody tr[data-world]")
    assert [r.get_attribute("data-world") for r in rows] == [
        "truth", *map(str, range(1, node.worlds + 1))]
    truth = set(node.state)
    for row, diff in zip(rows[1:], node.world_diffs, strict=True):
        cells = row.find_elements(By.CSS_SELECTOR, "td[data-atom]")
        got = {c.get_attribute("data-atom"): c.text for c in cells}
        want = {a: "T" if (a in diff["true"] or (a in truth and a not in diff["false"]))
                else "F" for a in expected_atoms}
        assert got == want
    move = first_moves(policy)[node.id]
    assert browser.find_element(By.ID, "fact-k").text.startswith(f"{node.k} of K = {policy.K}")
    assert browser.find_element(By.ID, "fact-worlds").text == str(node.worlds)
    assert browser.find_element(By.ID, "fact-cost").text == str(move.cost)
    assert browser.find_element(By.ID, "fact-action").text.startswith(move.action)
    copresent = browser.find_element(By.ID, "fact-copresent").text
    assert copresent.startswith("together" if node.copresent else "apart")
    assert f"node={node.id}" in browser.current_url
    # the label gives the unseen turns against K, not a "K=" that reads as the bound
    sub = browser.find_element(By.CSS_SELECTOR, f'[data-node-id="{node.id}"] text.sub').text
    assert f"k={node.k}/{policy.K}" in sub and "K=" not in sub

    # the branch through it, as a timeline with parallel lanes while the agents are apart
    lanes = browser.find_elements(By.CSS_SELECTOR, "#timeline .tl-parallel .tl-lane")
    assert {lane.get_attribute("data-agent") for lane in lanes} == set(policy.agents.values())
    current = browser.find_element(By.CSS_SELECTOR, "#timeline .tl-step.current")
    assert current.get_attribute("data-step-node") == str(node.id)

    # a reference leads to the first copy of its node
    ref = refs[0]
    target = ref.get_attribute("data-ref-id")
    ref.click()
    assert browser.find_element(By.CSS_SELECTOR, ".node.selected").get_attribute(
        "data-node-id") == target

    # fold and unfold the whole tree at the root
    browser.find_element(By.CSS_SELECTOR, '[data-toggle-id="0"]').click()
    assert len(browser.find_elements(By.CSS_SELECTOR, "[data-node-id]")) == 1
    browser.find_element(By.CSS_SELECTOR, '[data-toggle-id="0"]').click()
    assert len(browser.find_elements(By.CSS_SELECTOR, "[data-node-id]")) == len(policy.nodes)

    # communications are listed, each move once, and jump to their node
    comms = browser.find_elements(By.CSS_SELECTOR, "#comm-list [data-goto]")
    assert len(comms) == sum(m.kind in ("inform", "ask") for _, m in policy.edges()) > 0
    comms[0].click()
    assert browser.find_element(By.CSS_SELECTOR, ".node.selected.comm")

    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == []


def big_policy(levels: int, width: int) -> Policy:
    """A synthetic policy graph: the human chooses between two moves at every node, each
    leading one level down (node j to 2j and 2j + 1, modulo the level's width, at most
    ``width``), so nodes are shared and the tree unfolding has 2 ** levels branches."""
    sizes = [min(2 ** level, width) for level in range(levels + 1)]
    first = [sum(sizes[:level]) for level in range(levels + 1)]  # id of each level's node 0
    nodes = []
    for level, size in enumerate(sizes):
        for j in range(size):
            i = first[level] + j
            goal = level == levels
            nodes.append(PolicyNode(
                id=i, copresent=level % 3 == 0, k=level % 3, worlds=1 + i % 3, divergence=[],
                world_diffs=[{"true": [], "false": []}] * (1 + i % 3), state=[f"at(p{level})"],
                robot_agenda=[], human_agenda=[] if goal else ["walk"],
                to_move=None if goal else "H", value=levels - level, goal=goal,
                moves=[] if goal else [
                    PolicyMove("H", "action", f"go(b{j}, {d})", "go", [f"b{j}", str(d)], 1,
                               first[level + 1] + (2 * j + d) % sizes[level + 1])
                    for d in range(2)]))
    policy = Policy("big", "synthetic", {"robot": "R", "human": "H"}, 2,
                    {"inform": 1, "ask": 1, "wait": 1, "pass": 1, "actions": {}}, nodes,
                    levels, 0, 0)
    policy.leaves = policy.count_branches()
    return policy


@pytest.mark.slow  # a real Chromium
@pytest.mark.parametrize("name", ["p2", "big"])
def test_explorer_opens_readable_with_a_timeline(policy_files: dict[str, Path], tmp_path: Path,
                                                 browser: Any, name: str) -> None:
    from selenium.webdriver.common.by import By

    if name == "big":
        source = tmp_path / "big.json"
        big_policy(100, 300).write(source)
    else:
        source = policy_files[name]
    policy = Policy.load(source)
    page = tmp_path / f"{name}.html"
    assert run(source, "--format", "html", "--out", page).exit_code == 0
    open_page(browser, page)
    least, shown = browser.execute_script(SMALLEST_TEXT)
    assert shown > 0 and least >= 10, (least, shown)
    # the root is in view, and so are its details and the branch along first choices
    root = browser.find_element(By.CSS_SELECTOR, '[data-node-id="0"]')
    assert root.is_displayed() and browser.execute_script(
        "const r = arguments[0].getBoundingClientRect(), p = document.getElementById('tree')"
        ".getBoundingClientRect(); return r.top >= p.top && r.bottom <= p.bottom && "
        "r.left >= p.left && r.right <= p.right;", root)
    assert browser.find_element(By.ID, "details-body").is_displayed()
    steps = browser.find_elements(By.CSS_SELECTOR, "#timeline .tl-step")
    first = next(policy.iter_branches())
    # (steps taken apart are grouped in lanes, one per agent)
    assert sorted(int(s.get_attribute("data-step-node")) for s in steps) == sorted(
        n.id for n in first[1:])
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == []
