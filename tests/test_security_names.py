"""Names cannot drive a terminal (docs/security.md): a problem, object, task or policy name
holding a control character (ESC included) is refused when the file is read, in one line
``file:place: problem; fix`` with exit 2, and what the commands print shows control characters
escaped."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ehatp.cli import solve as solve_command
from ehatp.cli.app import app
from ehatp.errors import control_char, printable

ROOT = Path(__file__).resolve().parents[1]
P1 = ROOT / "examples" / "cubes" / "p1.toml"
HDDL = ROOT / "tests" / "data" / "hddl"
ESC = "\x1b]0;pwned\x07\x1b[2J"  # set the window title, clear the screen
runner = CliRunner()


def cli(*args: str | Path, stdin: str | None = None) -> subprocess.CompletedProcess[str]:
    """The real command line, as a terminal would receive its bytes."""
    return subprocess.run([sys.executable, "-m", "ehatp.cli", *map(str, args)], input=stdin,
                          capture_output=True, text=True, timeout=120, check=False)


def refused(r: subprocess.CompletedProcess[str], place: str) -> str:
    """Assert ``r`` is one escaped ``error:`` line (exit 2) naming ``place``; return it."""
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert control_char(r.stderr.rstrip("\n")) is None and control_char(r.stdout) is None
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    assert place in lines[0] and "control character" in lines[0], lines[0]
    return lines[0]


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string, control characters as \\u escapes."""
    return json.dumps(text)  # JSON's escapes are TOML's


# --- refused when read ------------------------------------------------------------------------


@pytest.mark.parametrize(("old", "new", "place"), [
    ('name = "P1"', f"name = {toml_string('P1' + ESC)}", "[problem] name"),
    ('cube = ["r", "w"]', f'cube = ["r", {toml_string("w" + ESC)}]', "[objects] cube"),
    ('robot = ["organize"]', f"robot = [{toml_string('organize' + ESC)}]", "[agenda] robot"),
    ('"on(r, mt)"', toml_string("on(r, mt" + ESC + ")"), "[init] true"),
    ('description = "cube', f'description = {toml_string("two" + ESC)}\nx = "cube',
     "[problem] description"),
])
def test_a_problem_name_with_a_control_character_is_refused_in_one_line(
        tmp_path: Path, old: str, new: str, place: str) -> None:
    text = P1.read_text(encoding="utf-8")
    assert old in text
    f = tmp_path / "esc.toml"
    f.write_text(text.replace(old, new, 1), encoding="utf-8")
    line = refused(cli("solve", f, "--out", tmp_path / "p.json"), place)
    assert re.match(rf"error: {re.escape(str(f))}:\d+: ", line) and "\\x1b" in line
    assert not (tmp_path / "p.json").exists()


def test_a_description_may_hold_lines_but_no_escape_code(tmp_path: Path) -> None:
    text = P1.read_text(encoding="utf-8").replace(
        'description = "cube', 'description = """two cubes,\n\ttransparent boxes"""\n#', 1)
    f = tmp_path / "lines.toml"
    f.write_text(text, encoding="utf-8")
    assert cli("solve", f, "--out", tmp_path / "p.json").returncode == 0


def test_a_policy_name_with_a_control_character_is_refused_by_every_command_that_reads_it(
        tmp_path: Path) -> None:
    good = tmp_path / "p1.json"
    assert cli("solve", P1, "--out", good).returncode == 0
    policy = json.loads(good.read_text(encoding="utf-8"))
    policy["nodes"][0]["moves"][0]["action"] += ESC
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(policy), encoding="utf-8")
    for args in (["show", bad], ["render", bad], ["export", "bt", bad], ["validate", P1, bad],
                 ["execute", P1, "--policy", bad],
                 ["expand", bad, "--problem", P1, "--out", tmp_path / "x.json"]):
        refused(cli(*args, stdin=""), str(bad))


def test_an_escaped_backslash_before_letters_is_not_a_control_character(tmp_path: Path) -> None:
    good = tmp_path / "p1.json"
    assert cli("solve", P1, "--out", good).returncode == 0
    policy = json.loads(good.read_text(encoding="utf-8"))
    policy["problem"] = "P1\\n\\u001b"  # backslashes, then letters: printable text
    f = tmp_path / "slashes.json"
    f.write_text(json.dumps(policy), encoding="utf-8")
    r = cli("show", f)
    assert r.returncode == 0 and "P1\\n\\u001b" in r.stdout, r.stderr


def test_an_hddl_sidecar_name_with_a_control_character_is_refused(tmp_path: Path) -> None:
    pytest.importorskip("unified_planning", reason="unified-planning is not installed "
                                                   "(pip install 'ehatp[hddl]')")
    side = tmp_path / "side.toml"
    text = (HDDL / "transport-sidecar.toml").read_text(encoding="utf-8")
    assert "\n[problem]\n" in text
    name = f"\n[problem]\nname = {toml_string('t' + ESC)}\n"
    side.write_text(text.replace("\n[problem]\n", name), encoding="utf-8")
    r = cli("import-hddl", HDDL / "transport-domain.hddl", HDDL / "transport-p1.hddl",
            "--sidecar", side, "--out", tmp_path / "t.py")
    refused(r, str(side))
    assert not (tmp_path / "t.py").exists()


def test_an_hddl_name_with_a_control_character_is_refused_in_one_line(tmp_path: Path) -> None:
    pytest.importorskip("unified_planning", reason="unified-planning is not installed "
                                                   "(pip install 'ehatp[hddl]')")
    prob = tmp_path / "p.hddl"
    prob.write_text((HDDL / "transport-p1.hddl").read_text(encoding="utf-8")
                    .replace("t1 - truck", f"t1{ESC} - truck"), encoding="utf-8")
    r = cli("import-hddl", HDDL / "transport-domain.hddl", prob, "--out", tmp_path / "t.py")
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
    assert control_char(r.stderr.rstrip("\n")) is None
    assert not (tmp_path / "t.py").exists()


# --- printed escaped ------------------------------------------------------------------------


def test_printable_writes_every_control_character_as_its_escape() -> None:
    assert printable("a\x1b[31mb\x07\x9b\x7f\n") == "a\\x1b[31mb\\x07\\x9b\\x7f\\n"
    assert printable("two\n\tlines\x1b", lines=True) == "two\n\tlines\\x1b"
    assert printable("ünïcödé ✓ \u2028") == "ünïcödé ✓ \u2028"


def test_an_error_line_prints_a_file_name_with_its_escape_codes_escaped(tmp_path: Path) -> None:
    r = cli("show", tmp_path / f"missing{ESC}.json")
    assert r.returncode == 2 and "\x1b" not in r.stderr and "\\x1b]0;pwned" in r.stderr


def test_solve_prints_a_name_built_in_python_escaped(monkeypatch: pytest.MonkeyPatch,
                                                     tmp_path: Path) -> None:
    import dataclasses

    real = solve_command.load_problem

    def named(path: Path) -> object:
        return dataclasses.replace(real(path), name="P1" + ESC)

    monkeypatch.setattr(solve_command, "load_problem", named)
    r = runner.invoke(app, ["solve", str(P1), "--out", str(tmp_path / "p.json")])
    assert r.exit_code == 0, r.output
    assert "\x1b" not in r.output and "P1\\x1b]0;pwned" in r.output


def test_execute_echoes_an_input_line_with_no_raw_control_character(tmp_path: Path) -> None:
    policy = tmp_path / "p1.json"
    assert cli("solve", P1, "--out", policy).returncode == 0
    sent = json.dumps({"human": "pick(w\u009b31m\x1b[2J\x7f)"}) + "\n"
    r = cli("execute", P1, "--policy", policy, stdin=sent)
    assert r.returncode == 1, r.stderr
    assert control_char(r.stdout.replace("\n", "")) is None
    messages = [json.loads(line) for line in r.stdout.splitlines()]
    assert any(m.get("action") == "pick(w\u009b31m\x1b[2J\x7f)" for m in messages)
