"""The registry of shipped examples (tests/conftest.py) is whole and true: it lists every problem
file under examples/, each solves to the figures it records, and the README's Table 1 prints
those figures."""

from __future__ import annotations

import re

import pytest

from .conftest import EXAMPLES, EXAMPLES_DIR, ROOT, TABLE1, Example, solved


def test_the_registry_lists_every_shipped_example_once() -> None:
    files = sorted(str(p.relative_to(EXAMPLES_DIR).with_suffix(""))
                   for p in EXAMPLES_DIR.glob("**/*.toml"))
    assert sorted(e.name for e in EXAMPLES) == files
    assert len({e.name for e in EXAMPLES}) == len(EXAMPLES)
    assert [e.table1.instance for e in TABLE1 if e.table1] == [
        "Cooking 1", "Cooking 2", "Cooking 3", "P1", "P2", "P3", "P4", "P5", "P6"]


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_example_solves_to_its_registered_figures(example: Example) -> None:
    got = solved(example)
    problem, policy, result = got.problem, got.policy, got.result
    assert result.status == "solved" and result.optimal
    assert (policy.cost, policy.communications, policy.leaves, result.stats["max_worlds"]) == (
        example.cost, example.communications, example.leaves, example.worlds)
    assert result.stats["cost"] == policy.cost and result.stats["leaves"] == policy.leaves
    if example.table1 is not None:
        row = example.table1
        assert problem.K == row.K and problem.name == row.instance
        assert (result.stats["generated"], result.stats["distinct"]) == (row.generated,
                                                                         row.distinct)


def _readme_table1() -> dict[str, list[str]]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Table 1, reproduced", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        m = re.match(r"(P\d|Cooking \d)\b", cells[0])
        if line.startswith("|") and m:
            rows[m[1]] = cells
    return rows


def test_the_readme_prints_table1_as_the_registry_records_it() -> None:
    rows = _readme_table1()
    assert sorted(rows) == sorted(e.table1.instance for e in TABLE1 if e.table1)
    for e in TABLE1:
        t = e.table1
        assert t is not None
        # inst | states (paper) | distinct | |W| (paper) | leaves (paper) | cost | comm | ...
        assert rows[t.instance][:7] == [
            rows[t.instance][0], f"{t.generated} ({t.paper_states})", str(t.distinct),
            f"{e.worlds} ({t.paper_worlds})", f"{e.leaves} ({t.paper_leaves})", str(e.cost),
            str(e.communications)], t.instance
        assert f"K={t.K}" in rows[t.instance][0]


def test_each_caller_gets_its_own_copy() -> None:
    first = solved("cubes/p2")
    first.policy.nodes.clear()
    first.result.stats["distinct"] = -1
    first.problem.K = 99
    again = solved("cubes/p2")
    assert again.policy.nodes and again.result.stats["distinct"] > 0 and again.problem.K == 2
    assert again.result.policy is again.policy
