"""The fixture layer every test file shares: the shipped examples with the figures solving them
gives, and solved policies cached for the whole session.

- :data:`EXAMPLES` is the one registry of ``examples/**/*.toml`` (``tests/test_examples.py``
  checks it lists every file and that each solves to its figures): worst-case cost,
  communications, leaves and |W| for all; for the nine rows of the paper's Table 1 also K,
  the states generated and distinct (the README's table) and the paper's own figures.
  Parametrise over it with ``@pytest.mark.parametrize("example", EXAMPLES, ids=str)``.
- :func:`solved` solves a problem file once per session (an example, by name or path, or any
  other file such as ``tests/data/cubes-8.toml``) and hands each caller its own copies: a
  freshly loaded problem, a deep copy of the policy and of the statistics. A test may change
  what it gets without changing what the next test sees.

Hand-built problems whose answers are derived by hand are in ``tests/scenarios.py``.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

import ehatp
from ehatp import Policy, Problem, Result

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES_DIR = ROOT / "examples"
DATA = Path(__file__).resolve().parent / "data"


@dataclass(frozen=True)
class Table1:
    """An example's row of the paper's Table 1: ours (with the default symmetry reduction) and
    the paper's published figures."""

    instance: str  # "P2", "Cooking 1": the name `ehatp bench table1` prints
    K: int
    generated: int  # states generated (the README's "states")
    distinct: int  # distinct states
    paper_states: int
    paper_worlds: int
    paper_leaves: int


@dataclass(frozen=True)
class Example:
    """A shipped problem file and what ``ehatp.solve`` gives on it with its own options."""

    name: str  # below examples/, without ".toml": "cubes/p2"
    cost: int  # worst case (every shipped example minimises it)
    communications: int
    leaves: int
    worlds: int  # |W|: the most worlds the human entertains at once (stats["max_worlds"])
    table1: Table1 | None = None

    @property
    def path(self) -> Path:
        return EXAMPLES_DIR / f"{self.name}.toml"

    @property
    def stem(self) -> str:
        return self.name.rsplit("/", 1)[-1]

    @property
    def folder(self) -> str:
        return self.name.split("/", 1)[0]

    def __str__(self) -> str:  # the test id
        return self.name


def _t1(instance: str, K: int, generated: int, distinct: int, paper: tuple[int, int, int]
        ) -> Table1:
    return Table1(instance, K, generated, distinct, *paper)


EXAMPLES: tuple[Example, ...] = (
    Example("communication/late-fatal", 8, 1, 3, 1),
    Example("communication/other-room", 3, 1, 1, 1),
    Example("communication/starts-on-false-belief", 6, 1, 3, 1),
    # preferences (C11): the worst case of the profile's policy; tests/test_domain_metrics.py
    Example("concurrent/stack-prefs", 8, 0, 14, 1),
    Example("concurrent/stack-prefs10", 20, 0, 1440, 1),
    Example("concurrent/stack10", 20, 0, 960, 1),  # joint steps: docs/domains/stacking.md
    Example("concurrent/stack4", 8, 0, 18, 1),  # tests/test_stacking.py derives it
    # Cooking: 2h + 9 with h = 5, 6, 7 human actions (tests/test_cooking.py derives it)
    Example("cooking/cooking1", 19, 0, 12, 4, _t1("Cooking 1", 2, 250, 172, (603, 3, 5))),
    Example("cooking/cooking2", 21, 0, 10, 5, _t1("Cooking 2", 3, 294, 209, (1054, 4, 5))),
    Example("cooking/cooking3", 23, 0, 10, 6, _t1("Cooking 3", 4, 353, 255, (1800, 5, 5))),
    Example("cubes/p1", 13, 0, 4, 4, _t1("P1", 2, 59, 44, (218, 4, 3))),
    Example("cubes/p2", 13, 0, 6, 4, _t1("P2", 2, 87, 60, (236, 4, 3))),
    Example("cubes/p3", 17, 0, 9, 7, _t1("P3", 2, 159, 109, (1643, 7, 6))),
    Example("cubes/p4", 17, 2, 12, 7, _t1("P4", 2, 180, 119, (2003, 7, 6))),
    Example("cubes/p5", 21, 0, 6, 13, _t1("P5", 4, 203, 150, (4107, 14, 5))),
    Example("cubes/p6", 21, 0, 8, 13, _t1("P6", 4, 270, 187, (5607, 14, 5))),
    Example("cubes/qualitative", 4, 1, 2, 2),
    Example("cubes/qualitative-ask", 4, 2, 2, 2),
    Example("cubes/x1-4cubes-k2", 21, 2, 25, 10),
    Example("cubes/x2-4cubes-k4", 25, 2, 14, 28),
    Example("sally-anne/defer", 15, 0, 4, 1),
    Example("sally-anne/inform", 15, 1, 4, 1),
)

# The IPC-2020 HTN track's domains (unified-planning ships them, one problem each) that the
# report (benchmarks/hddl_report.py) imports, solves and validates, the robot alone: each is
# solved, validated and walked on every branch by one test, IPC_LIFTED (those with
# interchangeable objects, written lifted: docs/hddl.md, "Lifted policies") lifted and expanded
# by tests/test_policy_v3.py, the others by tests/test_every_policy_runs.py. All are slow:
# seconds each, Childsnack and Minecraft-Player tens of seconds.
IPC_VALIDATED = ("2020-to-Blocksworld-GTOHP", "2020-to-Factories-simple", "2020-to-Towers",
                 "2020-po-Satellite", "2020-to-Elevator-Learned-ECAI-16", "2020-to-Robot",
                 "2020-to-Transport", "2020-po-Transport", "2020-to-Hiking", "2020-to-Snake",
                 "2020-to-Blocksworld-HPDDL", "2020-to-Multiarm-Blocksworld", "2020-to-Depots",
                 "2020-to-Minecraft-Regular", "2020-to-Rover-GTOHP",
                 "2020-to-AssemblyHierarchical", "2020-to-Logistics-Learned-ECAI-16",
                 "2020-to-Satellite-GTOHP", "2020-po-PCP", "2020-po-Rover",
                 "2020-to-Childsnack", "2020-to-Minecraft-Player")
IPC_LIFTED = ("2020-to-Hiking", "2020-to-Minecraft-Regular", "2020-to-Rover-GTOHP",
              "2020-to-AssemblyHierarchical", "2020-to-Satellite-GTOHP", "2020-to-Childsnack")

# a problem whose search takes seconds and grows past 100 MB (8 cubes, 3 boxes, K=8, without
# the symmetry reduction, docs/semantics.md §3): far more than the limits tests allow it
BIG_POINT = ("cubes", 8, 8, 3)  # domain, K, cubes, boxes


def big_problem(tmp_path: Path) -> Path:
    """Write the big problem (:data:`BIG_POINT`) into ``tmp_path``; return its path."""
    from ehatp.experiments.bench import GridPoint

    domain, K, cubes, boxes = BIG_POINT
    point = GridPoint(domain, K, cubes=cubes, boxes=boxes, transparent=False)
    path = tmp_path / f"{point.name}.toml"
    path.write_text(point.toml() + "\n[limits]\nsymmetry = false\n", encoding="utf-8")
    return path


def policy_text(p: Problem, **options: Any) -> tuple[str, str]:
    """Solve ``p`` with ``options`` (and the agreement benchmark's state limit, 20 s); return
    the status and the policy's JSON without its statistics (two searches that count other
    states write other counts), or the reason there is none."""
    import json

    from ehatp.experiments import agreement

    r = ehatp.solve(p, max_states=agreement.MAX_STATES, timeout=20, **options)
    if r.policy is None:
        return r.status, r.reason
    data = json.loads(r.policy.to_json())
    data.pop("stats")
    return r.status, json.dumps(data, sort_keys=True)


def same_policy_either_way(p: Problem, option: str,
                           symmetries: tuple[bool | None, ...] = (None, False)) -> None:
    """Assert that ``p`` gets the same :func:`policy_text` with the solve option ``option``
    on and off, under each of ``symmetries``."""
    for symmetry in symmetries:
        assert (policy_text(p, **{option: True, "symmetry": symmetry})
                == policy_text(p, **{option: False, "symmetry": symmetry}))


def random_policies_agree(seeds: range, first: dict[str, Any], second: dict[str, Any],
                          symmetries: tuple[bool | None, ...] = (None,)) -> int:
    """Assert that the random problems of ``seeds`` get the same :func:`policy_text` solved
    with the options ``first`` and with ``second`` (each symmetry setting of ``symmetries``;
    a solve stopped by a limit is left out); return how many solved ones were compared."""
    from ehatp.experiments import randomgen

    compared = 0
    for seed in seeds:
        p = randomgen.problem(seed)
        for symmetry in symmetries:
            a = policy_text(p, symmetry=symmetry, **first)
            b = policy_text(p, symmetry=symmetry, **second)
            if "limit" in a[0] or "limit" in b[0] or "timeout" in (a[0], b[0]):
                continue
            assert a == b, (seed, symmetry)
            compared += a[0] == "solved"
    return compared


BRANCHES_FAST = 500
"""Tests that run every branch of every example mark slow the examples of more leaves (the
ten-cube stacking ones): they run in CI, and `make test-fast` stays a quick loop."""


def every_example_by_branch() -> list[Any]:
    """The examples as parameters of a test that runs each branch, ``slow`` past
    :data:`BRANCHES_FAST` leaves."""
    return [pytest.param(e, id=str(e), marks=[pytest.mark.slow] if e.leaves > BRANCHES_FAST
                         else []) for e in EXAMPLES]


TABLE1: tuple[Example, ...] = tuple(e for e in EXAMPLES if e.table1 is not None)
CUBES_TABLE1: tuple[Example, ...] = tuple(e for e in TABLE1 if e.folder == "cubes")


def example(name: str) -> Example:
    """The registered example ``name`` ("cubes/p2", or "p2" where that is unambiguous)."""
    found = [e for e in EXAMPLES if name in (e.name, e.stem)]
    if len(found) != 1:
        raise LookupError(f"no single registered example {name!r}")
    return found[0]


@dataclass(frozen=True)
class Solved:
    """One caller's copies of a solved problem; it unpacks as ``problem, policy``."""

    problem: Problem
    policy: Policy
    result: Result  # status, stats, reason, optimal; its .policy is ``policy``

    def __iter__(self) -> Iterator[Problem | Policy]:
        return iter((self.problem, self.policy))


_SOLVED: dict[tuple[Path, bool], Result] = {}


def _path(which: Example | str | Path) -> Path:
    if isinstance(which, Example):
        return which.path
    if isinstance(which, str):
        return example(which).path
    return which.resolve()


def solved(which: Example | str | Path, *, expand: bool = False) -> Solved:
    """``which`` solved with its own options, once per session; the caller's own copies.
    ``expand``: the policy over the real objects (format version 2) even where the search ran
    over canonical states (:func:`solved_v2`)."""
    path = _path(which)
    result = _SOLVED.get((path, expand))
    if result is None:
        result = ehatp.solve(ehatp.load(path), expand=expand)
        assert result.policy is not None, f"{path}: {result.status}: {result.reason}"
        _SOLVED[(path, expand)] = result
    mine = dataclasses.replace(result, policy=copy.deepcopy(result.policy),
                               stats=copy.deepcopy(result.stats))
    assert mine.policy is not None
    return Solved(ehatp.load(path), mine.policy, mine)


def solved_v2(which: Example | str | Path) -> Solved:
    """:func:`solved` over the real objects (format version 2): for the tests that read or edit
    a policy's labels and states node by node, as a version 2 file has them."""
    return solved(which, expand=True)

