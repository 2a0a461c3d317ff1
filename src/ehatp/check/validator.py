"""The independent validator: replays a policy and checks it against docs/semantics.md.

Written from the semantics document, not from the planner's code, so that a planner bug shows
up as a violation instead of being copied. It uses only the model layer (grounded atoms,
operators, methods, formulas) and re-implements refinement, situation assessment, world
updates, the product of unseen robot turns and both agents' options with plain sets and loops.

Every node of the policy is recomputed from the initial state (after the fixed opening
``policy.after``) and its recorded facts, the moves out of it, their costs and its value are
compared with the recomputation. Checking stops at the first violation of a branch; other
branches go on. The policy is a graph (docs/policy-format.md): a node reached again by another
path is not checked again, but the state recomputed along that path must equal the one of its
first visit, so the replay is linear in the policy's nodes and moves, and so are the values and
the branch counts, computed over the graph children first.

The problem's options are read as the document states them: the human's pass rule, whether
it anticipates unseen robot turns and whether the robot sees its method choices (``[human]``,
§3-§4), where and how the robot may inform, announce or ask and whether the human asks
(``[communication]``, §5), and the objective the values are under (``[objective]``, §7). Both
the worst-case and the expected value of every node are recomputed from the validator's own
move costs.

What the robot observes (§3): it sees the human's actions, never its methods, so a node holds
the set A_H of human agendas that fit what it saw, and the human's options are grouped by label
(one AND branch per label). The policy must be executable by a robot that sees only that: a
robot node has one move, a human node never two moves with the same label (that would branch
on a hidden choice), and each recorded edge leads to the node of the move it names, also when
several robot moves share a label.

A lifted policy (format version 3: canonical nodes, each edge with the renaming of
interchangeable objects that maps its successor onto its child) is checked without expanding
it (§3, "Symmetry"): every renaming it uses is a permutation within its declared classes and an
automorphism of the ground problem, the root is the initial node renamed by the table's root
renaming, each edge's successor renamed is its child, and where a node stands for a renamed
real state no move there decides by index or name order (observation order, the informing
set's name tie-break). Values, costs and counts are checked as for version 2.

The validator in modules: :mod:`.rules` (refinement, observation, moves, goal: §1-§4, §6),
:mod:`.network` (partially ordered agendas, §1), :mod:`.communication` (§5), :mod:`.replay`
(walking the policy, comparing recorded facts and moves), :mod:`.summary` (values, costs
and counts, §7), :mod:`.automorphism` (renamings of interchangeable objects, §3) and
:mod:`.lifted` (a lifted policy's table and renamings); this module checks a policy with them
and gives the verdict.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from ..formats.policy import Policy
from ..model.problem import Problem
from ..model.vocabulary import HUMAN, ROBOT
from .communication import Semantics
from .lifted import Lifted, LiftedCheck, lifted_of
from .network import Agenda, Block
from .replay import Replay
from .rules import EState, Step, _same
from .summary import check_costs, check_objective, check_summary

_Semantics = Semantics  # its older name (tests and notebooks use it)


@dataclass
class Report:
    """The verdict: ``message`` is the first violation (branch and rule), or a summary."""

    ok: bool
    message: str
    violations: list[str] = field(default_factory=list)
    nodes_checked: int = 0
    branches_checked: int = 0

    def __bool__(self) -> bool:
        return self.ok

    def __str__(self) -> str:
        return self.message


def validate(problem: Problem, policy: Policy, lifted: Lifted | None = None, *,
             check: Callable[[], None] | None = None) -> Report:
    """Check ``policy`` against ``problem``: every rule of docs/semantics.md, §1-§7 (see the
    module docstring). The steps: the policy's header (:func:`_header`), its recorded costs
    and objective, the opening moves and the walk from the root (:class:`~.replay.Replay`),
    the graph's shape, then the values and counts (:func:`~.summary.check_summary`).

    A lifted policy (format version 3: its ``symmetry`` table, or ``lifted`` given apart) is
    checked on its canonical nodes, never expanded (:mod:`.lifted`): each renaming it uses is
    an automorphism of the problem, the root is the initial node renamed by
    ``renamings[root]``, and each edge's renaming maps the successor onto its child.

    ``check`` is called now and then while grounding, refining and walking the policy (every
    few hundred steps); a caller's time or memory limit raises from it to stop the check,
    and the exception goes through unchanged: a stopped check is no verdict."""
    rp = Replay(problem, policy, check)
    nodes = policy.nodes
    if not nodes or not _header(rp):
        return _report(rp, None)
    lifted = lifted if lifted is not None else lifted_of(policy)
    if lifted is not None:
        rp.lifted = LiftedCheck(problem, rp.sem, lifted)
        if rp.lifted.table_error is not None:
            rp.fail([], rp.lifted.table_error)
            return _report(rp, None)
    check_costs(rp)
    check_objective(rp)
    root_es = rp.replay_after()
    found = rp.order()
    order = found if isinstance(found, list) else None
    if rp.lifted is not None and order is not None:
        rp.renamed = rp.lifted.renamed_nodes(policy, order)
    if root_es is not None:
        rp.walk(root_es)
    if order is None:
        rp.fail([], f"node {found} is its own descendant: the policy has a cycle "
                "(§7: policies are acyclic)")
    elif len(order) != len(nodes):
        rp.fail([], f"{len(nodes) - len(order)} node(s) are not reachable from the root")
    check_summary(rp, order)
    if rp.lifted is not None:
        _unused_renamings(rp, rp.lifted)
    return _report(rp, order)


def _unused_renamings(rp: Replay, check: LiftedCheck) -> None:
    """§3: the renamings of the table no edge used are automorphisms too."""
    used = check.checked()
    for rid in range(len(check.lifted.renamings)):
        if rid not in used:
            ren = check.renaming(rid)
            if isinstance(ren, str):
                rp.fail([], f"symmetry.renamings[{rid}]: {ren}")


def _header(rp: Replay) -> bool:
    """Check what the policy says of itself (docs/policy-format.md): node ids, the problem and
    domain it was planned for, K and the agents' names. Return whether checking may go on
    (ids, problem and domain names right)."""
    pol, sem, problem = rp.policy, rp.sem, rp.problem
    if any(n.id != i for i, n in enumerate(pol.nodes)):
        rp.fail([], "node ids are not their positions in the node list")
        return False
    if pol.problem != problem.name:
        rp.fail([], f"the policy was planned for problem {pol.problem!r}, not for "
                f"{problem.name!r}: solve this problem, or validate against the "
                "policy's own problem")
        return False
    if pol.domain != problem.domain.name:
        rp.fail([], f"the policy was planned for domain {pol.domain!r}, not for "
                f"{problem.domain.name!r}: solve this problem, or validate against the "
                "policy's own problem")
        return False
    if pol.K != sem.K:
        rp.fail([], f"policy K is {pol.K}, the problem's is {sem.K}")
    if pol.agents != {"robot": sem.names[ROBOT], "human": sem.names[HUMAN]}:
        rp.fail([], f"policy agents {pol.agents} are not the domain's")
    st = rp.problem.steps
    want = ({"mode": st.mode.value, "first": st.first.value, "witness": st.witness.value,
             "commute": st.commute.value, "cost": st.cost} if st.concurrent else None)
    same = (pol.step_options == want or pol.step_options is not None and want is not None
            and {**pol.step_options, "cost": 0} == {**want, "cost": 0}
            and _same(pol.step_options.get("cost"), want["cost"]))
    if not same:
        rp.fail([], f"policy steps are {pol.step_options}, the problem's [steps] are {want} "
                "(docs/concurrent.md)")
    return True


def _report(rp: Replay, order: list[int] | None) -> Report:
    """Return the verdict: the first violation and all of them, or a summary of what was
    checked (nodes, and branches counted over the graph)."""
    branches = rp.branches_checked(order)
    if rp.violations:
        return Report(False, rp.violations[0], list(rp.violations), rp.nodes_checked,
                      branches)
    return Report(True, f"valid: {rp.nodes_checked} nodes, {branches} branches checked",
                  [], rp.nodes_checked, branches)


__all__ = ["Agenda", "Block", "EState", "Report", "Step", "validate"]
