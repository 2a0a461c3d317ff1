"""Policy extraction: the robot policy chosen by the values, as a :class:`Policy` (the file
format lives in :mod:`ehatp.policy_format`), and why no policy exists when none does."""

from __future__ import annotations

from typing import Any

from ..epistemic.semantics import ACTION, ASK, INFORM, WAIT, Move, bits_of
from ..epistemic.state import ROBOT, EState
from ..model.grounding import FINISH
from ..model.options import Objective, ObjectiveKind
from ..model.problem import Cost
from ..policy_format import Policy, PolicyNode, num
from .andor import GOAL, Graph
from .values import Values, weighted_mean


def extract(gr: Graph, root: int, values: Values, *, problem_name: str,
            optimal: bool = True, stats: dict[str, Any] | None = None) -> Policy:
    """The policy the values chose, from ``root``, as a tree in preorder (docs/policy-format.md).

    Both costs of §7 are computed again on the extracted tree: its worst case (the maximum over
    human branches) and its expected cost (their weighted mean, ``[objective.weights]``); each
    node's ``value`` and the policy's ``cost`` are the objective's."""
    sem = gr.sem
    g = sem.g
    p = g.problem
    r_name, h_name = p.domain.robot_name, p.domain.human_name
    nodes: list[PolicyNode] = []

    def agenda(ag: tuple[int, ...]) -> list[str]:
        return [g.task_names[t] for t in ag if t != FINISH]

    def make(n: int, move: Move | None, before: int = 0) -> PolicyNode:
        es: EState = gr.states[n]
        t = es.true
        div = 0
        diffs = []
        for s in sorted({s for s, _ in es.worlds}):
            div |= s ^ t
            diffs.append({"true": g.mask_atoms(s & ~t), "false": g.mask_atoms(t & ~s)})
        cost: Cost = 0
        told: list[str] = []
        if move is None:
            agent, kind, label, name, args = None, "start", "start", "start", []
        else:
            agent = r_name if move.agent == ROBOT else h_name
            kind, cost = move.kind, move.cost
            name, call_args, label = sem.describe(move)
            args = list(call_args)
            if kind in (ACTION, WAIT) and move.atoms:  # said while acting (§5), as labelled
                told = list(sem.literals(before, move.atoms))
        node = PolicyNode(
            id=len(nodes), agent=agent, kind=kind, action=label, name=name, args=args,
            cost=cost, copresent=sem.copresent(t), k=es.k, worlds=len(es.worlds),
            divergence=[(a if t >> i & 1 else f"not {a}")
                        for i, a in ((i, g.atoms[i]) for i in bits_of(div))],
            world_diffs=diffs, state=g.state_atoms(t), robot_agenda=agenda(es.robot_agenda),
            human_agenda=agenda(es.human_agenda),
            to_move=None if gr.status[n] == GOAL else (r_name if es.turn == ROBOT else h_name),
            value=0, goal=gr.status[n] == GOAL, told=told)
        nodes.append(node)
        return node

    # iterative DFS in canonical child order; ids are preorder positions
    root_node = make(root, None)
    stack: list[tuple[int, PolicyNode]] = [(root, root_node)]
    while stack:
        n, pn = stack.pop()
        if gr.status[n] == GOAL:
            continue
        edges = gr.edges[n]
        chosen = [edges[values.choice[n]]] if gr.is_robot(n) else edges
        kids = []
        for e in chosen:
            kids.append((e.child, make(e.child, e.move, gr.states[n].true)))
        pn.children = [k.id for _, k in kids]
        stack.extend(reversed(kids))
    # renumber to preorder so ids read top-down
    order: list[PolicyNode] = []
    st = [nodes[0]]
    while st:
        x = st.pop()
        order.append(x)
        st.extend(reversed([nodes[i] for i in x.children]))
    remap = {x.id: i for i, x in enumerate(order)}
    for x in order:
        x.id = remap[x.id]
        x.children = [remap[c] for c in x.children]
    leaves = sum(1 for x in order if not x.children)
    comms = sum(1 for x in order if x.kind in (INFORM, ASK) or x.told)
    costs = {"inform": num(p.costs.inform), "ask": num(p.costs.ask),
             "wait": num(p.costs.wait), "pass": num(p.costs.pass_),
             "actions": {k: num(v) for k, v in sorted(p.costs.actions.items())}}
    obj = p.objective
    worst, mean = tree_costs(order, obj)
    own = mean if obj.kind == ObjectiveKind.EXPECTED else worst
    for x in order:
        x.value = own[x.id]
    objective = {"kind": obj.kind.value,
                 "weights": {k: num(v) for k, v in sorted(obj.weights.items())},
                 "ties": list(obj.ties)}
    return Policy(problem_name, p.domain.name, {"robot": r_name, "human": h_name}, p.K, costs,
                  order, own[0], comms, leaves, optimal, stats or {}, list(p.after), objective,
                  worst[0], mean[0])


def tree_costs(nodes: list[PolicyNode], objective: Objective) -> tuple[list[Cost], list[Cost]]:
    """§7 on a policy tree in preorder: each node's worst-case and expected cost to the end
    (the maximum, resp. the weighted mean, over a human node's branches; a robot node has one
    child)."""
    worst: list[Cost] = [0] * len(nodes)
    mean: list[Cost] = [0] * len(nodes)
    for x in reversed(nodes):  # preorder reversed: children first
        if not x.children:
            continue
        kids = [nodes[c] for c in x.children]
        worst[x.id] = max(k.cost + worst[k.id] for k in kids)
        if len(kids) == 1:
            mean[x.id] = kids[0].cost + mean[kids[0].id]
            continue
        mean[x.id] = weighted_mean([objective.weight(k.action, k.name) for k in kids],
                                   [k.cost + mean[k.id] for k in kids])
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


__all__ = ["explain_failure", "extract", "tree_costs"]
