"""Every mistake in a problem file is one clear line: the file, the place, what to do."""

from __future__ import annotations

from pathlib import Path

import pytest

import ehatp
from ehatp import InputError

EX = Path(__file__).resolve().parents[1] / "examples"
P2 = (EX / "cubes" / "p2.toml").read_text()


def load_text(tmp_path: Path, text: str) -> ehatp.Problem:
    f = tmp_path / "bad.toml"
    f.write_text(text)
    return ehatp.load(f)


def error(tmp_path: Path, text: str) -> str:
    with pytest.raises(InputError) as e:
        load_text(tmp_path, text)
    line = str(e.value)
    assert "\n" not in line and line.startswith(str(tmp_path / "bad.toml"))
    return line


def test_the_shipped_instance_loads(tmp_path: Path) -> None:
    p = load_text(tmp_path, P2)
    assert p.name == "P2" and p.K == 2 and p.starts == "human"
    assert ("on", ("r", "mt")) in p.init


@pytest.mark.parametrize(("old", "new", "expect"), [
    ('"on(r, mt)"', '"onn(r, mt)"', "unknown predicate 'onn'; use one of"),
    ('"on(r, mt)"', '"on(r)"', "on takes 2 argument(s), got 1"),
    ('"on(r, mt)"', '"on(q, mt)"', "unknown object 'q'"),
    ('"on(r, mt)"', '"on(box1, mt)"', "'box1' is a box, but on expects a cube there"),
    ('"on(r, mt)"', '"on(r, mt"', "cannot read atom"),
    ('robot = ["organize"]', 'robot = ["organise"]', "R has no task or action 'organise'"),
    ("K = 2", "K = -1", "K must be a whole number >= 0"),
    ("K = 2", 'K = "two"', "K must be a whole number"),
    ('starts = "human"', 'starts = "alice"', "unknown agent 'alice'"),
    ('name = "cubes"', 'name = "cubez"', "unknown domain 'cubez'"),
    ('name = "cubes"', 'name = "no.such.module:dom"', "declared no domain"),
    ("turn_before_move = false", "turn_before_mov = false", "bad domain options"),
    ('box = ["box1", "box2"]', 'box = ["box1", "box1"]', "declared twice"),
    ('box = ["box1", "box2"]', 'crate = ["box1"]', "unknown type 'crate'"),
    ("[agenda]", "[agendas]", "unknown table or key 'agendas'"),
])
def test_mistakes_name_the_place_and_the_fix(tmp_path: Path, old: str, new: str,
                                              expect: str) -> None:
    assert old in P2
    line = error(tmp_path, P2.replace(old, new, 1))
    assert expect in line


def test_error_points_at_the_line(tmp_path: Path) -> None:
    text = P2.replace('"on(r, mt)"', '"onn(r, mt)"')
    line = error(tmp_path, text)
    lineno = next(i for i, s in enumerate(text.splitlines(), 1) if "onn(r, mt)" in s)
    assert f"bad.toml:{lineno}: [init] true" in line


def test_missing_tables_and_bad_values(tmp_path: Path) -> None:
    assert "missing table [agenda]" in error(tmp_path, P2.split("[agenda]")[0])
    no_init = P2.split("[init]")[0] + "[agenda]" + P2.split("[agenda]")[1]
    assert "missing table [init]" in error(tmp_path, no_init)
    assert "must be positive" in error(tmp_path, P2 + "\n[costs]\ninform = 0\n")
    assert "unknown action 'fly'" in error(tmp_path, P2 + "\n[costs.actions]\nfly = 2\n")
    assert "unknown key 'talk'" in error(tmp_path, P2 + "\n[costs]\ntalk = 2\n")
    assert "expected true or false" in error(
        tmp_path, P2 + '\n[options]\nhuman_passes_when_blocked = "yes"\n')
    assert "not valid TOML" in error(tmp_path, P2 + "\n[costs\n")


def test_beliefs_state_only_real_differences(tmp_path: Path) -> None:
    assert "is already true" in error(tmp_path, P2 + '\n[beliefs]\ntrue = ["on(r, mt)"]\n')
    assert "is already false" in error(tmp_path, P2 + '\n[beliefs]\nfalse = ["in(r, box1)"]\n')
    p = load_text(tmp_path, P2 + '\n[[beliefs.world]]\ntrue = ["in(r, box1)"]\n'
                  'false = ["on(r, mt)", "empty(box1)"]\n\n[[beliefs.world]]\n')
    assert len(p.beliefs) == 2


def test_a_wrong_opening_says_which_step_and_what_was_possible(tmp_path: Path) -> None:
    p = load_text(tmp_path, P2.replace("K = 2", 'K = 2\nafter = ["H move(mt, ot)", "R fly"]'))
    with pytest.raises(InputError) as e:
        ehatp.solve(p)
    msg = str(e.value)
    assert "[problem] after, step 2" in msg and "options: pick(r), wait" in msg


def test_missing_file() -> None:
    with pytest.raises(InputError, match="cannot read the file"):
        ehatp.load("/nonexistent/p.toml")


def test_domain_from_a_python_file_next_to_the_problem() -> None:
    p = ehatp.load(EX / "sally-anne" / "inform.toml")
    assert p.domain.name == "sally-anne"
