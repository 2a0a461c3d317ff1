"""An internal-error report (exit 3) goes to a new file made by :func:`tempfile.mkstemp`:
no name to predict in the shared temporary folder, readable by the user alone
(docs/security.md)."""

from __future__ import annotations

import os
import re
import stat
import tempfile
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ehatp.cli import solve as solve_command
from ehatp.cli.app import app
from ehatp.cli.common import report_file

ROOT = Path(__file__).resolve().parents[1]
P1 = ROOT / "examples" / "cubes" / "p1.toml"
runner = CliRunner()


def test_an_internal_error_report_is_a_new_private_file_each_time(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args: object, **kwargs: object) -> None:
        raise ZeroDivisionError("planted bug")

    monkeypatch.setattr(solve_command, "solve", broken)
    paths = []
    for _ in range(2):
        r = runner.invoke(app, ["solve", str(P1)])
        assert r.exit_code == 3
        m = re.search(r"details in (\S+) ", r.stderr)
        assert m, r.stderr
        paths.append(Path(m.group(1)))
    try:
        assert paths[0] != paths[1]  # the same failure twice: two files, no name to predict
        for p in paths:
            assert p.parent == Path(tempfile.gettempdir())
            assert p.name.startswith("ehatp-internal-error-") and p.suffix == ".txt"
            assert stat.S_IMODE(p.stat().st_mode) == 0o600
            assert "planted bug" in p.read_text(encoding="utf-8")
    finally:
        for p in paths:
            p.unlink(missing_ok=True)


def test_a_report_is_a_file_of_its_own_and_touches_no_file_already_there(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    victim = tmp_path / "victim.txt"
    victim.write_text("keep", encoding="utf-8")
    for i in range(20):  # links planted where a predictable report would go
        (tmp_path / f"ehatp-internal-error-{i}.txt").symlink_to(victim)
    made = report_file("report")
    assert made.parent == tmp_path and not made.is_symlink()
    assert made.read_text(encoding="utf-8") == "report"
    assert stat.S_IMODE(made.stat().st_mode) == 0o600 and made.stat().st_uid == os.getuid()
    assert victim.read_text(encoding="utf-8") == "keep"
