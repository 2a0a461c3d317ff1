"""A set of the human's worlds kept as classes (issue 17 §2; docs/semantics.md §3, "Worlds as
classes"): the container the search's nodes hold instead of listing every world. What the
classes are, and the operations on them, are ``search/worldclasses.py``'s; this module is
only the value, a tuple of representatives with the cells and sizes beside it, so that code
that carries a node's worlds carries it unchanged (a Python class, never compiled: mypyc
compiles no subclass of ``tuple``, docs/compiled.md)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from .state import World, Worlds

Cells = tuple[tuple[int, ...], ...]  # each cell's objects (indices into Symmetry.objects), sorted


class WorldClasses(tuple[World, ...]):
    """A set of worlds kept as classes: the tuple holds each class's representative, sorted;
    ``cells`` the cells of the group, ``mults`` each class's size, ``size`` ``|W|``.

    Equal sets of worlds have equal forms when both have the node's cells (every form the
    search keeps: ``Classer.fit``, search/worldclasses.py), so equality and the hash read the
    form; an order between two sets reads the worlds themselves, as the order of moves by
    their child does (it compares the worlds listed)."""

    cells: Cells
    mults: tuple[int, ...]
    size: int
    classer: Any  # what lists the worlds: search/worldclasses.py, Classer

    def __new__(cls, reps: Iterable[World], cells: Cells, mults: Iterable[int],
                classer: Any) -> WorldClasses:
        self = tuple.__new__(cls, reps)
        self.cells = cells
        self.mults = tuple(mults)
        self.size = sum(self.mults)
        self.classer = classer
        return self

    def __eq__(self, other: object) -> bool:
        if isinstance(other, WorldClasses):
            return self.cells == other.cells and tuple.__eq__(self, other)
        return False

    def __ne__(self, other: object) -> bool:
        return not self == other

    def __hash__(self) -> int:
        return hash((self.cells, tuple.__hash__(self)))

    def _worlds(self, other: object) -> tuple[Worlds, Worlds]:
        mine = self.classer.expand(self)
        theirs = (other.classer.expand(other) if isinstance(other, WorldClasses)
                  else tuple(other))  # type: ignore[arg-type]
        return mine, theirs

    def __lt__(self, other: object) -> bool:
        a, b = self._worlds(other)
        return a < b

    def __le__(self, other: object) -> bool:
        a, b = self._worlds(other)
        return a <= b

    def __gt__(self, other: object) -> bool:
        a, b = self._worlds(other)
        return a > b

    def __ge__(self, other: object) -> bool:
        a, b = self._worlds(other)
        return a >= b

    def __reduce__(self) -> Any:
        return (tuple, (self.classer.expand(self),))


def count(worlds: Worlds) -> int:
    """Return ``|W|``: the number of worlds ``worlds`` holds or stands for."""
    return worlds.size if isinstance(worlds, WorldClasses) else len(worlds)


__all__ = ["Cells", "WorldClasses", "count"]
