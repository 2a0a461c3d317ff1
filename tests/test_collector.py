"""The cyclic garbage collector while a solve runs (search/planner.py, GC_YOUNG): collected a
hundredfold less often during the solve, the caller's setting back afterwards, whatever ends
the solve."""

from __future__ import annotations

import gc
from collections.abc import Iterator
from pathlib import Path

import pytest

import ehatp
from ehatp.errors import InputError
from ehatp.search import andor
from ehatp.search.planner import GC_YOUNG
from ehatp.search.stats import Stats

CUBES = Path(__file__).resolve().parents[1] / "examples" / "cubes"


@pytest.fixture
def default_threshold() -> Iterator[tuple[int, int, int]]:
    """Python's default thresholds for the test, the test runner's put back after it."""
    old = gc.get_threshold()
    gc.set_threshold(700, 10, 10)
    yield (700, 10, 10)
    gc.set_threshold(*old)


def _seen_during(problem: ehatp.Problem, **kw: object) -> set[tuple[int, int, int]]:
    """Return the thresholds in force whenever the solve reported its progress."""
    seen: set[tuple[int, int, int]] = set()

    def progress(stats: Stats, frontier: int) -> None:
        seen.add(gc.get_threshold())

    ehatp.solve(problem, progress=progress, **kw)  # type: ignore[arg-type]
    return seen


def test_the_search_runs_with_the_raised_threshold_and_the_callers_comes_back(
        default_threshold: tuple[int, int, int]) -> None:
    seen = _seen_during(ehatp.load(CUBES / "p4.toml"))
    assert seen == {(GC_YOUNG, 10, 10)}
    assert gc.get_threshold() == default_threshold


def test_a_callers_higher_threshold_is_left_alone(
        default_threshold: tuple[int, int, int]) -> None:
    gc.set_threshold(GC_YOUNG * 2, 5, 5)
    assert _seen_during(ehatp.load(CUBES / "p4.toml")) == {(GC_YOUNG * 2, 5, 5)}
    assert gc.get_threshold() == (GC_YOUNG * 2, 5, 5)


def test_the_threshold_comes_back_after_an_error_and_after_a_limit(
        default_threshold: tuple[int, int, int], monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args: object, **kw: object) -> None:
        raise InputError("x.toml", "[goal]", "a planted error", "none")

    p = ehatp.load(CUBES / "p4.toml")
    assert ehatp.solve(p, max_states=3).status == "state-limit"
    assert gc.get_threshold() == default_threshold
    monkeypatch.setattr(andor, "_expand", broken)
    with pytest.raises(InputError):
        ehatp.solve(p)
    assert gc.get_threshold() == default_threshold
