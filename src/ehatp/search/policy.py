"""Policy extraction: the robot policy chosen by the values, as a :class:`Policy` graph (the
file format lives in :mod:`ehatp.policy_format`), and why no policy exists when none does."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from itertools import combinations
from typing import Any

from ..epistemic.semantics import ACTION, ASK, WAIT, Move, bits_of
from ..epistemic.state import HUMAN, ROBOT, EState
from ..formats.policy import Policy, PolicyMove, PolicyNode, num, topological_order
from ..model.options import Objective, ObjectiveKind
from ..model.problem import Cost, Problem
from .graph import DEAD, EXPANDED, GOAL, OPEN, Edge, Graph, move_key
from .values import Values, weighted_mean


def extract(gr: Graph, root: int, values: Values, *, problem_name: str,
            optimal: bool = True, stats: dict[str, Any] | None = None,
            check: Callable[[], None] | None = None,
            objective: Objective | None = None) -> Policy:
    """Return the policy the values chose, from ``root``, as a graph (docs/policy-format.md):
    one policy node per search node the policy reaches, memoised by search node, so the work
    and the file are linear in the policy's distinct states however many branches share them.
    Node ids are the depth-first preorder of first visits, moves in canonical order.

    Both costs of §7 are computed again on the extracted graph: its worst case (the maximum over
    human branches) and its expected cost (their weighted mean, ``[objective.weights]``); each
    node's ``value`` and the policy's ``cost`` are the objective's. Branches and communications
    are counted over the graph too (:meth:`Policy.count_branches`). ``objective`` (default:
    the problem's) is the one ``values`` were computed for (C11: relabelling chooses another
    profile); under ``kind = "preferences"`` the file records the profile and each node's
    vector of its metrics (``values.vector``). ``check`` (e.g. a time
    limit's, docs/semantics.md §7 "Search") is called once per policy node and may raise to
    stop the work.

    Over canonical states (``gr.sym``, docs/semantics.md §3 "Symmetry") the policy is
    *lifted* (format version 3): its nodes are the canonical nodes the policy reaches, each
    move carries the renaming from its child, seen from its node, to the child node (the
    search's :attr:`Edge.perm`), and ``symmetry`` holds the table of renamings, numbered in
    order of first use (0 the identity, then the root's). Costs and counts are those of the
    real policy: a renaming keeps them."""
    if check is None:
        check = _no_check

    def chosen(n: int) -> list[Edge]:
        if gr.status[n] == GOAL:
            return []
        edges = gr.edges[n]
        return [edges[values.choice[n]]] if gr.is_robot(n) else list(edges)

    order = _preorder(root, chosen, check)
    index = {n: i for i, n in enumerate(order)}
    table = _Table(gr) if gr.sym is not None else None
    nodes: list[PolicyNode] = []
    for i, n in enumerate(order):
        check()
        nodes.append(_policy_node(gr, i, n, [_policy_move(gr, e, index, table)
                                             for e in chosen(n)]))
    p = gr.sem.grounded.problem
    obj = p.objective if objective is None else objective
    policy = _policy(replace(p, objective=obj), problem_name, nodes, optimal, stats or {})
    if obj.kind == ObjectiveKind.PREFERENCES:
        assert values.vector is not None
        vectors: list[list[Any]] = []
        for n in order:
            v = values.vector[n]
            assert v is not None  # every node of the chosen policy has its vector
            vectors.append([num(x) for x in v])
        policy.objective["vectors"] = vectors
        policy.objective["value"] = policy.objective["vectors"][0]
    if table is not None:
        policy.symmetry = table.as_dict()
    return policy


class _Table:
    """The renamings a lifted policy uses, numbered in order of first use: 0 the identity,
    then the root's (the search's ``root_perm``), then the edges' in node and move order."""

    def __init__(self, gr: Graph) -> None:
        sym = gr.sym
        assert sym is not None
        self.sym = sym
        self.ids: dict[int, int] = {0: 0}
        self.root = self.local(gr.root_perm)

    def local(self, pid: int) -> int:
        """The file's index of the search's renaming ``pid``."""
        i = self.ids.get(pid)
        if i is None:
            i = self.ids[pid] = len(self.ids)
        return i

    def as_dict(self) -> dict[str, Any]:
        sym = self.sym
        return {"objects": list(sym.objects),
                "classes": [[sym.objects[i] for i in cls] for cls in sym.classes],
                "renamings": [list(sym.perms[pid]) for pid in self.ids], "root": self.root}


def _no_check() -> None:
    """The ``check`` of extraction and realisation when no limit is watched."""


def _preorder(root: int, chosen: Callable[[int], list[Edge]],
              check: Callable[[], None]) -> list[int]:
    """Return the search nodes the policy reaches from ``root`` through the ``chosen`` edges,
    depth first, in the preorder of first visits (a node reached again is not expanded
    again): the policy's node ids."""
    order: list[int] = []
    seen: set[int] = set()
    stack = [root]
    while stack:
        n = stack.pop()
        if n in seen:
            continue
        check()
        seen.add(n)
        order.append(n)
        stack.extend(e.child for e in reversed(chosen(n)))
    return order


def _policy_move(gr: Graph, e: Edge, index: dict[int, int],
                 table: _Table | None = None) -> PolicyMove:
    """Return the edge ``e`` as a policy move (docs/policy-format.md): the agent's name, the
    move's kind, label, name and arguments, cost, the policy node it leads to (``index``: by
    search node) and what was said with it (§5, as it is after the move). In a lifted policy
    (``table``) the move is in its node's names, what was said read in the child as seen from
    there, and it carries the renaming to the child node."""
    sem = gr.sem
    move: Move = e.move
    renaming = 0
    if table is not None and e.perm:
        renaming = table.local(e.perm)
        if move.child is not None:  # the descriptor holds the child node's state: see it
            move = replace(move, child=table.sym.apply(table.sym.inverse(e.perm), move.child))
    name, call_args, label = sem.describe(move)
    told: list[str] = []
    if move.kind in (ACTION, WAIT) and move.atoms:  # said with a move (§5): as it is after
        assert move.child is not None
        told = list(sem.literals(move.child.true, move.atoms))
    step = ""
    if sem.grounded.problem.steps.concurrent:  # docs/concurrent.md: the moves of a step
        first = sem.grounded.problem.steps.first.value  # who decides first (C4)
        step = ("ask" if move.kind == ASK else first if sem.names[move.agent] == sem.names[
            HUMAN if first == "human" else ROBOT] else "reply")
    return PolicyMove(agent=sem.names[move.agent], kind=str(move.kind), action=label,
                      name=str(name), args=list(call_args), cost=move.cost, to=index[e.child],
                      told=told, renaming=renaming, step=step)


def _policy_node(gr: Graph, i: int, n: int, moves: list[PolicyMove]) -> PolicyNode:
    """Return search node ``n`` as policy node ``i`` with its ``moves``: the recorded facts
    of its state (docs/policy-format.md; the agendas with partially ordered blocks as
    ``{a | b}``, §1), its value left 0 (see :func:`_policy`)."""
    sem = gr.sem
    grounded = sem.grounded
    es: EState = gr.states[n] if gr.sym is None else gr.sym.explicit(gr.states[n])
    t = es.true
    div = 0
    diffs = []
    for s in sorted({s for s, _ in es.worlds}):
        div |= s ^ t
        diffs.append(grounded.world_diff(s, t))
    goal = gr.status[n] == GOAL
    if not div & grounded.multi_mask:
        divergence = [grounded.atoms[b] if t >> b & 1 else f"not {grounded.atoms[b]}"
                      for b in bits_of(div)]
    else:  # a variable or counter told whole
        divergence = grounded.literals(t, div)
    return PolicyNode(
        id=i, copresent=sem.copresent(t), k=es.k, worlds=len(es.worlds), divergence=divergence,
        world_diffs=diffs, state=grounded.state_atoms(t),
        robot_agenda=sem.net.names_of(es.robot_agenda),
        human_agenda=sem.net.names_of(es.human_agendas[0]),
        to_move=None if goal else sem.names[es.turn], value=0, goal=goal, moves=moves,
        hypotheses=([sem.net.names_of(h) for h in es.human_agendas]
                    if len(es.human_agendas) > 1 else []))


def _policy(p: Problem, problem_name: str, nodes: list[PolicyNode], optimal: bool,
            stats: dict[str, Any]) -> Policy:
    """Return the policy of ``nodes`` for problem ``p``: its costs and objective as the file
    records them, each node's value and the policy's cost under the objective (§7, computed
    on the graph), both costs, and its branches and communications counted."""
    costs = {"inform": num(p.costs.inform), "ask": num(p.costs.ask),
             "wait": num(p.costs.wait), "pass": num(p.costs.pass_),
             "actions": {k: num(v) for k, v in sorted(p.costs.actions.items())}}
    obj = p.objective
    worst, mean = graph_costs(nodes, obj)
    own = mean if obj.kind == ObjectiveKind.EXPECTED else worst
    for x in nodes:
        x.value = own[x.id]
    objective: dict[str, Any] = {
        "kind": obj.kind.value, "weights": {k: num(v) for k, v in sorted(obj.weights.items())},
        "ties": [str(t) for t in obj.ties]}
    if obj.kind == ObjectiveKind.PREFERENCES:  # C11: the profile; the vectors: see extract
        objective.update(profile=obj.profile, metrics=[str(m) for m in obj.metrics])
        declared = {m: p.domain.metrics[m].declaration() for m in obj.metrics
                    if m in p.domain.metrics}
        if declared:  # what the domain's metrics the profile names count
            objective["domain_metrics"] = declared
        objective["estimate"] = str(obj.estimate)
    policy = Policy(problem_name, p.domain.name, {"robot": p.domain.robot_name,
                                                  "human": p.domain.human_name}, p.K,
                    costs, nodes, own[0], 0, 0, optimal, stats, list(p.after), objective,
                    worst[0], mean[0])
    if p.steps.concurrent:
        st = p.steps
        policy.step_options = {"mode": st.mode.value, "first": st.first.value,
                        "witness": st.witness.value, "commute": st.commute.value,
                        "cost": num(st.cost)}
    policy.leaves = policy.count_branches()
    policy.communications = policy.count_communications()
    return policy


def liftable(gr: Graph, root: int, values: Values) -> bool:
    """Whether the chosen policy of a search over canonical states can be written lifted
    (docs/policy-format.md, "Version 3"): no robot move it plays, at a node that stands for a
    *renamed* real state, says an informing set chosen by name among sets as good on
    everything else (§5), one of them naming an interchangeable object. There the real rules
    choose by the real names, maybe another set (docs/semantics.md §3), which only the mapping
    back to the real objects (:func:`realise`) follows; the planner then writes the policy
    over the real objects. The renamings a node stands for are composed along the policy's
    paths from the real root, two kept per node (one of two distinct ones moves something)."""
    sym = gr.sym
    assert sym is not None
    taus: dict[int, set[int]] = {root: {sym.inverse(gr.root_perm)}}
    stack = [root]
    while stack:
        n = stack.pop()
        if gr.status[n] == GOAL:
            continue
        edges = gr.edges[n]
        chosen = [edges[values.choice[n]]] if gr.is_robot(n) else list(edges)
        for e in chosen:
            if gr.is_robot(n) and e.move.atoms and any(taus[n]) \
                    and _named_tie(gr.sem, sym.explicit(gr.states[n]), e.move.atoms):
                return False
            mine = taus.setdefault(e.child, set())
            grew = False
            for tau in taus[n]:
                if len(mine) >= 2:
                    break
                child = sym.compose(tau, sym.inverse(e.perm))
                if child not in mine:
                    mine.add(child)
                    grew = True
            if grew:
                stack.append(e.child)
    return True


def _named_tie(sem: Any, es: EState, mask: int) -> bool:
    """Whether ``mask``, an informing set the rules chose at ``es`` (§5), ties with another
    set of its size on everything but names, one of the two naming an interchangeable
    object (the ranking of :meth:`~.symmetry.SymSemantics.informing_set`'s watch)."""
    sym = getattr(sem, "sym", None)
    if sym is None:
        return False
    grounded, t = sem.grounded, es.true
    watch = getattr(sem, "watch", None)
    sem.watch = False
    try:
        plans = [plan for plan in (False, True) if sem.informing_set(es, plan) == mask]
        if not plans:
            return False
        div = 0
        for s, _ in es.worlds:
            div |= s ^ t
        size = len(grounded.units(mask))

        def rank(m: int, combo: Any) -> tuple[int, int]:
            w2 = sem.observe(t, es.worlds, m)
            return len(w2), -sum(1 for u in combo if t & u or u in grounded.unit_names)

        best = rank(mask, grounded.units(mask))
        for plan in plans:
            want_r = sem.fixes(es, sem.observe(t, es.worlds, mask), True, plan)
            for combo in combinations(grounded.units(div), size):
                other = 0
                for u in combo:
                    other |= u
                if other == mask or not (other | mask) & sym.movable_mask:
                    continue
                if sem.fixes(es, sem.observe(t, es.worlds, other), want_r, plan) \
                        and rank(other, combo) == best:
                    return True
        return False
    finally:
        sem.watch = watch


def realise(gr: Graph, root: int, values: Values,
            check: Callable[[], None] | None = None) -> tuple[Graph, int, Values] | str:
    """The chosen policy of a search over canonical states (docs/semantics.md §3,
    "Symmetry") on the real objects: a graph of the real states the policy reaches, each move
    the real semantics' own move (with its real label and child), ready for :func:`extract`.

    A policy node is a search node ``n`` and the renaming ``tau`` from its canonical state to
    the real one; the root's is the inverse of the root's canonicalisation, and an edge whose
    real child was renamed by ``rho`` to reach its node gives the child ``tau . rho^-1``. Real
    states are memoised, so the result is a function of the real state (a real state reached
    under two renamings keeps the first: both sub-policies are images of one). Every real node
    is expanded again with the real semantics and each chosen edge matched to a real move with
    the renamed child (and the renamed action or atoms told); a human node's real moves must
    match its edges one to one. A mismatch is returned as a message (the caller then solves
    without symmetry): it would mean the semantics is not equivariant where
    :class:`~.symmetry.SymSemantics` did not notice."""
    sym, sem = gr.sym, gr.sem
    assert sym is not None
    if check is None:
        check = _no_check
    watch = getattr(sem, "watch", None)
    if watch is not None:
        sem.watch = False  # type: ignore[attr-defined]  # real states: their own decisions
    try:
        return _realise(gr, root, values, check)
    finally:
        if watch is not None:
            sem.watch = watch  # type: ignore[attr-defined]


def _realise(gr: Graph, root: int, values: Values,
             check: Callable[[], None]) -> tuple[Graph, int, Values] | str:
    """Return the real graph of :func:`realise` (see there), or why it cannot be built."""
    sym, sem = gr.sym, gr.sem
    assert sym is not None
    rg = Graph(sem)
    tau0 = sym.inverse(gr.root_perm)
    # the real states with their worlds listed (worlds kept as classes: search/worldclasses.py)
    real_root = rg.add(sym.explicit(sym.apply(tau0, gr.states[root])), 0, 0)
    choice: dict[int, int] = {}
    stack = [(root, tau0, real_root)]
    while stack:
        n, tau, r = stack.pop()
        check()
        if gr.status[n] == GOAL:
            rg.status[r] = GOAL
            continue
        rg.status[r] = EXPANDED
        edges = gr.edges[n]
        chosen = [edges[values.choice[n]]] if gr.is_robot(n) else list(edges)
        real = sorted((m if m.child is None else replace(m, child=sym.explicit(m.child))
                       for m in sem.moves(rg.states[r])), key=move_key)
        if not gr.is_robot(n) and len(real) != len(chosen):
            return f"{len(real)} real moves for {len(chosen)} canonical ones"
        used: set[int] = set()
        out: list[Edge] = []
        for e in chosen:
            if e.child < 0:
                return "a failing move in the policy"
            sigma = sym.compose(tau, sym.inverse(e.perm))
            z = sym.explicit(sym.apply(sigma, gr.states[e.child]))
            j = _match(sym, tau, e.move, z, real, used)
            if j < 0:  # a tie decided by name (§5): a real move to a renaming of the child
                j, z, sigma = _match_orbit(sym, e.move, gr.states[e.child], real, used)
                if j < 0:
                    return f"no real move for {sym.label(tau, e.move.label)}"
            used.add(j)
            c = rg.index.get(z)
            if c is None:
                c = rg.add(z, 0, 0)
                stack.append((e.child, sigma, c))
            rg.add_parent(c, r)
            out.append(Edge(rg.descriptor(real[j], c), c))
        rg.edges[r] = tuple(out)
        if gr.is_robot(n):
            choice[r] = 0
    zeros: list[Cost | float] = [0] * len(rg.states)
    return rg, real_root, Values(zeros, choice, zeros)


def _match(sym: Any, tau: int, move: Move, child: EState, real: list[Move],
           used: set[int]) -> int:
    """The real move that is ``m`` renamed by ``tau`` and leads to ``child``: same agent,
    kind and cost, the renamed action and atoms told, preferably the renamed label."""
    op = sym.task_image(tau, move.op) if move.op >= 0 else move.op
    atoms = sym.state(tau, move.atoms)
    found = -1
    label = sym.label(tau, move.label)
    for j, x in enumerate(real):
        if j in used or x.child != child or x.agent != move.agent or x.kind != move.kind \
                or x.cost != move.cost or x.op != op or x.atoms != atoms:
            continue
        if x.label == label:
            return j
        if found < 0:
            found = j
    return found


def _match_orbit(sym: Any, move: Move, node: EState, real: list[Move],
                 used: set[int]) -> tuple[int, EState, int]:
    """A real move of the same agent, kind and cost as ``m`` whose child has the canonical
    form ``node`` (an ``inform`` of another set tied with the canonical one on everything but
    names, :class:`~.symmetry.SymSemantics`); its index, child and the renaming from ``node``
    to that child."""
    for j, x in enumerate(real):
        if j in used or x.child is None or x.agent != move.agent or x.kind != move.kind \
                or x.cost != move.cost:
            continue
        c, pid = sym.canon(x.child)
        if c == node:
            return j, x.child, sym.inverse(pid)
    return -1, node, 0


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
        worst[i] = max(move.cost + worst[move.to] for move in moves)
        if len(moves) == 1:
            mean[i] = moves[0].cost + mean[moves[0].to]
            continue
        mean[i] = weighted_mean([objective.weight(move.action, move.name) for move in moves],
                                [move.cost + mean[move.to] for move in moves])
    return worst, mean


def explain_failure(gr: Graph, root: int) -> str:
    """Follow one failing line of play from the root and say where it dies (over canonical
    states, docs/semantics.md §3, the moves are renamed back to the real objects)."""
    sem = gr.sem
    sym = gr.sym
    tau = sym.inverse(gr.root_perm) if sym is not None else 0

    def real(text: str) -> str:
        return sym.label(tau, text) if sym is not None else text

    names = sem.names
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
                return _why(path, f"every option of {names[ROBOT]} leads back to an earlier state")
        else:
            bad = [e for e in edges if e.child < 0 or not gr.solved[e.child]]
            fail = next((e for e in bad if e.child < 0), None)
            if fail is not None:
                path.append(f"{names[HUMAN]} {real(fail.move.label)}")
                return _why(path, real(fail.move.failure))
            nxt = next((e for e in bad if e.child not in seen), None)
            if nxt is None:
                return _why(path, "every human choice here loops back to an earlier state")
        agent = names[nxt.move.agent]
        path.append(f"{agent} {real(nxt.move.label)}")
        if sym is not None:
            tau = sym.compose(tau, sym.inverse(nxt.perm))
        n = nxt.child
        seen.add(n)


def _why(path: list[str], reason: str) -> str:
    steps = ", ".join(path[-12:])
    more = "…, " if len(path) > 12 else ""
    return (f"after {more}{steps}: {reason}" if path else reason)


__all__ = ["explain_failure", "extract", "graph_costs", "liftable", "realise"]
