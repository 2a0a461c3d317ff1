"""Run one fuzz case (ehatp.experiments.fuzz) through the command line, in this process:
shared by tests/test_fuzz_inputs.py and benchmarks/fuzz.py."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from typer.testing import CliRunner

from ehatp.cli.app import app


@dataclass(frozen=True)
class Verdict:
    """How a command ended on a case: ``ok`` when the exit code is 0, 1 or 2, exit 2 gave one
    line on stderr, and nothing was raised; ``why`` says what was wrong otherwise."""

    exit_code: int
    ok: bool
    why: str = ""


def run_case(args: Sequence[str], stdin: str | None = None) -> Verdict:
    """Return how ``ehatp ARGS`` (in this process, stdin given) ends: see :class:`Verdict`."""
    r = CliRunner().invoke(app, list(args), input=stdin)
    code = r.exit_code
    if r.exception is not None and not isinstance(r.exception, SystemExit):
        return Verdict(code, False, f"raised {type(r.exception).__name__}: {r.exception}")
    if code not in (0, 1, 2):
        return Verdict(code, False, f"exit {code}: {(r.stderr or r.output).strip()[:300]}")
    if code == 2:
        lines = (r.stderr or "").strip().splitlines()
        if len(lines) != 1:
            return Verdict(code, False, f"exit 2 with {len(lines)} lines: {lines[:3]}")
    return Verdict(code, True)



__all__ = ["Verdict", "run_case"]
