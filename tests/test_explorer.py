"""The HTML explorer (``ehatp render --format html``), in a real Chromium: sibling moves that
read the same are numbered and say what tells them apart, the truth lists the static facts of
``[init]`` (given the problem), and the header gives the worst-case and the expected cost."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from ehatp import load
from ehatp.cli.app import app
from ehatp.experiments.examples import examples_dir
from ehatp.formats.policy import Policy, PolicyMove, PolicyNode
from ehatp.formats.policy_check import check_consistent
from ehatp.formats.render import static_facts, to_html

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
