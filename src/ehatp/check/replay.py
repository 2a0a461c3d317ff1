"""The validator's replay (docs/semantics.md §3-§6, docs/policy-format.md): walk the policy
from the root, recompute every node from the initial state and the moves that lead to it, and
compare the recorded facts and moves with the recomputation.

Checking stops at the first violation of a branch; other branches go on. The policy is a graph:
a node reached again by another path is not checked again, but the state recomputed along that
path must equal the one of its first visit, so the replay is linear in the policy's nodes and
moves. The values and the summary are :mod:`.summary`'s.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction

from ..formats.policy import Policy, PolicyMove, PolicyNode
from ..model.grounded import FINISH
from ..model.options import InformWhere, Intentions, Speech
from ..model.problem import Problem
from ..model.vocabulary import HUMAN, ROBOT, Agent
from .communication import INTENTION, Semantics
from .concurrent import JointRules
from .lifted import LiftedCheck, shown
from .rules import ACTION, ASK, INFORM, PASS, SILENCE, EState, Step, _num, _same


def _differences(a: EState, b: EState, sem: Semantics) -> str:
    """What tells two states of §3 apart, in the domain's words."""
    g = sem.grounded
    out = []
    if a.turn != b.turn:
        out.append(f"{sem.names[a.turn]} moved next then, {sem.names[b.turn]} now")
    if a.true != b.true:
        out.append("the true state T differs on " + ", ".join(g.mask_atoms(a.true ^ b.true)))
    if a.robot != b.robot:
        out.append(f"the robot agenda is {sem.shown(a.robot)} then, {sem.shown(b.robot)} now")
    if a.humans != b.humans:
        out.append(f"the human agendas are {[sem.shown(h) for h in sem.ordered(a.humans)]} "
                   f"then, {[sem.shown(h) for h in sem.ordered(b.humans)]} now")
    if a.worlds != b.worlds:
        out.append(f"the human's worlds differ ({len(a.worlds)} then, {len(b.worlds)} now)")
    for what, i, j in (("k", a.k, b.k), ("the passive count", a.passive, b.passive)):
        if i != j:
            out.append(f"{what} is {i} then, {j} now")
    if a.forced != b.forced:
        out.append("the robot's last wait was forced on one path only (§4)")
    if a.opening != b.opening:
        out.append("it is the speech opening on one path only (§5)")
    if a.answering != b.answering:
        out.append("the human answers the robot's question on one path only (§5)")
    return "; ".join(out)


def _ask_matches(step: Step, label: str) -> bool:
    """Return whether the question ``step`` is the label ``label``: its conjuncts in any order
    (§5)."""
    if step.label == label:
        return True
    if len(step.texts) > 7:
        return False
    return any(f"ask({' and '.join(p)})" == label for p in itertools.permutations(step.texts))


ORDER = ("a move here observes atoms in an order a renaming changes (two or more units on "
         "which the worlds differ, none agreeing with T on all of them, one naming an "
         "interchangeable object): the lifted policy's nodes do not stand for their renamings "
         "(§3)")


TIE = ("the robot's inform here is chosen by atom names among informing sets equally good on "
       "everything else, one naming an interchangeable object: a renaming can change the "
       "choice, so the lifted policy's nodes do not stand for their renamings (§3, §5)")


@dataclass
class _Item:
    """A node to check: the state the replay reached it in, the path there, the move into it."""

    node: PolicyNode
    es: EState
    path: list[str]
    move: PolicyMove | None
    via: str = ""  # a lifted policy's edge: the renaming that took the state to the node


class Replay:
    """One validation's replay: the semantics, the violations found, and what the values and
    the summary (:mod:`.summary`) need of the walk: the goals reached, each checked move's
    cost and weight, who moves at each checked node, and the branches checked."""

    def __init__(self, problem: Problem, policy: Policy,
                 check: Callable[[], None] | None = None) -> None:
        self.problem = problem
        self.policy = policy
        self.sem = (JointRules(problem, check) if problem.steps.concurrent
                    else Semantics(problem, check))
        self.violations: list[str] = []
        self.nodes_checked = 0
        self.goals_reached: set[int] = set()  # goal leaves whose branch checked out
        # (node id, move index) -> the move's cost and weight (§7), for checked moves
        self.step_cost: dict[tuple[int, int], Fraction] = {}
        self.weight: dict[tuple[int, int], Fraction] = {}
        self.turn: dict[int, Agent] = {}  # node id -> who moves next there (checked nodes)
        # the DAG walk: the state each node was first reached in, and by which path
        self.first: dict[int, EState] = {}
        self.path_of: dict[int, list[str]] = {}
        # branches checked, counted over the graph: where a branch's check ends at a node,
        # and the children a node's branches go on into
        self.ends: dict[int, int] = {}
        self.goes_on: dict[int, list[int]] = {}
        self.lifted: LiftedCheck | None = None  # a lifted policy's renamings (version 3)
        self.renamed: set[int] = set()  # its nodes standing for a renamed real state (§3)

    def fail(self, path: Sequence[str], rule: str) -> None:
        self.violations.append(f"branch [{', '.join(path)}]: {rule}")

    def name(self, agent: Agent) -> str:
        return self.sem.names[agent]

    def move_label(self, agent: Agent, label: str) -> str:
        return f"{self.name(agent)} {label}"

    # -- moves ---------------------------------------------------------------------------------

    def robot_steps(self, es: EState, label: str) -> list[Step] | str:
        """The robot moves a policy label can denote here (§4, §5), or why it is not an
        option."""
        sem, g = self.sem, self.sem.grounded
        if isinstance(sem, JointRules):
            return self.reply_steps(sem, es, label)
        if es.opening:
            if label == SILENCE:
                return [sem.silence(es)]
            if not label.startswith("inform(") or " + " in label:
                return f"at the speech opening (§5) the robot may only inform or stay " \
                       f"silent, not {label}"
            r = self.inform_atoms(es, label)
            return r if isinstance(r, str) else [sem.inform(es, r)]
        if label == SILENCE:
            return "silence is a move only at the speech opening, before the human's first " \
                   "move (§5)"
        if " + " in label:
            if self.problem.communication.speech != Speech.WITH_ACTION:
                return 'speaking while acting needs [communication] speech = "with-action" ' \
                       '(§5)'
            said, _, act = label.partition(" + ")
            if act.startswith(("inform(", "ask(", "announce(")) or act == SILENCE:
                return f"{act} cannot be said with an inform; only an action or wait can"
            steps = self.robot_steps(es, act)
            if isinstance(steps, str):
                return steps
            # §5: what is said with a move is judged on the node the move leads to (the
            # human's next decision), with the values of the true state after it
            out: list[Step] = []
            why = ""
            for st in steps:
                assert st.after is not None  # robot moves never fail
                r = self.inform_atoms(st.after, said, f" after {act} (§5, with-action)")
                if isinstance(r, str):
                    why = why or r
                else:
                    out.append(sem.with_speech(r, st))
            return out or why
        if label == "wait":
            return [sem.robot_wait(es)]
        if label.startswith("inform("):
            r = self.inform_atoms(es, label)
            return r if isinstance(r, str) else [sem.inform(es, r)]
        if label == INTENTION:
            asked = sem.robot_ask(es)
            return asked if isinstance(asked, str) else [asked]
        if label.startswith("announce("):
            want = f"announce({', '.join(sem.shown(es.robot))})"
            if label != want:
                return f"the robot may announce only its own agenda, {want} (§5)"
            said_it = sem.announce(es)
            return said_it if isinstance(said_it, str) else [said_it]
        if label == "pass" or label.startswith(("ask(", "answer(")):
            return f"{label} is not a robot move"
        opts = [(a, r) for a, r in sem.robot_actions(es) if g.task_names[a] == label]
        if opts:
            return [sem.robot_act(es, a, r) for a, r in opts]
        if not (sem.cop(es.true) or es.k < sem.K):
            return f"the agents are apart and k = K = {sem.K}: only wait is allowed"
        tid = g.task_index.get(label)
        op = g.robot.ops.get(tid) if tid is not None else None
        if op is None:
            if label.partition("(")[0] in self.problem.domain.robot.operators:
                return (f"{label} is not applicable in T (nor anywhere: no refinement of "
                        f"{self.name(ROBOT)}'s agenda reaches it)")
            return f"{label} is not an action of {self.name(ROBOT)}"
        if not op.pre(es.true):
            return f"{label} is not applicable in T (its precondition does not hold)"
        agenda = sem.shown(es.robot)
        return f"{label} is not the first action of any refinement of the robot agenda " \
               f"{agenda} under T"

    def reply_steps(self, sem: JointRules, es: EState, label: str) -> list[Step] | str:
        """docs/concurrent.md C3-C9: the robot replies a label can denote at a reply node, or
        why it is none."""
        if sem.first == ROBOT:
            if es.pending:
                return "the robot has chosen its move of this step already (C4)"
            if label.startswith("inform("):
                if not (sem.cop(es.true)
                        or self.problem.communication.inform == InformWhere.ANYWHERE):
                    return "inform is offered only while co-present (§5)"
                r = self.inform_atoms(es, label)
                return r if isinstance(r, str) else [sem.robot_tells(es, r)]
            found = [st for st in sem.robot_choices(es) if st.label == label]
            return found or (f"{label} is not one of the robot's options here (C2): "
                             f"{[st.label for st in sem.robot_choices(es)]}")
        if not es.pending:
            return "the robot replies only once the human has chosen its move (C4)"
        steps, mids = sem.replies(es)
        if label.startswith("inform("):
            mid, heard = mids[0]
            if not heard:
                return ("the human does not hear an inform in this step: it does not witness "
                        'it (C8) and [communication] inform is not "anywhere"')
            r = self.inform_atoms(mid, label, " after the human's move (C2, §5)")
            return r if isinstance(r, str) else [sem.joint_inform(mid, r)]
        found = [st for st in steps if st.label == label]
        if found:
            return found
        if label == "wait":
            return "(pass, wait) is never a step (C3, C5)"
        return (f"{label} is not an admissible reply to the human's move here (C3: still an "
                "option after it, the same state either way, no common resource); "
                f"admissible: {[st.label for st in steps]}")

    def inform_atoms(self, es: EState, label: str, when: str = "") -> list[int] | str:
        """The units of ``inform(...)`` (atoms, state variables, counters, as masks) in label
        order, if it is a legal inform at ``es`` (§5; ``when`` says which state the label's
        values are read in, in messages: T, or T after the action it is said with)."""
        sem = self.sem
        parsed = sem.parse_inform(label)
        if isinstance(parsed, str):
            return parsed
        units = [u for u, _ in parsed]
        if len(set(units)) != len(units):
            return "an atom is told twice"
        why = sem.inform_where(es)
        if why is not None:
            return why
        for u, said in parsed:  # the label tells literals (values) of T
            truth = sem.say(es.true, u)
            if said != truth:
                if u in sem.grounded.unit_names:
                    return f"the label tells {said}, but T has {truth}{when}"
                value = not said.startswith("not ")
                name = said[4:] if not value else said
                return f"the label tells {name} is {str(value).lower()}, but it is " \
                       f"{str(not value).lower()} in T{when}"
        why = sem.check_inform(es, units)
        return units if why is None else why + when

    def human_steps(self, es: EState, label: str,
                    options: list[Step] | None = None) -> list[Step]:
        """The human option a label denotes (§4: labels are unique at a node; a question
        matches in any order of its conjuncts)."""
        opts = options if options is not None else self.sem.human_options(es)
        return [o for o in opts if (_ask_matches(o, label) if o.kind == ASK else
                                    o.label == label)]

    # -- recorded facts ------------------------------------------------------------------------

    def facts(self, node: PolicyNode, es: EState, goal: bool) -> list[str]:
        """Return how the facts recorded at ``node`` differ from the state ``es`` the replay
        reached it in (docs/policy-format.md: state, agendas and hypotheses, co-presence, k,
        worlds, whose move, goal, divergence and the worlds' differences), one message each;
        none when they agree."""
        sem, g = self.sem, self.sem.grounded
        bad: list[str] = []

        def cmp(what: str, got: object, want: object) -> None:
            if got != want:
                bad.append(f"{what} is {got!r}, expected {want!r}")

        if set(node.state) != set(g.state_atoms(es.true)):
            extra = sorted(set(node.state) - set(g.state_atoms(es.true)))
            missing = sorted(set(g.state_atoms(es.true)) - set(node.state))
            bad.append(f"state differs from the true state T (recorded but false: {extra}; "
                       f"true but not recorded: {missing})")
        cmp("robot_agenda", list(node.robot_agenda), sem.shown(es.robot))
        want_h = sorted(sem.shown(h) for h in es.humans)
        got_h = sorted(list(h) for h in node.human_agendas)
        if len(want_h) == 1 and len(got_h) == 1:
            cmp("human_agenda", list(node.human_agenda), want_h[0])
        elif got_h != want_h:
            bad.append(f"hypotheses (the human agendas the robot cannot tell apart, §3) are "
                       f"{got_h}, expected {want_h}")
        if len(node.hypotheses) > 1 and list(node.human_agenda) != list(node.hypotheses[0]):
            bad.append(f"human_agenda is {list(node.human_agenda)}, but a node with hypotheses "
                       f"records the first of them, {list(node.hypotheses[0])}")
        cmp("copresent", node.copresent, sem.cop(es.true))
        cmp("k", node.k, es.k)
        cmp("worlds", node.worlds, len(es.worlds))
        cmp("to_move", node.to_move, None if goal else self.name(es.turn))
        if (node.id == 0 and not self.policy.after and es.turn == HUMAN and not goal
                and node.to_move == self.name(ROBOT)
                and self.problem.communication.speech == Speech.WITH_ACTION):
            why = sem.inform_found(replace(es, turn=ROBOT, opening=True))
            if isinstance(why, str):  # the robot may not open: say why (§5)
                bad.append(f"no speech opening, since no informing set exists in the initial "
                           f"state: {why}")
        cmp("goal", node.goal, goal)
        div = 0
        diffs = []
        t = es.true
        for s in {s for s, _ in es.worlds}:
            div |= s ^ t
            # atoms true in the world only, and true in T only; a counter by its values
            counters = [u for u in sem.units(s ^ t) if u in g.counter_max]
            plain = s ^ t
            for u in counters:
                plain &= ~u
            diffs.append((frozenset([*g.mask_atoms(s & plain), *(sem.say(s, u) for u in counters)]),
                          frozenset([*g.mask_atoms(t & plain),
                                     *(sem.say(t, u) for u in counters)])))
        want_div = {sem.say(t, u) for u in sem.units(div)}
        if set(node.divergence) != want_div:
            cmp("divergence", sorted(node.divergence), sorted(want_div))
        got_diffs = sorted((sorted(d.get("true", [])), sorted(d.get("false", [])))
                           for d in node.world_diffs)
        want_diffs = sorted((sorted(t), sorted(f)) for t, f in diffs)
        if got_diffs != want_diffs:
            bad.append(f"world_diffs (the worlds' differences from T) are {got_diffs}, "
                       f"expected {want_diffs}")
        return bad

    # -- the replay ----------------------------------------------------------------------------

    def replay_after(self) -> EState | None:
        """§4: replay the problem's opening moves (``after``, which the policy must record as
        the problem fixes them) from the initial state; return the root's state (the one whose
        recorded facts fit, when a label leaves a choice), or None after a violation."""
        sem = self.sem
        pol, prob = self.policy, self.problem
        if list(pol.after) != list(prob.after):
            i = next((j for j, (a, b) in enumerate(zip(pol.after, prob.after, strict=False))
                      if a != b), min(len(pol.after), len(prob.after)))
            got = pol.after[i] if i < len(pol.after) else "(nothing)"
            want = prob.after[i] if i < len(prob.after) else "(nothing)"
            self.fail(list(pol.after[:i]), f"opening: after[{i}] is {got!r}, but the problem "
                      f"fixes {want!r} (policy after {list(pol.after)} != problem after "
                      f"{list(prob.after)})")
        states = [sem.initial()]
        done: list[str] = []
        for i, mv in enumerate(pol.after):
            agent_name, _, label = mv.partition(" ")
            nxt: list[EState] = []
            why = ""
            for es in states:
                if agent_name != self.name(es.turn):
                    why = f"it is {self.name(es.turn)}'s turn, not {agent_name}'s"
                    continue
                if es.turn == ROBOT:
                    r = self.robot_steps(es, label)
                    base, bracket, names = label.rstrip().rpartition(" [")
                    if isinstance(r, str) and bracket and names.endswith("]"):
                        # §4: "fetch [shelve]" names the move by the agenda it leaves
                        r = self.robot_steps(es, base)
                        if not isinstance(r, str):
                            left = "".join(names[:-1].split())
                            r = [st for st in r if st.after is not None and "".join(
                                ",".join(sem.shown(st.after.robot)).split()) == left]
                    if isinstance(r, str):
                        why = r
                        continue
                    steps = r
                else:
                    steps = self.human_steps(es, label)
                    if not steps and label.strip() == PASS and es.forced:
                        # §4: a pass the fairness rule need not cover may still have happened
                        steps = self.human_steps(replace(es, forced=False), label)
                    if not steps:
                        why = f"{label} is not one of the human's options"
                        continue
                for st in steps:
                    if st.after is None:
                        why = f"{label} is not applicable in T: the human acts on a false belief"
                    elif st.after not in nxt:
                        nxt.append(st.after)
            if not nxt:
                self.fail(done, f"opening: after[{i}] {mv!r} is not a legal move: {why}")
                return None
            states = nxt
            done.append(mv)
        root = pol.root
        if self.lifted is not None:  # §3: the root node is the real one renamed
            ren = self.lifted.renaming(self.lifted.lifted.root)
            if isinstance(ren, str):
                self.fail([], f"node 0 (start): symmetry.root: {ren}")
                return None
            states = [ren.estate(es) for es in states]
        for es in states:  # an ambiguous opening is settled by the root's recorded agendas
            if not self.facts(root, es, sem.is_goal(es)):
                return es
        return states[0]


    def order(self) -> list[int] | int:
        """The nodes reachable from the root, children before parents, or a node on a cycle
        of moves (a policy is acyclic, §7)."""
        nodes = self.policy.nodes
        state: dict[int, int] = {0: 1}  # 1: on the stack, 2: done
        post: list[int] = []
        stack = [(0, 0)]
        while stack:
            i, j = stack[-1]
            kids = [c for c in nodes[i].children if 0 <= c < len(nodes)]
            if j == len(kids):
                stack.pop()
                state[i] = 2
                post.append(i)
                continue
            stack[-1] = (i, j + 1)
            c = kids[j]
            if state.get(c) == 1:
                return c
            if c not in state:
                state[c] = 1
                stack.append((c, 0))
        return post

    def walk(self, root_es: EState) -> None:
        """Replay the policy depth-first from the root. A node reached again by another path
        is not checked again: the state recomputed along the new path must equal the one of
        its first visit (then everything below follows as before), so the walk is linear in
        the policy's nodes and moves however many branches share them."""
        nodes = self.policy.nodes
        self.first[0], self.path_of[0] = root_es, []
        stack = [_Item(nodes[0], root_es, [], None)]
        while stack:
            it = stack.pop()
            node = it.node
            self.nodes_checked += 1
            if not self.nodes_checked & 63:
                self.sem.check()
            kids_ok = self.visit(node, it.es, it.path, it.move, it.via)
            goes_on = self.goes_on.setdefault(node.id, [])
            for j, st in reversed(kids_ok):
                assert st.after is not None
                move = node.moves[j]
                child = nodes[move.to]
                path = [*it.path, self.move_label(st.agent, move.action)]
                arrived = self.arrive(node.id, j, st.after)
                if isinstance(arrived, str):
                    self.fail(path, f"node {child.id} ({move.agent} {move.action}): {arrived}")
                    self.end(node.id)
                    continue
                after, via = arrived
                bad = [] if self.lifted is None else self.facts(child, after,
                                                               self.sem.is_goal(after))
                if bad:  # §3: each edge's renaming maps the successor onto the child node
                    self.fail(path, f"node {child.id} ({move.agent} {move.action}{via}): "
                              "recorded facts differ from the semantics (the edge's renaming "
                              "does not map the successor onto the node, §3): "
                              + "; ".join(bad))
                    self.end(node.id)
                    continue
                seen = self.first.get(child.id)
                if seen is None:
                    self.first[child.id], self.path_of[child.id] = after, path
                    stack.append(_Item(child, after, path, move, via))
                elif seen != after:
                    lifted = "" if self.lifted is None else " (its edge's renaming does " \
                        "not map the successor onto the node, §3)"
                    self.fail(path, f"node {child.id} ({move.agent} {move.action}{via}) is "
                              "shared, but this path reaches it in another state than its "
                              f"first one (by [{', '.join(self.path_of[child.id])}]){lifted}: "
                              + _differences(seen, after, self.sem))
                    self.end(node.id)
                    continue
                goes_on.append(child.id)

    def arrive(self, node: int, j: int, es: EState) -> tuple[EState, str] | str:
        """The state move ``j`` of ``node`` reaches the child node in: ``es``, or for a
        lifted policy ``es`` renamed by the move's renaming (§3), with how messages name the
        renaming; why not, when the renaming is not a checked automorphism."""
        if self.lifted is None:
            return es, ""
        rid = self.lifted.lifted.renaming_of(node, j)
        ren = self.lifted.renaming(rid)
        if isinstance(ren, str):
            return ren
        return ren.estate(es), shown(rid, ren)

    def end(self, node: int) -> None:
        """One branch's check ends at ``node`` (a leaf, or at a violation)."""
        self.ends[node] = self.ends.get(node, 0) + 1

    def branches_checked(self, order: list[int] | None) -> int:
        """Branches checked, each to its end or its first violation, counted over the graph
        (a node's count is the sum of its children's, plus the branches ending there)."""
        if order is None:
            return sum(self.ends.values())
        count: dict[int, int] = {}
        for n in order:  # children first
            count[n] = self.ends.get(n, 0) + sum(count.get(c, 0)
                                                 for c in self.goes_on.get(n, []))
        return count.get(0, 0)

    def visit(self, node: PolicyNode, es: EState, path: list[str],
              move: PolicyMove | None, via: str = "") -> list[tuple[int, Step]]:
        """Check one node reached by ``move`` (``via``: the renaming of a lifted policy's edge
        into it, as messages name it); return the moves to follow (by index) with the steps
        the semantics gives for them."""
        sem = self.sem
        nodes = self.policy.nodes
        if move is None and self.lifted is not None:
            via = shown(self.lifted.lifted.root, self.lifted.renaming(self.lifted.lifted.root))
        where = (f"node {node.id} (start{via})" if move is None
                 else f"node {node.id} ({move.agent} {move.action}{via})")
        goal = sem.is_goal(es)
        self.turn[node.id] = es.turn
        bad = self.facts(node, es, goal)
        if bad:
            self.fail(path, f"{where}: recorded facts differ from the semantics: "
                      + "; ".join(bad))
            self.end(node.id)
            return []
        if any(c < 0 or c >= len(nodes) for c in node.children):
            self.fail(path, f"{where}: a move leads to a node id out of range")
            self.end(node.id)
            return []
        if goal:
            if node.moves:
                self.fail(path, f"{where}: a goal (§6) must be a leaf, but it has "
                          f"{len(node.moves)} move(s)")
            else:
                self.goals_reached.add(node.id)
            self.end(node.id)
            return []
        if not node.moves:
            self.fail(path, f"{where}: leaf that is not a goal (§6): "
                      + self.why_not_goal(es))
            self.end(node.id)
            return []
        if es.passive >= 3:
            self.fail(path, f"{where}: dead end: third passive move (wait/pass) in a row and "
                      "not a goal (§6)")
            self.end(node.id)
            return []
        if self.lifted is not None:
            self.lifted.order_issue = self.lifted.tie_issue = False
        kids = (self.robot_node(node, es, path, where) if es.turn == ROBOT
                else self.human_node(node, es, path, where))
        if self.lifted is not None and node.id in self.renamed and (
                self.lifted.order_issue or self.lifted.tie_issue):
            self.fail(path, f"{where}: {ORDER if self.lifted.order_issue else TIE}")
            self.end(node.id)
            return []
        return kids

    def why_not_goal(self, es: EState) -> str:
        """§6: return why ``es`` is not a goal, the first condition that fails."""
        sem, g = self.sem, self.sem.grounded
        if not g.goal(es.true):
            return "the goal formula does not hold in T"
        if (FINISH, ()) not in sem.refine(g.robot, es.robot, es.true):
            return "the robot's agenda cannot finish under T"
        for h in sem.ordered(es.humans):
            if not sem.human_done(h, es.worlds):
                which = f" {sem.shown(h)}" if len(es.humans) > 1 else ""
                return f"the human's agenda{which} does not certainly finish over W"
        return "in some world the robot agenda the human attributes to the robot cannot finish"

    def check_move(self, node: PolicyNode, j: int, st: Step, path: list[str]) -> bool:
        """The recorded move ``node.moves[j]`` is the move ``st`` of the semantics: agent,
        kind, name and arguments, what was said with it, and cost (§4, §5, §7)."""
        move = node.moves[j]
        child = self.policy.nodes[move.to]
        lbl = self.move_label(st.agent, st.label)
        cpath = [*path, self.move_label(st.agent, move.action)]
        where = f"node {child.id} ({lbl})"
        if move.agent != self.name(st.agent):
            self.fail(cpath, f"{where}: agent is {move.agent!r}, expected "
                      f"{self.name(st.agent)!r}")
            return False
        if move.kind != st.kind:
            self.fail(cpath, f"{where}: kind is {move.kind!r}, expected {str(st.kind)!r}")
            return False
        want_call = self.call(st)
        if (move.name, list(move.args)) != want_call:
            self.fail(cpath, f"{where}: name and args are {move.name!r} {list(move.args)}, "
                      f"expected {str(want_call[0])!r} {want_call[1]}")
            return False
        if list(move.told) != list(st.told):
            self.fail(cpath, f"{where}: told is {list(move.told)}, but the move says "
                      + (f"{list(st.told)}" if st.told else "nothing")
                      + " (speech, §5)")
            return False
        want_step = self.sem.step_of(st) if isinstance(self.sem, JointRules) else ""
        if move.step != want_step:
            self.fail(cpath, f"{where}: step is {move.step!r}, expected {want_step!r} "
                      "(docs/concurrent.md: the moves of a joint step)")
            return False
        if not _same(move.cost, st.cost):
            self.fail(cpath, f"{where}: cost is {move.cost}, but the move costs "
                      f"{_num(st.cost)} under the problem's costs (§7)")
            return False
        self.step_cost[node.id, j] = st.cost
        self.weight[node.id, j] = self.problem.objective.weight(move.action, want_call[0])
        return True

    def call(self, st: Step) -> tuple[str, list[str]]:
        """The name and arguments a policy records for a move (docs/policy-format.md)."""
        g = self.sem.grounded
        if st.kind == ACTION:
            op = (g.robot if st.agent == ROBOT else g.human).ops[g.task_index[st.act]]
            return op.schema, list(op.args)
        if st.kind == INFORM:
            parsed = self.sem.parse_inform(st.label)
            assert not isinstance(parsed, str)
            return INFORM, [said for _, said in parsed]
        if st.kind == ASK:
            return ASK, [st.label[len("ask("):-1]]
        # wait, pass, silence (also a wait said with an inform), answer, announce
        return st.kind, []

    def robot_node(self, node: PolicyNode, es: EState, path: list[str],
                   where: str) -> list[tuple[int, Step]]:
        """§4: check a robot node: exactly one move, a legal robot option here, whose recorded
        edge leads to the node of the move it names; return it with its step, or nothing after a
        violation."""
        if len(node.moves) != 1:
            self.fail(path, f"{where}: a robot node must have exactly one move (its child: "
                      f"an OR choice), it has {len(node.moves)}: "
                      f"{[m.action for m in node.moves]}")
            self.end(node.id)
            return []
        move = node.moves[0]
        child = self.policy.nodes[move.to]
        cpath = [*path, self.move_label(ROBOT, move.action)]
        r = self.robot_steps(es, move.action)
        if isinstance(r, str):
            self.fail(cpath, f"node {child.id} (R {move.action}): not a legal robot option "
                      f"(§4): {r}")
            self.end(node.id)
            return []
        if self.lifted is not None:  # the edge's renaming, checked when the walk follows it
            arrived = self.arrive(node.id, 0, es)
            if isinstance(arrived, str):
                self.fail(cpath, f"node {child.id} (R {move.action}): {arrived}")
                self.end(node.id)
                return []
            ren = self.lifted.renaming(self.lifted.lifted.renaming_of(node.id, 0))
            assert not isinstance(ren, str)
            # matched on the child's canonical names; the walk renames the step it follows
            renamed = [replace(s, after=ren.estate(s.after)) if s.after is not None else s
                       for s in r]
            got = self.recorded(child, renamed)
            st = None if got is None else r[renamed.index(got)]
        else:
            st = self.recorded(child, r)
        if st is None:
            # §4: one label, several moves (robot methods starting with the same action):
            # the recorded edge must lead to the node of one of them
            sem = self.sem
            ways = [(sem.shown(s.after.robot), sorted(sem.shown(h) for h in s.after.humans))
                    for s in r if s.after is not None]
            self.fail(cpath, f"node {child.id} (R {move.action}): the recorded edge is none of "
                      f"the {len(r)} robot moves labelled {move.action} here (§4): its node "
                      f"has robot agenda {child.robot_agenda} and human agendas "
                      f"{sorted(child.human_agendas)}; the moves lead to (robot agenda, human "
                      f"agendas) {ways}")
            self.end(node.id)
            return []
        if not self.check_move(node, 0, st, path):
            self.end(node.id)
            return []
        return [(0, st)]

    def recorded(self, child: PolicyNode, steps: list[Step]) -> Step | None:
        """The move of ``steps`` (several moves one label denotes) whose node is ``child``:
        the one the recorded edge names. Matched on the agendas (the robot's, and the human
        agendas A_H), then on every recorded fact; None when several moves share the label
        and none has the child's agendas (a lone move is checked by its child's facts)."""
        sem = self.sem
        if len(steps) == 1:
            return steps[0]
        want = sorted(list(h) for h in child.human_agendas)
        fits = [s for s in steps if s.after is not None
                and sem.shown(s.after.robot) == list(child.robot_agenda)
                and sorted(sem.shown(h) for h in s.after.humans) == want]
        if not fits:
            return None
        return next((s for s in fits if s.after is not None
                     and not self.facts(child, s.after, sem.is_goal(s.after))), fits[0])

    def hidden_choice(self, node: PolicyNode, path: list[str], where: str) -> bool:
        """§3: whether two human moves at ``node`` share a label (compared without spaces): the
        robot cannot tell them apart, so the policy would branch on a choice it cannot see."""
        first: dict[str, PolicyMove] = {}
        for move in node.moves:
            key = "".join(move.action.split())
            seen = first.setdefault(key, move)
            if seen is move:
                continue
            visible = self.problem.human.intentions == Intentions.VISIBLE
            self.fail(path, f"{where}: two human branches have the label {move.action} (to "
                      f"nodes {seen.to} and {move.to}): the robot sees the same move in both, "
                      "so the policy branches on a hidden choice (§3"
                      + (', under intentions = "visible" a repeated action label names the '
                         'intention: grab(c1) [rest]' if visible else "") + ")")
            self.end(node.id)
            return True
        return False

    def human_node(self, node: PolicyNode, es: EState, path: list[str],
                   where: str) -> list[tuple[int, Step]]:
        """§3-§4: check a human node: no two branches on one label, every branch one of the
        human's options and applicable in T, every option covered; return the branches to follow
        with their steps."""
        if self.hidden_choice(node, path, where):
            return []
        options = self.sem.human_options(es)
        used: list[Step] = []
        out: list[tuple[int, Step]] = []
        for j, move in enumerate(node.moves):
            child = self.policy.nodes[move.to]
            cpath = [*path, self.move_label(HUMAN, move.action)]
            matches = self.human_steps(es, move.action, options)
            if not matches:
                self.fail(cpath, f"node {child.id} (H {move.action}): extra human branch: "
                          f"not one of the human's options (§4) "
                          f"{[o.label for o in options]}")
                self.end(node.id)
                continue
            st = next((option for option in matches if option not in used), matches[0])
            if st in used:
                self.fail(cpath, f"node {child.id} (H {move.action}): duplicate human "
                          "branch: this option is already covered")
                self.end(node.id)
                continue
            used.append(st)
            if st.after is None:
                self.fail(cpath, f"node {child.id} (H {move.action}): the human's action is "
                          "not applicable in T: the branch fails (acting on a false belief)")
                self.end(node.id)
                continue
            if not self.check_move(node, j, st, path):
                self.end(node.id)
                continue
            out.append((j, st))
        for o in options:
            if o in used:
                continue
            if o.after is None:
                self.fail(path, f"{where}: dead end: the human may do {o.label}, certain over "
                          "its worlds, which fails in T (acting on a false belief)")
            else:
                self.fail(path, f"{where}: missing human branch {self.name(HUMAN)} {o.label} "
                          "(every human option is an AND branch, §4)")
        return out



__all__ = ["Replay"]
