"""Every Python snippet of docs/modelling.md runs: in order, in one namespace (a snippet may
use what an earlier one declared), as a reader would type them."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parent.parent / "docs" / "modelling.md"
SNIPPETS = re.findall(r"^```python\n(.*?)^```", DOC.read_text(encoding="utf-8"), re.S | re.M)


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
