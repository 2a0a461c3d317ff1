"""``show`` and ``render`` refuse a hand-edited policy that contradicts itself (a value, who
moves, a goal, the worlds against the state, a move's text, the K-counter, the header's
costs) or that was planned for another problem: one line, exit 2."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from ehatp.cli.app import app
from ehatp.errors import InputError
from ehatp.experiments.examples import examples_dir
from ehatp.formats.policy_check import check_consistent, read_policy

CUBES = examples_dir() / "cubes"
FIX = ("give the policy `ehatp solve` wrote, unedited (`ehatp validate PROBLEM POLICY` checks "
       "every rule)")
runner = CliRunner()


def invoke(*args: str | Path) -> typer.testing.Result:
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def p2(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Return P2's lifted policy (26 nodes) as JSON data."""
    out = tmp_path_factory.mktemp("p2") / "p2.json"
    assert invoke("solve", CUBES / "p2.toml", "--out", out).exit_code == 0
    data: dict[str, Any] = json.loads(out.read_text(encoding="utf-8"))
    return data


def set_value(i: int, v: int) -> Callable[[dict[str, Any]], None]:
    def edit(d: dict[str, Any]) -> None:
        d["nodes"][i]["value"] = v
    return edit


def set_field(key: str, v: Any) -> Callable[[dict[str, Any]], None]:
    def edit(d: dict[str, Any]) -> None:
        d[key] = v
    return edit


def set_node(i: int, key: str, v: Any) -> Callable[[dict[str, Any]], None]:
    def edit(d: dict[str, Any]) -> None:
        d["nodes"][i][key] = v
    return edit


def drop_atom(i: int, atom: str) -> Callable[[dict[str, Any]], None]:
    def edit(d: dict[str, Any]) -> None:
        d["nodes"][i]["state"].remove(atom)
    return edit


def set_action(i: int, j: int, text: str) -> Callable[[dict[str, Any]], None]:
    def edit(d: dict[str, Any]) -> None:
        d["nodes"][i]["moves"][j]["action"] = text
    return edit


# P2: the human moves to the other table (node 1, value 8) or passes; node 2, apart, the
# human entertains 2 worlds, one where the robot still holds nothing (holding(R, r) false
# unlike the truth); node 7 is the goal; K = 2; worst case 13, expected 9.5
EDITS: list[tuple[str, Callable[[dict[str, Any]], None], str]] = [
    ("a node's value", set_value(1, 9),
     "nodes[1].value: is 9, but its worst move costs 8 to the goal (move cost plus the next "
     "node's value)"),
    ("the header's cost", set_field("cost", 12), "cost: says 12, but the root's value is 13"),
    ("the header's worst case", set_field("worst_case", 14),
     "worst_case: says 14, but the policy's worst branch costs 13"),
    ("the header's expected cost", set_field("expected", 9),
     "expected: says 9, but the policy's expected cost is 9.5"),
    ("who moves", set_node(0, "to_move", "R"),
     "nodes[0].to_move: says 'R' moves, but the moves are H's"),
    ("the state under the worlds", drop_atom(2, "holding(R, r)"),
     "nodes[2].world_diffs[1].false: 'holding(R, r)' is listed as false unlike the truth, but "
     "the node's state does not hold it"),
    ("a move's text", set_action(1, 0, "place(r)"),
     "nodes[1].moves[0].action: 'place(r)' is not a move named 'pick', as its name says"),
    ("a goal", set_node(7, "goal", False),
     "nodes[7].goal: a node without moves ends a branch, so it is a goal, but goal is false"),
    ("the K-counter over K", set_node(4, "k", 3),
     "nodes[4].k: 3 robot turns unseen is over the bound K = 2"),
    ("the K-counter while together", set_node(5, "k", 1),
     "nodes[5].k: is 1, but the agents are together, where the counter is 0"),
    ("the number of worlds", set_node(2, "worlds", 3),
     "nodes[2].worlds: says 3, but world_diffs lists 2"),
]


def edited(p2: dict[str, Any], tmp_path: Path, edit: Callable[[dict[str, Any]], None]) -> Path:
    data = json.loads(json.dumps(p2))
    edit(data)
    f = tmp_path / "edited.json"
    f.write_text(json.dumps(data), encoding="utf-8")
    return f


@pytest.mark.parametrize(("what", "edit", "line"), EDITS, ids=[e[0] for e in EDITS])
def test_show_refuses_a_policy_edited_into_contradiction(
        p2: dict[str, Any], tmp_path: Path, what: str, edit: Callable[[dict[str, Any]], None],
        line: str) -> None:
    f = edited(p2, tmp_path, edit)
    r = invoke("show", f)
    assert r.exit_code == 2
    assert r.stderr == f"error: {f}:{line} (the file contradicts itself); {FIX}\n"
    assert r.stdout == ""


@pytest.mark.parametrize(("what", "edit", "line"), [EDITS[0], EDITS[5], EDITS[6]],
                         ids=[EDITS[i][0] for i in (0, 5, 6)])
def test_render_refuses_a_policy_edited_into_contradiction(
        p2: dict[str, Any], tmp_path: Path, what: str, edit: Callable[[dict[str, Any]], None],
        line: str) -> None:
    f = edited(p2, tmp_path, edit)
    for fmt in ("dot", "html"):
        r = invoke("render", f, "--format", fmt, "--out", tmp_path / f"out.{fmt}")
        assert r.exit_code == 2
        assert r.stderr == f"error: {f}:{line} (the file contradicts itself); {FIX}\n"
        assert not (tmp_path / f"out.{fmt}").exists()


def test_show_and_render_refuse_a_policy_for_another_problem(p2: dict[str, Any],
                                                             tmp_path: Path) -> None:
    f = edited(p2, tmp_path, lambda d: None)
    for command in ("show", "render"):
        r = invoke(command, f, "--problem", CUBES / "p4.toml")
        assert r.exit_code == 2
        assert r.stderr == (
            f"error: {f}:problem: planned for problem 'P2', but {CUBES / 'p4.toml'} has 'P4'; "
            f"give the policy solved for that problem (ehatp solve {CUBES / 'p4.toml'} --out "
            f"{f})\n")


def test_an_unedited_policy_is_consistent_in_every_objective(tmp_path: Path) -> None:
    for name, extra in [("p4", []), ("p4-expected", ["--objective", "expected"]),
                        ("p4-expanded", ["--expand"])]:
        out = tmp_path / f"{name}.json"
        assert invoke("solve", CUBES / "p4.toml", "--out", out, *extra).exit_code == 0
        check_consistent(read_policy(out), str(out))  # no error


def test_an_expected_cost_policy_with_an_edited_value_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "p2-expected.json"
    assert invoke("solve", CUBES / "p2.toml", "--objective", "expected", "--out",
                  out).exit_code == 0
    data = json.loads(out.read_text(encoding="utf-8"))
    # the root: the human moves (1 + 7) or passes (1 + 10), with equal weights: 9.5
    assert [n["value"] for n in data["nodes"][:1]] == [9.5]
    data["nodes"][0]["value"] = 11
    data["cost"] = 11
    out.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(InputError) as e:
        check_consistent(read_policy(out), str(out))
    assert e.value.line() == (
        f"{out}:nodes[0].value: is 11, but its moves' mean cost to the goal is 9.5 (move cost "
        f"plus the next node's value) (the file contradicts itself); {FIX}")
