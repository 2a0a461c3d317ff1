"""Every policy a tool reads is checked whole first: a mutated policy file is either refused
with one :class:`InputError` line, or read and then shown, drawn and validated without any
other exception (issue 18, "the policy reader is not total")."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ehatp
from ehatp.errors import InputError
from ehatp.formats.policy_check import read_policy
from ehatp.formats.render import to_dot
from ehatp.formats.text import policy_lines

from .conftest import ROOT, solved

P1 = ROOT / "examples/cubes/p1.toml"
P2 = ROOT / "examples/cubes/p2.toml"

JSON = st.recursive(st.none() | st.booleans() | st.integers(-3, 3) | st.floats(allow_nan=False)
                    | st.text(max_size=4),
                    lambda xs: st.lists(xs, max_size=3) | st.dictionaries(st.text(max_size=3),
                                                                          xs, max_size=3),
                    max_leaves=5)


def _paths(x: Any, at: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every place in a JSON value, as a path of keys and indices."""
    out = [at]
    if isinstance(x, dict):
        for k, v in x.items():
            out += _paths(v, (*at, k))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            out += _paths(v, (*at, i))
    return out


def _mutate(doc: Any, path: tuple[Any, ...], value: Any, delete: bool) -> Any:
    """``doc`` with the value at ``path`` replaced by ``value`` (or deleted)."""
    if not path:
        return value
    parent = doc
    for k in path[:-1]:
        parent = parent[k]
    if delete and isinstance(parent, dict):
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return doc


def _policy_text(problem: Path) -> str:
    policy = solved(problem).policy
    assert policy is not None
    return policy.to_json()


@pytest.mark.parametrize("problem", [P1, P2], ids=["p1-v2", "p2-v3"])
@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_mutated_policy_is_refused_in_one_line_or_read_whole(problem: Path, tmp_path: Path,
                                                             data: st.DataObject) -> None:
    text = _policy_text(problem)
    doc = json.loads(text)
    path = data.draw(st.sampled_from(_paths(doc)))
    doc = _mutate(doc, path, data.draw(JSON), data.draw(st.booleans()))
    f = tmp_path / "mutated.json"
    f.write_text(json.dumps(doc), encoding="utf-8")
    try:
        policy = read_policy(f)
    except InputError as e:
        assert "\n" not in str(e) and str(f) in str(e)
        return
    # read: every reader copes (a violation is a verdict, not a crash)
    policy_lines(policy)
    to_dot(policy)
    ehatp.validate(ehatp.load(problem), policy)


@pytest.mark.parametrize(("text", "needle"), [
    ('"worst_case": Infinity', "Infinity is not a number JSON allows"),
    ('"worst_case": NaN', "NaN is not a number JSON allows"),
    # a number too large for a float, which Python's reader turns into infinity
    ('"worst_case": 1e999', "1e999 is too large a number for a policy"),
    ('"objective": true', "objective: must be an object"),
])
def test_numbers_json_does_not_allow_and_wrong_shapes_are_refused_before_reading(
        tmp_path: Path, text: str, needle: str) -> None:
    doc = json.loads(_policy_text(P2))
    key = text.split(":")[0].strip('"')
    doc[key] = "@@"
    f = tmp_path / "p.json"
    f.write_text(json.dumps(doc).replace('"@@"', text.split(": ", 1)[1]), encoding="utf-8")
    with pytest.raises(InputError, match=needle):
        read_policy(f)


def test_the_validator_refuses_a_policy_planned_for_another_domain(tmp_path: Path) -> None:
    doc = json.loads(_policy_text(P2))
    doc["domain"] = "cooking"
    f = tmp_path / "p.json"
    f.write_text(json.dumps(doc), encoding="utf-8")
    report = ehatp.validate(ehatp.load(P2), read_policy(f))
    assert not report.ok and "planned for domain 'cooking', not for 'cubes'" in report.message
