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
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from ..errors import printable
from ..model.problem import Problem
from .lifted import expanded
from .policy import COMM_KINDS, Policy, PolicyMove, PolicyNode, timeline

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


def header(policy: Policy) -> list[Line]:
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
    lines.append(Line((), [(f"graph: {len(policy.nodes)} nodes, {moves} moves "
                            f"({policy.tree_size()} nodes as a tree)", "dim")]))
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


def timeline_lines(policy: Policy, limit: int | None = MAX_TIMELINES) -> list[Line]:
    """One numbered timeline per branch (the first ``limit`` of them): turns while together,
    lanes while apart."""
    total = policy.leaves
    shown = total if limit is None else min(total, limit)
    title = f"Timelines ({total} branches" + (
        f"; the first {shown} are shown)" if shown < total else ")")
    out = [Line((), [(title, "bold")])]
    name_w = max(len(a) for a in policy.agents.values())
    for b, path in enumerate(policy.iter_branches(), 1):
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
        out.append(Line((), [(f"... and {total - shown} more branches: the policy's graph "
                              "above covers them all; `ehatp render --format html` shows any "
                              "branch", "dim")]))
    return out


def policy_lines(policy: Policy, *, tree: bool = True, timelines: bool = True,
                 details: bool = False, max_timelines: int | None = MAX_TIMELINES
                 ) -> list[Line]:
    """The lines of ``ehatp show``; a lifted policy (format version 3) is expanded first
    (:func:`~ehatp.formats.lifted.expanded`)."""
    policy = expanded(policy)
    lines = header(policy)
    if tree:
        lines += [Line((), []), Line((), [("Tree", "bold")]), *tree_lines(policy, details)]
    if timelines:
        lines += [Line((), []), *timeline_lines(policy, max_timelines)]
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


__all__ = ["MAX_TIMELINES", "Line", "cost_lines", "fmt_cost", "fmt_exact", "header", "plain",
           "policy_lines", "print_notes", "print_rich", "timeline_lines", "tree_lines"]
