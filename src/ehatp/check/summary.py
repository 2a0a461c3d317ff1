"""The validator's last checks (docs/semantics.md §7, docs/policy-format.md): the costs and
objective a policy records, every node's value recomputed from the validator's own move costs
(worst case and expected), the policy's cost, and its branches and communications counted in
its tree unfolding.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

from ..formats.policy import PolicyMove
from ..model.options import Metric, ObjectiveKind
from ..model.vocabulary import ROBOT
from .metrics import MetricReader
from .replay import Replay
from .rules import ACTION, ANNOUNCE, ASK, INFORM, _num, _same

COMMUNICATIONS = (INFORM, ASK, ANNOUNCE)  # the moves counted as communications (§5)


def check_costs(rp: Replay) -> None:
    """§7: the costs the policy records are the problem's (inform, ask, wait, pass and each
    action's)."""
    c = rp.problem.costs
    want: dict[str, object] = {"inform": c.inform, "ask": c.ask, "wait": c.wait,
                               "pass": c.pass_}
    got = rp.policy.costs
    for key, v in want.items():
        if key not in got or not _same(got[key], v):
            rp.fail([], f"policy costs[{key!r}] is {got.get(key)}, the problem's is {v}")
    acts = got.get("actions", {})
    if set(acts) != set(c.actions) or any(not _same(acts[a], c.actions[a]) for a in acts):
        rp.fail([], f"policy costs['actions'] is {acts}, the problem's is "
                  f"{dict(c.actions)}")


def values(rp: Replay, order: list[int] | None
           ) -> tuple[dict[int, Fraction | None], dict[int, Fraction | None]]:
    """§7: the worst-case and the expected cost-to-go of every node, from the validator's
    own move costs and the problem's weights, children before parents; None under a
    violation (or everywhere on a cyclic policy)."""
    nodes = rp.policy.nodes
    worst: dict[int, Fraction | None] = {}
    mean: dict[int, Fraction | None] = {}
    for n in order or []:
        node = nodes[n]
        worst[n] = mean[n] = None
        if not node.moves:
            if n in rp.goals_reached:
                worst[n] = mean[n] = Fraction(0)
            continue
        turn = rp.turn.get(n)
        if turn is None or (turn == ROBOT and len(node.moves) != 1):
            continue
        parts: list[tuple[Fraction, Fraction, Fraction]] = []
        for j, move in enumerate(node.moves):
            w, v, cost = worst.get(move.to), mean.get(move.to), rp.step_cost.get((n, j))
            if w is None or v is None or cost is None:
                break
            parts.append((cost + w, cost + v, rp.weight.get((n, j), Fraction(1))))
        else:
            worst[n] = max(p[0] for p in parts)
            total = sum((p[2] for p in parts), Fraction(0))
            mean[n] = sum((p[2] * p[1] for p in parts), Fraction(0)) / total
    return worst, mean


def check_objective(rp: Replay) -> None:
    """§7: the policy's objective is the problem's (kind, and weights and ties if given)."""
    got, want = rp.policy.objective, rp.problem.objective
    kind = got.get("kind") if isinstance(got, dict) else None
    if kind != want.kind.value:
        rp.fail([], f"policy objective kind is {kind!r}, but the problem's objective is "
                  f"{want.kind.value!r} (§7)")
        return
    weights = got.get("weights")
    if weights is not None:
        mine = {"".join(str(k).split()): v for k, v in dict(weights).items()}
        if set(mine) != set(want.weights) or any(not _same(mine[k], want.weights[k])
                                                 for k in mine):
            theirs = ", ".join(f"{k!r}: {_num(v)}" for k, v in want.weights.items())
            rp.fail([], f"policy objective weights are {dict(weights)}, but the "
                      f"problem's are {{{theirs}}} (§7)")
    ties = got.get("ties")
    if ties is not None and list(ties) != list(want.ties):
        rp.fail([], f"policy objective ties are {list(ties)}, but the problem's are "
                  f"{[str(t) for t in want.ties]} (§7)")
    if want.kind == ObjectiveKind.PREFERENCES:
        # C11: any of the problem's profiles (a relabelled policy chose another one)
        profile = str(got.get("profile"))
        if profile not in want.profiles:
            rp.fail([], f"policy profile is {profile!r}, not one of the problem's "
                      f"({', '.join(sorted(want.profiles))}) (C11)")
        elif got.get("metrics") != [str(m) for m in want.profiles[profile]]:
            rp.fail([], f"policy profile {profile!r} orders {got.get('metrics')}, the "
                      f"problem's orders {[str(m) for m in want.profiles[profile]]} (C11)")
        else:  # the domain's metrics it names, as the domain declares them
            declared = rp.problem.domain.metrics
            mine = {m: declared[m].declaration() for m in want.profiles[profile]
                    if m in declared}
            if got.get("domain_metrics", {}) != mine:
                rp.fail([], f"policy objective domain_metrics is "
                          f"{got.get('domain_metrics', {})}, but the domain declares {mine} "
                          "(C11)")
        if got.get("estimate") != str(want.estimate):
            rp.fail([], f"policy estimate is {got.get('estimate')!r}, the problem's is "
                      f"{str(want.estimate)!r} (C11)")


def check_summary(rp: Replay, order: list[int] | None) -> None:
    """§7: every node's recorded value is its cost-to-go under the objective, recomputed from
    the validator's own move costs; the policy's cost, worst case and expected cost agree; its
    communications and leaves are those of its tree unfolding."""
    pol = rp.policy
    nodes = pol.nodes
    worst, mean = values(rp, order)
    expected = rp.problem.objective.kind == ObjectiveKind.EXPECTED
    val, what = (mean, "expected") if expected else (worst, "worst-case")
    path_to = paths(rp)
    for n in sorted(val, key=lambda i: (len(path_to.get(i, [])), i)):
        v = val[n]
        if v is not None and not _same(nodes[n].value, v):
            rp.fail(path_to.get(n, []), f"node {n} ({reached_by(rp, n)}): value is "
                      f"{nodes[n].value}, but its {what} cost-to-go is {_num(v)} "
                      "(§7)")
    root_value = val.get(0)
    if not _same(pol.cost, nodes[0].value):
        rp.fail([], f"policy cost is {pol.cost}, but the root's value is "
                  f"{nodes[0].value}")
    elif root_value is not None and not _same(pol.cost, root_value):
        rp.fail([], f"policy cost is {pol.cost}, but the {what} cost is "
                  f"{_num(root_value)}")
    for name, got, want in (("worst_case", pol.worst_case, worst.get(0)),
                            ("expected", pol.expected, mean.get(0))):
        if got is not None and want is not None and not _same(got, want):
            rp.fail([], f"policy {name} is {got}, but the policy's "
                      f"{name.replace('_', '-')} cost is {_num(want)} (§7)")
    if order is None:
        return
    if rp.problem.objective.kind == ObjectiveKind.PREFERENCES:
        check_preferences(rp, order)
    # counted in the tree unfolding, by the number of root paths reaching each node
    reach = dict.fromkeys(order, 0)
    reach[0] = 1
    comms = leaves = 0
    for n in reversed(order):  # parents first
        for move in nodes[n].moves:
            reach[move.to] += reach[n]
            if move.kind in COMMUNICATIONS or move.told:
                comms += reach[n]
        if not nodes[n].moves:
            leaves += reach[n]
    if pol.communications != comms:
        rp.fail([], f"communications is {pol.communications}, but the policy has "
                  f"{comms} inform/ask/announce moves and moves said with an inform "
                  "(counted in its tree unfolding)")
    if pol.leaves != leaves:
        rp.fail([], f"leaves is {pol.leaves}, but the policy has {leaves} leaves in its "
                  "tree unfolding (root-to-leaf branches)")


def check_preferences(rp: Replay, order: list[int]) -> None:
    """C11: the profile's vector the policy records at every node (``objective.vectors``) is
    its branches' worst (or, ``estimate = "optimistic"``, best) vector, recomputed here from
    the moves (children first, ``order``). A step ends at a move marked ``"reply"`` or
    ``"ask"`` and costs ``[steps] cost`` of ``makespan``; ``human_end`` adds that when the
    human acts in the step (its own move an action: the reply itself with the robot first,
    the move into the reply node with the human first) or later; ``human_effort`` counts the
    human's actions, ``effort`` every action, ``communications`` inform, ask and announce
    moves and moves said with an inform. A metric the domain declares
    (:class:`~.metrics.MetricReader`, read from its declaration) adds 1 at a step's end when
    an action of the step (the ending move's, or the move into the reply node) is one it
    counts, its condition read in the step's start state (the reply node's recorded
    state)."""
    pol, problem = rp.policy, rp.problem
    obj = pol.objective
    names = obj.get("metrics")
    vectors = obj.get("vectors")
    declared = problem.domain.metrics
    if not isinstance(names, list) or not isinstance(vectors, list) \
            or len(vectors) != len(pol.nodes) \
            or any(not isinstance(m, str) or m not in list(Metric) and m not in declared
                   for m in names):
        rp.fail([], "a preferences policy records objective.metrics (built in or the "
                "domain's) and one vector per node (objective.vectors) (C11)")
        return
    metrics = [Metric(m) if m in list(Metric) else str(m) for m in names]
    reader = MetricReader(problem, rp.sem.grounded)
    optimistic = obj.get("estimate") == "optimistic"
    human = pol.agents.get("human")
    step = problem.steps.cost
    acting: set[int] = set()  # reply nodes whose step's human move is an action
    opened: dict[int, PolicyMove] = {}  # reply node -> the move that started its step
    for node in pol.nodes:
        for move in node.moves:
            if move.step == "human" and move.agent == human and move.kind == ACTION:
                acting.add(move.to)
            if move.step in ("human", "robot") and 0 <= move.to < len(pol.nodes):
                opened[move.to] = move

    def counted(n: int, move: PolicyMove, metric: str) -> bool:
        """Whether the step ``move`` ends at node ``n`` has an action ``metric`` counts."""
        state = frozenset(pol.nodes[n].state)
        first = opened.get(n) if move.step == "reply" else None
        return any(m.kind == ACTION and reader.counts(
            declared[metric], "human" if m.agent == human else "robot", m.name, m.args, state)
            for m in (move, first) if m is not None)
    vec: dict[int, tuple[Fraction, ...]] = {}
    for n in order:
        node = pol.nodes[n]
        if not node.moves:
            vec[n] = tuple(Fraction(0) for _ in metrics)
            continue
        options: list[tuple[Fraction, ...]] = []
        for move in node.moves:
            after = vec.get(move.to)
            if after is None:
                return  # a cycle or a violation reported elsewhere
            ends = move.step in ("reply", "ask")
            is_human = move.agent == human
            acts = move.kind == ACTION
            human_acts = acts if is_human else n in acting
            out: list[Fraction] = []
            for m, x in zip(metrics, after, strict=True):
                if m == Metric.MAKESPAN:
                    out.append(x + step if ends else x)
                elif m == Metric.HUMAN_END:
                    out.append(x + step if ends and (human_acts or x > 0) else x)
                elif m == Metric.HUMAN_EFFORT:
                    out.append(x + 1 if is_human and acts else x)
                elif m == Metric.EFFORT:
                    out.append(x + 1 if acts else x)
                elif m == Metric.COMMUNICATIONS:
                    out.append(x + 1 if move.kind in COMMUNICATIONS or move.told else x)
                else:  # the domain's
                    out.append(x + 1 if ends and counted(n, move, m) else x)
            options.append(tuple(out))
        vec[n] = min(options) if optimistic else max(options)
    path_to = paths(rp)
    for n in sorted(vec, key=lambda i: (len(path_to.get(i, [])), i)):
        got: Any = vectors[n]
        if not isinstance(got, list) or len(got) != len(metrics) \
                or any(not _same(g, w) for g, w in zip(got, vec[n], strict=True)):
            rp.fail(path_to.get(n, []), f"node {n} ({reached_by(rp, n)}): its recorded "
                    f"{'/'.join(names)} are {got}, but its "
                    f"{'best' if optimistic else 'worst'} branch's are "
                    "[" + ", ".join(_num(x) for x in vec[n]) + "] (C11)")
            return
    if obj.get("value") != vectors[0]:
        rp.fail([], f"policy objective value is {obj.get('value')}, but the root's vector is "
                f"{vectors[0]} (C11)")


def reached_by(rp: Replay, n: int) -> str:
    """How node ``n`` was first reached: "start", or the move into it."""
    path = paths(rp).get(n)
    return path[-1] if path else "start"


def paths(rp: Replay) -> dict[int, list[str]]:
    """The path to each node: the one it was first checked by, else the first found."""
    nodes = rp.policy.nodes
    out: dict[int, list[str]] = {0: [], **rp.path_of}
    stack = list(out)
    while stack:
        n = stack.pop()
        for move in nodes[n].moves:
            if 0 <= move.to < len(nodes) and move.to not in out:
                out[move.to] = [*out[n], f"{move.agent} {move.action}"]
                stack.append(move.to)
    return out



__all__ = ["check_costs", "check_objective", "check_summary"]
