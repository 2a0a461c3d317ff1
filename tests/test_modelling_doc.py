"""Every Python snippet of docs/modelling.md and docs/modelling-pitfalls.md runs: in order, in one
namespace per document (a snippet may use what an earlier one declared), as a reader would type
them; the pitfalls page's claims are its snippets' asserts, and what it quotes is what they
print."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path
from typing import Any

import pytest

from .scenarios import labels, walk, world_atoms

DOCS = Path(__file__).resolve().parent.parent / "docs"
DOC = DOCS / "modelling.md"
SNIPPETS = re.findall(r"^```python\n(.*?)^```", DOC.read_text(encoding="utf-8"), re.S | re.M)
PITFALLS = DOCS / "modelling-pitfalls.md"


def run(doc: Path) -> tuple[dict[str, Any], str]:
    """Run every Python snippet of ``doc`` in order; the namespace and what they printed."""
    namespace: dict[str, Any] = {"__name__": "modelling_doc"}
    out = io.StringIO()
    text = doc.read_text(encoding="utf-8")
    for i, code in enumerate(re.findall(r"^```python\n(.*?)^```", text, re.S | re.M), 1):
        try:
            with contextlib.redirect_stdout(out):
                exec(compile(code, f"docs/{doc.name} snippet {i}", "exec"), namespace)  # noqa: S102
        except Exception as e:  # noqa: BLE001 - the message says which snippet
            pytest.fail(f"snippet {i} of docs/{doc.name} fails: {type(e).__name__}: {e}\n{code}")
    return namespace, out.getvalue()


def test_the_document_has_snippets() -> None:
    assert len(SNIPPETS) >= 6


def test_every_snippet_runs_in_order() -> None:
    namespace: dict[str, object] = {"__name__": "modelling_doc"}
    for i, code in enumerate(SNIPPETS, 1):
        out = io.StringIO()
        try:
            with contextlib.redirect_stdout(out):
                exec(compile(code, f"docs/modelling.md snippet {i}", "exec"), namespace)  # noqa: S102
        except Exception as e:  # noqa: BLE001 - the message says which snippet
            pytest.fail(f"snippet {i} of docs/modelling.md fails: {type(e).__name__}: {e}\n{code}")


@pytest.mark.parametrize("needle", [
    "put(c: cube, b: box) wants a cube for c",   # the subtype error names the hierarchy
    "'pasta_at = room'",                         # policies print values
])
def test_snippets_print_what_the_comments_say(needle: str) -> None:
    namespace: dict[str, object] = {"__name__": "modelling_doc"}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        for i, code in enumerate(SNIPPETS, 1):
            exec(compile(code, f"docs/modelling.md snippet {i}", "exec"), namespace)  # noqa: S102
    assert needle in out.getvalue()


# -- docs/modelling-pitfalls.md ----------------------------------------------------------------


def test_the_pitfalls_page_runs_and_quotes_what_its_snippets_print() -> None:
    namespace, printed = run(PITFALLS)
    text = PITFALLS.read_text(encoding="utf-8")
    quoted = next(line for line in printed.splitlines() if line.startswith("no policy exists"))
    assert f"```\n{quoted}\n```" in text  # the planner's own words for the committed human
    assert namespace["committed"].status == "unsolvable"


def test_a_committed_human_left_alone_fails_on_its_false_belief() -> None:
    """The page's "without the inform": after walking to the low shelf, the human reaches into
    it; in the step-by-step model the inform leaves it a new choice of shelf."""
    namespace, _ = run(PITFALLS)
    sem, es = walk(namespace["cup_problem"](step_by_step=False), "H walk(low)", "R wait")
    take = next(m for m in sem.moves(es) if m.label == "take(low)")
    assert take.child is None and "false belief" in take.failure
    sem, es = walk(namespace["cup_problem"](step_by_step=False), "H walk(low)",
                   "R inform(not cup_on(low))")
    assert labels(sem, es) == ["pass"]  # informed, it still means to take from the low shelf
    sem, es = walk(namespace["cup_problem"](step_by_step=True), "H walk(low)",
                   "R inform(cup_on(high), not cup_on(low))")
    assert "walk(high)" in labels(sem, es)


def test_without_copresence_the_human_sees_the_robot_from_anywhere() -> None:
    namespace, _ = run(PITFALLS)
    keys = namespace["keys_problem"]
    # with co-presence the move while the human is out is unseen: back, the human still
    # believes the keys are in the tray, and the robot may tell it
    sem, es = walk(keys(copresence=True), "H leave", "R move(tray, box)", "H back")
    assert any("inform(" in label for label in labels(sem, es))
    # without, the human's one world already has them in the box
    sem, es = walk(keys(copresence=False), "H leave", "R move(tray, box)")
    (world,) = world_atoms(sem, es)
    assert "keys_in(box)" in world and "keys_in(tray)" not in world
