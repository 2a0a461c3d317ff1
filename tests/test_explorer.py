"""The HTML explorer (``ehatp render --format html``), in a real Chromium: sibling moves that
read the same are numbered and say what tells them apart, the truth lists the static facts of
``[init]`` (given the problem), and the header gives the worst-case and the expected cost. Both
pages (eager and lazy) run one shared core with their own model of the policy: what the core
does (keyboard, timeline steps, expand and collapse all) is checked on both alike."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

import ehatp
from ehatp import load
from ehatp.cli.app import app
from ehatp.experiments.examples import examples_dir
from ehatp.formats.lifted import expanded
from ehatp.formats.policy import COMM_KINDS, Policy, PolicyMove, PolicyNode
from ehatp.formats.policy_check import check_consistent
from ehatp.formats.render import _asset, explorer_script, static_facts, to_html

from .test_render import browser, open_page  # noqa: F401  (browser is a fixture)

CUBES = examples_dir() / "cubes"
runner = CliRunner()


def invoke(*args: str | Path) -> typer.testing.Result:
    return runner.invoke(app, [str(a) for a in args])


def node(i: int, state: list[str], moves: list[PolicyMove], value: int,
         human: list[str] | None = None) -> PolicyNode:
    return PolicyNode(id=i, copresent=True, k=0, worlds=1, divergence=[],
                      world_diffs=[{"true": [], "false": []}], state=state, robot_agenda=[],
                      human_agenda=human or [], to_move="H" if moves else None, value=value,
                      goal=not moves, moves=moves)


def twins() -> Policy:
    """Return a policy whose root offers the human ``pick(w)`` twice (the box it ends in
    differs) and ``pass``, after which it offers ``wave`` twice (what the human means to do
    next differs): four branches, worst case 2."""
    def h(action: str, to: int) -> PolicyMove:
        name = action.split("(")[0]
        args = action[len(name) + 1:-1].split(", ") if "(" in action else []
        return PolicyMove("H", "pass" if action == "pass" else "action", action, name, args, 1,
                          to)
    nodes = [
        node(0, ["at(w, ot)"], [h("pick(w)", 1), h("pick(w)", 2), h("pass", 3)], 2),
        node(1, ["holding(H, w)", "in(r, box1)"], [], 0),
        node(2, ["holding(H, w)", "in(r, box2)"], [], 0),
        node(3, ["at(w, ot)"], [h("wave", 4), h("wave", 5)], 1),
        node(4, ["at(w, ot)"], [], 0, human=["leave"]),
        node(5, ["at(w, ot)"], [], 0, human=["stay"]),
    ]
    policy = Policy("twins", "synthetic", {"robot": "R", "human": "H"}, 2,
                    {"inform": 1, "ask": 1, "wait": 1, "pass": 1, "actions": {}}, nodes, 2, 0, 4,
                    worst_case=2)  # no expected cost recorded: the explorer shows both or one
    check_consistent(policy, "twins")
    return policy


def test_the_static_facts_of_p2_are_the_cubes_origins() -> None:
    assert static_facts(load(CUBES / "p2.toml")) == ["origin(r, mt)", "origin(w, ot)"]


def test_the_page_carries_the_static_facts_as_data() -> None:
    page = to_html(twins(), static=["adjacent(a, b)"])
    config = page.split('id="explorer-config">')[1].split("</script>")[0]
    assert json.loads(config)["staticFacts"] == ["adjacent(a, b)"]


@pytest.mark.slow  # a real Chromium
def test_sibling_moves_that_read_the_same_are_numbered_and_told_apart(
        tmp_path: Path, browser: Any) -> None:  # noqa: F811
    from selenium.webdriver.common.by import By

    source = tmp_path / "twins.json"
    twins().write(source)
    page = tmp_path / "twins.html"
    assert invoke("render", source, "--format", "html", "--out", page).exit_code == 0
    open_page(browser, page)
    boxes = browser.find_elements(By.CSS_SELECTOR, "[data-node-id][data-sibling]")
    seen = {(b.get_attribute("data-node-id"), b.get_attribute("data-sibling"),
             b.get_attribute("data-differs"),
             b.find_element(By.CSS_SELECTOR, "text").text) for b in boxes}
    assert seen == {
        ("1", "1/2", "in(r, box1), not in(r, box2)", "H: pick(w) (1/2)"),
        ("2", "2/2", "in(r, box2), not in(r, box1)", "H: pick(w) (2/2)"),
        ("4", "1/2", "human: leave", "H: wave (1/2)"),
        ("5", "2/2", "human: stay", "H: wave (2/2)"),
    }
    # the pass is alone of its label: no number
    passed = browser.find_element(By.CSS_SELECTOR, '[data-node-id="3"]')
    assert passed.get_attribute("data-sibling") is None
    assert passed.find_element(By.CSS_SELECTOR, "text").text == "H: pass"
    # the details say it too, and the branch list tells the leaves apart
    browser.find_element(By.CSS_SELECTOR, '[data-node-id="2"]').click()
    assert browser.find_element(By.ID, "fact-differs").text == \
        'move 2 of 2 that read "H: pick(w)"; this one: in(r, box2), not in(r, box1)'
    browser.find_element(By.CSS_SELECTOR, '[data-node-id="3"]').click()
    assert not browser.find_element(By.ID, "fact-differs").is_displayed()
    options = [o.text for o in browser.find_elements(By.CSS_SELECTOR, "#branch-select option")]
    assert options == ["leaf #1: H: pick(w) (1/2)", "leaf #2: H: pick(w) (2/2)",
                       "leaf #4: H: wave (1/2)", "leaf #5: H: wave (2/2)"]


@pytest.mark.slow  # a real Chromium
def test_the_truth_lists_the_static_facts_and_the_header_both_costs(
        tmp_path: Path, browser: Any) -> None:  # noqa: F811
    from selenium.webdriver.common.by import By

    policy = tmp_path / "p2.json"
    assert invoke("solve", CUBES / "p2.toml", "--out", policy).exit_code == 0
    page = tmp_path / "p2.html"
    assert invoke("render", policy, "--format", "html", "--problem", CUBES / "p2.toml",
                  "--out", page).exit_code == 0
    open_page(browser, page)
    # as `ehatp show` says: worst-case cost 13 (optimised), expected cost 9.5
    assert browser.find_element(By.ID, "policy-worst-case").text == \
        "worst-case cost 13 (optimised)"
    assert browser.find_element(By.ID, "policy-expected").text == "expected cost 9.5"
    # the root's truth: its ten fluent facts, then the two static ones of [init], marked
    facts = browser.find_elements(By.CSS_SELECTOR, "#designated-world li")
    static = [li for li in facts if li.get_attribute("data-static") == "true"]
    assert len(facts) == 12
    assert [browser.execute_script("return arguments[0].firstChild.textContent", li)
            for li in static] == ["origin(r, mt)", "origin(w, ot)"]
    assert all(li.find_element(By.CSS_SELECTOR, ".tag").text.lower() == "static"
               for li in static)
    assert facts[-2:] == static  # after the facts that can change


@pytest.mark.slow  # a real Chromium
def test_an_expected_cost_policy_marks_the_expected_cost_optimised(
        tmp_path: Path, browser: Any) -> None:  # noqa: F811
    from selenium.webdriver.common.by import By

    policy = tmp_path / "p2e.json"
    assert invoke("solve", CUBES / "p2.toml", "--objective", "expected", "--out",
                  policy).exit_code == 0
    page = tmp_path / "p2e.html"
    assert invoke("render", policy, "--format", "html", "--out", page).exit_code == 0
    open_page(browser, page)
    # P2 planned for the expected cost: 9.5, its worst branch 13 (docs/benchmarks.md)
    assert browser.find_element(By.ID, "policy-worst-case").text == "worst-case cost 13"
    assert browser.find_element(By.ID, "policy-expected").text == \
        "expected cost 9.5 (optimised)"


# --------------------------------------------------------------------------- one core, two models


def _code_lines(js: str) -> list[str]:
    """The lines of a script that carry code: stripped, without blank lines, comments and
    lone brackets."""
    out = []
    for line in js.splitlines():
        t = line.strip()
        if t and not t.startswith(("//", "/*", "*")) and t not in ("}", "};", "});", ")", "]"):
            out.append(t)
    return out


def _runs_of_six(js: str) -> set[tuple[str, ...]]:
    lines = _code_lines(js)
    return {tuple(lines[i:i + 6]) for i in range(len(lines) - 5)}


def test_both_pages_run_the_one_shared_core_with_their_own_model() -> None:
    """Each page's one script is the shared core (explorer.js, which defines ehatpExplorer)
    followed by the page's model, which calls it once; a model defines none of the core's
    functions and the two models share no run of six lines of code (the copy the lazy page
    once was of the eager one must not come back)."""
    core, eager, lifted = (_asset(a) for a in
                           ("explorer.js", "explorer-eager.js", "explorer-lifted.js"))
    assert explorer_script(False) == f"{core}\n{eager}"
    assert explorer_script(True) == f"{core}\n{lifted}"
    assert explorer_script(False) in to_html(twins())
    lifted_policy = ehatp.solve(load(CUBES / "p2.toml")).policy
    assert lifted_policy is not None and lifted_policy.symmetry is not None
    assert explorer_script(True) in to_html(lifted_policy, expand_limit=0)
    assert core.count("function ehatpExplorer(") == 1
    own = set(re.findall(r"function (\w+)\(", core)) | set(
        re.findall(r"const (\w+) = \(", core))
    assert {"drawNode", "showDetails", "showTimeline", "worldTable", "initialFolding",
            "select", "toggle", "differs", "label"} <= own
    for model in (eager, lifted):
        assert model.count("ehatpExplorer(") == 1
        assert not own & set(re.findall(r"function (\w+)\(", model))
    assert not _runs_of_six(eager) & _runs_of_six(lifted)


KEY = """
const e = document.querySelector(arguments[0]);
e.dispatchEvent(new KeyboardEvent("keydown", {key: arguments[1], bubbles: true}));
"""


@pytest.mark.slow  # a real Chromium
@pytest.mark.parametrize("lazy", [False, True], ids=["eager", "lazy"])
def test_keys_timeline_steps_and_expand_all_work_alike_on_both_pages(
        lazy: bool, tmp_path: Path, browser: Any) -> None:  # noqa: F811
    """P2 (lifted; its expansion has 26 nodes and 29 moves, its tree unfolding 41 items), on
    the eager page of its expansion and on the lazy page of the lifted file: ``-`` on the
    root folds the tree to the root and ``+`` unfolds it as it was; Enter on the root's first
    child selects it (its move in the details, the URL fragment names it); clicking the third
    step of the timeline (the first branch, from the Python expansion) selects that step's
    box; *collapse all* leaves the root and its children, *expand all* draws every item: one
    per move plus the root on the eager page (30), the tree unfolding on the lazy one (41)."""
    from selenium.webdriver.common.by import By

    policy = ehatp.solve(load(CUBES / "p2.toml")).policy
    assert policy is not None and policy.symmetry is not None
    e = expanded(policy)
    page = tmp_path / "p2.html"
    page.write_text(to_html(policy, expand_limit=0) if lazy else to_html(e), encoding="utf-8")
    open_page(browser, page)

    def boxes() -> int:
        return len(browser.find_elements(By.CSS_SELECTOR, "#nodes g.node"))

    def action(m: PolicyMove) -> str:
        return m.action + (f" (communication: {m.kind})" if m.kind in COMM_KINDS else "")

    root = '#nodes g.node[data-item="0"]'
    opened = boxes()
    assert opened > 1
    browser.execute_script(KEY, root, "-")
    assert boxes() == 1
    browser.execute_script(KEY, root, "+")
    assert boxes() == opened
    first = e.nodes[0].moves[0]
    child = '#nodes g.node[data-path="0"]' if lazy else f'#nodes g.node[data-node-id="{first.to}"]'
    browser.execute_script(KEY, child, "Enter")
    assert browser.find_element(By.ID, "fact-action").text == action(first)
    assert browser.current_url.endswith("#path=0" if lazy else f"#node={first.to}")
    branch = [first]
    while e.nodes[branch[-1].to].moves:
        branch.append(e.nodes[branch[-1].to].moves[0])
    assert len(branch) > 3
    steps = browser.find_elements(By.CSS_SELECTOR, "#timeline .tl-step")
    assert sorted(s.text for s in steps) == sorted(
        f"{f'c{policy_node_at(policy, i + 1)}' if lazy else f'#{m.to}'}{m.action}"
        for i, m in enumerate(branch))  # while apart, the steps are in lanes, not in order
    third = '[data-step-path="0.0.0"]' if lazy else f'[data-step-node="{branch[2].to}"]'
    browser.find_element(By.CSS_SELECTOR, f"#timeline .tl-step{third}").click()
    assert browser.find_element(By.ID, "fact-action").text == action(branch[2])
    current = browser.find_element(By.CSS_SELECTOR, "#timeline .tl-step.current")
    assert current.get_attribute("data-step-node") == str(
        policy_node_at(policy, 3) if lazy else branch[2].to)
    selected = browser.find_element(By.CSS_SELECTOR, "#nodes g.node.selected")
    assert selected.get_attribute("data-item") == current.get_attribute("data-step-item")
    browser.find_element(By.ID, "collapse-all").click()
    assert boxes() == 1 + len(e.nodes[0].moves)
    browser.find_element(By.ID, "expand-all").click()
    every = policy.tree_size() if lazy else 1 + sum(len(n.moves) for n in e.nodes)
    assert (every, boxes()) == ((41, 41) if lazy else (30, 30))
    count = browser.find_element(By.ID, "node-count").text
    assert count == ("41 of 41 tree items shown" if lazy else "26 of 26 nodes shown")
    errors = [x for x in browser.get_log("browser") if x["level"] == "SEVERE"]
    assert errors == []


def policy_node_at(policy: Policy, depth: int) -> int:
    """The canonical node of a lifted policy reached by ``depth`` first moves."""
    n = 0
    for _ in range(depth):
        n = policy.nodes[n].moves[0].to
    return n
