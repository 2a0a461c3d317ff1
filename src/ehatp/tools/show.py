"""Read a policy JSON and print it as an indented tree plus one timeline per branch.

The output is built once as styled segments; :func:`plain` turns it into ASCII text (pipes,
files, tests) and :func:`print_rich` colours it on a terminal, so both show the same thing.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import typer
from rich.console import Console
from rich.text import Text

from ..model.problem import Problem
from ..policy_format import Policy, PolicyNode, timeline

COMM_KINDS = ("inform", "ask")

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
        typer.echo(f"note: {note}", err=True)


def _role(policy: Policy, agent: str | None) -> str:
    if agent == policy.agents["robot"]:
        return "robot"
    return "human" if agent == policy.agents["human"] else "start"


def _node_segments(policy: Policy, n: PolicyNode, width: int, name_w: int) -> list[Segment]:
    role = _role(policy, n.agent)
    comm = n.kind in COMM_KINDS
    segs: list[Segment] = [(f"#{n.id:<4}", "dim"), ((n.agent or "").ljust(name_w) + "  ", role)]
    segs.append((n.action.ljust(width), "bold yellow" if comm else ""))
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
    lines.append(Line((), [(f"legend: {r} = robot, {h} = human, COMM = communication, "
                            "GOAL = goal reached, W = worlds the human entertains, "
                            "apart = not co-present", "dim")]))
    return lines


def tree_lines(policy: Policy, details: bool = False) -> list[Line]:
    """The policy tree; straight runs stay at one indent, only human choices nest."""
    width = max(len(n.action) for n in policy.nodes)
    name_w = max(len(a) for a in policy.agents.values())
    out: list[Line] = []
    # (node, guides for its first line, guides for the lines after it)
    stack: list[tuple[int, tuple[str, ...], tuple[str, ...]]] = [(0, (), ())]
    while stack:
        i, first, rest = stack.pop()
        guides = first
        while True:
            n = policy.nodes[i]
            out.append(Line(guides, _node_segments(policy, n, width, name_w)))
            if details and (d := _detail_segments(n)):
                out.append(Line(rest, d))
            guides = rest
            if len(n.children) != 1:
                break
            i = n.children[0]
        if len(n.children) > 1:
            who = n.to_move or "?"
            out.append(Line(rest, [(f"{who} may do one of {len(n.children)}:", "italic")]))
            kids = n.children
            for j in reversed(range(len(kids))):
                last = j == len(kids) - 1
                stack.append((kids[j], (*rest, "last" if last else "branch"),
                              (*rest, "space" if last else "pipe")))
    return out


def timeline_lines(policy: Policy) -> list[Line]:
    """One numbered timeline per branch: turns while together, lanes while apart."""
    branches = policy.branches()
    out = [Line((), [(f"Timelines ({len(branches)} branches)", "bold")])]
    name_w = max(len(a) for a in policy.agents.values())
    for b, path in enumerate(branches, 1):
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
    return out


def policy_lines(policy: Policy, *, tree: bool = True, timelines: bool = True,
                 details: bool = False) -> list[Line]:
    lines = header(policy)
    if tree:
        lines += [Line((), []), Line((), [("Tree", "bold")]), *tree_lines(policy, details)]
    if timelines:
        lines += [Line((), []), *timeline_lines(policy)]
    return lines


def plain(lines: Sequence[Line]) -> str:
    return "\n".join(
        ("".join(_GUIDES[g][0] for g in ln.guides) + "".join(t for t, _ in ln.segments)).rstrip()
        for ln in lines) + "\n"


_ROLE_STYLE = {"robot": "bold cyan", "human": "bold magenta", "start": "dim"}


def print_rich(lines: Sequence[Line], console: Console) -> None:
    for ln in lines:
        text = Text()
        text.append("".join(_GUIDES[g][1] for g in ln.guides), style="dim")
        for t, style in ln.segments:
            text.append(t, style=_ROLE_STYLE.get(style, style))
        text.rstrip()
        console.print(text, soft_wrap=True, highlight=False)


__all__ = ["Line", "cost_lines", "fmt_cost", "fmt_exact", "header", "plain", "policy_lines",
           "print_notes", "print_rich", "timeline_lines", "tree_lines"]
