"""Drive one execution of a robot policy, step by step, for a robot controller or a simulator.

:class:`Executor` walks the policy graph, move by move, while it tracks the epistemic state with the
:class:`~ehatp.epistemic.semantics.Semantics` of the problem, so both views are checked against
each other at every step. The robot asks :meth:`Executor.next_robot_action`, does it, and reports
it with :meth:`Executor.robot_action_done`; what the human does is reported with
:meth:`Executor.observe_human_action`, which raises :class:`UncoveredHumanAction` when the
policy has no branch for it. A problem's fixed opening (``[problem] after``) is replayed first,
as moves the executor expects (or at once, as moves already made: :meth:`Executor.replay_opening`).

The executor moves along the policy's recorded edges: where several moves share the label the
policy names (two robot methods that start with the same action), it takes the one whose result
is the node the edge leads to (:meth:`Executor.edge_move`), never merely the first.

A lifted policy (format version 3, docs/policy-format.md) is realised lazily, never expanded:
the executor keeps the renaming ``tau`` from the current canonical node to the real state and
reads the node, its moves and the nodes they lead to through it (:attr:`Executor.node` is the
node on the real objects, its id the canonical node's); each move's label is the real
semantics' own (the move with the renamed child, preferably the renamed label).

When the human leaves the policy, :meth:`Executor.as_problem` states the execution so far as a new
problem and :meth:`Executor.replan` plans from where the robot is and follows the new policy. See
``docs/simulation.md`` and ``docs/execution.md``.

What the executor records is :mod:`ehatp.run.step` (:class:`Action`, :class:`Step`); what a step
changed and what each agent believes, in words for people, is :mod:`ehatp.run.narrative`.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import TYPE_CHECKING, Any

from ..epistemic.concurrent import ConcurrentSemantics
from ..epistemic.semantics import ACTION, WAIT, Move, Semantics
from ..epistemic.state import EState, Worlds, states_of
from ..errors import (
    ExecutionError,
    InputError,
    PolicyMismatch,
    UncoveredHumanAction,
)
from ..formats.lifted import Perm, Renamings
from ..formats.policy import Policy, PolicyMove, PolicyNode, label_key
from ..model.agenda import Agenda
from ..model.formula import conj
from ..model.grounding import Grounded, ground_problem
from ..model.problem import Cost, Problem
from ..model.vocabulary import HUMAN, ROBOT
from . import narrative
from .narrative import WorldView, human_agendas
from .step import Action, Step

if TYPE_CHECKING:
    from ..search.planner import Relabeler, Result


class _TracingSemantics(Semantics):
    """The problem's semantics, remembering what situation assessment received, so a step can
    say which worlds the human ruled out by looking."""

    def __init__(self, g: Grounded) -> None:
        super().__init__(g)
        self.seen: dict[tuple[int, Worlds], Worlds] = {}

    def assess(self, t: int, worlds: Worlds) -> Worlds:
        out = super().assess(t, worlds)
        self.seen.setdefault((t, out), worlds)
        return out


class _TracingJoint(_TracingSemantics, ConcurrentSemantics):
    """Joint steps (docs/concurrent.md), remembering situation assessment likewise: a step is
    the human's move observed, then the robot's compliant reply. The tracing class comes
    first: compiled, ``ConcurrentSemantics``'s ``super()`` calls go straight to
    ``Semantics`` (docs/compiled.md), which is what follows it here."""


def _tracing(g: Grounded) -> _TracingSemantics:
    """Return the problem's semantics (turns, or joint steps) with assessment traced."""
    return _TracingJoint(g) if g.problem.steps.concurrent else _TracingSemantics(g)


class Executor:
    """Follow ``policy`` (solved from ``problem`` when None) through one execution."""

    def __init__(self, problem: Problem, policy: Policy | None = None) -> None:
        if policy is None:
            from ..search.planner import solve

            result = solve(problem)
            if result.policy is None:
                raise ExecutionError(f"{problem.source}: no policy to execute: "
                                     f"{result.reason or result.status}")
            policy = result.policy
        if tuple(policy.after) != tuple(problem.after):
            raise PolicyMismatch(f"the policy was planned after the opening {list(policy.after)}"
                                 f" but the problem's opening is {list(problem.after)}; "
                                 "solve this problem again")
        self.problem = problem
        self.grounded = ground_problem(problem)
        self.policy = policy
        self._lifted: Renamings | None = None
        self.tau: Perm = ()  # lifted: the renaming from the current node to the real state
        self._use(policy)
        self.sem = _tracing(self.grounded)
        self.robot_name, self.human_name = self.sem.names
        self.state: EState = self.sem.initial()
        self.initial_assessed = self.sem.seen.get((self.state.true, self.state.worlds))
        self.history: list[Step] = []
        self._opening = list(policy.after)
        self.node: PolicyNode | None = None
        self._moves_at: tuple[EState, list[Move]] | None = None  # the last state's moves
        if not self._opening:
            self._enter_policy()

    # -- where we are ---------------------------------------------------------------------------
    @property
    def in_opening(self) -> bool:
        """True while the problem's fixed opening is being replayed."""
        return self.node is None

    @property
    def done(self) -> bool:
        """The policy has reached one of its leaves (a goal)."""
        return self.node is not None and not self.node.moves

    @property
    def goal_reached(self) -> bool:
        return self.sem.is_goal(self.state)

    @property
    def to_move(self) -> str | None:
        """The name of the agent to move, None when done."""
        if self.done:
            return None
        return self.robot_name if self.state.turn == ROBOT else self.human_name

    @property
    def cost(self) -> Cost:
        """Cost of the moves executed so far, the opening included."""
        return sum((s.action.cost for s in self.history), 0)

    # -- the robot ------------------------------------------------------------------------------
    def next_robot_action(self) -> Action | None:
        """What the robot must do now; None when it is the human's turn or the task is done."""
        if self.done or self.state.turn != ROBOT:
            return None
        return self._action(self._robot_move()[0])

    def robot_action_done(self, label: str | None = None) -> Step:
        """Record that the robot did its action (``label``, when given, is checked)."""
        if self.done or self.state.turn != ROBOT:
            raise ExecutionError(f"it is not {self.robot_name}'s turn: "
                                 + ("the task is done" if self.done
                                    else f"{self.human_name} is to move"))
        move, edge = self._robot_move()
        if label is not None and label_key(self.strip_agent(label)) != label_key(move.label):
            raise ExecutionError(f"{self.robot_name} reports {label!r} but the policy says "
                                 f"{move.label}")
        return self._advance(move, edge)

    # -- the human ------------------------------------------------------------------------------
    def possible_human_moves(self) -> list[Move]:
        """Every move the human model allows now (the semantics' view), policy or not."""
        if self.done or self.state.turn != HUMAN:
            return []
        return self._moves()

    def legal_human_moves(self) -> list[Move]:
        """Return every move the human can make now: the model's options
        (:meth:`possible_human_moves`) and a ``pass`` the fairness rule leaves out after a
        forced robot wait (docs/semantics.md §4: such a pass *need not be covered*, which does
        not make it impossible; a human who does it leaves the policy, and ``execute --replan``
        plans again from there)."""
        if self.done or self.state.turn != HUMAN:
            return []
        return self.sem.legal_moves(self.state)

    def expected_human_actions(self) -> list[Action]:
        """The human moves the policy covers now (empty at the robot's turn or when done)."""
        if self.done or self.state.turn != HUMAN:
            return []
        if self.node is None:
            return [self._action(self._follow(self._opening[0]))]
        return [self._action(self.edge_move(self.node, pm)) for pm in self.node.moves]

    def observe_human_action(self, action: str | Action) -> Step:
        """Record what the human did (a label such as ``place(w, box2)``, ``ask(...)``,
        ``pass``; the human's name may lead). The policy is followed along the edge the policy
        recorded for that label (:meth:`edge_move`). Raises :class:`UncoveredHumanAction` when
        the policy has no branch for it (nothing changes then): its ``reason`` says whether
        the move is not one of the human's here, fails, or is legal but not covered."""
        if self.done or self.state.turn != HUMAN:
            raise ExecutionError(f"it is not {self.human_name}'s turn: "
                                 + ("the task is done" if self.done
                                    else f"{self.robot_name} is to move"))
        label = action.label if isinstance(action, Action) else self.strip_agent(action)
        move, edge = self._human_move(label)
        return self._advance(move, edge)

    def copy(self) -> Executor:
        """An independent executor at the same point of the same execution, without grounding
        the problem again (e.g. to run many executions from one start)."""
        other = copy.copy(self)
        other.sem = copy.copy(self.sem)  # its memo tables are shared: they are pure
        other.sem.seen = dict(self.sem.seen)  # what assessment saw of the moves computed now
        other.history, other._opening = list(self.history), list(self._opening)
        return other

    # -- the opening, and leaving the policy ----------------------------------------------------
    def replay_opening(self) -> list[Step]:
        """Play what is left of the problem's fixed opening at once, as moves already made (the
        problem says the policy starts after them), instead of expecting them one by one;
        returns their steps. Nothing happens when there is no opening left."""
        steps = []
        while self.node is None:
            steps.append(self._advance(self._follow(self._opening[0]), None))
        return steps

    def as_problem(self) -> Problem:
        """The execution so far as a new problem: the same problem whose fixed opening
        (``[problem] after``) is every move played so far, then what is left of the original
        opening. Solving it plans from where the execution is now.

        Why the history and not the current epistemic state as a new start: a problem's start
        cannot say all that the rules read in a state -- the K counter, the count of passive
        moves, a forced wait, agendas part-way through a method, the speech opening -- and a new
        start is assessed again (``Semantics.initial``). Replaying the moves through the same
        semantics gives exactly the tracked state (:meth:`replan` checks the new policy's root
        against it); the cost is a replay of the moves, linear in the history."""
        played = tuple(s.played for s in self.history)
        desc = self.problem.description
        return dataclasses.replace(
            self.problem, after=played + tuple(self._opening), notes=(),
            description=(f"{desc}; " if desc else "") + f"replanned after {len(played)} moves")

    def replan(self, action: str | Action | None = None, **solve_options: Any) -> Result:
        """Plan again from where the execution is, and follow the new policy from its root.

        ``action``, when given, is a human move the human can make now
        (:meth:`legal_human_moves`: the model's options, and a pass the fairness rule lets a
        policy leave out) that the policy may not cover: it is applied to the tracked state
        first (a step marked ``replanned``). Then :meth:`as_problem` is solved
        (``solve_options`` go to :func:`ehatp.solve`) and its policy replaces :attr:`policy`
        and :attr:`problem`. Raises :class:`UncoveredHumanAction` when ``action`` is not a move
        of the human here or fails, and :class:`ExecutionError` when no policy is found; nothing
        changes then (also when the planner cannot replay the execution: an
        :class:`UncoveredHumanAction` after ``action``). Returns the solver's result."""
        from ..search.planner import solve

        move: Move | None = None
        if action is not None:
            if self.done or self.state.turn != HUMAN:
                raise ExecutionError(f"it is not {self.human_name}'s turn: "
                                     + ("the task is done" if self.done
                                        else f"{self.robot_name} is to move"))
            label = action.label if isinstance(action, Action) else self.strip_agent(action)
            move = self._legal_move(label)
        problem = self.as_problem()
        if move is not None:  # played after the history; the rest of the opening is dropped
            problem = dataclasses.replace(problem, after=tuple(
                s.played for s in self.history) + (f"{self.human_name} {move.label}",))
        try:
            result = solve(problem, **solve_options)
        except InputError as e:  # the planner cannot replay the execution as an opening
            why = (f"the planner cannot plan after it: it does not replay the execution "
                   f"({e.problem})")
            if move is None:
                raise ExecutionError(f"no policy from here: {why}") from None
            raise UncoveredHumanAction(
                move.label, [a.label for a in self.expected_human_actions()],
                [m.label for m in self.legal_human_moves()],
                f"{self.human_name} did {move.label}, which the policy does not cover, and "
                + why) from None
        if result.policy is None:
            raise ExecutionError(f"no policy from here: {result.reason or result.status}")
        if move is None and self.node is None:  # within the opening: the policy follows it
            self.problem = problem
            self._use(result.policy)
            return result
        before, assessed = self.state, None
        if move is not None:
            assert move.child is not None
            assessed = self.sem.seen.get((move.child.true, move.child.worlds))
            self.state = move.child
        old = (self.policy, self._lifted, self.tau)
        self._use(result.policy)
        root = self._view(0)
        try:
            self._check(root)
        except PolicyMismatch:
            self.state = before
            self.policy, self._lifted, self.tau = old
            raise
        self._forget()
        self.problem, self.node, self._opening = problem, root, []
        if move is not None:
            self.history.append(Step(len(self.history) + 1, self._action(move, before.true),
                                     before, self.state, root, False,
                                     assessed if assessed != self.state.worlds else None,
                                     replanned=True))
        return result

    def switch_profile(self, graph: Relabeler | Result, profile: str) -> Policy:
        """C11: follow from now on the policy optimal for another preference ``profile`` (the
        human's true one, learnt during the task), relabelled from the current state on the
        explored graph ``graph`` kept by ``solve(problem, keep_graph=True)`` (the
        :class:`~ehatp.search.planner.Relabeler`, or the result holding it): no new search.

        The current state was reached through the old profile's choices and need not be in
        the new profile's policy from the root, so the new policy's root is the current
        state's node of the kept graph (:meth:`Relabeler.relabel` with ``after`` the moves
        played so far, which reach it, and ``at`` the tracked state, checked against them),
        and its opening (``after``) those moves: it is a policy of :meth:`as_problem` with
        ``profile`` chosen, which becomes :attr:`problem` (a later :meth:`replan` plans for
        ``profile``). The history is kept; the new root is checked against the tracked state
        as every node is. Returns the new policy.

        A switch is allowed at the start of a step (a decision node, docs/concurrent.md C1),
        past the problem's fixed opening and before the goal: never in the middle of a step,
        where the move decided first was chosen under the old profile and its reply is due.
        Raises :class:`ExecutionError`, nothing changed, when the problem is no preferences
        problem, ``profile`` is none of its profiles, no graph was kept, the switch comes at
        another point, or the current state is not in the kept graph (after a replan that
        left the explored graph: :meth:`replan` instead)."""
        from ..model.options import ObjectiveKind
        from ..search.planner import Result

        obj = self.problem.objective
        if obj.kind != ObjectiveKind.PREFERENCES:
            raise ExecutionError(f"{self.problem.source}: cannot switch to profile {profile!r}:"
                                 f' the problem\'s [objective] kind is "{obj.kind.value}", not '
                                 '"preferences" with [objective.profiles]')
        if profile not in obj.profiles:
            raise ExecutionError(f"no profile {profile!r}: the problem names "
                                 + ", ".join(sorted(obj.profiles)))
        kept = graph.graph if isinstance(graph, Result) else graph
        if kept is None:
            raise ExecutionError("no explored graph was kept: solve with keep_graph=True")
        if self.node is None:
            raise ExecutionError("the problem's fixed opening is still being played: switch "
                                 "profile once the policy is followed (replay_opening())")
        if self.done:
            raise ExecutionError("the task is done: there is nothing left to relabel")
        if self.state.pending:
            raise ExecutionError(f"in the middle of a step ({self.sem.names[self.state.turn]}"
                                 "'s reply is due): switch profile at the start of a step, "
                                 "once this one is done")
        if (kept.problem.name != self.problem.name
                or kept.outcome.graph.sem.grounded.atoms != self.grounded.atoms
                or kept.outcome.graph.sem.grounded.task_names != self.grounded.task_names):
            raise ExecutionError(f"the kept graph is of problem {kept.problem.name!r}, not of "
                                 f"this execution's {self.problem.name!r}: keep the graph of "
                                 "this problem's solve")
        played = tuple(s.played for s in self.history)
        try:
            policy = kept.relabel(profile, at=self.state, after=played)
        except (KeyError, ValueError) as e:  # KeyError: the kept graph's problem lacks it
            raise ExecutionError(f"cannot switch to profile {profile!r}: {e.args[0]}"
                                 ) from None
        desc = self.problem.description
        problem = dataclasses.replace(
            self.problem, after=played, notes=(), objective=obj.with_profile(profile),
            description=(f"{desc}; " if desc else "")
            + f"profile {profile} after {len(played)} moves")
        old = (self.policy, self._lifted, self.tau)
        self._use(policy)
        root = self._view(0)
        try:
            self._check(root)
        except PolicyMismatch:
            self.policy, self._lifted, self.tau = old
            raise
        self.problem, self.node = problem, root
        return policy

    # -- what the human believes, in words (run/narrative.py) -----------------------------------
    def human_worlds(self) -> list[WorldView]:
        """The worlds the human entertains now, in the domain's vocabulary."""
        return narrative.world_views(self.sem, self.state)

    def uncertain_atoms(self) -> list[str]:
        """The atoms on which the human's worlds disagree."""
        return narrative.disputed_atoms(self.sem, self.state)

    def truth(self) -> list[str]:
        """The atoms true now (the robot knows them)."""
        return self.grounded.state_atoms(self.state.true)

    def explain(self, step: Step) -> list[str]:
        """What ``step`` changed, in the domain's vocabulary: the truth, co-presence, and how the
        human's worlds were added, ruled out or told."""
        return narrative.step_lines(self.sem, step, self.answer)

    def start_lines(self) -> list[str]:
        """The situation before the first move."""
        return narrative.start_lines(self.sem, self.state, self.initial_assessed)

    def belief_lines(self, es: EState | None = None) -> list[str]:
        """What each agent believes in ``es`` (default: now)."""
        return narrative.belief_lines(self.sem, self.state if es is None else es)

    # -- following the policy's edges ----------------------------------------------------------
    def edge_move(self, node: PolicyNode, edge: PolicyMove, es: EState | None = None) -> Move:
        """Return the move of the semantics at ``es`` (default: the state now) that is the
        policy's recorded ``edge`` out of ``node``: among the moves labelled ``edge.action``
        -- several, when two robot methods start with the same action (docs/semantics.md §4)
        -- the one whose child is the state the policy records at node ``edge.to``
        (:meth:`differences`), never merely the first with that label. Raises
        :class:`PolicyMismatch` when there is none: the policy does not fit the problem."""
        want = label_key(edge.action)
        same = [m for m in self._moves(es) if label_key(m.label) == want]
        to = self._target(edge)
        fit = [m for m in same if m.child is not None and not self.differences(m.child, to)]
        if len(fit) > 1:  # equal on what the node records in short: its worlds decide
            fit = [m for m in fit if m.child is not None
                   and self._world_diffs(m.child) == to.world_diffs] or fit
        if fit:
            return fit[0]
        who = edge.agent
        if not same:
            raise PolicyMismatch(f"policy node {node.id} says {who} {edge.action}, which is not "
                                 f"a move of {who} here; the policy does not fit this problem")
        why = sorted({d for m in same if m.child is not None
                      for d in self.differences(m.child, to)}) or ["it fails"]
        raise PolicyMismatch(f"policy node {node.id} says {who} {edge.action} to node "
                             f"{edge.to}, but no move {edge.action} here leads to that node "
                             f"(they differ on {', '.join(why)}); the policy does not fit this "
                             "problem")

    def differences(self, es: EState, node: PolicyNode) -> list[str]:
        """Return what policy node ``node`` records differently from the epistemic state
        ``es`` (empty when it is ``es``'s node): the agent to move, the K-counter, the number
        of worlds, the robot's agenda, the human agendas the robot cannot tell apart
        (docs/semantics.md §3) and the true state."""
        out = []
        if node.to_move is not None and node.to_move != self.sem.names[es.turn]:
            out.append("to_move")
        if es.k != node.k:
            out.append("k")
        if len(es.worlds) != node.worlds:
            out.append("worlds")
        if self._agenda(es.robot_agenda) != node.robot_agenda:
            out.append("robot_agenda")
        if sorted(self._agenda(a) for a in human_agendas(es)) != sorted(node.human_agendas):
            out.append("human_agendas")
        if not self._same_state(es.true, node):
            out.append("state")
        return out

    # -- a lifted policy (format version 3) ----------------------------------------------------
    def _use(self, policy: Policy) -> None:
        """Follow ``policy`` from now on (its renamings, if lifted, read in the problem's atom
        and task order)."""
        self.policy = policy
        g = self.grounded
        self._lifted = (None if policy.symmetry is None
                        else Renamings(policy.symmetry, g.atom_index, g.task_index))
        self.tau = () if self._lifted is None else self._lifted.root

    def _target(self, edge: PolicyMove) -> PolicyNode:
        """The node ``edge`` (a move of the current node) leads to, on the real objects."""
        node = self.policy.nodes[edge.to]
        if self._lifted is None:
            return node
        return self._lifted.node(self._lifted.child(self.tau, edge.renaming), node)

    def _view(self, n: int) -> PolicyNode:
        """Policy node ``n``, the current one, on the real objects: a lifted node renamed by
        ``tau``, each move labelled as the real semantics labels the move it stands for (one
        real move per policy move: the renamed label when it leads to the renamed child, else
        a move of the same agent, kind and cost that does; docs/policy-format.md)."""
        node = self.policy.nodes[n]
        if self._lifted is None:
            return node
        view = self._lifted.node(self.tau, node)
        real = self._moves()
        names = self.sem.names
        labels = {label_key(m.label) for m in real}
        used: set[int] = set()
        moves: list[PolicyMove | None] = [None] * len(view.moves)
        for exact in (True, False):
            for i, pm in enumerate(view.moves):
                if moves[i] is not None:
                    continue
                to, want = self._target(pm), label_key(pm.action)
                if not exact and want in labels:  # a label of the real semantics: its own
                    continue
                j = next((j for j, m in enumerate(real) if j not in used
                          and m.child is not None and names[m.agent] == pm.agent
                          and m.kind == pm.kind and m.cost == pm.cost
                          and (label_key(m.label) == want or not exact)
                          and not self.differences(m.child, to)), -1)
                if j < 0:
                    continue
                used.add(j)
                act = self._action(real[j])
                moves[i] = pm if label_key(act.label) == want else dataclasses.replace(
                    pm, action=act.label, name=act.name, args=list(act.args),
                    told=list(act.told))
        # a move no real move fits stays as renamed: following it says why it does not fit
        if all(m is pm for m, pm in zip(moves, view.moves, strict=True)):
            return view
        return dataclasses.replace(view, moves=[m if m is not None else pm for m, pm
                                                in zip(moves, view.moves, strict=True)])

    def _same_state(self, t: int, node: PolicyNode) -> bool:
        """Whether ``node`` records the true state ``t`` (in any order, lifted)."""
        atoms = self.grounded.state_atoms(t)
        return atoms == node.state or (self._lifted is not None
                                       and sorted(atoms) == sorted(node.state))

    # -- internals ------------------------------------------------------------------------------
    def strip_agent(self, label: str) -> str:
        """Drop a leading agent name (``H place(w, box2)`` -> ``place(w, box2)``)."""
        head, _, rest = label.strip().partition(" ")
        return rest.strip() if rest and head in (self.robot_name, self.human_name) else label

    def _moves(self, es: EState | None = None) -> list[Move]:
        """The semantics' moves at ``es`` (default: now), kept for the last state asked."""
        es = self.state if es is None else es
        if self._moves_at is None or self._moves_at[0] is not es:
            self._moves_at = (es, self.sem.moves(es))
        return self._moves_at[1]

    def _forget(self) -> None:
        """Forget what the semantics computed for the previous state."""
        self.sem.seen.clear()
        self._moves_at = None

    def _world_diffs(self, es: EState) -> list[dict[str, list[str]]]:
        t = es.true
        return [self.grounded.world_diff(s, t) for s in states_of(es.worlds)]

    def _follow(self, label: str) -> Move:
        try:
            return self.sem.follow(self.state, label)
        except ValueError as e:
            raise PolicyMismatch(f"the problem's opening step {label!r} cannot be played: {e}"
                                 ) from None

    def _robot_move(self) -> tuple[Move, PolicyMove | None]:
        """The robot's move now and the policy's edge it follows (None within the opening)."""
        if self.node is None:
            return self._follow(self._opening[0]), None
        moves = self.node.moves
        if len(moves) != 1:
            raise PolicyMismatch(f"policy node {self.node.id} is a robot node with "
                                 f"{len(moves)} moves, not 1")
        return self.edge_move(self.node, moves[0]), moves[0]

    def _legal_move(self, label: str) -> Move:
        """The human's move ``label`` among :meth:`legal_human_moves`; raises
        :class:`UncoveredHumanAction` when it is none of them or fails (a false belief)."""
        want, who = label_key(label), self.human_name
        legal = self.legal_human_moves()
        same = [m for m in legal if label_key(m.label) == want]
        move = next((m for m in same if m.child is not None), None)
        if move is None:
            possible = [m.label for m in legal]
            expected = [a.label for a in self.expected_human_actions()]
            if not same:
                raise UncoveredHumanAction(label, expected, possible,
                                           f"{who} did {label}, which is not a move of {who} "
                                           f"here (the model allows {', '.join(possible)})")
            raise UncoveredHumanAction(same[0].label, expected, possible,
                                       f"{who} did {same[0].label}, which fails: "
                                       f"{same[0].failure}")
        return move

    def _human_move(self, label: str) -> tuple[Move, PolicyMove | None]:
        """The human's move ``label`` along the policy's edge for it (None within the
        opening); raises :class:`UncoveredHumanAction` when the policy does not cover it."""
        move = self._legal_move(label)
        want = label_key(move.label)
        if self.node is None:
            opening = self._follow(self._opening[0])
            if label_key(opening.label) == want:
                return opening, None
            where = "the problem's fixed opening"
        else:
            edge = next((pm for pm in self.node.moves if label_key(pm.action) == want), None)
            if edge is not None:
                return self.edge_move(self.node, edge), edge
            where = f"policy node {self.node.id}"
        who = self.human_name
        legal = self.legal_human_moves()
        aside = ("" if any(m.label == move.label for m in self._moves()) else
                 " (a policy need not: after a forced robot wait, docs/semantics.md §4)")
        raise UncoveredHumanAction(move.label, [a.label for a in self.expected_human_actions()],
                                   [m.label for m in legal],
                                   f"{who} did {move.label}, which {where} does not cover{aside}")

    def _advance(self, move: Move, edge: PolicyMove | None) -> Step:
        """Play ``move``: the tracked state becomes its child and, past the opening, the
        policy moves to the node of ``edge``, the edge actually taken."""
        assert move.child is not None
        before = self.state
        trace = ""  # robot moves that share the label and lead elsewhere: name the agenda
        if move.agent == ROBOT and any(m.label == move.label and m.child != move.child
                                       for m in self._moves()):
            trace = self.sem.trace_label(before, move)
        assessed = self.sem.seen.get((move.child.true, move.child.worlds))
        self._forget()  # only the chosen move's assessment matters
        self.state = move.child
        opening = self.node is None
        node: PolicyNode | None = None
        if opening:
            self._opening.pop(0)
            if not self._opening:
                self._enter_policy()
                node = self.node
        else:
            assert edge is not None
            # the node the edge leads to may be shared by other paths: the tracked state is
            # checked against it all the same
            if self._lifted is not None:
                self.tau = self._lifted.child(self.tau, edge.renaming)
            node = self._view(edge.to)
            self.node = node
            self._check(node)
        step = Step(len(self.history) + 1, self._action(move, before.true), before, self.state,
                    node, opening, assessed if assessed != self.state.worlds else None,
                    trace=trace)
        self.history.append(step)
        return step

    def _enter_policy(self) -> None:
        self.node = self._view(0)
        self._check(self.node)

    def _check(self, node: PolicyNode) -> None:
        """The policy node and the tracked epistemic state must describe the same situation."""
        es, sem = self.state, self.sem
        names = self.sem.names
        want = {"state": node.state if self._same_state(es.true, node)
                else self.grounded.state_atoms(es.true), "worlds": len(es.worlds), "k": es.k,
                "copresent": sem.copresent(es.true),
                "to_move": None if node.goal else names[es.turn]}
        got = {"state": node.state, "worlds": node.worlds, "k": node.k,
               "copresent": node.copresent, "to_move": node.to_move}
        bad = [k for k in want if want[k] != got[k]]
        if node.goal and not sem.is_goal(es):
            bad.append("goal")
        if bad:
            raise PolicyMismatch(f"policy node {node.id} disagrees with the problem's semantics "
                                 f"on {', '.join(bad)} (policy {[got.get(k) for k in bad]}, "
                                 f"semantics {[want.get(k, False) for k in bad]}); "
                                 "the policy does not fit this problem, solve it again")

    def _action(self, m: Move, t: int | None = None) -> Action:
        """``m`` in the domain's vocabulary, played in the true state ``t`` (default: now).
        What is said with an action or a wait (``speech = "with-action"``) is told as it is
        in the true state *after* the move (docs/semantics.md §5)."""
        name, args, label = self.sem.describe(m)
        told: tuple[str, ...] = ()
        if m.kind in (ACTION, WAIT) and m.atoms:  # said while acting (§5), as labelled
            after = m.child.true if m.child is not None else self.state.true if t is None else t
            told = self.sem.literals(after, m.atoms)
        return Action(self.sem.names[m.agent], m.kind, label, name, args, m.cost, told)

    def _agenda(self, ag: Agenda) -> list[str]:  # a partially ordered block as {a | b} (§1)
        return self.sem.net.names_of(ag)

    def answer(self, es: EState, label: str) -> bool | None:
        """Return the robot's truthful answer to the human's question ``label`` in ``es``
        (docs/semantics.md §5: the value of the question's formula in the true state), None
        when ``label`` is no question the human may ask there."""
        sem = self.sem
        states = states_of(es.worlds)
        full = (1 << len(states)) - 1
        for h in human_agendas(es):
            for u in sem.H.refine_in_all(h, states):
                if u.worlds != full and u.conds:
                    phi = sem.uncertain_part(conj(*u.conds), states)
                    if f"ask({sem.show(phi)})" == label:
                        return bool(sem.g.compile(phi)(es.true))
        return None


# Action and Step live in .step, WorldView in .narrative: importable from here all the same
__all__ = ["Action", "ExecutionError", "Executor", "PolicyMismatch", "Step",
           "UncoveredHumanAction", "WorldView", "human_agendas"]
