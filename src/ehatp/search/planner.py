"""``solve``: ground a problem, search it, and return the policy with its statistics."""

from __future__ import annotations

import gc
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Any

from ..epistemic.state import EState
from ..errors import InputError
from ..formats.policy import Policy
from ..model.grounded import Grounded
from ..model.grounding import ground_problem
from ..model.options import Intentions, ObjectiveKind
from ..model.problem import Problem
from . import symmetry as _symmetry
from .andor import SearchOutcome, search
from .diagnose import diagnose
from .limits import LIMITS, Budget, LimitReached, SolveStatus, start_budget
from .policy import explain_failure, extract, liftable, realise
from .stats import Progress, SolveStats, Stats
from .values import compute_values

INF = float("inf")


@dataclass
class Result:
    """What :func:`solve` returns. ``status`` compares equal to its string (``"solved"``,
    ``"unsolvable"``, ``"timeout"``, ``"state-limit"``, ``"memory-limit"``,
    ``"depth-limit"``); ``policy`` is the best policy found, ``optimal`` whether it is proven
    optimal, ``reason`` why there is none or why it may not be (in words)."""

    status: SolveStatus
    policy: Policy | None
    stats: SolveStats = field(default_factory=lambda: SolveStats())
    reason: str = ""
    optimal: bool = False
    # the lifted policy (format version 3) when ``policy`` is its expansion (``expand``): what
    # a writer stopped by a limit can still write, small as the search
    lifted: Policy | None = None
    # solve(..., keep_graph=True): the explored graph, to relabel for another profile (C11)
    graph: Relabeler | None = None

    @property
    def solved(self) -> bool:
        return self.policy is not None

    def __repr__(self) -> str:
        """Return a one-line summary: status, the policy's, the search's size and time."""
        st = self.stats
        size = f", distinct={st['distinct']}" if "distinct" in st else ""
        took = f", time_ms={st['time_ms']:.1f}" if "time_ms" in st else ""
        why = f", reason={self.reason!r:.80}" if self.reason else ""
        return (f"Result(status={str(self.status)!r}, optimal={self.optimal}, "
                f"policy={self.policy!r}{size}{took}{why})")


@dataclass
class Relabeler:
    """C11: a solved problem's explored graph, kept (``solve(..., keep_graph=True)``) so that
    another of the problem's preference profiles relabels it without a new search: the values
    are computed again for that profile and its policy extracted, exactly the policy a fresh
    solve with that profile chosen writes (a preferences search explores the whole reachable
    graph whatever the profile, so the graph is the same)."""

    problem: Problem
    outcome: SearchOutcome
    stats: dict[str, Any]  # the policy file's statistics (the search's, without the time)

    @property
    def profiles(self) -> list[str]:
        """The problem's profile names, sorted."""
        return sorted(self.problem.objective.profiles)

    def node(self, state: EState) -> int | None:
        """Return the id of the kept graph's node for the epistemic state ``state`` (C1: a
        step's decision node or a reply node), None when the search never reached it. Joint
        steps have no symmetry reduction, so the graph's states are the real ones: ``state`` is
        looked up as it is (the semantics already normalise the worlds, C7)."""
        gr = self.outcome.graph
        if gr.sym is not None:  # not reached: preferences are joint steps, never reduced
            raise ValueError("the kept graph is over canonical states: relabel from its root")
        return gr.index.get(state)

    def relabel(self, profile: str, at: EState | None = None, *,
                after: Sequence[str] | None = None) -> Policy:
        """Return the policy optimal for ``profile`` (one of the problem's
        ``[objective.profiles]``; :class:`KeyError` otherwise) on the kept graph (C11).

        From the root by default. With ``after``, the moves played from the problem's start,
        as ``[problem] after`` lists them (``Executor.as_problem().after``), the policy's root
        is the node of the state they reach (replayed through the search's own semantics, as
        the search replays an opening): the values are computed for ``profile`` on what that
        node reaches and the policy extracted from it, the policy a fresh solve of the problem
        played up to there would choose; its ``after`` is those moves, so that it is a policy
        of that problem and validates as such. ``at``, the state an executor tracks there
        (:meth:`ehatp.run.executor.Executor.switch_profile`), is checked against the replay.
        :class:`ValueError` when the moves cannot be played, do not reach ``at``, or reach a
        state not in the kept graph (the search never reached it: plan again from there
        instead), or no policy reaches the goal from it."""
        obj = self.problem.objective.with_profile(profile)
        out = self.outcome
        assert out.values is not None
        root = out.root
        if after is not None:
            state = self._replay(after)
            if at is not None and state != at:
                raise ValueError("the moves given do not reach the state given")
            n = self.node(state)
            if n is None:
                raise ValueError("this state is not in the kept graph (the search never "
                                 "reached it, e.g. after a replan that left it): plan again "
                                 "from here instead of relabelling")
            root = n
        elif at is not None:
            raise ValueError("relabelling from a state needs after=, the moves played to "
                             "reach it")
        values = compute_values(out.graph, root, obj)
        if values.value[root] == INF:
            raise ValueError("the kept graph has no policy" + ("" if after is None
                                                                  else " from this state"))
        optimal = values.exact and (out.optimal or not out.values.exact)
        policy = extract(out.graph, root, values, problem_name=self.problem.name,
                         optimal=optimal, stats=self.stats, objective=obj)
        if after is not None:
            policy.after = list(after)
        return policy

    def _replay(self, after: Sequence[str]) -> EState:
        """The state the moves ``after`` reach from the problem's start (§4: each a move
        possible at that point; :class:`ValueError` naming the move otherwise)."""
        sem = self.outcome.graph.sem
        es = sem.initial()
        for i, label in enumerate(after):
            try:
                child = sem.follow(es, label).child
            except ValueError as e:
                raise ValueError(f"move {i + 1}, {label!r}: {e}") from None
            if child is None:
                raise ValueError(f"move {i + 1}, {label!r}, fails")
            es = child
        return es


def relabel(result: Result, profile: str) -> Policy:
    """C11: ``result``'s kept graph (``solve(..., keep_graph=True)``) relabelled for another
    ``profile``: the policy a fresh solve with that profile gives."""
    if result.graph is None:
        raise ValueError("no graph kept: solve with keep_graph=True "
                         '(and [objective] kind = "preferences")')
    return result.graph.relabel(profile)


@dataclass(frozen=True)
class _Settings:
    """A solve's options beyond the problem's: state and depth limits (None: the problem's)
    and whether to search over canonical states and order by ``g + h``."""

    max_states: int | None
    max_depth: int | None
    symmetry: bool
    heuristic: bool | None
    expand: bool = False
    focus: bool = True
    world_classes: bool = False


GC_YOUNG = 100_000
"""The cyclic garbage collector's young-generation threshold while :func:`solve` runs
(Python's default: 700 container objects allocated). The search pauses the collector
(:func:`~.andor.search`, the values over the graph included); the phases around it
(grounding, extracting the policy and building its nodes) allocate hundreds of thousands of
objects that live on, and at the default the collector re-scans the whole graph again and
again, to free almost nothing: 3-7 % of a solve at the K=8 points and in the compiled core
(docs/benchmarks.md, "The garbage collector around the search"). At this threshold it still
runs, a hundredfold less often."""


@contextmanager
def _few_collections() -> Iterator[None]:
    """Raise the collector's young-generation threshold to :data:`GC_YOUNG` for the call it
    decorates (:func:`solve`), then put the caller's back; a threshold already as high (an
    outer solve, or the caller's own setting) is left alone."""
    old = gc.get_threshold()
    if old[0] >= GC_YOUNG:
        yield
        return
    gc.set_threshold(GC_YOUNG, *old[1:])
    try:
        yield
    finally:
        gc.set_threshold(*old)


@_few_collections()
def solve(problem: Problem, *, timeout: float | None = None, max_states: int | None = None,
          max_depth: int | None = None, progress: Progress | None = None,
          max_memory: int | None = None, budget: Budget | None = None,
          symmetry: bool | None = None, heuristic: bool | None = None,
          expand: bool = False, keep_graph: bool = False, focus: bool = True,
          world_classes: bool = False) -> Result:
    """Plan a robot policy for ``problem``, optimal under ``problem.objective``
    (docs/semantics.md §7: worst-case by default, or expected cost).

    Limits default to the problem's ``[limits]``; ``timeout`` (seconds) and ``max_memory``
    (bytes of resident memory) bound the whole call — grounding, search, values and
    extraction — or pass a ``budget`` (:class:`~ehatp.search.limits.Budget`) shared with the
    caller's own work, such as writing the policy. When a limit stops the work the result
    carries partial statistics, and the best policy found so far if there is one (``optimal``
    False); ``reason`` says which limit. ``progress(stats, frontier)`` is called about 20 times
    a second, ``stats.phase`` naming the work under way.

    ``symmetry`` (default: ``[limits] symmetry``) searches over canonical states
    (docs/semantics.md §3, "Symmetry"); the policy is then *lifted* (format version 3: its
    nodes are the canonical states, its moves carry renamings; docs/policy-format.md), or with
    ``expand`` mapped back to the real objects (version 2, every real move checked against the
    real semantics). When the reduction cannot be trusted for this problem (a decision taken
    by name or index order, or, expanding, a move that does not map back) the problem is solved
    again without it. ``heuristic`` (default:
    on) orders a worst-case search by a lower bound (:mod:`.heuristic`): fewer states, the
    same policy. ``focus`` (default: on) expands, with that bound, only the tips of the best
    partial policy (docs/semantics.md §7, "Search"; :mod:`.bounds`): far fewer states again,
    the same policy; off, or where the human has no task, every state whose ``g + h`` is at
    most the optimum is expanded. ``world_classes`` (with ``symmetry``) keeps the human's
    worlds as classes of renamings of one another (:mod:`.worldclasses`,
    docs/semantics.md §3, "Worlds as classes"): the same search node for node, the same
    policy and ``max_worlds``.

    ``keep_graph`` keeps the explored graph in ``Result.graph`` (a :class:`Relabeler`) when
    the objective is ``"preferences"`` (C11), to relabel it for another profile.

    The steps: ground (:func:`_ground`), search (:func:`_search`), extract the chosen policy
    (:func:`_extract`), then say why there is no policy or why it is not proven optimal
    (:func:`_reason`).
    """
    if problem.objective.kind == ObjectiveKind.PREFERENCES:  # C11
        if not problem.steps.concurrent:
            raise InputError(problem.source, "[objective] kind", "preference profiles are "
                             "built for joint steps only", 'add [steps] mode = "concurrent"')
        if problem.objective.profile not in problem.objective.profiles:
            raise InputError(problem.source, "[objective] profile", "no profile of "
                             "[objective.profiles] is chosen", "name one in [objective] "
                             "profile")
    live = Stats()
    budget = start_budget(problem.limits, live, timeout=timeout, max_memory=max_memory,
                          budget=budget, progress=progress)
    grounded = _ground(problem, budget, live)
    if isinstance(grounded, Result):
        return grounded
    settings = _Settings(max_states, max_depth, _symmetry.enabled(symmetry, problem.limits),
                         heuristic, expand, focus, world_classes)
    try:
        out = _search(grounded, budget, live, settings)
    except LimitReached as e:  # before the first state: looking for symmetry, the bound
        stats = live.as_dict()
        stats["time_ms"] = round(budget.elapsed() * 1000, 1)
        return Result(e.status, None, stats, e.reason)
    stats = out.stats.as_dict()
    stats["atoms"] = len(grounded.atoms)
    status, reason, optimal = out.status, out.reason, out.optimal
    policy = lifted = None
    if out.values is not None and out.values.value[out.root] != INF:
        public = {k: v for k, v in stats.items() if k != "time_ms"}
        if expand and out.graph.sym is not None and out.status == SolveStatus.SOLVED:
            lifted = _proven(problem, out, public)  # kept in case expanding is cut
        got = _extract(problem, out, public, budget, expand)
        if isinstance(got, str):  # not expected: solve without symmetry
            live.restart()
            return solve(problem, max_states=max_states, max_depth=max_depth, budget=budget,
                         symmetry=False, heuristic=heuristic, expand=expand, focus=focus)
        if isinstance(got, LimitReached) and out.status == SolveStatus.SOLVED:
            # §7: the search is finished: what it proved is kept, whatever stopped the rest
            policy = lifted if lifted is not None else _proven(problem, out, public)
            if policy is not None:
                what = ("the lifted policy (format version 3) is returned instead"
                        if lifted is not None else "the policy was extracted past the limit")
                reason = f"{got.reason}, after the search had finished: {what}"
                lifted = None
            else:
                status, reason, optimal = got.status, got.reason, False
        elif isinstance(got, LimitReached):
            status, reason, optimal = got.status, got.reason, False
        else:
            policy = got
        if policy is not None:
            _policy_stats(stats, policy)
    reason = _reason(problem, grounded, out, status, reason, optimal, budget, settings)
    budget.phase = "done"
    kept = None
    if (keep_graph and policy is not None and out.values is not None
            and problem.objective.kind == ObjectiveKind.PREFERENCES):
        kept = Relabeler(problem, out, public)
    return Result(status, policy, stats, reason, optimal, lifted, kept)


def _proven(problem: Problem, out: SearchOutcome, public: dict[str, Any]) -> Policy | None:
    """The policy a finished search chose, extracted without the limits (lifted over canonical
    states: linear in the canonical nodes the policy reaches, which the search already holds);
    None when even that runs out of memory."""
    assert out.values is not None
    try:
        return extract(out.graph, out.root, out.values, problem_name=problem.name,
                       optimal=out.optimal, stats=public)
    except MemoryError:
        return None


def _ground(problem: Problem, budget: Budget, live: Stats) -> Grounded | Result:
    """Return the grounded problem (§1, "Grounding"), or the result of a limit that stopped
    grounding (partial statistics: none yet, and the time)."""
    budget.phase = "grounding"
    try:
        return ground_problem(problem, check=budget.check)
    except LimitReached as e:
        stats = live.as_dict()
        stats["time_ms"] = round(budget.elapsed() * 1000, 1)
        return Result(e.status, None, stats, e.reason)
    except MemoryError:
        oom = budget.out_of_memory()
        return Result(oom.status, None, live.as_dict(), oom.reason)


def _search(grounded: Grounded, budget: Budget, live: Stats,
            settings: _Settings) -> SearchOutcome:
    """Return the search's outcome (§7), over canonical states when ``settings.symmetry``
    says so, and again over real states when that reduction is unsafe for this problem
    (§3, "Symmetry": a decision taken by name or index order)."""
    out = search(grounded, max_states=settings.max_states, max_depth=settings.max_depth,
                 budget=budget, stats=live, symmetry=settings.symmetry,
                 heuristic=settings.heuristic, focus=settings.focus,
                 world_classes=settings.world_classes)
    if out.status == SolveStatus.SYMMETRY_UNSAFE:
        live.restart()
        out = search(grounded, max_states=settings.max_states, max_depth=settings.max_depth,
                     budget=budget, stats=live, heuristic=settings.heuristic,
                     focus=settings.focus)
    return out


def _extract(problem: Problem, out: SearchOutcome, public: dict[str, Any],
             budget: Budget, expand: bool = False) -> Policy | LimitReached | str:
    """Return the policy the values chose (docs/policy-format.md, ``public`` its statistics):
    over canonical states the lifted policy, or with ``expand`` the policy on the real objects;
    the limit that stopped extraction; or, expanding, why the chosen policy could not be mapped
    back (then the caller solves without symmetry)."""
    budget.phase = "extraction"
    try:
        budget.check()
        graph, root, values = out.graph, out.root, out.values
        assert values is not None
        if graph.sym is not None and not expand and not liftable(graph, root, values):
            expand = True  # an inform chosen by name: only the real objects can say it (§3)
        if graph.sym is not None and expand:
            budget.phase = "expansion"
            real = realise(graph, root, values, check=budget.check)
            budget.phase = "extraction"
            if isinstance(real, str):
                return real
            graph, root, values = real
        policy = extract(graph, root, values, problem_name=problem.name,
                         optimal=out.optimal, stats=public, check=budget.check)
        budget.check()
        return policy
    except LimitReached as e:
        return e
    except MemoryError:
        return budget.out_of_memory()


def _policy_stats(stats: SolveStats, policy: Policy) -> None:
    """Add the policy's figures to the statistics a result reports."""
    stats["cost"] = policy.cost
    stats["communications"] = policy.communications
    stats["leaves"] = policy.leaves
    stats["worst_case"] = policy.worst_case
    stats["expected"] = policy.expected


def _reason(problem: Problem, grounded: Grounded, out: SearchOutcome, status: SolveStatus,
            reason: str, optimal: bool, budget: Budget, settings: _Settings) -> str:
    """Return what a result says besides its status: why no policy exists (the goal
    literals or agendas that fail everywhere, the choice the robot cannot see, else one
    failing line of play), why a policy is not proven optimal (§7: expected cost on a graph
    with cycles), or the limit's ``reason``."""
    if status == SolveStatus.UNSOLVABLE:
        # name the goal literals or agendas that fail everywhere; a line of play that dies
        # is only the fallback (it is one of many, and may look arbitrary)
        graph, root = out.graph, out.root
        hidden = ""
        if any(len(es.human_agendas) > 1 for es in graph.states):
            hidden = _hidden_choice(problem, budget, settings)
        return "no policy exists: " + hidden + diagnose(grounded, graph,
                                                        lambda: explain_failure(graph, root))
    if status == SolveStatus.SOLVED and not optimal:
        return ("not proven optimal: the solvable graph has cycles, so choices inside them "
                "were restricted to those of the worst-case pass")
    return reason


def _hidden_choice(problem: Problem, budget: Budget, settings: _Settings) -> str:
    """docs/semantics.md §3-§4: when a robot that saw the human's method choices would have
    a policy, the choice it cannot see is the reason there is none: return it in words
    (the first human move of that policy whose label had to name the intention), else ""."""
    seen = replace(problem, human=replace(problem.human, intentions=Intentions.VISIBLE))
    try:
        other = solve(seen, max_states=settings.max_states, max_depth=settings.max_depth,
                      budget=budget, heuristic=settings.heuristic, expand=True,
                      focus=settings.focus)
    except LimitReached:
        return ""
    if other.policy is None:
        return ""
    for node in other.policy.nodes:
        told = [move.action for move in node.moves
                if move.action.endswith("]") and " [" in move.action]
        if told:
            act = told[0].partition(" [")[0]
            means = " or ".join(t.partition(" [")[2][:-1] for t in told
                                if t.partition(" [")[0] == act)
            h = problem.domain.human_name
            return (f"the robot cannot see which method {h} chose when it does {act} (for "
                    f"{means}); with [human] intentions = \"visible\", or a question "
                    f"([communication] robot_asks = true), a policy exists (worst case "
                    f"{other.policy.worst_case}); ")
    return ""


__all__ = ["LIMITS", "Relabeler", "Result", "relabel", "solve"]
