"""Communication as the validator re-implements it (docs/semantics.md §5): the robot's
``inform``, ``announce``, question and silence, speech said with a move, the human's answers,
and when a divergence is relevant enough to tell (the informing sets).

Part of the independent validator: :class:`Semantics` is :class:`~.rules.Rules` (§1-§4, §6)
with §5 added, written from the document like the rest.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace
from fractions import Fraction

from ..model.grounded import FINISH
from ..model.options import InformWhere, Relevance, Speech
from ..model.problem import Problem
from ..model.vocabulary import HUMAN, ROBOT
from .network import Agenda
from .rules import (
    ANNOUNCE,
    ANSWER,
    ASK,
    INFORM,
    SILENCE,
    EState,
    Rules,
    Step,
    Worlds,
    _bits,
    _frac,
)

BLOCKED = -2  # the end of a human plan where no action applies (relevance "plan", §5)
NOT_DONE = -3  # §5: what a blocked, unfinished robot agenda offers: "the robot is not done"
INTENTION = "ask(intention)"  # the robot's question (robot_asks, §5)


class Semantics(Rules):
    """The rules of docs/semantics.md §1-§6 over one grounded problem: :class:`Rules` and
    communication (§5)."""

    def __init__(self, problem: Problem, check: Callable[[], None] | None = None) -> None:
        super().__init__(problem, check)
        # §3: shown the informing set a policy's inform tells when name order chose it among
        # sets equally good on everything else (a lifted policy's check watches it)
        self.ties: Callable[[tuple[int, ...], list[tuple[int, ...]]], None] | None = None
        self._plans: dict[tuple[Agenda, int, int], frozenset[tuple[int, ...]]] = {}

    def initial(self) -> EState:
        """§1-§3 and §5: the initial node; a robot opening turn when the human starts, the
        robot may speak while acting and an informing set exists in the initial state."""
        es = super().initial()
        if es.turn == HUMAN and self.p.communication.speech == Speech.WITH_ACTION:
            opening = replace(es, turn=ROBOT, opening=True)
            if not isinstance(self.inform_found(opening), str):
                return opening
        return es

    def human_options(self, es: EState) -> list[Step]:
        """§4 (Human, :meth:`Rules.human_options`); at an answering node the answers (§5)."""
        if es.answering:
            return self.answers(es)
        return super().human_options(es)

    # -- §5: the robot's moves -----------------------------------------------------------------

    def silence(self, es: EState) -> Step:
        """§5: the robot's silent move at a speech opening (cost 0, no effect)."""
        after = self.advance(es, SILENCE, es.true, es.robot, es.humans, es.worlds, es.k)
        return Step(ROBOT, SILENCE, "silence", Fraction(0), after)

    def literals(self, t: int, units: Iterable[int]) -> tuple[str, ...]:
        return tuple(self.say(t, u) for u in units)


    def heard(self, worlds: Worlds, t: int, units: Sequence[int]) -> Worlds:
        """§5: what the human believes after an inform of ``units`` it hears (:meth:`tell`,
        shown to :attr:`watch`)."""
        if self.watch is not None:
            mask = 0
            for u in units:
                mask |= u
            self.watch(worlds, t, mask)
        return self.tell(worlds, t, units)

    def tell(self, worlds: Worlds, t: int, units: Iterable[int]) -> Worlds:
        """§5: the human learns T's value of every unit (an atom, a variable, a counter)."""
        return self.observe(worlds, t, [i for u in sorted(units) for i in _bits(u)])

    def inform(self, es: EState, units: Sequence[int]) -> Step:
        """§5: ``inform(A)``: the human learns T's value of every unit of A (an atom, a state
        variable, a counter), nothing else is witnessed (k unchanged, no world multiplied,
        also while apart)."""
        worlds = self.heard(es.worlds, es.true, units)
        after = self.advance(es, INFORM, es.true, es.robot, es.humans, worlds, es.k)
        label = f"inform({', '.join(self.literals(es.true, sorted(units)))})"
        return Step(ROBOT, INFORM, label, _frac(self.p.costs.inform), after)

    def with_speech(self, units: Sequence[int], st: Step) -> Step:
        """§5: ``inform(A) + a``: said with the action (or wait) ``st`` and judged on the node
        it leads to: the human learns the values A has in the true state after ``st`` (T'), in
        its worlds after ``st``; the costs add up."""
        assert st.after is not None
        after = st.after
        told = self.literals(after.true, units)
        label = f"inform({', '.join(told)}) + {st.act}"
        heard = replace(after, worlds=self.heard(after.worlds, after.true, units))
        return Step(ROBOT, st.kind, label, _frac(self.p.costs.inform) + st.cost, heard,
                    act=st.act, told=told)

    def talk_where(self, es: EState, what: str) -> str | None:
        """§5: why the robot may not talk (``what``: inform, ask, announce) here for where the
        agents are (None if it may): while co-present, or anywhere under ``inform =
        "anywhere"``."""
        if self.cop(es.true) or self.p.communication.inform == InformWhere.ANYWHERE:
            return None
        return f"{what} is offered only while co-present"

    def robot_ask(self, es: EState) -> Step | str:
        """§5 (``robot_asks``): the robot asks the human what it is about to do, when more than
        one human agenda fits what it saw; the human answers at once (an answering node: same
        T, W, robot agenda and k, no passive move)."""
        if not self.p.communication.robot_asks:
            return "the robot asks the human's intention only under [communication] " \
                   "robot_asks = true (§5)"
        if len(es.humans) < 2:
            return "only one human agenda fits what the robot saw: there is nothing to ask (§5)"
        why = self.talk_where(es, "asking")
        if why is not None:
            return why
        after = replace(es, turn=HUMAN, passive=0, forced=False, answering=True)
        return Step(ROBOT, ASK, INTENTION, _frac(self.p.costs.ask), after)

    def answers(self, es: EState) -> list[Step]:
        """§5: at an answering node the human tells which agenda it follows (cost 0, no turn
        spent): then it is the human's turn, with that one agenda."""
        out = []
        for h in self.ordered(es.humans):
            after = replace(es, answering=False, humans=frozenset({h}))
            out.append(Step(HUMAN, ANSWER, f"answer({', '.join(self.shown(h))})", Fraction(0),
                            after))
        return out

    def announce(self, es: EState) -> Step | str:
        """§5 (``announce``): the robot tells its own agenda: the worlds whose attributed robot
        agenda is the announced one stay; if none, every world's agenda becomes it. Offered
        where the robot options the human expects differ from the robot's real ones (read per
        world) and the announcement changes the worlds."""
        if not self.p.communication.announce:
            return "the robot announces its agenda only under [communication] announce = " \
                   "true (§5)"
        why = self.talk_where(es, "announce")
        if why is not None:
            return why
        if self.robot_view(es.worlds) == self.true_robot_view(es):
            return "the robot options the human expects equal the robot's real ones: the " \
                   "divergence is not relevant (§5)"
        mine = self.attributed(es.robot)
        worlds = frozenset(w for w in es.worlds if w[1] == mine)
        if not worlds:
            worlds = frozenset((s, mine) for s, _ in es.worlds)
        if worlds == es.worlds:
            return "announcing changes none of the human's worlds (§5)"
        after = self.advance(es, ANNOUNCE, es.true, es.robot, es.humans, worlds, es.k)
        label = f"announce({', '.join(self.shown(es.robot))})"
        return Step(ROBOT, ANNOUNCE, label, _frac(self.p.costs.inform), after)


    # -- §5: relevance of a divergence, the informing set -------------------------------------

    def human_view(self, agenda: Agenda, states: frozenset[int]) -> frozenset[tuple[int, bool]]:
        """§5: the human's next actions on ``states``, each with whether it is certain (what
        it would choose; the method behind an action is not part of it)."""
        return frozenset((r.action, r.states == states) for r in self.hrefine(agenda, states))

    def plans(self, agenda: Agenda, s: int) -> frozenset[tuple[int, ...]]:
        """§5 (relevance "plan"): plans(S), the sequences of human actions refining ``agenda``
        with M_H in the single state S, each action applied and the robot idle, up to the end
        of the agenda (FINISH) or ``plan_horizon`` actions; a sequence that ends early where
        no action applies ends with BLOCKED."""
        memo = self._plans

        def go(ag: Agenda, st: int, n: int) -> frozenset[tuple[int, ...]]:
            key = (ag, st, n)
            got = memo.get(key)
            if got is not None:
                return got
            if n == 0:
                out: set[tuple[int, ...]] = {()}
            else:
                res = self.refine(self.grounded.human, ag, st)
                out = set() if res else {(BLOCKED,)}
                for a, rest in res:
                    if a == FINISH:
                        out.add((FINISH,))
                        continue
                    nxt = go(rest, self.grounded.human.ops[a].apply(st), n - 1)
                    out.update((a, *tail) for tail in nxt)
            memo[key] = frozenset(out)
            return memo[key]

        return go(agenda, s, self.p.communication.plan_horizon)

    def robot_view(self, worlds: Worlds) -> frozenset[int]:
        """§5: the robot options the human expects, read per world: the first actions of the
        attributed agenda under each world's state with M_R^H (FINISH when it can finish); a
        world whose agenda is unfinished and offers no option contributes NOT_DONE."""
        out: set[int] = set()
        for s, tn in worlds:
            ops = {a for a, _ in self.refine(self.grounded.robot_seen_by_human, tn, s)}
            out |= ops or {NOT_DONE}
        return frozenset(out)

    def true_robot_view(self, es: EState) -> frozenset[int]:
        """§5: the robot's real options: the first actions of its agenda under T with M_R
        (FINISH when it can finish), or NOT_DONE when it is unfinished and blocked."""
        ops = frozenset(a for a, _ in self.refine(self.grounded.robot, es.robot, es.true))
        return ops or frozenset({NOT_DONE})

    def views_differ(self, es: EState, worlds: Worlds, plan: bool) -> tuple[bool, bool, bool]:
        """(human's options differ, anticipated robot options differ, human plans differ)
        between W and T, the human's for some hypothesis of A_H (§5); the third only when
        ``plan`` (relevance "plan")."""
        states = frozenset(s for s, _ in worlds)
        truth = frozenset({es.true})
        human = any(self.human_view(h, states) != self.human_view(h, truth) for h in es.humans)
        # the robot's options include being done (FINISH): a divergence that hides from the
        # human that the robot has finished is relevant, since the goal needs H to believe it
        robot = self.robot_view(worlds) != self.true_robot_view(es)
        plans = plan and any(self.plans(h, s) != self.plans(h, es.true)
                             for h in es.humans for s in states)
        return human, robot, plans

    def inform_where(self, es: EState) -> str | None:
        """§5: why no ``inform`` may be offered here for where the agents are (None if it
        may). Under ``inform = "anywhere"`` an inform is heard while apart even at k = K: it
        is no robot turn the human imagines (no world multiplied, k unchanged), so the K bound
        of §4, which limits what the robot does unseen, does not apply to it."""
        return self.talk_where(es, "inform")

    def inform_found(self, es: EState) -> list[tuple[str, int, list[tuple[int, ...]], bool]] | str:
        """§5: the informing searches that find sets here, or why no ``inform`` is offered.
        Under relevance "plan", the sets fixing the plans and, beside them, the sets that fix
        the next step as under "next": "plan" never offers less than "next"."""
        plan = self.p.communication.relevance == Relevance.PLAN
        first = self.inform_search(es, plan)
        found = [] if isinstance(first, str) else [(*first, plan)]
        if plan:
            nxt = self.inform_search(es, False)
            if not isinstance(nxt, str):
                found.append((*nxt, False))
        if not found:
            assert isinstance(first, str)
            return first
        return found

    def inform_search(self, es: EState, plan: bool
                      ) -> tuple[str, int, list[tuple[int, ...]]] | str:
        """§5: the informing sets of one relevance reading (``plan``: relevance "plan", else
        "next"): (what they fix, their size, every smallest set that fixes it, in canonical
        order), or why no such ``inform`` is offered.

        Sets fixing the human's options, the anticipated robot options (and, under relevance
        "plan", the plans) come first; failing those, sets fixing the human's options (and the
        plans) -- only when those differ: a set cannot fix what is not broken, and telling the
        human something that changes none of its options is not worth a move."""
        why = self.inform_where(es)
        if why is not None:
            return why
        now = self.views_differ(es, es.worlds, plan)
        if not any(now):
            return ("the divergence is not relevant (the human's and the anticipated robot's "
                    "options" + (" and the human's plans" if plan else "") +
                    " on W equal those on T)")
        div = 0
        for s, _ in es.worlds:
            div |= s ^ es.true
        cands = self.units(div)  # an atom, or a state variable or counter told whole
        limit = self.p.communication.inform_max_atoms
        fixed: dict[tuple[int, ...], tuple[bool, bool, bool]] = {}
        for n in range(1, limit + 1):
            for sub in itertools.combinations(cands, n):
                h, r, p = self.views_differ(es, self.tell(es.worlds, es.true, sub), plan)
                fixed[sub] = (not h, not r, not p)
        both = "the human's views" + (" and plans" if plan else "")
        alone = "the human's options" + (" and plans" if plan else "")
        tiers: list[tuple[str, Callable[[tuple[bool, bool, bool]], bool]]] = [(both, all)]
        if now[0] or now[2]:
            tiers.append((alone, lambda f: f[0] and f[2]))
        for what, test in tiers:
            for n in range(1, limit + 1):
                sets = [a for a, f in fixed.items() if len(a) == n and test(f)]
                if sets:
                    return what, n, sets
        if len(tiers) == 1:
            return (f"no set of at most inform_max_atoms = {limit} atoms fixes {both}, and the "
                    "human's options" + (" and plans" if plan else "") + " need no fixing")
        return f"no set of at most inform_max_atoms = {limit} atoms fixes {alone}"

    def check_inform(self, es: EState, atoms: Sequence[int]) -> str | None:
        """§5: why ``inform(atoms)`` (units, as masks) is not a legal robot option here (None
        when it is): it must be the set one of the informing searches chooses."""
        why = self.inform_where(es)
        if why is not None:
            return why
        div = 0
        for s, _ in es.worlds:
            div |= s ^ es.true
        for u in atoms:
            if not div & u:
                return (f"every world already agrees with the truth on {self.unit_name(u)}: "
                        "informing the human of what it believes is never generated")
        limit = self.p.communication.inform_max_atoms
        found = self.inform_found(es)
        if isinstance(found, str):
            return found
        if len(atoms) > limit:
            return f"informs {len(atoms)} atoms, more than inform_max_atoms = {limit}"
        mine = tuple(sorted(atoms))
        choices = [self.check_choice(es, mine, sets) for _, _, sets, _ in found if mine in sets]
        if choices:
            return None if None in choices else choices[0]
        what, n, _, plan = found[0]
        h, r, p = self.views_differ(es, self.tell(es.worlds, es.true, mine), plan)
        fixes = (not h and not p) if what.startswith("the human's options") else not (h or r or p)
        if not fixes:
            return f"it does not fix {what}, yet a set of {n} atom(s) does"
        if what.startswith("the human's options"):
            return f"not a smallest set fixing {what}: {len(atoms)} atoms where {n} suffice"
        return f"not a smallest fixing set: {len(atoms)} atoms where {n} suffice"

    def check_choice(self, es: EState, atoms: tuple[int, ...],
                     sets: list[tuple[int, ...]]) -> str | None:
        """§5: among smallest sets, the one leaving the fewest worlds, then telling more true
        atoms, then the first by atom names."""
        def key(a: tuple[int, ...]) -> tuple[int, int, tuple[str, ...]]:
            left = len(self.tell(es.worlds, es.true, a))
            told_true = sum(1 for u in a if es.true & u or u in self.grounded.unit_names)  # a value
            return left, -told_true, tuple(self.unit_name(u) for u in a)

        best = min(sets, key=key)
        if best == atoms:
            if self.ties is not None:  # §3: name order decided between equally good sets
                tied = [a for a in sets if a != atoms and key(a)[:2] == key(atoms)[:2]]
                if tied:
                    self.ties(atoms, tied)
            return None
        told = ", ".join(self.literals(es.true, best))
        return f"not the informing set the rules choose among smallest sets (fewest worlds " \
               f"left, then more true atoms, then atom names): inform({told})"

    # -- reading labels ------------------------------------------------------------------------

    def parse_inform(self, label: str) -> list[tuple[int, str]] | str:
        """``inform(a, not b(x, y), loc(r) = mt, balls(b1) = 2)`` -> (unit, literal as
        written) pairs: an atom told true or false, a state variable's or counter's value."""
        inner = label[len("inform("):-1] if label.startswith("inform(") and label.endswith(
            ")") else None
        if not inner:
            return f"cannot read {label!r} as inform(atom, ...)"
        g = self.grounded
        valued = {name: u for u, name in g.unit_names.items()}
        out: list[tuple[int, str]] = []
        buf = ""
        for tok in inner.split(", "):  # atoms contain ", " too: grow until one is known
            buf = f"{buf}, {tok}" if buf else tok
            head, eq_, value = buf.rpartition(" = ")
            u = valued.get(head) if eq_ else None
            if u is not None:
                top = g.counter_max.get(u)
                if (buf in self.atom_of and self.unit(self.atom_of[buf]) == u if top is None
                        else value.isdigit() and int(value) <= top):
                    out.append((u, buf))
                    buf = ""
                continue
            neg = buf.startswith("not ")
            name = buf[4:] if neg else buf
            i = self.atom_of.get(name)
            if i is not None and self.unit(i) == 1 << i:
                out.append((1 << i, buf))
                buf = ""
        if buf or not out:
            return f"cannot read {label!r}: {buf!r} is not a fluent atom or a value"
        return out



__all__ = ["BLOCKED", "INTENTION", "NOT_DONE", "Semantics"]
