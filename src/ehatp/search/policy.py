"""Policy extraction: the robot policy chosen by the values, as a :class:`Policy` graph (the
file format lives in :mod:`ehatp.policy_format`), and why no policy exists when none does."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..epistemic.semantics import ACTION, WAIT, Move, bits_of
from ..epistemic.state import ROBOT, EState
from ..model.htn import Agenda
from ..model.options import Objective, ObjectiveKind
from ..model.problem import Cost
from ..policy_format import Policy, PolicyMove, PolicyNode, num, topological_order
from .andor import GOAL, Edge, Graph
from .values import Values, weighted_mean


def extract(gr: Graph, root: int, values: Values, *, problem_name: str,
            optimal: bool = True, stats: dict[str, Any] | None = None,
            check: Callable[[], None] | None = None) -> Policy:
    """The policy the values chose, from ``root``, as a graph (docs/policy-format.md): one
    policy node per search node the policy reaches, memoised by search node, so the work and
    the file are linear in the policy's distinct states however many branches share them.
    Node ids are the depth-first preorder of first visits, moves in canonical order.

    Both costs of §7 are computed again on the extracted graph: its worst case (the maximum over
    human branches) and its expected cost (their weighted mean, ``[objective.weights]``); each
    node's ``value`` and the policy's ``cost`` are the objective's. Branches and communications
    are counted over the graph too (:meth:`Policy.count_branches`). ``check`` (e.g. a time
    limit's, docs/semantics.md §7 "Search") is called once per policy node and may raise to
    stop the work."""
    sem = gr.sem
    if check is None:
        def check() -> None:
            pass

    g = sem.g
    p = g.problem
    r_name, h_name = p.domain.robot_name, p.domain.human_name

    def chosen(n: int) -> list[Edge]:
        if gr.status[n] == GOAL:
            return []
        edges = gr.edges[n]
        return [edges[values.choice[n]]] if gr.is_robot(n) else list(edges)

    # depth-first, first visits in preorder: a node reached again is not expanded again
    order: list[int] = []
    index: dict[int, int] = {}
    stack = [root]
    while stack:
        n = stack.pop()
        if n in index:
            continue
        check()
        index[n] = len(order)
        order.append(n)
        stack.extend(e.child for e in reversed(chosen(n)))

    def agenda(ag: Agenda) -> list[str]:  # a partially ordered block as {a | b} (§1)
        return sem.net.names_of(ag)

    def move_of(e: Edge, before: int) -> PolicyMove:
        move: Move = e.move
        name, call_args, label = sem.describe(move)
        told: list[str] = []
        if move.kind in (ACTION, WAIT) and move.atoms:  # said while acting (§5), as labelled
            told = list(sem.literals(before, move.atoms))
        return PolicyMove(agent=r_name if move.agent == ROBOT else h_name, kind=move.kind,
                          action=label, name=name, args=list(call_args), cost=move.cost,
                          to=index[e.child], told=told)

    nodes: list[PolicyNode] = []
    for i, n in enumerate(order):
        check()
        es: EState = gr.states[n]
        t = es.true
        div = 0
        diffs = []
        for s in sorted({s for s, _ in es.worlds}):
            div |= s ^ t
            diffs.append(g.world_diff(s, t))
        goal = gr.status[n] == GOAL
        nodes.append(PolicyNode(
            id=i, copresent=sem.copresent(t), k=es.k, worlds=len(es.worlds),
            divergence=([g.atoms[b] if t >> b & 1 else f"not {g.atoms[b]}" for b in bits_of(div)]
                        if not div & g.multi_mask else g.literals(t, div)),  # values whole
            world_diffs=diffs, state=g.state_atoms(t), robot_agenda=agenda(es.robot_agenda),
            human_agenda=agenda(es.human_agenda),
            to_move=None if goal else (r_name if es.turn == ROBOT else h_name),
            value=0, goal=goal, moves=[move_of(e, t) for e in chosen(n)]))
    costs = {"inform": num(p.costs.inform), "ask": num(p.costs.ask),
             "wait": num(p.costs.wait), "pass": num(p.costs.pass_),
             "actions": {k: num(v) for k, v in sorted(p.costs.actions.items())}}
    obj = p.objective
    worst, mean = graph_costs(nodes, obj)
    own = mean if obj.kind == ObjectiveKind.EXPECTED else worst
    for x in nodes:
        x.value = own[x.id]
    objective = {"kind": obj.kind.value,
                 "weights": {k: num(v) for k, v in sorted(obj.weights.items())},
                 "ties": list(obj.ties)}
    policy = Policy(problem_name, p.domain.name, {"robot": r_name, "human": h_name}, p.K,
                    costs, nodes, own[0], 0, 0, optimal, stats or {}, list(p.after), objective,
                    worst[0], mean[0])
    policy.leaves = policy.count_branches()
    policy.communications = policy.count_communications()
    return policy


def graph_costs(nodes: list[PolicyNode], objective: Objective) -> tuple[list[Cost], list[Cost]]:
    """§7 on a policy graph: each node's worst-case and expected cost to the end (the maximum,
    resp. the weighted mean, over a human node's moves; a robot node has one move), children
    before parents."""
    worst: list[Cost] = [0] * len(nodes)
    mean: list[Cost] = [0] * len(nodes)
    for i in reversed(topological_order(nodes)):
        moves = nodes[i].moves
        if not moves:
            continue
        worst[i] = max(m.cost + worst[m.to] for m in moves)
        if len(moves) == 1:
            mean[i] = moves[0].cost + mean[moves[0].to]
            continue
        mean[i] = weighted_mean([objective.weight(m.action, m.name) for m in moves],
                                [m.cost + mean[m.to] for m in moves])
    return worst, mean


def explain_failure(gr: Graph, root: int) -> str:
    """Follow one failing line of play from the root and say where it dies."""
    from .andor import DEAD, OPEN

    sem = gr.sem
    names = (sem.names[0], sem.names[1])
    path: list[str] = []
    seen = {root}
    n = root
    while True:
        if gr.status[n] == DEAD:
            return _why(path, gr.dead_why.get(n, "dead end"))
        if gr.status[n] == OPEN:
            return _why(path, "the search stopped before this state was explored")
        edges = gr.edges[n]
        if gr.is_robot(n):
            nxt = next((e for e in edges if e.child not in seen), None)
            if nxt is None:
                return _why(path, f"every option of {names[0]} leads back to an earlier state")
        else:
            bad = [e for e in edges if e.child < 0 or not gr.solved[e.child]]
            fail = next((e for e in bad if e.child < 0), None)
            if fail is not None:
                path.append(f"{names[1]} {fail.move.label}")
                return _why(path, fail.move.failure)
            nxt = next((e for e in bad if e.child not in seen), None)
            if nxt is None:
                return _why(path, "every human choice here loops back to an earlier state")
        agent = names[0] if nxt.move.agent == ROBOT else names[1]
        path.append(f"{agent} {nxt.move.label}")
        n = nxt.child
        seen.add(n)


def _why(path: list[str], reason: str) -> str:
    steps = ", ".join(path[-12:])
    more = "…, " if len(path) > 12 else ""
    return (f"after {more}{steps}: {reason}" if path else reason)


__all__ = ["explain_failure", "extract", "graph_costs"]
