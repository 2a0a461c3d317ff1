"""Whatever the input, every command ends with one line and a documented exit code: 0 ok, 1 no
policy, 2 bad input, 3 internal error. Never a traceback; problem files are data; the README's
set-up works as written."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

import ehatp
from ehatp import DomainError, EhatpError, InputError, Problem
from ehatp.cli import solve as solve_command
from ehatp.cli.app import app
from ehatp.cli.common import user_errors
from ehatp.domains.cubes import make_domain

ROOT = Path(__file__).resolve().parents[1]
CUBES = ROOT / "examples" / "cubes"
P1, P2, P3 = CUBES / "p1.toml", CUBES / "p2.toml", CUBES / "p3.toml"
runner = CliRunner()


def run(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """The real console script, so what reaches the terminal is what a user sees."""
    script = Path(sys.executable).with_name("ehatp")
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "ehatp.cli"]
    return subprocess.run([*cmd, *map(str, args)], capture_output=True, text=True, timeout=120)


def invoke(*args: str | Path) -> tuple[int, str, str]:
    """The CLI in-process; an exception escaping it would be a traceback for a user."""
    r = runner.invoke(app, [str(a) for a in args])
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    return r.exit_code, r.stdout, r.stderr


def one_line(result: tuple[int, str, str] | subprocess.CompletedProcess[str],
             code: int = 2) -> str:
    """Assert the run failed with ``code``, no traceback and exactly one line on stderr."""
    if isinstance(result, subprocess.CompletedProcess):
        result = (result.returncode, result.stdout, result.stderr)
    rc, out, err = result
    assert rc == code, (rc, out, err)
    assert "Traceback" not in out + err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def variant(tmp_path: Path, old: str, new: str, source: Path = P2, name: str = "bad.toml",
            ) -> Path:
    text = source.read_text(encoding="utf-8")
    assert old in text
    f = tmp_path / name
    f.write_text(text.replace(old, new, 1), encoding="utf-8")
    return f


def with_domain(tmp_path: Path, ref: str, code: str | None = None,
                module: str = "mydomain.py") -> Path:
    """P2 with ``[domain] name = ref``, and ``code`` written to ``module`` beside it."""
    if code is not None:
        (tmp_path / module).write_text(code, encoding="utf-8")
    text = P2.read_text(encoding="utf-8")
    text = re.sub(r"(?ms)^\[domain\]\n.*?(?=^\[)", f'[domain]\nname = "{ref}"\n\n', text)
    f = tmp_path / "dom.toml"
    f.write_text(text, encoding="utf-8")
    return f


# --- 1. a binary problem file -----------------------------------------------------------------


def test_binary_problem_file_is_one_line(tmp_path: Path) -> None:
    f = tmp_path / "binary.toml"
    f.write_bytes(b"[problem]\nname = \"x\xff\xfe\"\n\x00\x01")
    line = one_line(run("solve", f))
    assert line.startswith(f"error: {f}:2: ") and "not a UTF-8 text file" in line


@pytest.mark.parametrize("kind", ["empty", "directory", "missing"])
def test_unreadable_problem_file_is_one_line(tmp_path: Path, kind: str) -> None:
    f = tmp_path / "p.toml"
    if kind == "empty":
        f.write_text("", encoding="utf-8")
    elif kind == "directory":
        f.mkdir()
    assert str(f) in one_line(invoke("solve", f))


@pytest.mark.parametrize(("old", "new", "expect"), [
    ('name = "P2"', "name = 3", "[problem] name: expected a string"),
    ('starts = "human"', 'starts = ["human"]', "[problem] starts: expected a string"),
    ("K = 2", "K = 2\nafter = [5]", "[problem] after: expected a list of strings"),
    ('description = "', 'description = 7  # "', "[problem] description: expected a string"),
    ('name = "cubes"', "name = 3", "[domain] name: expected a string"),
    ('cube = ["r", "w"]', 'cube = "r"', "[objects] cube: expected a list of strings"),
    ('robot = ["organize"]', "robot = 5", "[agenda] robot: expected a list of strings"),
    ("[problem]", "beliefs = 5\n[problem]", "beliefs must be a table"),
    ("[agenda]", "[beliefs]\nworld = [1]\n[agenda]", "a world must be a table"),
    ("[agenda]", "[costs]\nactions = 5\n[agenda]", "actions must be a table"),
    ("[agenda]", "[limits]\ntimeout = inf\n[agenda]", "expected a finite number"),
    ("[agenda]", "[limits]\nmax_states = 1.5\n[agenda]", "expected a whole number > 0"),
    ("[agenda]", "[human]\npasses = 5\n[agenda]", "[human] passes: unknown value 5"),
    ("[agenda]", "[objective]\nties = 5\n[agenda]", "[objective] ties: bad tie-breaks"),
    ("[agenda]", "[init.x]\ny = 1\n[agenda]", "[init] x: unknown key 'x'"),
    ("[agenda]", "a = " + "[" * 3000 + "]" * 3000 + "\n[agenda]", "nested too deeply"),
])
def test_wrong_types_in_any_table_are_one_line(tmp_path: Path, old: str, new: str,
                                               expect: str) -> None:
    assert expect in one_line(invoke("solve", variant(tmp_path, old, new)))


def test_a_binary_script_is_one_line(tmp_path: Path) -> None:
    f = tmp_path / "moves.txt"
    f.write_bytes(b"\xff\xfe move")
    assert "not a UTF-8 text file" in one_line(invoke("simulate", P1, "--script", f))


# --- 2. a domain module that raises ----------------------------------------------------------


@pytest.mark.parametrize(("code", "where", "what"), [
    ("from ehatp import Domain\n\ndomain = Domain('x')\nboom = 1 / 0\n", ":4", "ZeroDivisionError"),
    ("def broken(:\n    pass\n", ":1", "SyntaxError"),
    ("from ehatp.model.domain import domain_factory\n\n\n@domain_factory\ndef make():\n"
     "    return {}['x']\n", ":6", "KeyError"),
    ("import no_such_package_for_ehatp\n", ":1", "ModuleNotFoundError"),
])
def test_domain_module_errors_name_the_file_and_line(tmp_path: Path, code: str, where: str,
                                                     what: str) -> None:
    attr = "make" if "def make" in code else "domain"
    f = with_domain(tmp_path, f"mydomain.py:{attr}", code)
    line = one_line(run("solve", f, "--out", tmp_path / "x.json"))
    assert f"{tmp_path / 'mydomain.py'}{where}" in line and what in line
    assert line.startswith(f"error: {f}:")
    assert not (tmp_path / "x.json").exists()


# --- 3. an unbound variable in an effect ------------------------------------------------------


def test_unbound_variable_in_an_effect_is_a_domain_error(tmp_path: Path) -> None:
    code = ("from ehatp import Domain, Var\n\nd = Domain('eff')\nT = d.type('thing')\n"
            "x, y = Var('x', T), Var('y', T)\non = d.predicate('on', x)\n"
            "a = d.robot.action('a', x, effects=[on(y)])\ndomain = d\n")
    f = with_domain(tmp_path, "mydomain.py:domain", code)
    line = one_line(invoke("solve", f))
    assert "action a: an effect uses unbound y" in line and "mydomain.py:7" in line
    assert issubclass(DomainError, EhatpError)  # one exception tree
    with pytest.raises(typer.Exit) as e, user_errors("f.toml"):  # still one line, exit 2
        raise DomainError("predicate on declared twice")
    assert e.value.exit_code == 2


# --- 4. misplaced keys, and the documented example loads ------------------------------------


def test_a_top_level_key_after_a_table_says_to_move_it(tmp_path: Path) -> None:
    f = tmp_path / "late-goal.toml"
    f.write_text(P2.read_text(encoding="utf-8") + '\ngoal = ["in(r, box1)"]\n',
                 encoding="utf-8")
    line = one_line(invoke("solve", f))
    assert "unknown key 'goal' in [agenda]" in line
    assert "move it above the first table ([problem])" in line
    line = one_line(invoke("solve", variant(tmp_path, "K = 2", "K = 2\ntimeout = 5")))
    assert "timeout belongs in [limits]; move it under that header" in line


def _with_tables(base: str, fragment: str) -> str:
    """``base`` with the top-level tables ``fragment`` defines replaced by the fragment's."""
    def table(section: str) -> str:  # "[objective.weights] ..." -> "objective"
        m = re.match(r"\[\[?\s*([^\].]+)", section)
        return m.group(1).strip() if m else ""

    names = {table(s) for s in re.split(r"(?m)^(?=\[)", fragment)} - {""}
    kept = [s for s in re.split(r"(?m)^(?=\[)", base) if table(s) not in names]
    return "".join(kept) + "\n" + fragment


def test_every_toml_block_of_the_problem_format_doc_loads(tmp_path: Path) -> None:
    text = (ROOT / "docs" / "problem-format.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```toml\n(.*?)```", text, re.S)
    assert blocks and "[problem]" in blocks[0]
    for i, block in enumerate(blocks):
        tomllib.loads(block)  # plain TOML
        # a block without [problem] documents some tables: try them in the full example
        whole = block if "[problem]" in block else _with_tables(blocks[0], block)
        f = tmp_path / f"doc{i}.toml"
        f.write_text(whole, encoding="utf-8")
        p = ehatp.load(f)  # raises with the line if the doc drifts from the loader
        assert p.notes == (), p.notes  # and it uses no deprecated spelling


# --- 5. an unreachable goal is named ---------------------------------------------------------


def test_an_unreachable_goal_literal_is_named(tmp_path: Path) -> None:
    f = tmp_path / "unreachable.toml"
    f.write_text('goal = ["on(r, ot)", "in(w, box1)"]\n' + P2.read_text(encoding="utf-8"),
                 encoding="utf-8")
    rc, out, err = invoke("solve", f, "--out", tmp_path / "x.json")
    assert rc == 1 and "Traceback" not in out + err
    first = out.splitlines()[0]
    # the literal first, then one failing line of play only as an example
    assert first.startswith("P2: no policy exists: the goal needs on(r, ot), which holds in "
                            "none of the")
    assert "in(w, box1)" not in first.split("; one failing line:")[0]  # reachable


# --- 6. a Problem built in Python is checked too ---------------------------------------------


@pytest.mark.parametrize(("field", "value", "expect"), [
    ("init", frozenset({("onn", ("r", "mt"))}), "init: unknown predicate 'onn'"),
    ("goal", ((True, ("in", ("r", "box9"))),), "goal: unknown object 'box9'"),
    ("robot_agenda", (("organise", ()),), "R has no task or action 'organise'"),
    ("objects", {"crate": ["c1"]}, "unknown type 'crate'"),
])
def test_a_python_problem_is_checked_like_a_file(field: str, value: object,
                                                 expect: str) -> None:
    kw: dict[str, object] = dict(
        name="py", domain=make_domain(), objects={"cube": ["r"], "box": ["box1"]},
        init=frozenset({("on", ("r", "mt"))}), robot_agenda=(("organize", ()),),
        human_agenda=(("organize", ()),))
    kw[field] = value
    with pytest.raises(InputError) as e:
        ehatp.solve(Problem(**kw))  # type: ignore[arg-type]
    assert expect in str(e.value) and str(e.value).startswith("<python>:")


# --- 7. error lines point at the key --------------------------------------------------------


def test_error_line_is_the_keys_line_not_a_mention_elsewhere(tmp_path: Path) -> None:
    text = P3.read_text(encoding="utf-8")
    assert "K=2" in text.split("K = 2")[0]  # the description mentions K first
    f = variant(tmp_path, "K = 2", "K = -1", P3)
    k_line = next(i for i, s in enumerate(f.read_text().splitlines(), 1) if s.startswith("K ="))
    assert f":{k_line}: [problem] K: K must be a whole number" in one_line(invoke("solve", f))


# --- 8. show and render check the policy file ------------------------------------------------


@pytest.fixture(scope="module")
def p1_policy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("pol") / "p1.json"
    rc, _, _ = invoke("solve", P1, "--out", out)
    assert rc == 0
    return out


@pytest.mark.parametrize(("edit", "expect"), [
    (lambda d: d.update(leaves=99), "leaves: says 99, but the policy has"),
    (lambda d: d["nodes"][1].update(worlds="two"), "nodes[1].worlds: must be a whole number"),
    (lambda d: d["nodes"][1]["moves"][0].update(agent="Z"), "nodes[1].moves[0].agent"),
    (lambda d: d["nodes"][1]["moves"][0].update(cost="1"), "nodes[1].moves[0].cost: must be"),
    (lambda d: d["nodes"][1]["moves"][0].update(to=0), "nodes[1].moves[0].to"),
    (lambda d: d["nodes"][1].update(moves=7), "nodes[1].moves: must be a list"),
    (lambda d: d.update(nodes="none"), "nodes: must be a list"),
    (lambda d: d["nodes"].__setitem__(2, 5), "nodes[2]: must be an object"),
    (lambda d: d.update(stats=[]), "stats: must be an object"),
    (lambda d: d.update(cost=None), "cost: must be a number"),
])
def test_show_and_render_refuse_an_inconsistent_policy(p1_policy: Path, tmp_path: Path,
                                                       edit: object, expect: str) -> None:
    data = json.loads(p1_policy.read_text(encoding="utf-8"))
    edit(data)  # type: ignore[operator]
    f = tmp_path / "edited.json"
    f.write_text(json.dumps(data), encoding="utf-8")
    for command in ("show", "render"):
        line = one_line(invoke(command, f))
        assert line.startswith(f"error: {f}") and expect in line, line


def test_show_and_render_check_the_policys_problem(p1_policy: Path) -> None:
    for command in ("show", "render"):
        line = one_line(invoke(command, p1_policy, "--problem", P2))
        assert "planned for problem 'P1'" in line and str(P2) in line
        rc, out, _ = invoke(command, p1_policy, "--problem", P1)
        assert rc == 0 and out


# --- 9. the program's own faults -------------------------------------------------------------


def test_an_internal_error_is_one_line_naming_the_details_file(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args: object, **kwargs: object) -> None:
        raise ZeroDivisionError("planted bug")

    monkeypatch.setattr(solve_command, "solve", broken)
    line = one_line(invoke("solve", P1), code=3)
    m = re.fullmatch(r"internal error: ZeroDivisionError: planted bug; .*details in (\S+) .*",
                     line)
    assert m, line
    details = Path(m.group(1)).read_text(encoding="utf-8")
    assert "Traceback" in details and "planted bug" in details and "solve" in details
    r = runner.invoke(app, ["--debug", "solve", str(P1)])
    assert r.exit_code == 3 and "Traceback" in r.stderr
    assert r.stderr.strip().splitlines()[-1].startswith("internal error: ZeroDivisionError")


@pytest.mark.parametrize("args", [["solve"], ["solve", "a", "b"], ["frob"], ["--bogus"],
                                  ["bench", "table1", "--repeat", "0"]])
def test_usage_mistakes_are_one_line(args: list[str]) -> None:
    assert "--help" in one_line(invoke(*args))


# --- 10. problem files are data ---------------------------------------------------------------


def test_a_problem_file_cannot_call_os_mkdir(tmp_path: Path) -> None:
    target = tmp_path / "created-by-the-problem"
    f = with_domain(tmp_path, "os:mkdir")
    f.write_text(f.read_text().replace('name = "os:mkdir"',
                                       f'name = "os:mkdir"\npath = "{target}"'))
    line = one_line(run("solve", f))
    assert "[domain] name" in line and "os" in line
    assert not target.exists()


@pytest.mark.parametrize(("ref", "code", "expect"), [
    ("ehatp.formats.problem_toml:load", None, "declared no domain, so it is not imported"),
    ("ehatp.domains.cubes:REGISTRY_OF_NOTHING", None, "has no attribute"),
    ("mydomain.py:make", "def make():\n    open('CALLED', 'w')\n",
     "neither a Domain nor a function marked"),
    ("../mydomain.py:domain", None, "not inside the problem file's folder"),
    ("/etc/mydomain.py:domain", None, "not inside the problem file's folder"),
])
def test_only_a_domain_or_a_marked_factory_is_used(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                  ref: str, code: str | None,
                                                  expect: str) -> None:
    monkeypatch.chdir(tmp_path)
    f = with_domain(tmp_path, ref, code)
    assert expect in one_line(invoke("solve", f))
    assert not (tmp_path / "CALLED").exists()


def test_a_marked_factory_in_a_subfolder_is_used(tmp_path: Path) -> None:
    (tmp_path / "lib").mkdir()
    code = ("from ehatp.domains.cubes import make_domain as cubes\n"
            "from ehatp.model.domain import domain_factory\n\n\n"
            "@domain_factory\ndef make(turn_before_move: bool = False):\n"
            "    return cubes(turn_before_move=turn_before_move)\n")
    f = with_domain(tmp_path, "lib/mydomain.py:make", code, module="lib/mydomain.py")
    assert ehatp.load(f).domain.name == "cubes"


# --- 11. the README works as written ---------------------------------------------------------


def test_readme_activates_the_venv_before_use_and_make_demo_says_so() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    setup, use = readme.split("## Use it", 1)
    assert ". .venv/bin/activate" in setup
    assert re.search(r"(?m)^ehatp solve ", use)
    make = (ROOT / "Makefile").read_text(encoding="utf-8")
    demo = make.split("\ndemo:", 1)[1].split("\n\n", 1)[0]
    assert "bin/activate" in demo
    addopts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"][
        "ini_options"]["addopts"].split()
    assert addopts.count("-q") == 1 and "-rs" in addopts
