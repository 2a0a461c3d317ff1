"""The JSON Schemas shipped beside the readers (the policy file's, the HDDL sidecar's), and
where a value first fails one, in the words of the other input errors."""

from __future__ import annotations

import json
from collections.abc import Callable
from functools import cache
from importlib import resources
from typing import Any, cast

_SAY = {f"must be {kind}": f"must be {say}" for kind, say in [
    ("integer", "a whole number"), ("number", "a number"), ("string", "a string"),
    ("boolean", "true or false"), ("array", "a list"), ("object", "an object"),
    ("number or null", "a number or null"), ("string or null", "a string or null")]}
"""The schema checker's words for a type, in the words of the other input errors."""


@cache
def _compiled(name: str) -> Callable[[Any], Any]:
    """Return the compiled check of the schema file ``name`` beside this module (compiled
    once per process; the checker is imported on first use, so that ``ehatp --help`` does
    not load it)."""
    import fastjsonschema

    schema = json.loads(resources.files(__package__).joinpath(name).read_text("utf-8"))
    return cast(Callable[[Any], Any], fastjsonschema.compile(schema))


def mismatch(name: str, data: Any) -> tuple[str, str] | None:
    """Return where ``data`` first fails the schema file ``name`` and what is wrong there
    (``("nodes[2]", "must be an object")``; the place is ``""`` for the whole value), or None
    when it matches. Data nested deeper than Python can follow fails at the top."""
    import fastjsonschema

    check = _compiled(name)
    try:
        check(data)
    except fastjsonschema.JsonSchemaValueException as e:
        where = str(e.name or "data")
        place = where[len("data."):] if where.startswith("data.") else ""
        what = str(e.message)
        if what.startswith(where + " "):
            what = what[len(where) + 1:]
        return place, _SAY.get(what, what)[:200]
    except RecursionError:
        return "", "nested too deeply"
    return None


__all__ = ["mismatch"]
