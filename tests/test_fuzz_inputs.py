"""Every kind of input file, mutated, ends every command that reads it with exit 0, 1 or 2,
and exit 2 is one line (issue 18: "keep the fuzzers"). A small budget here; benchmarks/fuzz.py
runs thousands of cases (ehatp.experiments.fuzz is shared by both)."""

from __future__ import annotations

import importlib.util
import random
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ehatp
from ehatp.experiments.fuzz import KINDS, Seeds, fuzz_case, mutate_text

from .conftest import ROOT
from .fuzzing import run_case

HDDL = ROOT / "tests" / "data" / "hddl"


@pytest.fixture(scope="module")
def seeds(tmp_path_factory: pytest.TempPathFactory) -> Seeds:
    folder = tmp_path_factory.mktemp("seeds")
    problem = ROOT / "examples" / "cubes" / "p2.toml"
    policy = folder / "p2.json"
    result = ehatp.solve(ehatp.load(problem))
    assert result.policy is not None
    result.policy.write(policy)
    return Seeds(problem, policy, HDDL / "transport-domain.hddl", HDDL / "transport-p1.hddl",
                 HDDL / "transport-sidecar.toml")


def _kinds() -> list[str]:
    if importlib.util.find_spec("unified_planning") is None:
        return [k for k in KINDS if k not in ("sidecar", "hddl")]
    return list(KINDS)


@pytest.mark.parametrize("kind", _kinds())
@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**32 - 1))
def test_a_mutated_input_ends_with_exit_0_1_or_2_and_one_line(
        kind: str, seed: int, seeds: Seeds, tmp_path: Path) -> None:
    args, stdin = fuzz_case(kind, seeds, random.Random(seed), tmp_path)
    verdict = run_case(args, stdin)
    assert verdict.ok, f"{kind} seed {seed}: ehatp {' '.join(args)}: {verdict.why}"


def test_the_mutator_changes_the_text_and_keeps_it_a_string() -> None:
    rng = random.Random(1)
    text = '[problem]\nname = "P"\nK = 2\n'
    out = {mutate_text(text, rng) for _ in range(20)}
    assert len(out) > 15 and text not in out


def test_a_file_that_is_not_a_policy_is_one_line() -> None:
    verdict = run_case(["show", str(ROOT / "README.md")])
    assert verdict.ok and verdict.exit_code == 2


def test_a_crash_is_not_ok(monkeypatch: pytest.MonkeyPatch) -> None:
    # the verdict's own check: a command that raises fails it
    from ehatp.formats import text

    def broken(*args: object, **kwargs: object) -> None:
        raise RuntimeError("a bug")

    monkeypatch.setattr(text, "policy_lines", broken)
    verdict = run_case(["show", str(ROOT / "tests" / "data" / "p4-v1.json")])
    assert not verdict.ok and "RuntimeError" in verdict.why
