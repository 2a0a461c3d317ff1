"""Locate the example problems shipped with ehatp.

A wheel carries them inside the package (``ehatp/examples``, see ``force-include`` in
pyproject.toml); an editable install or a source checkout has them in the repository's
``examples/`` next to ``src/``. Either way callers get a real directory they can pass to
:func:`ehatp.load`.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ExamplesNotFound

_PACKAGE = Path(__file__).resolve().parent.parent  # .../ehatp


def examples_dir() -> Path:
    """The directory holding ``cubes/``, ``cooking/``, ... example problems."""
    shipped = _PACKAGE / "examples"
    if shipped.is_dir():
        return shipped
    # <repo>/src/ehatp -> <repo>/examples; only a few levels up so an unrelated
    # examples/ higher in the file system is never picked by accident
    for parent in list(_PACKAGE.parents)[:3]:
        candidate = parent / "examples"
        if candidate.is_dir() and (parent / "pyproject.toml").is_file():
            return candidate
    raise ExamplesNotFound(
        f"{_PACKAGE}: the example problems are not installed; reinstall ehatp from a wheel "
        "or run it from a source checkout")


def example(relative: str) -> Path:
    """The path of one example, e.g. ``example("cubes/p1.toml")`` (it may not exist yet)."""
    return examples_dir() / relative


__all__ = ["ExamplesNotFound", "example", "examples_dir"]
