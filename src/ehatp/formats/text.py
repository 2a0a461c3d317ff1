"""A policy as text (``ehatp show``): an indented tree plus one timeline per branch; and the
other lines the commands print about policies and problems (costs, notes).

The policy is a graph (docs/policy-format.md): the tree is printed depth-first, each node
expanded once, where the depth-first walk first reaches it; a move into a node already printed
is one line ending ``→ see node N``. The output is linear in the policy's nodes and moves;
timelines, one per branch, stop after :data:`MAX_TIMELINES` branches.

The output is built once as styled segments; :func:`plain` turns it into ASCII text (pipes,
files, tests) and :func:`print_rich` colours it on a terminal, so both show the same thing.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from ..errors import PolicyTooLarge, printable
from ..model.problem import Problem
from .lifted import EXPAND_LIMIT, expanded, real_branches
from .policy import COMM_KINDS, PathStep, Policy, PolicyMove, PolicyNode, timeline

if TYPE_CHECKING:
    from rich.console import Console

MAX_TIMELINES = 100  # branches whose timelines are printed; there can be exponentially many

# tree guides: (plain, unicode)
_GUIDES = {"branch": ("+- ", "├─ "), "last": ("`- ", "└─ "), "pipe": ("|  ", "│  "),
           "space": ("   ", "   ")}

Segment = tuple[str, str]  # (text, rich style)


@dataclass
class Line:
    guides: tuple[str, ...]  # keys of _GUIDES, outermost first
    segments: list[Segment]


def fmt_cost(c: Any) -> str:
    if isinstance(c, Fraction) and c.denominator == 1:
        c = int(c)
    if isinstance(c, float):
        return str(int(c)) if c.is_integer() else f"{c:g}"
    return str(c)


def fmt_exact(c: Any) -> str:
    """A cost for people: ``8.75 (35/4)`` when it is a fraction, else as :func:`fmt_cost`."""
    if isinstance(c, Fraction) and c.denominator != 1:
        return f"{float(c):g} ({c})"
    return fmt_cost(c)


def cost_lines(policy: Policy) -> list[tuple[str, str]]:
    """The policy's worst-case and expected cost (docs/semantics.md §7), marking the one its
    objective minimised; a file without them only has its ``cost``."""
    kind = policy.objective.get("kind", "worst-case")
    mark = " (optimised)"
    if policy.worst_case is None or policy.expected is None:
        return [("cost", f"{fmt_exact(policy.cost)} ({kind.replace('-', ' ')}){mark}")]
    return [("worst case", fmt_exact(policy.worst_case) + (mark if kind == "worst-case" else "")),
            ("expected cost", fmt_exact(policy.expected) + (mark if kind == "expected" else ""))]


def print_notes(problem: Problem) -> None:
    """The problem's notes (deprecated spellings and the like), one ``note:`` line each on
    stderr."""
    for note in problem.notes:
        print(f"note: {printable(note)}", file=sys.stderr, flush=True)


def _role(policy: Policy, agent: str | None) -> str:
    if agent == policy.agents["robot"]:
        return "robot"
    return "human" if agent == policy.agents["human"] else "start"


def _move_segments(policy: Policy, move: PolicyMove | None, width: int,
                   name_w: int) -> list[Segment]:
    agent = None if move is None else move.agent
    action = "start" if move is None else move.action
    return [((agent or "").ljust(name_w) + "  ", _role(policy, agent)),
            (action.ljust(width), "bold yellow" if _comm(move) else "")]


def _comm(move: PolicyMove | None) -> bool:
    return move is not None and move.kind in COMM_KINDS


def _node_segments(policy: Policy, move: PolicyMove | None, n: PolicyNode, width: int,
                   name_w: int) -> list[Segment]:
    comm = _comm(move)
    segs: list[Segment] = [(f"#{n.id:<4}", "dim"), *_move_segments(policy, move, width, name_w)]
    segs.append((f"  W={n.worlds}", "cyan" if n.worlds > 1 else "dim"))
    if not n.copresent:
        segs.append(("  apart", "blue"))
    if comm:
        segs.append(("  COMM", "bold yellow"))
    if n.goal:
        segs.append(("  GOAL", "bold green"))
    return segs


def _detail_segments(n: PolicyNode) -> list[Segment]:
    parts = []
    if n.divergence:
        parts.append("unsure about: " + ", ".join(n.divergence))
    if n.k:
        parts.append(f"k={n.k}")
    return [("      " + "; ".join(parts), "dim italic")] if parts else []


def header(policy: Policy, too_large: PolicyTooLarge | None = None) -> list[Line]:
    """The lines above the tree: the problem, the costs and counts, the search's figures, the
    graph's size (``too_large``: a lifted policy not expanded, and why) and the legend."""
    r, h = policy.agents["robot"], policy.agents["human"]
    opt = ("optimal" if policy.optimal
           else "NOT proven optimal (the search stopped early)")
    lines = [
        Line((), [(f"Policy for {policy.problem}", "bold"),
                  (f"  (domain {policy.domain}, K={policy.K}; robot {r}, human {h})", "")]),
        Line((), [(", ".join(f"{k.replace('worst case', 'worst-case cost')} {v}"
                             for k, v in cost_lines(policy))
                   + f", {policy.leaves} leaves, {policy.communications} communications, {opt}",
                   "" if policy.optimal else "bold red")]),
    ]
    st = policy.stats
    if st:
        lines.append(Line((), [(f"search: {st.get('generated', '?')} states generated, "
                                f"{st.get('distinct', '?')} distinct, "
                                f"|W| up to {st.get('max_worlds', '?')}", "dim")]))
    moves = sum(len(n.moves) for n in policy.nodes)
    if too_large is None:
        lines.append(Line((), [(f"graph: {len(policy.nodes)} nodes, {moves} moves "
                                f"({policy.tree_size()} nodes as a tree)", "dim")]))
    else:
        lines.append(Line((), [(f"graph: lifted, {len(policy.nodes)} canonical nodes, {moves} "
                                f"moves ({policy.tree_size()} nodes as a tree); more than "
                                f"{too_large.limit:,} nodes over the real objects", "dim")]))
    lines.append(Line((), [(f"legend: {r} = robot, {h} = human, COMM = communication, "
                            "GOAL = goal reached, W = worlds the human entertains, "
                            "apart = not co-present, → see node N = a node printed above "
                            "(reached by several paths)", "dim")]))
    return lines


def tree_lines(policy: Policy, details: bool = False) -> list[Line]:
    """The policy as a tree; straight runs stay at one indent, only human choices nest. Each
    node is expanded once, at its first line; a later move into it says ``→ see node N``."""
    width = max([len("start"), *(len(m.action) for _, m in policy.edges())])
    name_w = max(len(a) for a in policy.agents.values())
    out: list[Line] = []
    printed: set[int] = set()
    # (move into the node, None at the root; node id; guides for its first line; guides for
    # the lines after it)
    stack: list[tuple[PolicyMove | None, int, tuple[str, ...], tuple[str, ...]]] = [
        (None, 0, (), ())]
    while stack:
        move, i, guides, rest = stack.pop()
        fork: PolicyNode | None = None
        while True:
            if i in printed:  # shared: printed above, with everything below it
                segs = [(" " * 5, ""), *_move_segments(policy, move, width, name_w),
                        (f"  → see node {i}", "dim")]
                if _comm(move):
                    segs.append(("  COMM", "bold yellow"))
                out.append(Line(guides, segs))
                break
            printed.add(i)
            n = policy.nodes[i]
            out.append(Line(guides, _node_segments(policy, move, n, width, name_w)))
            if details and (d := _detail_segments(n)):
                out.append(Line(rest, d))
            guides = rest
            if len(n.moves) != 1:
                fork = n if n.moves else None
                break
            move, i = n.moves[0], n.moves[0].to
        if fork is None:
            continue
        out.append(Line(rest, [(f"{fork.to_move or '?'} may do one of {len(fork.moves)}:",
                                "italic")]))
        for j in reversed(range(len(fork.moves))):
            last = j == len(fork.moves) - 1
            m = fork.moves[j]
            stack.append((m, m.to, (*rest, "last" if last else "branch"),
                          (*rest, "space" if last else "pipe")))
    return out


def timeline_lines(policy: Policy, limit: int | None = MAX_TIMELINES,
                   branches: Iterable[list[PathStep]] | None = None) -> list[Line]:
    """One numbered timeline per branch (the first ``limit`` of them): turns while together,
    lanes while apart. ``branches``: the branches to print (default the policy's own; a lifted
    policy's realised lazily, :func:`~ehatp.formats.lifted.real_branches`, whose leaves are
    numbered by their canonical nodes)."""
    total = policy.leaves
    shown = total if limit is None else min(total, limit)
    title = f"Timelines ({total} branches" + (
        f"; the first {shown} are shown)" if shown < total else ")")
    out = [Line((), [(title, "bold")])]
    name_w = max(len(a) for a in policy.agents.values())
    for b, path in enumerate(policy.iter_branches() if branches is None else branches, 1):
        if limit is not None and b > limit:
            break
        tl = timeline(policy, path)
        cost = sum(n.cost for n in path)
        leaf = path[-1]
        end = "goal" if leaf.goal else "no goal"
        out.append(Line((), [(f"branch {b}", "bold"),
                             (f" -> leaf #{leaf.id} ({end}), cost {fmt_cost(cost)}", "")]))
        for s, step in enumerate(tl["steps"], 1):
            num = f"  {s:>3}  "
            if "parallel" in step:
                lanes: dict[str, list[str]] = step["parallel"]
                for k, (agent, acts) in enumerate(lanes.items()):
                    lead = num + "apart  " if k == 0 else " " * (len(num) + 7)
                    out.append(Line((), [
                        (lead, "blue" if k == 0 else ""),
                        (agent.ljust(name_w) + " | ", _role(policy, agent)),
                        (" -> ".join(acts) if acts else "(nothing)", "")]))
            else:
                agent = step["agent"]
                out.append(Line((), [(num, ""),
                                     (agent.ljust(name_w) + "  ", _role(policy, agent)),
                                     (step["action"], "")]))
    if shown < total:
        covered = ("the policy's graph above covers them all" if branches is None
                   else "`ehatp simulate` follows any of them")
        out.append(Line((), [(f"... and {total - shown} more branches: {covered}; "
                              "`ehatp render --format html` shows any branch", "dim")]))
    return out


def policy_lines(policy: Policy, *, tree: bool = True, timelines: bool = True,
                 details: bool = False, max_timelines: int | None = MAX_TIMELINES,
                 expand_limit: int | None = EXPAND_LIMIT,
                 too_large: PolicyTooLarge | None = None) -> list[Line]:
    """The lines of ``ehatp show``; a lifted policy (format version 3) is expanded first
    (:func:`~ehatp.formats.lifted.expanded`), unless it stands for more than ``expand_limit``
    nodes over the real objects: then the tree is left out (said in one line) and the
    timelines' branches are realised one at a time (:func:`~ehatp.formats.lifted.real_branches`),
    so the work is the branches printed, not the expansion (``too_large``: known already, not
    tried again). A policy in joint steps
    (docs/concurrent.md) is printed a step a line (:func:`joint_tree_lines`,
    :func:`joint_timeline_lines`), with its preference vectors when it has them
    (:class:`Preferences`)."""
    try:
        if too_large is not None and policy.symmetry is not None:
            raise too_large
        policy = expanded(policy, expand_limit)
    except PolicyTooLarge as e:
        lines = header(policy, e)
        if tree:
            lines += [Line((), []), Line((), [("Tree", "bold")]), Line((), [(
                f"not printed: {e}; `--expand-limit` raises the limit, `ehatp render "
                "--format html` browses it, `ehatp simulate` follows a branch (leaves below "
                "are numbered by the lifted policy's canonical nodes)", "dim")])]
        if timelines:
            lines += [Line((), []), *timeline_lines(policy, max_timelines,
                                                    real_branches(policy))]
        return lines
    if joint(policy):
        return joint_policy_lines(policy, tree=tree, timelines=timelines, details=details,
                                  max_timelines=max_timelines)
    lines = header(policy)
    if tree:
        lines += [Line((), []), Line((), [("Tree", "bold")]), *tree_lines(policy, details)]
    if timelines:
        lines += [Line((), []), *timeline_lines(policy, max_timelines)]
    return lines


# --- joint steps (docs/concurrent.md) ---------------------------------------------------------


def joint(policy: Policy) -> bool:
    """Whether ``policy`` was planned in joint steps (its file's ``steps`` table, C1)."""
    return (policy.step_options or {}).get("mode") == "concurrent"


@dataclass(frozen=True)
class Preferences:
    """What a ``kind = "preferences"`` policy file records (C11, docs/policy-format.md): the
    chosen profile, its metrics most important first, the estimate and each node's vector
    (that of its sub-policy: at a robot node the chosen move's, at a human node its worst
    branch's, or best with ``estimate = "optimistic"``)."""

    profile: str
    metrics: tuple[str, ...]
    estimate: str
    vectors: tuple[tuple[Any, ...], ...]

    @classmethod
    def of(cls, policy: Policy) -> Preferences | None:
        """The preferences ``policy`` records, or None (another objective, or a file whose
        vectors do not match its nodes)."""
        o = policy.objective
        vectors, metrics = o.get("vectors"), o.get("metrics")
        if (o.get("kind") != "preferences" or not isinstance(vectors, list)
                or not isinstance(metrics, list) or len(vectors) != len(policy.nodes)
                or not all(isinstance(v, list) and len(v) == len(metrics) for v in vectors)):
            return None
        return cls(str(o.get("profile", "")), tuple(map(str, metrics)),
                   str(o.get("estimate", "worst-case")),
                   tuple(tuple(v) for v in vectors))

    def text(self, n: int) -> str:
        """Node ``n``'s vector, its values in the profile's order: ``(2, 1)``."""
        return "(" + ", ".join(fmt_cost(x) for x in self.vectors[n]) + ")"

    def named(self, n: int) -> str:
        """Node ``n``'s vector with its metrics: ``makespan = 2, human_effort = 1``."""
        return ", ".join(f"{m} = {fmt_cost(x)}"
                         for m, x in zip(self.metrics, self.vectors[n], strict=True))

    @property
    def aggregate(self) -> str:
        """Which of a human node's branches gives its vector."""
        return "best" if self.estimate == "optimistic" else "worst"


def _first(policy: Policy) -> str:
    """The name of the agent who decides first in a step (C4)."""
    who = (policy.step_options or {}).get("first", "human")
    return policy.agents["robot" if who == "robot" else "human"]


def _mid_step(policy: Policy) -> bool:
    """Whether the root is in the middle of a step: its moves are replies (``[problem] after``
    ends with the move that starts the step)."""
    return bool(policy.after) and any(m.step == "reply" for m in policy.root.moves)


def joint_header(policy: Policy, prefs: Preferences | None) -> list[Line]:
    """:func:`header`, its legend for steps, and a line each for the steps' options and the
    preference profile with the root's vector."""
    lines = header(policy)
    legend = lines.pop()
    so = policy.step_options or {}
    r, h = policy.agents["robot"], policy.agents["human"]
    first = _first(policy)
    who = (f"{h} moves first, {r} replies (the compliant robot)" if first == h else
           f"{r} moves first, {h} moves beside it")
    lines.insert(2, Line((), [(
        f"joint steps: {who}; witness {so.get('witness', 'whole')}, commute "
        f"{so.get('commute', 'state')}, a step costs {fmt_cost(so.get('cost', 1))}", "")]))
    if policy.after:
        lines.insert(3, Line((), [(f"after: {', '.join(policy.after)} (played before the root"
                                   + ("; [..] in the timelines)" if _mid_step(policy) else ")"),
                                   "")]))
    if prefs is not None:
        lines.insert(3 + bool(policy.after), Line((), [(
            f"preferences: profile {prefs.profile} = ({', '.join(prefs.metrics)}), "
            f"{prefs.estimate} estimate; root: {prefs.named(0)}", "bold")]))
    other = r if first == h else h
    text = legend.segments[0][0].replace(
        "legend: ", f"legend: a line of the tree is a step, {first}'s move then {other}'s "
                    "(#N = the node a move reaches; W, apart, GOAL: after the step), ")
    if prefs is not None:
        text += (f"; (..) = the vector of ({', '.join(prefs.metrics)}) from the robot's move "
                 f"on, at a fork the {prefs.aggregate} branch's")
    lines.append(Line((), [(text, legend.segments[0][1])]))
    return lines


def joint_tree_lines(policy: Policy, details: bool = False,
                     prefs: Preferences | None = None) -> list[Line]:
    """The policy in joint steps as a tree, a line a step: the move of the agent who decides
    first (C4), then on the same line the other's reply, then the node after the step (W,
    apart, GOAL) and, with preferences, the vector of the robot's choice (that of the node
    where the robot moves: the reply's with the human first, the step's start with the robot
    first). The tree forks where the human chooses, as :func:`tree_lines` does (with the
    robot first, the human's moves beside the robot's fork below it, a line each, and the
    robot's line, which ends in mid-step, has no W); a question is a step of its own, the
    robot's answer implied. A node printed above is ``→ see node N``."""
    robot = policy.agents["robot"]
    name_w = max(len(a) for a in policy.agents.values())
    w1 = max([len("start"), *(len(m.action) for _, m in policy.edges() if m.step != "reply")])
    w2 = max([len(ANSWER), *(len(m.action) for _, m in policy.edges() if m.step == "reply")])
    vw = max(len(prefs.text(i)) for i in range(len(policy.nodes))) if prefs else 0
    out: list[Line] = []
    printed: set[int] = set()

    def vector(at: int | None) -> list[Segment]:
        """The robot's choice's vector (``at``: where the robot moves), or blanks."""
        if prefs is None:
            return []
        return [("  " + (prefs.text(at) if at is not None else "").ljust(vw), "green")]

    def half(move: PolicyMove, to: int, width: int) -> list[Segment]:
        node = " " * 5 if to in printed else f"#{to:<4}"
        return [(node, "dim"), *_move_segments(policy, move, width, name_w)]

    def end(segs: list[Segment], i: int, comm: bool) -> bool:
        """Close the line at node ``i``: its flags, or ``→ see node i`` (then True)."""
        c: list[Segment] = [("  COMM", "bold yellow")] if comm else []
        if i in printed:
            out.append(Line(guides, [*segs, (f"  → see node {i}", "dim"), *c]))
            return True
        printed.add(i)
        n = policy.nodes[i]
        flags: list[Segment] = []
        if i == 0 or not any(m.step == "reply" for m in n.moves):  # not in mid-step
            flags.append((f"  W={n.worlds}", "cyan" if n.worlds > 1 else "dim"))
            if not n.copresent:
                flags.append(("  apart", "blue"))
        if n.goal:
            c.append(("  GOAL", "bold green"))
        out.append(Line(guides, [*segs, *flags, *c]))
        if details and (d := _detail_segments(n)):
            out.append(Line(rest, d))
        return False

    # (node the move is played at, the move, None at the root; guides for the first line;
    # guides for the lines after it)
    stack: list[tuple[int, PolicyMove | None, tuple[str, ...], tuple[str, ...]]] = [
        (0, None, (), ())]
    while stack:
        at, move, guides, rest = stack.pop()
        while True:
            if move is None:  # the root
                i = 0
                stop = end([(f"#{0:<4}", "dim"), (" " * (name_w + 2) + "start", "dim")], 0,
                           False)
            elif move.step == "reply":  # a reply alone: after a fork, or at a root mid-step
                i = move.to
                stop = end([*half(move, i, w2), *vector(at if move.agent == robot else None)],
                           i, _comm(move))
            else:  # a step's first move, and the other's reply on the same line
                i, comm = move.to, _comm(move)
                segs = half(move, i, w1)
                mid = policy.nodes[i]
                one = mid.moves[0] if len(mid.moves) == 1 else None
                if i in printed or move.step == "ask" or one is None or one.step != "reply":
                    if move.step == "ask":
                        segs += [("  " + " " * 5 + robot.ljust(name_w) + "  ", "robot"),
                                 (ANSWER.ljust(w2), "dim")]
                    stop = end([*segs, *vector(at if move.agent == robot else None)], i,
                               comm)
                else:  # the step whole: its middle node is shown by its number
                    printed.add(i)
                    segs += [("  ", ""), *half(one, one.to, w2)]
                    segs += vector(at if move.agent == robot else i)
                    at, i = i, one.to
                    stop = end(segs, i, comm or _comm(one))
            guides = rest
            n = policy.nodes[i]
            if stop or len(n.moves) != 1:
                break
            at, move = i, n.moves[0]
        if stop or not n.moves:
            continue
        beside = " beside it" if n.moves[0].step == "reply" else ""
        which = f"; {prefs.aggregate} {prefs.text(n.id)}" if prefs is not None else ""
        out.append(Line(rest, [(f"{n.to_move or '?'} may do one of {len(n.moves)}"
                                f"{beside}{which}:", "italic")]))
        for j in reversed(range(len(n.moves))):
            last = j == len(n.moves) - 1
            stack.append((n.id, n.moves[j], (*rest, "last" if last else "branch"),
                          (*rest, "space" if last else "pipe")))
    return out


ANSWER = "(answers)"
"""The robot's part of a question's step (C3: the step is the answer)."""


def joint_timeline_lines(policy: Policy, limit: int | None = MAX_TIMELINES) -> list[Line]:
    """One numbered timeline per branch (the first ``limit``), a line a step: the move of the
    agent who decides first, then the other's reply (C4; a question's answer implied),
    ``apart`` when the agents are apart after the step."""
    total = policy.leaves
    shown = total if limit is None else min(total, limit)
    first = _first(policy)
    other = policy.agents["robot" if first == policy.agents["human"] else "human"]
    title = f"Timelines ({total} branch{'' if total == 1 else 'es'}" + (
        f"; the first {shown} are shown)" if shown < total else ")")
    out = [Line((), [(title, "bold")])]
    w1 = max([len(first), *(len(m.action) for _, m in policy.edges() if m.step != "reply"),
              *([len(policy.after[-1].partition(" ")[2]) + 2] if _mid_step(policy) else [])])
    w2 = max([len(other), len(ANSWER),
              *(len(m.action) for _, m in policy.edges() if m.step == "reply")])
    for b, path in enumerate(policy.iter_branches(), 1):
        if limit is not None and b > limit:
            break
        # each step: [first's move, the reply, the node after it]
        rows: list[list[Any]] = []
        for ps in path[1:]:
            assert ps.move is not None
            if ps.move.step == "reply" and rows and rows[-1][1] is None:
                rows[-1][1:] = [ps.move.action, ps.node]
            elif ps.move.step == "reply":  # a root in the middle of a step: its first move
                played = policy.after[-1].partition(" ")[2] if policy.after else ""
                rows.append([f"[{played}]", ps.move.action, ps.node])
            else:
                rows.append([ps.move.action,
                             ANSWER if ps.move.step == "ask" else None, ps.node])
        cost = sum(ps.cost for ps in path)
        leaf = path[-1]
        end = "goal" if leaf.goal else "no goal"
        out.append(Line((), [(f"branch {b}", "bold"),
                             (f" -> leaf #{leaf.id} ({end}), {len(rows)} step"
                              f"{'' if len(rows) == 1 else 's'}, cost {fmt_cost(cost)}", "")]))
        out.append(Line((), [("  step  ", "dim"), (first.ljust(w1) + "  ", _role(policy, first)),
                             (other, _role(policy, other))]))
        for s, (act, reply, node) in enumerate(rows, 1):
            segs: list[Segment] = [(f"  {s:>4}  ", ""), (act.ljust(w1) + "  ", ""),
                                   ((reply or "").ljust(w2), "dim" if reply == ANSWER
                                    else "")]
            if not node.copresent:
                segs.append(("  apart", "blue"))
            out.append(Line((), segs))
    if shown < total:
        out.append(Line((), [(f"... and {total - shown} more branches: the policy's graph "
                              "above covers them all; `ehatp render --format html` shows any "
                              "branch", "dim")]))
    return out


def joint_policy_lines(policy: Policy, *, tree: bool = True, timelines: bool = True,
                       details: bool = False, max_timelines: int | None = MAX_TIMELINES
                       ) -> list[Line]:
    """:func:`policy_lines` of a policy in joint steps (``policy`` a version 2 graph)."""
    prefs = Preferences.of(policy)
    lines = joint_header(policy, prefs)
    if tree:
        lines += [Line((), []), Line((), [("Tree", "bold")]),
                  *joint_tree_lines(policy, details, prefs)]
    if timelines:
        lines += [Line((), []), *joint_timeline_lines(policy, max_timelines)]
    return lines


_ASCII = str.maketrans({"→": "->"})


def plain(lines: Sequence[Line]) -> str:
    """Return ``lines`` as plain text, control characters of names written escaped."""
    return "\n".join(
        ("".join(_GUIDES[g][0] for g in ln.guides)
         + printable("".join(t for t, _ in ln.segments)).translate(_ASCII)).rstrip()
        for ln in lines) + "\n"


_ROLE_STYLE = {"robot": "bold cyan", "human": "bold magenta", "start": "dim"}


def print_rich(lines: Sequence[Line], console: Console) -> None:
    """Print ``lines`` in colour, control characters of names written escaped (a name cannot
    send a terminal escape code)."""
    from rich.text import Text

    for ln in lines:
        text = Text()
        text.append("".join(_GUIDES[g][1] for g in ln.guides), style="dim")
        for t, style in ln.segments:
            text.append(printable(t), style=_ROLE_STYLE.get(style, style))
        text.rstrip()
        console.print(text, soft_wrap=True, highlight=False)


__all__ = ["MAX_TIMELINES", "Line", "Preferences", "cost_lines", "fmt_cost", "fmt_exact", "header",
           "joint", "joint_header", "joint_policy_lines", "joint_timeline_lines",
           "joint_tree_lines", "plain", "policy_lines", "print_notes", "print_rich",
           "timeline_lines", "tree_lines"]
