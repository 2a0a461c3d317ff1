"""The Python source an HDDL import writes (:mod:`ehatp.formats.hddl`): identifiers made from
HDDL names, unique and readable, and string literals that carry any name as data (docs/security.md:
a string from a file reaches generated code only as an escaped literal)."""

from __future__ import annotations

import keyword
import re
from collections.abc import Sequence

_TAKEN = {"d", "m", "Domain", "Var", "TRUE", "FALSE", "eq", "exists", "forall", "when",
          "for_each", "observable", "HIDDEN", "INFERABLE", "domain_factory", "make_domain",
          "annotations", "Path", "run_sidecar"}


class _Names:
    """Python identifiers for the module, unique, readable (``get-to`` -> ``get_to``)."""

    def __init__(self) -> None:
        self.used: set[str] = set(_TAKEN)
        self.of: dict[tuple[str, str], str] = {}

    def get(self, kind: str, name: str, hint: str = "", base: str = "") -> str:
        """The identifier of ``name`` (a ``kind`` of thing), made from ``base`` (default the
        name); on a clash the ``hint`` (default the kind) is appended, then a number."""
        key = (kind, name)
        got = self.of.get(key)
        if got is None:
            base = _ident(base or name)
            cand = base
            if cand in self.used:
                cand = f"{base}_{_ident(hint or kind)}"
            k = 2
            while cand in self.used:
                cand = f"{base}_{k}"
                k += 1
            self.used.add(cand)
            got = self.of[key] = cand
        return got


def _ident(name: str) -> str:
    s = re.sub(r"\W", "_", name) or "x"
    if s[0].isdigit():
        s = "_" + s
    if keyword.iskeyword(s) or keyword.issoftkeyword(s):
        s += "_"
    return s


def _isort(name: str) -> tuple[int, str]:
    """isort's order inside one import: constants, classes, then functions."""
    return (0 if name.isupper() else 1 if name[:1].isupper() else 2), name


def _q(s: str) -> str:
    """A Python (and TOML basic) string literal: backslashes and quotes escaped, and every
    control or line-separating character as a ``\\uXXXX`` escape, which both languages read
    back as that character (so the literal never ends early, in either file)."""
    body = s.replace("\\", "\\\\").replace('"', '\\"')
    return '"' + _UNSAFE_IN_LITERAL.sub(lambda m: f"\\u{ord(m.group()):04x}", body) + '"'


_UNSAFE_IN_LITERAL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def _py(name: str, args: Sequence[str]) -> str:
    """A call in the module: ``at(x, "l1")``, ``busy()``."""
    return f"{name}({', '.join(args)})"


def _call(name: str, args: Sequence[str]) -> str:
    return f"{name}({', '.join(args)})" if args else name
