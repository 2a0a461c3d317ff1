"""The agreement check: planner, validator and executor on random problems
(:mod:`ehatp.experiments.randomgen`). For one seed, :func:`check` solves the problem, validates
the policy from its file text, looks in that file for a hidden choice, walks the policy on its
branches through the Executor and (on a sample) solves again, and again with the problem
declared in reverse order, expecting the same bytes. A problem with preference profiles
(``[objective] kind = "preferences"``, C11) is solved keeping its graph, which is relabelled
for each of its other profiles: each policy must be the one a fresh solve with that profile
chosen writes, byte for byte, valid, and executable (:func:`relabelled`).
``benchmarks/agreement.py`` and ``tests/test_agreement.py`` run it on many seeds through
:func:`run`.
"""

from __future__ import annotations

import functools
import json
import multiprocessing
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from ..formats.policy import Policy, label_key
from ..model.options import ObjectiveKind
from ..model.problem import Problem
from ..search.limits import SolveStatus
from .randomgen import build, draw

if TYPE_CHECKING:
    from ..search.planner import Result

MAX_STATES = 20_000
TIMEOUT = 4.0
DETERMINISM_EVERY = 10
WALK_CAP = 500
"""Branches of one policy walked through the Executor at most (:func:`check`)."""


@dataclass(frozen=True)
class Outcome:
    """What happened to one seed. ``kind``: solved | unsolvable | limit (the search stopped at
    a limit: skipped) | crash (an exception) | disagreement (the validator rejects the
    planner's policy) | nondeterministic (a second solve, or the problem declared in reverse
    order, gives another policy). ``status`` is the planner's; ``detail`` the first line of the
    validator's report or the exception, where it was raised; ``options`` the model options
    the problem sets away from their defaults (:meth:`Spec.options`).

    Every policy the planner returns is also *executed*: walked on its branches through the
    Executor (``ehatp.run.walk``); ``branches`` is how many it walked to their end,
    ``capped`` whether it stopped at :data:`WALK_CAP`, ``unexecutable`` the walk's failure
    ("" when every branch reached the goal), and ``hidden_choice`` names a human node of the
    policy file with two moves of one label (:func:`hidden_choices`). Either makes the seed
    a failure, whatever its kind."""

    seed: int
    kind: str
    status: str = ""
    detail: str = ""
    checked_determinism: bool = False
    seconds: float = 0.0
    options: tuple[str, ...] = ()  # the model options away from their defaults
    executed: bool = False  # the policy was walked through the Executor
    branches: int = 0
    capped: bool = False
    unexecutable: str = ""
    hidden_choice: str = ""
    walk_seconds: float = 0.0
    # preference profiles (C11): the problem has them; the other profiles relabelled (and
    # compared with a fresh solve); the first that differs, or whose policy the validator
    # rejects or the Executor cannot walk (:func:`relabelled`)
    preferences: bool = False
    relabelled: int = 0
    relabel_differs: str = ""
    # worlds kept as classes (issue 17 §2): the solve was with them, and its policy is not
    # the one solving with the worlds listed gives (what differs, first)
    classes_differ: str = ""

    @property
    def failed(self) -> bool:
        return self.kind in FAILURES or bool(self.unexecutable or self.hidden_choice
                                             or self.relabel_differs or self.classes_differ)


FAILURES = ("crash", "disagreement", "nondeterministic")
KINDS = ("solved", "unsolvable", "limit", *FAILURES)
EXECUTION = ("executed", "capped", "non-executable", "hidden-choice")
"""The execution counts of :func:`summary`: policies walked, walks stopped at the cap, walks
that failed, policies that branch on a hidden choice."""
RELABELLING = ("preferences", "relabelled", "relabel-differs")
"""The counts of :func:`summary` for preference profiles (C11): problems with profiles,
profiles relabelled on a kept graph, seeds where one differs from a fresh solve (or is
invalid, or does not execute)."""
CLASSES = ("classes-differ",)
"""The count of :func:`summary` for a run with the worlds kept as classes: seeds whose
policy (or status) differs from the one solving with the worlds listed gives."""


def _where(e: BaseException) -> str:
    tb = traceback.extract_tb(e.__traceback__)
    last = tb[-1] if tb else None
    at = f" (at {last.filename.rsplit('/', 1)[-1]}:{last.lineno} in {last.name})" if last else ""
    msg = str(e).splitlines()[0] if str(e) else ""
    return f"{type(e).__name__}: {msg}{at}"


def hidden_choices(policy: Policy) -> list[str]:
    """The human nodes of ``policy`` (as read from its file) that cover two moves whose labels
    are equal but for spaces: a robot sees the human's action, never its method
    (docs/semantics.md §3), so it cannot tell such branches apart. One line per node."""
    human = policy.agents.get("human")
    out = []
    for n in policy.nodes:
        if n.to_move != human:
            continue
        seen: dict[str, int] = {}
        for m in n.moves:
            key = label_key(m.action)
            if key in seen:
                out.append(f"node {n.id}: {human} {m.action} twice (to nodes {seen[key]} and "
                           f"{m.to})")
                break
            seen[key] = m.to
    return out


def relabelled(prob: Problem, result: Result, *, max_states: int, timeout: float,
               walk_cap: int, symmetry: bool | None) -> tuple[int, str]:
    """C11 on a solved preferences problem: ``result`` (solved with ``keep_graph=True``)
    relabelled for each profile of ``prob``, in name order. Each policy must have the bytes
    of a fresh solve with that profile chosen (``result``'s own for the chosen profile), be
    valid for that problem (read from its file text) and walk through the Executor on its
    branches. Return the profiles compared (a fresh solve stopped by a limit is not
    comparable, and not counted) and the first failure ("" when none)."""
    from ..check.validator import validate
    from ..run.walk import walk_policy
    from ..search.planner import solve

    assert result.graph is not None
    compared = 0
    for name in sorted(prob.objective.profiles):
        mine = replace(prob, objective=prob.objective.with_profile(name))
        text = result.graph.relabel(name).to_json()
        fresh = (result if name == prob.objective.profile else
                 solve(mine, max_states=max_states, timeout=timeout, symmetry=symmetry))
        if fresh.status in (SolveStatus.TIMEOUT, SolveStatus.STATE_LIMIT):
            continue
        compared += 1
        if fresh.policy is None or fresh.policy.to_json() != text:
            return compared, (f"profile {name}: the relabelled policy differs from a fresh "
                              f"solve's ({fresh.status})")
        report = validate(mine, Policy.from_dict(json.loads(text)))
        if not report.ok:
            return compared, f"profile {name}: {report.message.splitlines()[0]}"
        walk = walk_policy(mine, Policy.from_dict(json.loads(text)), cap=walk_cap)
        if not walk.ok:
            return compared, f"profile {name}: not executable: {walk.message.splitlines()[0]}"
    return compared, ""


def check(seed: int, *, determinism: bool | None = None, max_states: int = MAX_STATES,
          timeout: float = TIMEOUT, walk_cap: int = WALK_CAP,
          symmetry: bool | None = None, world_classes: bool = False) -> Outcome:
    """Solve the problem of ``seed``, validate any policy the planner returns, look in its file
    for a hidden choice and walk it on up to ``walk_cap`` branches through the Executor, and
    (when ``determinism``, by default for one seed in :data:`DETERMINISM_EVERY`) solve it again
    and declared in reverse order, expecting byte-identical policy JSON. ``symmetry`` and
    ``world_classes`` are :func:`~ehatp.search.planner.solve`'s (None: as the problem says);
    with ``world_classes`` the problem is also solved with the worlds listed, expecting the
    same policy but for its timings (``classes_differ``)."""
    from ..check.validator import validate
    from ..run.walk import walk_policy
    from ..search.planner import solve

    if determinism is None:
        determinism = seed % DETERMINISM_EVERY == 0
    start = time.perf_counter()
    stage = "draw"
    prefs = False
    status = ""
    options: tuple[str, ...] = ()
    execution: dict[str, Any] = {}

    def out(kind: str, detail: str = "", checked: bool = False) -> Outcome:
        return Outcome(seed, kind, status, detail, checked, time.perf_counter() - start,
                       options, preferences=prefs, **execution)

    try:
        spec = draw(seed)
        options = spec.options()
        stage = "build"
        prob = build(spec)
        stage = "solve"
        prefs = prob.objective.kind == ObjectiveKind.PREFERENCES
        r = solve(prob, max_states=max_states, timeout=timeout, symmetry=symmetry,
                  keep_graph=prefs, world_classes=world_classes)
        status = r.status
        if world_classes:
            stage = "listed worlds"
            listed = solve(prob, max_states=max_states, timeout=timeout, symmetry=symmetry,
                           keep_graph=prefs)
            execution["classes_differ"] = _differ(r, listed)
        if r.policy is not None:
            # from the policy's file text (format v2), as a user's validate would read it
            text = r.policy.to_json()
            stage = "validate"
            report = validate(prob, Policy.from_dict(json.loads(text)))
            stage = "hidden choice"
            read = Policy.from_dict(json.loads(text))
            hidden = hidden_choices(read)
            stage = "walk"
            t0 = time.perf_counter()
            walk = walk_policy(prob, read, cap=walk_cap)
            execution |= {"executed": True, "branches": walk.branches, "capped": walk.capped,
                         "unexecutable": "" if walk.ok else walk.message.splitlines()[0],
                         "hidden_choice": "; ".join(hidden),
                         "walk_seconds": time.perf_counter() - t0}
            if not report.ok:
                return out("disagreement", report.message.splitlines()[0])
            if prefs and r.graph is not None:
                stage = "relabel"
                n, differs = relabelled(prob, r, max_states=max_states, timeout=timeout,
                                        walk_cap=walk_cap, symmetry=symmetry)
                execution.update(relabelled=n, relabel_differs=differs)
        if r.status in (SolveStatus.TIMEOUT, SolveStatus.STATE_LIMIT):
            return out("limit", r.reason)
        if r.status not in (SolveStatus.SOLVED, SolveStatus.UNSOLVABLE):
            return out("crash", f"solve: unknown status {r.status!r}")
        if determinism:
            first = r.policy.to_json() if r.policy is not None else r.status
            for rev in (False, True):
                stage = "reverse" if rev else "re-solve"
                again = solve(build(draw(seed), reverse=rev), max_states=max_states,
                              timeout=timeout, symmetry=symmetry)
                if again.status in (SolveStatus.TIMEOUT, SolveStatus.STATE_LIMIT):
                    continue  # a limit hit is not comparable
                second = again.policy.to_json() if again.policy is not None else again.status
                if second != first:
                    what = ("solving twice" if not rev else
                            "declaring the problem in reverse order")
                    return out("nondeterministic", f"{what} gives another result "
                               f"({r.status} vs {again.status})", True)
            stage = "done"
        return out(r.status, r.reason.splitlines()[0] if r.reason else "", determinism)
    except Exception as e:  # noqa: BLE001 - every exception is a finding
        return out("crash", f"{stage}: {_where(e)}")


def _differ(a: Result, b: Result) -> str:
    """What differs between two solves of one problem, their timings aside ("" if nothing):
    the status, or the policy's JSON without its ``stats``, or the states searched."""
    if a.status != b.status:
        return f"status {a.status} vs {b.status}"
    if a.policy is None or b.policy is None:
        return "" if a.policy is b.policy else "one has a policy"
    texts = []
    for r in (a, b):
        d = json.loads(r.policy.to_json())  # type: ignore[union-attr]
        d.pop("stats", None)
        texts.append(json.dumps(d, sort_keys=True))
    if texts[0] != texts[1]:
        return "the policies differ"
    for key in ("distinct", "expanded", "max_worlds"):
        if a.stats.get(key) != b.stats.get(key):
            return f"{key} {a.stats.get(key)} vs {b.stats.get(key)}"
    return ""


def run(seeds: Iterable[int], *, jobs: int = 1,
        on_result: Callable[[Outcome], None] | None = None,
        walk_cap: int = WALK_CAP, symmetry: bool | None = None,
        world_classes: bool = False) -> list[Outcome]:
    """:func:`check` every seed (``walk_cap``, ``symmetry`` and ``world_classes`` as there),
    on ``jobs`` processes; the outcomes sorted by seed."""
    one = functools.partial(check, walk_cap=walk_cap, symmetry=symmetry,
                            world_classes=world_classes)
    seeds = list(seeds)
    results: list[Outcome] = []

    def collect(it: Iterator[Outcome]) -> None:
        for o in it:
            results.append(o)
            if on_result is not None:
                on_result(o)

    if jobs <= 1 or len(seeds) <= 1:
        collect(one(s) for s in seeds)
    else:
        # forkserver, not fork: a process with threads (a test run after Ray or Dask, a
        # notebook) can fork a child that blocks for ever on a lock another thread held; the
        # server forks from a clean process with the planner imported. One seed per task
        # keeps the load even.
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload([__name__])
        with ctx.Pool(jobs) as pool:
            collect(pool.imap_unordered(one, seeds, chunksize=1))
    return sorted(results, key=lambda o: o.seed)


def summary(outcomes: Sequence[Outcome]) -> dict[str, int]:
    """Counts by kind (every kind present, in :data:`KINDS` order), then the execution counts
    of :data:`EXECUTION`, then those of :data:`RELABELLING` and :data:`CLASSES`."""
    counts = dict.fromkeys((*KINDS, *EXECUTION, *RELABELLING, *CLASSES), 0)
    for o in outcomes:
        counts["classes-differ"] += bool(o.classes_differ)
        counts["preferences"] += o.preferences
        counts["relabelled"] += o.relabelled
        counts["relabel-differs"] += bool(o.relabel_differs)
        counts[o.kind] += 1
        counts["executed"] += o.executed
        counts["capped"] += o.capped
        counts["non-executable"] += bool(o.unexecutable)
        counts["hidden-choice"] += bool(o.hidden_choice)
    return counts


__all__ = ["CLASSES", "DETERMINISM_EVERY", "EXECUTION", "FAILURES", "KINDS", "MAX_STATES",
           "RELABELLING", "TIMEOUT", "WALK_CAP", "Outcome", "check", "hidden_choices",
           "relabelled", "run", "summary"]
