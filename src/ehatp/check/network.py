"""Partially ordered agendas as the validator reads them (docs/semantics.md §1, "Partial
order"): a :class:`Block` of tasks with an order between some of them, kept in one canonical
form so that equal task networks are equal blocks, and written as the policy file does.

Part of the independent validator (:mod:`ehatp.check`): written from the document, with plain
sets of position pairs, not from the planner's bitmask networks (:mod:`ehatp.model.agenda`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Block:
    """A partially ordered part of an agenda (§1, "Partial order"): its tasks, and the pairs
    (i, j) of positions where task i comes before task j (transitively closed). Built only by
    :meth:`Network.canon`, so equal task networks are equal blocks."""

    tasks: tuple[int, ...]
    before: frozenset[tuple[int, int]]

    def ready(self) -> list[int]:
        """Return the positions of the tasks no other task of the block comes before."""
        later = {j for _, j in self.before}
        return [i for i in range(len(self.tasks)) if i not in later]


Agenda = tuple["int | Block", ...]


class Network:
    """§1's operations on partially ordered agendas over one problem's ground task names."""

    def __init__(self, task_names: Sequence[str]) -> None:
        self.task_names = task_names

    def canon(self, tasks: Sequence[int], before: set[tuple[int, int]]) -> Agenda:
        """§1 (Partial order): the tasks ``tasks`` under the order ``before`` (pairs of
        positions, transitively closed) as an agenda in canonical form: cut into parts, each
        wholly before the next, as small as possible; a part of one task is that task, a larger
        one a block, its tasks in the order of :meth:`member_order`."""
        out: list[int | Block] = []
        left = list(range(len(tasks)))
        while left:
            # the first part holds a task nothing precedes, and with any task in it every task
            # that does not come after it
            x = next(i for i in left if not any((j, i) in before for j in left))
            part = {x}
            todo = [x]
            while todo:
                y = todo.pop()
                for z in left:
                    if z not in part and (y, z) not in before:
                        part.add(z)
                        todo.append(z)
            keep = [i for i in left if i in part]
            if len(keep) == 1:
                out.append(tasks[keep[0]])
            else:
                order = self.member_order(tasks, before, keep)
                pos = {i: k for k, i in enumerate(order)}
                out.append(Block(tuple(tasks[i] for i in order),
                                 frozenset((pos[i], pos[j]) for i, j in before
                                           if i in pos and j in pos)))
            left = [i for i in left if i not in part]
        return tuple(out)

    def member_order(self, tasks: Sequence[int], before: set[tuple[int, int]],
                     keep: list[int]) -> list[int]:
        """§1: the order of a block's members: by task name; tasks of the same name in the
        order that makes the list, member by member, of the sorted positions of the members
        before it smallest."""
        names = self.task_names
        by_name: dict[str, list[int]] = {}
        for i in keep:
            by_name.setdefault(names[tasks[i]], []).append(i)
        runs = [by_name[n] for n in sorted(by_name)]
        if math.prod(math.factorial(len(r)) for r in runs) > 720:
            # too many orders to try: by rank from below, then from above; only the
            # occurrences whose ranks tie are tried in every order (§1)
            low = self.rank(tasks, keep, lambda a, b: (a, b) in before)
            high = self.rank(tasks, keep, lambda a, b: (b, a) in before)
            split: list[list[int]] = []
            for r in runs:
                for key in sorted({(low[i], high[i]) for i in r}):
                    split.append([i for i in r if (low[i], high[i]) == key])
            runs = split
        best: tuple[list[tuple[int, ...]], list[int]] | None = None
        for choice in itertools.product(*(_orders_up_to_twins(r, tasks, keep, before)
                                          for r in runs)):
            order = [i for run in choice for i in run]
            at = {i: k for k, i in enumerate(order)}
            code = [tuple(sorted(at[j] for j in keep if (j, i) in before)) for i in order]
            if best is None or code < best[0]:
                best = (code, order)
        assert best is not None
        return best[1]

    def rank(self, tasks: Sequence[int], keep: list[int],
             below: Callable[[int, int], bool]) -> dict[int, tuple[int, int]]:
        """§1: each member's rank, ``below(a, b)`` saying a is under b: by the number of
        members under it, then by (its task's name, the sorted ranks of those under it)."""
        under = {i: [j for j in keep if below(j, i)] for i in keep}
        out: dict[int, tuple[int, int]] = {}
        for level in sorted({len(u) for u in under.values()}):
            members = [i for i in keep if len(under[i]) == level]
            key = {i: (self.task_names[tasks[i]], sorted(out[j] for j in under[i]))
                   for i in members}
            values = sorted({(k[0], tuple(k[1])) for k in key.values()})
            for i in members:
                out[i] = (level, values.index((key[i][0], tuple(key[i][1]))))
        return out

    def drop(self, b: Block, i: int) -> Agenda:
        """§1: the block once its task at position ``i`` is done."""
        def at(p: int) -> int:
            return p if p < i else p - 1

        return self.canon([t for p, t in enumerate(b.tasks) if p != i],
                          {(at(x), at(y)) for x, y in b.before if i not in (x, y)})

    def put(self, b: Block, i: int, rest: Agenda) -> Agenda:
        """§1: the block once its task at position ``i`` is refined into ``rest``: the tasks of
        ``rest`` (in its order, a block's in the block's) take its place, keep their own order,
        come after what came before it and before what came after it."""
        new: list[int] = []
        inner: set[tuple[int, int]] = set()
        for it in rest:
            base = len(new)
            if isinstance(it, Block):
                new.extend(it.tasks)
                inner |= {(base + x, base + y) for x, y in it.before}
            else:
                new.append(it)
            inner |= {(p, q) for p in range(base) for q in range(base, len(new))}
        n = len(new)

        def at(p: int) -> int:
            return p if p < i else p + n - 1

        pairs = {(i + x, i + y) for x, y in inner}
        for x, y in b.before:
            if x == i:
                pairs |= {(i + k, at(y)) for k in range(n)}
            elif y == i:
                pairs |= {(at(x), i + k) for k in range(n)}
            else:
                pairs.add((at(x), at(y)))
        tasks = [*b.tasks[:i], *new, *b.tasks[i + 1:]]
        return self.canon(tasks, pairs)

    def shown(self, agenda: Agenda) -> list[str]:
        """An agenda as the policy file writes it: tasks by name, a block in words (§1)."""
        return [self.block_text(t) if isinstance(t, Block) else self.task_names[t]
                for t in agenda]

    def block_text(self, b: Block) -> str:
        """§1: ``{x | y}`` for tasks in any order, ``x < y`` for one before the other, nested;
        an order that is neither as ``{a | b | c | d; a < c, b < c, b < d}``."""
        names = self.task_names

        def linked(i: int, j: int) -> bool:
            return (i, j) in b.before or (j, i) in b.before

        def par(ps: list[int]) -> str:
            groups: list[list[int]] = []
            for p in ps:
                if any(linked(p, q) for g in groups for q in g):
                    touching = [g for g in groups if any(linked(p, q) for q in g)]
                    merged = sorted([p, *(q for g in touching for q in g)])
                    groups = [g for g in groups if g not in touching] + [merged]
                else:
                    groups.append([p])
            groups.sort(key=lambda g: g[0])
            if len(groups) == 1:
                return ser(ps)
            return "{" + " | ".join(ser(g) for g in groups) + "}"

        def ser(ps: list[int]) -> str:
            if len(ps) == 1:
                return names[b.tasks[ps[0]]]
            parts = [[p for p in ps if p in part] for part in self._cuts(b, ps)]
            if len(parts) > 1:
                return " < ".join(par(part) for part in parts)
            pairs = [f"{names[b.tasks[p]]} < {names[b.tasks[q]]}" for p in ps for q in ps
                     if (p, q) in b.before
                     and not any((p, r) in b.before and (r, q) in b.before for r in ps)]
            return "{" + " | ".join(names[b.tasks[p]] for p in ps) + "; " + ", ".join(pairs) + "}"

        return par(list(range(len(b.tasks))))

    @staticmethod
    def _cuts(b: Block, ps: list[int]) -> list[set[int]]:
        """The positions ``ps`` of ``b`` cut into parts each wholly before the next."""
        out: list[set[int]] = []
        left = list(ps)
        while left:
            x = next(i for i in left if not any((j, i) in b.before for j in left))
            part = {x}
            todo = [x]
            while todo:
                y = todo.pop()
                for z in left:
                    if z not in part and (y, z) not in b.before:
                        part.add(z)
                        todo.append(z)
            out.append(part)
            left = [i for i in left if i not in part]
        return out



def _orders_up_to_twins(run: list[int], tasks: Sequence[int], keep: list[int],
                        before: set[tuple[int, int]]) -> list[tuple[int, ...]]:
    """The orders of ``run``, one of each set that only swaps twins (same task, same tasks
    before and after it: swapping them gives the same block)."""
    def twin(i: int) -> tuple[int, frozenset[int], frozenset[int]]:
        return (tasks[i], frozenset(j for j in keep if (j, i) in before),
                frozenset(j for j in keep if (i, j) in before))

    seen: set[tuple[tuple[int, frozenset[int], frozenset[int]], ...]] = set()
    out = []
    for order in itertools.permutations(run):
        look = tuple(twin(i) for i in order)
        if look not in seen:
            seen.add(look)
            out.append(order)
    return out



__all__ = ["Agenda", "Block", "Network"]
