"""Mutated input files for every command that reads one, and what a command may do with them.

Every file a user hands ehatp -- a problem, a policy, an HDDL domain, a sidecar, the JSON lines
of ``ehatp execute`` -- is data. Whatever it holds, a command ends with exit 0, 1 or 2; exit 2
is one line on stderr (``FILE:PLACE: problem; fix``); nothing else (exit 3 is ehatp's own
fault, a traceback a crash). The property tests (tests/test_fuzz_inputs.py) run a small budget
of these cases in the suite; ``benchmarks/fuzz.py`` runs thousands (both run a case with
``tests/fuzzing.py``'s ``run_case``: the command line is above this layer).

A case is a text mutated from a valid seed file (:func:`mutate_text`: cut, repeat, insert
syntax and hostile values) or, for JSON, a value replaced deep inside (:func:`mutate_json`);
a compressed policy has its text mutated, or its gzip bytes changed and cut.
"""

from __future__ import annotations

import gzip
import json
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any

SNIPPETS = (
    "[", "]", "{", "}", "(", ")", "=", ",", '"', "'", "\n", "\\", "?", "-", ":", "#", ".",
    "0", "-1", "1e309", "99999999999999999999", "NaN", "Infinity", "true", "null", "[[", "]]",
    "\x1b[31m", "\x00", "\u2028", '"""', "</script>", "not ", "and", "or", "*", "..", "K",
    "[[" * 40, "]]" * 40, "{" * 40, "(" * 40, "x" * 300,
)
"""What :func:`mutate_text` inserts: syntax, hostile values, deep nesting, long names."""


def mutate_text(text: str, rng: random.Random, edits: int = 3) -> str:
    """Return ``text`` with ``edits`` random edits: a slice cut, a slice repeated, a snippet
    (:data:`SNIPPETS`) or a random character inserted, a number replaced by an extreme one."""
    for _ in range(edits):
        n = len(text)
        i = rng.randrange(n + 1)
        j = min(n, i + rng.randrange(1, 40))
        kind = rng.randrange(5)
        if kind == 0:
            text = text[:i] + text[j:]
        elif kind == 1:
            text = text[:j] + text[i:j] + text[j:]
        elif kind == 2:
            text = text[:i] + rng.choice(SNIPPETS) + text[i:]
        elif kind == 3:
            text = text[:i] + chr(rng.randrange(1, 0x250)) + text[i:]
        else:
            digits = [k for k, c in enumerate(text) if c.isdigit()]
            if digits:
                k = rng.choice(digits)
                text = text[:k] + rng.choice(("-7", "0", "1e400", "4294967297", "0.5")) + \
                    text[k + 1:]
    return text


def _places(x: Any, at: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [at]
    if isinstance(x, dict):
        for k, v in x.items():
            out += _places(v, (*at, k))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            out += _places(v, (*at, i))
    return out


def _value(rng: random.Random, depth: int = 0) -> Any:
    kind = rng.randrange(9 if depth < 3 else 7)
    if kind == 0:
        return None
    if kind == 1:
        return rng.choice((True, False))
    if kind == 2:
        return rng.choice((0, -1, 1, 2**64, 3))
    if kind == 3:
        return rng.choice((0.5, -0.0, 1e300))
    if kind in (4, 5):
        return rng.choice(("", "x", "pick(r)", "\x1b[2J", "a" * 500, "R", "nodes"))
    if kind == 6:
        return []
    if kind == 7:
        return [_value(rng, depth + 1) for _ in range(rng.randrange(3))]
    return {rng.choice(("id", "moves", "to", "x")): _value(rng, depth + 1)
            for _ in range(rng.randrange(3))}


def mutate_json(doc: Any, rng: random.Random, edits: int = 2) -> Any:
    """Return ``doc`` (a parsed JSON value, changed in place) with ``edits`` values replaced
    by random ones, or deleted from their object, anywhere in it."""
    for _ in range(edits):
        places = _places(doc)
        path = rng.choice(places)
        if not path:
            return _value(rng)
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        if isinstance(parent, dict) and rng.random() < 0.3:
            del parent[path[-1]]
        else:
            parent[path[-1]] = _value(rng)
    return doc


KINDS = ("problem", "policy", "policy-json", "policy-gz", "sidecar", "hddl", "execute")
"""The kinds of input :func:`fuzz_case` mutates."""


@dataclass(frozen=True)
class Seeds:
    """The valid files cases are mutated from: a problem, its policy, an HDDL domain and
    problem with a sidecar."""

    problem: Path
    policy: Path
    hddl_domain: Path
    hddl_problem: Path
    sidecar: Path


def fuzz_case(kind: str, seeds: Seeds, rng: random.Random,
              folder: Path) -> tuple[list[str], str | None]:
    """Write one mutated input of ``kind`` (:data:`KINDS`) into ``folder`` and return the
    command line that reads it and its stdin (the HDDL kinds need ``ehatp[hddl]``)."""
    out = str(folder / "out")
    if kind == "problem":
        f = folder / "p.toml"
        f.write_text(mutate_text(seeds.problem.read_text(encoding="utf-8"), rng,
                                 edits=rng.randrange(1, 4)), encoding="utf-8")
        return ["solve", str(f), "--timeout", "5", "--max-states", "3000",
                "--out", out + ".json"], None
    if kind in ("policy", "policy-json", "policy-gz"):
        text = seeds.policy.read_text(encoding="utf-8")
        if kind == "policy-gz":  # a compressed policy: its text mutated, or its bytes
            f = folder / "p.json.gz"
            of_text = rng.randrange(2) == 1
            data = bytearray(gzip.compress(
                (mutate_text(text, rng) if of_text else text).encode("utf-8"), mtime=0))
            for _ in range(0 if of_text else rng.randrange(1, 4)):
                i = rng.randrange(len(data))
                if rng.randrange(2):
                    data[i] = rng.randrange(256)
                else:
                    del data[i:i + rng.randrange(1, 40)]
            f.write_bytes(bytes(data))
        else:
            if kind == "policy":
                text = mutate_text(text, rng, edits=rng.randrange(1, 4))
            else:
                text = json.dumps(mutate_json(json.loads(text), rng, edits=rng.randrange(1, 3)))
            f = folder / "p.json"
            f.write_text(text, encoding="utf-8")
        command = rng.choice((["show", str(f)], ["validate", str(seeds.problem), str(f)],
                              ["render", str(f), "--format", "dot", "--out", out + ".dot"],
                              ["export", "bt", str(f), "--out", out + ".xml"]))
        return command, None
    if kind == "sidecar":
        f = folder / "side.toml"
        f.write_text(mutate_text(seeds.sidecar.read_text(encoding="utf-8"), rng),
                     encoding="utf-8")
        return ["import-hddl", str(seeds.hddl_domain), str(seeds.hddl_problem), "--sidecar",
                str(f), "--out", out + ".py"], None
    if kind == "hddl":
        f = folder / "d.hddl"
        f.write_text(mutate_text(seeds.hddl_domain.read_text(encoding="utf-8"), rng),
                     encoding="utf-8")
        return ["import-hddl", str(f), str(seeds.hddl_problem), "--out", out + ".py"], None
    if kind == "execute":
        lines = ['{"human": "pick(w)"}', '{"robot_done": true}', '{"human": "pass"}',
                 '{"robot_failed": "pick(r)"}', '{"robot_done": "place(r, box1)"}']
        chosen = [mutate_text(rng.choice(lines), rng, edits=rng.randrange(3))
                  for _ in range(rng.randrange(1, 6))]
        return ["execute", str(seeds.problem), "--policy", str(seeds.policy)], \
            "\n".join(chosen) + "\n"
    raise ValueError(f"unknown kind {kind!r}; use one of {', '.join(KINDS)}")


__all__ = ["KINDS", "SNIPPETS", "Seeds", "fuzz_case", "mutate_json", "mutate_text"]
