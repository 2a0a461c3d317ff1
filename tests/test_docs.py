"""The documentation is true where a test can tell: every TOML block of every page under docs/
reads as what it shows, every page cites only files inside the repository, and the figures the
pages print are the planner's.

A TOML block is a whole problem file unless the line before it says otherwise:
``<!-- toml: part of a problem -->`` (its tables are applied to ``examples/cubes/p2.toml`` as a
sweep applies overrides), ``<!-- toml: import-hddl sidecar -->`` or ``<!-- toml: sweep grid -->``.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

import ehatp
from ehatp.experiments.sweep import check_grid, combinations, read_grid
from ehatp.formats.hddl_sidecar import read_sidecar
from ehatp.formats.problem_toml import loads

from .conftest import EXAMPLES_DIR, ROOT, example, solved

DOCS = ROOT / "docs"
PAGES = sorted(DOCS.glob("**/*.md"))
KINDS = ("problem", "part of a problem", "import-hddl sidecar", "sweep grid")
BLOCK = re.compile(r"(?:^<!-- toml: (?P<kind>[^>]*?) -->\n)?^```toml\n(?P<text>.*?)^```",
                   re.S | re.M)
P2 = EXAMPLES_DIR / "cubes" / "p2.toml"


def blocks() -> Iterator[Any]:
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for m in BLOCK.finditer(text):
            line = text.count("\n", 0, m.start("text")) + 1
            name = f"{page.relative_to(DOCS)}:{line}"
            yield pytest.param(m["kind"] or "problem", m["text"], id=name)


BLOCKS = list(blocks())


def flat(table: dict[str, Any], at: tuple[str, ...] = ()) -> Iterator[tuple[str, Any]]:
    """A TOML table as dotted keys, ``{"human.passes": "fair"}``."""
    for k, v in table.items():
        if isinstance(v, dict):
            yield from flat(v, (*at, k))
        else:
            yield ".".join((*at, k)), v


def test_the_documentation_has_toml_blocks_of_every_kind() -> None:
    kinds = {p.values[0] for p in BLOCKS}
    assert kinds == set(KINDS)
    names = [p.id for p in BLOCKS]
    assert any(n.startswith("problem-format.md:") for n in names)


@pytest.mark.parametrize(("kind", "text"), BLOCKS)
def test_every_toml_block_of_the_docs_reads_as_what_it_shows(kind: str, text: str,
                                                            tmp_path: Path) -> None:
    assert kind in KINDS, f"unknown marker <!-- toml: {kind} -->; use one of {KINDS}"
    f = tmp_path / "block.toml"
    f.write_text(text, encoding="utf-8")
    if kind == "problem":
        problem = ehatp.load(f)
        assert problem.domain is not None
    elif kind == "part of a problem":
        overrides = dict(flat(tomllib.loads(text)))
        assert overrides
        ehatp.load(P2, overrides=overrides)
    elif kind == "import-hddl sidecar":
        read_sidecar(f)
    else:
        check_grid(read_grid(f), f, [P2])


def test_the_main_example_of_problem_format_loads_with_what_it_says() -> None:
    text = (DOCS / "problem-format.md").read_text(encoding="utf-8")
    main = next(m["text"] for m in BLOCK.finditer(text) if "[problem]" in m["text"])
    problem = loads(main, Path("problem-format.toml"))
    assert (problem.name, problem.K, problem.starts) == ("P2", 2, "human")
    assert problem.after == ("H move(mt, ot)", "R pick(r)")
    assert problem.costs.actions == {"place": 2}


def test_the_sweep_page_counts_its_grid_right() -> None:
    text = (DOCS / "sweep.md").read_text(encoding="utf-8")
    grid = next(m["text"] for m in BLOCK.finditer(text) if m["kind"] == "sweep grid")
    f = ROOT / "docs" / "sweep.md"
    n = len(combinations(dict(flat(tomllib.loads(grid)))))
    assert f"= {n} variants of each file" in f.read_text(encoding="utf-8")


# -- citations ---------------------------------------------------------------------------------

# the specification the project was built from, and relative paths in code spans (links are
# resolved below)
OUTSIDE = re.compile(r"shared/spec|paper-domains\.md|`\.\./")
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


@pytest.mark.parametrize("page", [*PAGES, ROOT / "README.md", ROOT / "CHANGELOG.md"],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_no_page_cites_a_file_outside_the_repository(page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    found = [m[0] for m in OUTSIDE.finditer(text)]
    assert not found, f"{page.name} cites files outside the repository: {found}"
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):  # https:, mailto:
            continue
        path = (page.parent / target).resolve()
        assert path.is_relative_to(ROOT) and path.exists(), (page.name, target)


# -- figures the pages print ---------------------------------------------------------------------


def test_the_notebook_page_prints_p2_s_figures() -> None:
    text = (DOCS / "notebook.md").read_text(encoding="utf-8")
    p2 = example("cubes/p2")
    result = solved(p2).result
    shown = (result.stats["distinct"], result.policy.cost, result.policy.leaves)  # type: ignore[union-attr]
    assert shown == (p2.table1.distinct, p2.cost, p2.leaves)  # type: ignore[union-attr]
    assert f"Out[2]: {shown}" in text
    assert f"worst-case cost {p2.cost} · {p2.leaves} branches" in text


ROOTS = ("src", "tests", "docs", "examples", "benchmarks", "model", "epistemic", "search",
         "check", "formats", "run", "experiments", "cli", "domains")
CITED_FILE = re.compile(rf"`((?:{'|'.join(ROOTS)})(?:/[\w.-]+)+\.(?:py|md|toml|json|hddl))`")


@pytest.mark.parametrize("page", [*PAGES, ROOT / "README.md"],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_every_file_a_page_names_exists(page: Path) -> None:
    """A path in a code span (`tests/test_bt.py`, `search/heuristic.py`) names a file of the
    repository: from its root or from src/ehatp/."""
    missing = [name for name in CITED_FILE.findall(page.read_text(encoding="utf-8"))
               if not any((base / name).exists()
                          for base in (ROOT, ROOT / "src" / "ehatp"))]
    assert not missing, f"{page.name} names files that do not exist: {missing}"
