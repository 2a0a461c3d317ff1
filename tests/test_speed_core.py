"""The faster core where symmetry does not help (issue 17 §4) gives the rules' answers: a node's
moves read off an expanded node that differs from it by the count of consecutive passive moves
only (docs/semantics.md §3-§5, ``PASSIVE_CARRIED``), and what the search builds from them.
Answers derived by hand from the rules, the rule table checked against ``Semantics.moves`` on
every state of explored graphs, and the search's policies against a search that computes every
node's moves afresh."""

from __future__ import annotations

import pytest

import ehatp
from ehatp.epistemic.semantics import PASSIVE_CARRIED, Move, Semantics
from ehatp.epistemic.state import EState
from ehatp.experiments import randomgen
from ehatp.model.grounding import ground_problem
from ehatp.model.options import ObjectiveKind
from ehatp.model.problem import Problem
from ehatp.run.walk import walk_policy
from ehatp.search import andor, values
from ehatp.search.andor import search
from ehatp.search.graph import EXPANDED, GOAL, move_key
from ehatp.search.values import LiveWorst, compute_values, knuth

from .conftest import EXAMPLES_DIR


def _moves(sem: Semantics, es: EState) -> list[tuple[str, EState | None, int]]:
    return [(m.label, m.child, m.cost) for m in sorted(sem.moves(es), key=move_key)]


def _carried(moves: list[Move], p: int) -> list[tuple[str, EState | None, int]]:
    """The moves of a node with count 0, as the table says they are with count ``p``."""
    out: list[tuple[str, EState | None, int]] = []
    for m in sorted(moves, key=move_key):
        d = PASSIVE_CARRIED.get(m.kind)
        child = m.child
        if child is not None and d is not None:
            child = child._replace(passive=p + d)
        out.append((m.label, child, m.cost))
    return out


def test_a_pass_after_a_pass_counts_two_and_an_action_after_it_counts_none() -> None:
    """By hand, P1 (cubes, the human starts, co-present at ``mt``): §4 gives the human at the
    root ``move(mt, ot)`` (a human action: the robot's node after it has 0 passive moves) and
    ``pass`` (a passive move: 1). The same node reached after one passive move already (count
    1) has the same two moves, the action's child still at 0 and the pass's at 2 -- a third
    passive move from there (count 3) is the dead end of §6."""
    sem = Semantics(ground_problem(ehatp.load(EXAMPLES_DIR / "cubes" / "p1.toml")))
    root = sem.initial()
    assert root.passive == 0
    at0 = {m.label: m.child.passive for m in sem.moves(root) if m.child is not None}
    at1 = {m.label: m.child.passive for m in sem.moves(root._replace(passive=1))
           if m.child is not None}
    assert at0 == {"move(mt, ot)": 0, "pass": 1}
    assert at1 == {"move(mt, ot)": 0, "pass": 2}


def _problems() -> list[tuple[str, Problem]]:
    out = [(p.stem, ehatp.load(p)) for p in sorted(EXAMPLES_DIR.glob("*/*.toml"))
           if p.parent.name != "concurrent"]
    out += [(f"seed{seed}", randomgen.problem(seed)) for seed in range(40)]
    return out


@pytest.mark.parametrize("name,problem", _problems(), ids=lambda x: x if isinstance(x, str)
                         else "")
def test_a_nodes_moves_are_its_twins_with_the_passive_count_carried(
        name: str, problem: Problem) -> None:
    """§3-§5: on every state of the explored graph (every example but the joint-step ones,
    and 40 random problems, whose settings draw speech openings, the robot's question and
    announcements), the moves with 1 or 2 passive moves counted already are those with 0,
    each child of a carrying move (``wait``, ``pass``, also said with an ``inform``; the
    opening's ``silence`` and an ``answer``) counting that many more, every other child the
    same state."""
    grounded = ground_problem(problem)
    if grounded.problem.steps.concurrent:
        pytest.skip("joint steps count passive moves by C4, not by the table")
    out = search(grounded, symmetry=False, max_states=3000)
    sem = Semantics(grounded)
    for es in out.graph.states[:600]:
        base = sem.moves(es._replace(passive=0))
        for p in (1, 2):
            assert _moves(sem, es._replace(passive=p)) == _carried(base, p), (name, es)


@pytest.mark.parametrize("name,problem", _problems(), ids=lambda x: x if isinstance(x, str)
                         else "")
def test_the_search_reading_moves_off_a_twin_builds_the_same_graph_and_policy(
        name: str, problem: Problem, monkeypatch: pytest.MonkeyPatch) -> None:
    """The search reads a node's moves off an expanded twin (the same state with another
    passive count): every edge it builds is the move ``Semantics.moves`` gives the node, in
    the canonical order, to the node of that move's child; and the solve gives the same
    policy, byte for byte, and the same statistics as a search computing every node's moves,
    which the validator accepts and the executor walks on every branch."""
    grounded = ground_problem(problem)
    if grounded.problem.steps.concurrent:
        pytest.skip("joint steps count passive moves by C4, not by the table")
    reused = [0]
    real = andor._reused

    def counting(*args: object) -> object:
        reused[0] += 1
        return real(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(andor, "_reused", counting)
    out = search(grounded, symmetry=False, max_states=3000)
    gr, sem = out.graph, Semantics(grounded)
    for n, es in enumerate(gr.states):
        if gr.status[n] != EXPANDED:
            continue
        want = [(m.label, m.cost, m.child) for m in sorted(sem.moves(es), key=move_key)]
        got = [(e.move.label, e.move.cost, None if e.child < 0 else gr.states[e.child])
               for e in gr.edges[n]]
        assert got == want, (name, n)
    fast = ehatp.solve(problem, symmetry=False)
    monkeypatch.setattr(Semantics, "passive_carried", False)
    afresh = ehatp.solve(problem, symmetry=False)
    assert fast.status == afresh.status and fast.stats == afresh.stats | {
        "time_ms": fast.stats["time_ms"]}
    if fast.policy is not None:
        assert afresh.policy is not None
        assert fast.policy.to_json() == afresh.policy.to_json()
        assert ehatp.validate(problem, fast.policy).ok
        walked = walk_policy(problem, fast.policy)
        assert walked.ok, str(walked)
    if name in ("p1", "p2", "p6"):
        assert reused[0] > 0  # the twins are there: the reading is exercised


@pytest.mark.parametrize("name,problem", _problems(), ids=lambda x: x if isinstance(x, str)
                         else "")
def test_the_values_kept_during_the_search_give_knuths_values_and_order(
        name: str, problem: Problem) -> None:
    """§7: the worst-case values the search keeps up to date, and the order read off them
    when every edge costs more than 0 (by value, ties by node id), are what Knuth's pass
    computes on the final graph -- values and finalisation order alike, so the choices made
    from them are the same."""
    grounded = ground_problem(problem)
    for max_states in (200, 3000):
        out = search(grounded, symmetry=False, max_states=max_states)
        gr = out.graph
        if not gr.solved[out.root]:
            continue
        assert LiveWorst(gr).final() == knuth(gr)
        if out.values is not None:  # the search's, from the values it kept
            afresh = compute_values(gr, out.root)
            assert (out.values.worst, out.values.value, out.values.choice) == (
                afresh.worst, afresh.value, afresh.choice)


def test_knuths_order_is_by_value_then_id_when_every_move_costs_something(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """By hand, P1 (cubes; every move costs 1): the goals are finalised first, by id, then
    each value in turn; the order read off the kept values is the pass's own, and the pass is
    not run for it."""
    gr = search(ground_problem(ehatp.load(EXAMPLES_DIR / "cubes" / "p1.toml")),
                symmetry=False).graph
    live = LiveWorst(gr)
    value, order = knuth(gr)
    goals = [n for n in range(len(gr.states)) if gr.status[n] == GOAL]
    assert order[:len(goals)] == goals and all(value[n] == 0 for n in goals)
    assert [value[n] for n in order] == sorted(value[n] for n in order)

    def no_pass(*args: object) -> None:
        raise AssertionError("the pass was run")

    monkeypatch.setattr(values, "knuth", no_pass)
    assert live.final() == (value, order)


@pytest.mark.parametrize("name,problem", _problems(), ids=lambda x: x if isinstance(x, str)
                         else "")
def test_choosing_among_the_contenders_only_gives_the_choices_of_a_pass_over_every_node(
        name: str, problem: Problem) -> None:
    """§7, worst case: the robot's choices made over the nodes the root reaches through
    human branches and options of the node's value (the only ones a choice can take, tie
    keys apart) are those of the pass that visits every finalised node, and the totals they
    rest on are the sub-policies' own (a robot node's value is its chosen option's)."""
    grounded = ground_problem(problem)
    if grounded.problem.objective.kind != ObjectiveKind.WORST_CASE:
        pytest.skip("the contenders are the worst-case pass's")
    for max_states in (200, 3000):
        out = search(grounded, symmetry=False, max_states=max_states)
        gr, obj = out.graph, grounded.problem.objective
        worst, order = knuth(gr)
        pos = [len(worst)] * len(worst)
        for i, n in enumerate(order):
            pos[n] = i
        need_mean = "expected" in obj.ties
        every, _ = values._choose(gr, order, lambda n, c, pos=pos: pos[c] < pos[n], obj,
                                  need_mean)
        assert compute_values(gr, out.root).choice == values._reachable(gr, out.root, every)
