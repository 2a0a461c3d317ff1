"""The transition rules on worlds kept as classes (issue 17 §2; docs/semantics.md §3, "Worlds
as classes"; the representation is :mod:`.worldclasses`).

A node's worlds are the orbits of its representatives under a group ``G`` of renamings that
leave the node as it is; every rule commutes with an automorphism of the problem (§3,
"Symmetry"). Where a rule updates ``W`` world by world, it is applied to the representatives
alone, by these facts:

- *The robot's unseen moves* (the product, §4) read ``W`` alone: ``product(G·r)`` is
  ``G·product(r)`` (``product(g·w) = g·product(w)``), so the product of a class is the classes
  of its representative's successors under ``G``.
- *Situation assessment* keeps the worlds that agree with the true state ``t`` on what the
  human sees: under the part of ``G`` that fixes ``t`` (``G`` with its cells split where
  ``t`` tells objects apart, :meth:`~.worldclasses.Classer.refine`), which fixes what the
  human sees, a world is kept exactly when its representative is.
- *The human's action while apart* applies one operator to every world: under the part of
  ``G`` that fixes the objects it names, which fixes the operator, it is applied to the
  representatives (:meth:`ClassSemantics.human_exec`).
- *The human's options while apart* are those certain in every world: when no condition its
  refinement reads up to its first actions names an atom of an object in a cell, each such
  condition has one value over a class, so they are read on the representatives' states
  (:meth:`ClassSemantics._options_blind`).

When no world agrees (a revision, §2), the non-anticipating human's "sees it done" (§4), and at
every other node where a rule reads ``W`` as a whole (the human's options otherwise, speech,
the rules while together, the goal), the worlds are listed
(:meth:`~.worldclasses.Classer.expand`) and the rules of :class:`~.symmetry.SymSemantics`
applied as they are: their results are put back into
classes by the canonical form (:meth:`~.worldclasses.ClassSymmetry.canon`). The result is the
search over listed worlds, node for node: the same canonical renamings, the same policies.
"""

from __future__ import annotations

from dataclasses import replace

from ..epistemic.classworlds import WorldClasses
from ..epistemic.semantics import ACTION, WAIT, Move
from ..epistemic.state import HUMAN, ROBOT, EState, Worlds
from ..model.agenda import Agenda
from ..model.formula import Formula, ground_atoms
from ..model.grounded import FINISH, GOp, Grounded
from ..model.options import Passes, Speech
from .symmetry import SymSemantics
from .worldclasses import ClassSymmetry


def _atoms(f: Formula) -> int:
    """The atoms ground formula ``f`` reads, as a mask."""
    mask = 0
    for i in ground_atoms(f):
        mask |= 1 << i
    return mask


PRODUCT_CACHE = 1 << 14
"""How many sets of classes :meth:`ClassSemantics._lift_product` remembers the products of."""


class ClassSemantics(SymSemantics):
    """:class:`~.symmetry.SymSemantics` over nodes whose worlds are classes: the robot's moves
    while apart on the classes (the module's docstring), every other node on its worlds
    listed."""

    def __init__(self, grounded: Grounded, sym: ClassSymmetry) -> None:
        super().__init__(grounded, sym)
        self.classer = sym.classer
        self._class_products: dict[WorldClasses, WorldClasses] = {}
        self._reads_of: dict[Agenda, int] = {}
        self._reads_tasks: dict[int, tuple[int, bool]] = {}

    def moves(self, es: EState) -> list[Move]:
        """§4: the options of the agent to move; the robot's while apart, and the human's
        when its options read nothing the classes tell apart, read the classes."""
        if not isinstance(es.worlds, WorldClasses):
            return super().moves(es)
        if (es.turn == ROBOT and not es.opening and not self.together(es.true)
                and self.comm.speech != Speech.WITH_ACTION):
            return self._robot_apart(es)
        if (es.turn == HUMAN and not es.answering and not self.copresent(es.true)
                and self._options_blind(es)):
            # Semantics.human_options reads the representatives' states as W's (exact here:
            # every condition it reads has one value over a class), human_exec the classes
            return super().moves(es)
        return [self._keep_cells(es.worlds, m)
                for m in super().moves(self.sym.explicit(es))]

    def _keep_cells(self, wc: WorldClasses, move: Move) -> Move:
        """``move`` with its child's worlds as classes under the cells of ``wc`` (its node's)
        without the objects the move names, when they leave them as they are (a rule commutes
        with every renaming that fixes its node and what the move names; the count says
        so, :meth:`~.worldclasses.Classer.compress`), for :meth:`~.worldclasses.Classer.fit`
        to start from; else as they are."""
        child = move.child
        if child is None or not wc.cells or isinstance(child.worlds, WorldClasses):
            return move
        named = self.sym.named(move.label)
        cells = tuple(k for k in (tuple(o for o in c if o not in named) for c in wc.cells)
                      if len(k) > 1)
        got = self.classer.compress(child.worlds, cells) if cells else None
        if got is None:
            return move
        return replace(move, child=child._replace(worlds=got))

    def is_goal(self, es: EState) -> bool:
        """§6, on the worlds listed (read only when the rest of the goal holds)."""
        if not isinstance(es.worlds, WorldClasses):
            return super().is_goal(es)
        if not (self.grounded.goal(es.true) and self.robot_done(es)):
            return False
        return super().is_goal(self.sym.explicit(es))

    def _options_blind(self, es: EState) -> bool:
        """Whether no condition the human's next options read (for any hypothesis of
        ``A_H``) names an atom of an object in a cell of ``es``: then every such condition
        has one value over each class, the options in a world are those in its class's
        representative, and the options certain in every world are those certain in every
        representative (docs/semantics.md §3, "Worlds as classes")."""
        cells = es.worlds.cells  # type: ignore[attr-defined]
        moved = 0
        for c in cells:
            for o in c:
                moved |= self.classer.object_atoms(o)
        return all(not self._first_reads(h) & moved for h in es.human_agendas)

    def _first_reads(self, agenda: Agenda) -> int:
        """The atoms the human's refinement of ``agenda`` up to its first actions may read
        (§1: done-conditions, method and action preconditions), as a mask; remembered."""
        r = self._reads_of.get(agenda)
        if r is None:
            tasks = tuple(t for t in agenda if isinstance(t, int))  # no blocks: see detect
            r = self._reads_of[agenda] = self._reads_seq(tasks, set())[0]
        return r

    def _reads_seq(self, seq: tuple[int, ...], busy: set[int]) -> tuple[int, bool]:
        """The atoms read refining ``seq`` up to its first actions, and whether all of it
        may vanish (every task done, or refined to nothing) so that what follows is read."""
        mask = 0
        for t in seq:
            m, vanish = self._reads_task(t, busy)
            mask |= m
            if not vanish:
                return mask, False
        return mask, True

    def _reads_task(self, t: int, busy: set[int]) -> tuple[int, bool]:
        """:meth:`_reads_seq` for one task (a task met again inside itself counts as read
        and as possibly vanishing)."""
        got = self._reads_tasks.get(t)
        if got is not None:
            return got
        if t in busy:
            return 0, True
        model = self.grounded.human
        mask, vanish = 0, False
        op = model.ops.get(t)
        if op is not None:
            mask |= _atoms(op.pre_f)
            if op.done_f is not None:
                mask |= _atoms(op.done_f)
                vanish = True
        else:
            busy.add(t)
            d = model.done.get(t)
            if d is not None:
                mask |= _atoms(d[0])
                vanish = True
            for m in model.methods.get(t, ()):
                mask |= _atoms(m.pre_f)
                inner, gone = self._reads_seq(m.subtasks, busy)
                mask |= inner
                vanish = vanish or gone
            busy.discard(t)
        if not busy:
            self._reads_tasks[t] = (mask, vanish)
        return mask, vanish

    def human_exec(self, es: EState, op: GOp, rests: tuple[Agenda, ...]) -> Move:
        """§4: the human does ``op`` while apart, on classes: every world advances (and
        learns the inferable atoms ``op`` changed in T), which commutes with every renaming
        of the cells that fixes the objects ``op`` names; so under those cells (the classes
        split, :meth:`~.worldclasses.Classer.refine`) each representative advances; then
        situation assessment."""
        ws = es.worlds
        t = es.true
        if not isinstance(ws, WorldClasses) or not op.pre(t):
            return super().human_exec(self.sym.explicit(es), op, rests)
        t2 = op.apply(t)
        named = self.sym.named(op.name)
        classer = self.classer
        wc = classer.refine(ws, [o if o in named else -1 for o in range(len(self.sym.objects))])
        grounded, apply = self.grounded, op.apply
        inf = grounded.expand(t ^ t2) & grounded.inferable_mask
        if inf:
            keep, learnt = ~inf, t2 & inf
            new = [((apply(s) & keep) | learnt, ag) for s, ag in wc]
        else:
            new = [(apply(s), ag) for s, ag in wc]
        worlds = self._lift_sees_done(t2, es.robot_agenda,
                                      self._lift_assess(t2, classer.classes_of(new, wc.cells)))
        k = 0 if self.copresent(t2) else es.k
        return Move(HUMAN, ACTION, op.name, op.cost,
                    EState(ROBOT, t2, es.robot_agenda, rests, worlds, k, 0), op.id)

    def _robot_apart(self, es: EState) -> list[Move]:
        """§4: :meth:`~.semantics.Semantics.robot_moves` where the robot cannot talk to the
        human: the first actions of its agenda (while ``k < K``), unseen, and ``wait``."""
        t = es.true
        out: list[Move] = []
        acts: list[tuple[GOp, Agenda]] = []
        if es.k < self.K:
            acts = [(self.robot_op(op), rest) for op, rest in self.R.refine(es.robot_agenda, t)
                    if op != FINISH]
        for gop, rest in acts:
            self.check()
            t2 = gop.apply(t)
            worlds = self._lift_sees_done(
                t2, rest, self._lift_assess(t2, self._lift_product(es.worlds)))
            out.append(Move(ROBOT, ACTION, gop.name, gop.cost,
                            EState(HUMAN, t2, rest, es.human_agendas, worlds,
                                   0 if self.copresent(t2) else es.k + 1, 0), gop.id))
        forced = not acts or self.human_model.passes == Passes.PROTOTYPE
        worlds, k = es.worlds, es.k
        if k < self.K:
            worlds, k = self._lift_assess(t, self._lift_product(worlds)), k + 1
        out.append(Move(ROBOT, WAIT, "wait", self.costs.wait,
                        EState(HUMAN, t, es.robot_agenda, es.human_agendas, worlds, k,
                               es.passive + 1, forced, es.opening, es.answering, es.pending)))
        return out

    def _lift_product(self, wc: Worlds) -> Worlds:
        """§4 (the product) on classes: each class's representative's successors, as classes
        under the same cells (the module's docstring)."""
        if not isinstance(wc, WorldClasses):
            return self.product(wc)
        if not self.human_model.anticipates:  # it imagines nothing: W unchanged
            return wc
        r = self._class_products.get(wc)
        if r is None:
            classer, cells = self.classer, wc.cells
            r = classer.classes_of([x for rep in wc for x in self.successors(rep)], cells)
            if len(self._class_products) >= PRODUCT_CACHE:
                self._class_products.clear()
            self._class_products[wc] = r
        return r

    def _lift_assess(self, t: int, ws: Worlds) -> Worlds:
        """Situation assessment (§4) on classes: under the cells split where ``t`` tells
        objects apart, the classes whose representative agrees with ``t`` on what the human
        sees; a revision on the worlds listed."""
        if not isinstance(ws, WorldClasses):
            return self.assess(t, ws)
        vm = self.visible(t)
        if not vm:
            return ws
        wc = self.classer.refine(ws, self.classer.sprof(t))
        tv = t & vm
        keep = [i for i, (s, _) in enumerate(wc) if s & vm == tv]
        if not keep:
            return self.assess(t, self.classer.expand(wc))
        if len(keep) == len(wc):
            return wc
        return WorldClasses([wc[i] for i in keep], wc.cells, [wc.mults[i] for i in keep],
                            self.classer)

    def _lift_sees_done(self, t: int, robot_agenda: Agenda, ws: Worlds) -> Worlds:
        """§4 (a non-anticipating human sees the robot done), on the worlds listed when it
        changes them."""
        if (self.human_model.anticipates or not self.copresent(t)
                or self.R.refine(robot_agenda, t)[:1] != ((FINISH, ()),)
                or all(not ag for _, ag in ws)):
            return ws
        return self.sees_done(t, robot_agenda, self.classer.expand(ws))


__all__ = ["ClassSemantics"]
