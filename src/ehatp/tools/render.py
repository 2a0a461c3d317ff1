"""`ehatp render`: draw a robot policy as Graphviz DOT / SVG or as an offline HTML explorer.

DOT is always available (built with the ``graphviz`` Python package, which needs no binary);
SVG pipes that DOT through Graphviz's ``dot`` program. Big policies are collapsed by
:func:`plan_view`: identical subtrees (same content all the way down) are drawn once, and a
depth cap and a node budget fold what is left into "… N more" stubs. The HTML explorer is one
file: the template, CSS and JS under ``explorer/`` are inlined and the policy JSON embedded, so
it works offline. See ``docs/rendering.md``.
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
import sys
from collections import deque
from dataclasses import dataclass, field
from enum import StrEnum
from html import escape as html_escape
from importlib import resources
from pathlib import Path
from typing import Any

import graphviz  # type: ignore[import-untyped]
import typer

from ..errors import InputError
from ..model.problem import load
from ..policy_format import Policy, PolicyNode
from .common import Commands, check_policy_problem, die, read_policy, user_errors

DEFAULT_MAX_NODES = 400  # more than this and a drawing stops being readable
COMM_KINDS = ("inform", "ask")
IDLE_KINDS = ("wait", "pass")
INSTALL_DOT = ("--format svg needs Graphviz's `dot` program, which was not found; install "
               "Graphviz (Debian/Ubuntu: apt-get install graphviz; macOS: brew install graphviz) "
               "or use --format dot or --format html")


class Format(StrEnum):
    dot = "dot"
    svg = "svg"
    html = "html"


class DotMissing(Exception):
    """Graphviz's ``dot`` program is not installed."""


# --------------------------------------------------------------------------- reading


# --------------------------------------------------------------------------- collapsing


@dataclass
class View:
    """What to draw: policy node ids (a representative for shared subtrees) and edges."""

    nodes: list[int]  # drawn node ids, breadth-first
    edges: list[tuple[int, int]]
    folded: dict[int, int] = field(default_factory=dict)  # drawn id -> policy nodes not drawn
    stands_for: dict[int, int] = field(default_factory=dict)  # drawn id -> copies it stands for
    notes: list[str] = field(default_factory=list)

    @property
    def collapsed(self) -> bool:
        return bool(self.notes)


def _postorder(policy: Policy) -> list[int]:
    order: list[int] = []
    stack = [(0, False)]
    while stack:
        i, done = stack.pop()
        if done:
            order.append(i)
            continue
        stack.append((i, True))
        stack.extend((c, False) for c in reversed(policy.nodes[i].children))
    return order


def subtree_hashes(policy: Policy) -> list[str]:
    """A content hash per node covering everything in its subtree except the ids."""
    out = [""] * len(policy.nodes)
    for i in _postorder(policy):
        node = policy.nodes[i]
        own = {k: v for k, v in node.to_dict().items() if k not in ("id", "children")}
        h = hashlib.sha256(json.dumps(own, sort_keys=True, default=str).encode())
        for c in node.children:
            h.update(out[c].encode())
        out[i] = h.hexdigest()
    return out


def subtree_sizes(policy: Policy) -> list[int]:
    sizes = [1] * len(policy.nodes)
    for i in _postorder(policy):
        sizes[i] += sum(sizes[c] for c in policy.nodes[i].children)
    return sizes


def plan_view(policy: Policy, *, max_depth: int | None = None,
              max_nodes: int | None = DEFAULT_MAX_NODES, share: bool | None = None) -> View:
    """Decide what to draw.

    ``share`` None shares identical subtrees only when the tree is over ``max_nodes``. Then a
    breadth-first walk draws nodes down to ``max_depth`` and while the budget lasts; a node
    whose children do not all fit is drawn with a stub counting what is folded below it (all
    children or none, so a human choice is never shown half-expanded).
    """
    total = len(policy.nodes)
    if share is None:
        share = max_nodes is not None and total > max_nodes
    sizes = subtree_sizes(policy)
    canon = list(range(total))
    copies: dict[int, int] = {}
    notes: list[str] = []
    if share:
        first: dict[str, int] = {}
        for i, h in enumerate(subtree_hashes(policy)):
            canon[i] = first.setdefault(h, i)
            copies[canon[i]] = copies.get(canon[i], 0) + 1
        distinct = len(first)
        if distinct < total:
            notes.append(f"identical subtrees drawn once ({total} policy nodes, "
                         f"{distinct} distinct)")
    depth = {0: 0}
    order = [0]
    edges: list[tuple[int, int]] = []
    folded: dict[int, int] = {}
    cut_depth = cut_budget = 0
    queue = deque([0])
    while queue:
        i = queue.popleft()
        kids = [canon[c] for c in policy.nodes[i].children]
        if not kids:
            continue
        new = list(dict.fromkeys(k for k in kids if k not in depth))
        if max_depth is not None and depth[i] >= max_depth:
            folded[i] = sizes[i] - 1
            cut_depth += 1
            continue
        if max_nodes is not None and len(order) + len(new) > max_nodes:
            folded[i] = sizes[i] - 1
            cut_budget += 1
            continue
        for k in dict.fromkeys(kids):
            edges.append((i, k))
        for k in new:
            depth[k] = depth[i] + 1
            order.append(k)
            queue.append(k)
    if cut_depth:
        notes.append(f"cut at depth {max_depth} ({cut_depth} subtree(s) folded)")
    if cut_budget:
        notes.append(f"node budget {max_nodes} reached ({cut_budget} subtree(s) folded)")
    stands_for = {i: copies[i] for i in order if copies.get(i, 1) > 1}
    return View(order, edges, folded, stands_for, notes)


# --------------------------------------------------------------------------- DOT / SVG

_ROBOT_STYLE = {"shape": "box", "style": "rounded,filled", "fillcolor": "#d6e6ff",
                "color": "#1f4e99"}
_HUMAN_STYLE = {"shape": "ellipse", "style": "filled", "fillcolor": "#ffe3bf",
                "color": "#a35200"}
_COMM_STYLE = {"shape": "hexagon", "style": "filled,bold", "fillcolor": "#fff27a",
               "color": "#8a6d00", "penwidth": "2"}
_START_STYLE = {"shape": "box", "style": "rounded,filled,bold", "fillcolor": "#e6e6e6",
                "color": "#333333"}


def _dot_text(s: str) -> str:
    # the graphviz package quotes values but leaves backslashes for dot to interpret
    return s.replace("\\", "\\\\")


def worlds_text(n: PolicyNode) -> str:
    return f"{n.worlds} world" + ("" if n.worlds == 1 else "s")


def node_attrs(policy: Policy, n: PolicyNode, copies: int = 1) -> dict[str, str]:
    """Shape, colours, label and tooltip of one drawn policy node."""
    human = n.agent == policy.agents["human"]
    if n.kind == "start":
        attrs = dict(_START_STYLE)
    elif n.kind in COMM_KINDS:
        attrs = dict(_COMM_STYLE)
    else:
        attrs = dict(_HUMAN_STYLE if human else _ROBOT_STYLE)
        if n.kind in IDLE_KINDS:
            attrs["style"] += ",dashed"
            attrs["fillcolor"] = "#f3f3f3"
    head = n.action if n.agent is None else f"{n.agent}: {n.action}"
    info = [worlds_text(n), f"K={n.k}"]
    if not n.copresent:
        info.append("apart")
    lines = [head, " · ".join(info)]
    if n.goal:
        attrs["peripheries"] = "2"
        attrs["color"] = "#2e7d32"
        lines.append("goal")
    if copies > 1:
        lines.append(f"(×{copies})")
    attrs["label"] = "\\n".join(_dot_text(x) for x in lines)
    attrs["tooltip"] = _dot_text(
        f"node {n.id}: cost {n.cost}, cost to go {n.value}, "
        f"{'together' if n.copresent else 'apart'}; true: {', '.join(n.state)}")
    attrs["id"] = f"policy_node_{n.id}"  # Graphviz escapes "-" in SVG ids
    return attrs


def to_dot(policy: Policy, view: View | None = None) -> graphviz.Digraph:
    """The policy (or the part ``view`` keeps) as a Graphviz digraph, one node per policy node."""
    view = view or plan_view(policy, max_nodes=None, share=False)
    title = (f"{policy.problem} ({policy.domain}): worst-case cost {policy.cost}, "
             f"{policy.leaves} branches, {policy.communications} communication(s)")
    label = "\\l".join(_dot_text(x) for x in [title, *(f"collapsed: {t}" for t in view.notes)])
    g = graphviz.Digraph(name=re.sub(r"\W", "_", policy.problem) or "policy")
    g.attr(rankdir="TB", labelloc="t", labeljust="l", label=label + "\\l",
           fontname="Helvetica", fontsize="12")
    g.attr("node", fontname="Helvetica", fontsize="10", margin="0.08,0.04")
    g.attr("edge", color="#666666", arrowsize="0.6")
    for i in view.nodes:
        g.node(f"n{i}", **node_attrs(policy, policy.nodes[i], view.stands_for.get(i, 1)))
        if i in view.folded:
            g.node(f"more{i}", label=f"… {view.folded[i]} more", shape="note",
                   style="dashed", color="#888888", fontcolor="#555555")
            g.edge(f"n{i}", f"more{i}", style="dashed", color="#888888")
    human = policy.agents["human"]
    for a, b in view.edges:
        # human moves are the uncontrollable branches: dashed and orange
        if policy.nodes[b].agent == human:
            g.edge(f"n{a}", f"n{b}", style="dashed", color="#a35200")
        else:
            g.edge(f"n{a}", f"n{b}")
    return g


def to_svg(dot: graphviz.Digraph) -> str:
    """Lay out with Graphviz's ``dot``; :class:`DotMissing` when it is not installed."""
    if shutil.which("dot") is None:
        raise DotMissing(INSTALL_DOT)
    try:
        return str(dot.pipe(format="svg", encoding="utf-8"))
    except graphviz.ExecutableNotFound:
        raise DotMissing(INSTALL_DOT) from None
    except (subprocess.CalledProcessError, RuntimeError) as e:
        raise RuntimeError(f"Graphviz's dot failed: {e}") from None


# --------------------------------------------------------------------------- HTML

_TOKEN = re.compile(r"\{\{(\w+)\}\}")


def _asset(name: str) -> str:
    return (resources.files("ehatp.tools") / "explorer" / name).read_text(encoding="utf-8")


def _script_json(data: Any) -> str:
    # safe inside <script>: no "</script", no "<!--"; escaping "/" also keeps any URL-looking
    # string in the data from appearing literally in the page
    text = json.dumps(data, separators=(",", ":"), ensure_ascii=False, default=str)
    for ch, esc in (("<", "\\u003c"), (">", "\\u003e"), ("&", "\\u0026"), ("/", "\\/"),
                    ("\u2028", "\\u2028"), ("\u2029", "\\u2029")):
        text = text.replace(ch, esc)
    # letters only occur inside JSON strings, so this colon is always a string character
    return re.sub(r"(?i)(https?):", r"\1\\u003a", text)


def to_html(policy: Policy, *, max_depth: int | None = None,
            max_nodes: int | None = DEFAULT_MAX_NODES) -> str:
    """The self-contained explorer page; depth cap and budget only set what starts folded."""
    data = policy.to_dict()
    config = {"maxDepth": max_depth, "maxNodes": max_nodes}
    parts = {
        # entities for ":" and "/" keep a URL-like problem name from reading as a link
        "title": html_escape(f"{policy.problem} — ehatp policy").replace(":", "&#58;")
        .replace("/", "&#47;"),
        "css": _asset("explorer.css"),
        "js": _asset("explorer.js"),
        "policy_json": _script_json(data),
        "config_json": _script_json(config),
    }
    # one pass so that nothing inserted is scanned for tokens again
    return _TOKEN.sub(lambda m: parts[m.group(1)], _asset("explorer.html"))


# --------------------------------------------------------------------------- command


def render(path: str | Path | Policy, fmt: Format = Format.dot, *, max_depth: int | None = None,
           max_nodes: int | None = DEFAULT_MAX_NODES,
           share: bool | None = None) -> tuple[str, list[str]]:
    """The rendered text and the collapse notes (empty when drawn whole). A path is read
    with its structure checked (:func:`~ehatp.tools.common.read_policy`)."""
    policy = path if isinstance(path, Policy) else read_policy(path)
    if fmt is Format.html:
        return to_html(policy, max_depth=max_depth, max_nodes=max_nodes), []
    view = plan_view(policy, max_depth=max_depth, max_nodes=max_nodes, share=share)
    dot = to_dot(policy, view)
    return (dot.source if fmt is Format.dot else to_svg(dot)), view.notes


def render_command(
    policy: Path = typer.Argument(..., help="Policy JSON written by `ehatp solve --out FILE`.",
                                  show_default=False),
    fmt: Format = typer.Option(Format.dot, "--format", "-f",
                               help="dot (text), svg (needs Graphviz) or html (explorer)."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Write here instead of stdout."),
    max_depth: int | None = typer.Option(None, "--max-depth", min=0,
                                         help="Fold everything below this depth."),
    max_nodes: int = typer.Option(DEFAULT_MAX_NODES, "--max-nodes", min=1,
                                  help="Node budget; bigger policies are collapsed."),
    share: bool | None = typer.Option(None, "--share/--no-share",
                                      help="Draw identical subtrees once "
                                           "[default: only when over --max-nodes]."),
    problem: Path | None = typer.Option(None, "--problem", "-p", metavar="PROBLEM.toml",
                                        help="Check that the policy was planned for this "
                                             "problem file."),
) -> None:
    """Draw a policy as Graphviz DOT or SVG, or as a self-contained HTML explorer.

    The file's structure is checked first (exit 2 if it was edited into something else)."""
    with user_errors(policy):
        pol = read_policy(policy)
    if problem is not None:
        with user_errors(problem):
            prob = load(problem)
        with user_errors(policy):
            check_policy_problem(pol, policy, prob)
    with user_errors(policy):
        try:
            text, notes = render(pol, fmt, max_depth=max_depth, max_nodes=max_nodes,
                                 share=share)
        except DotMissing as e:
            die(str(e))
    if notes:
        typer.echo(f"render: {policy}: collapsed: {'; '.join(notes)}", err=True)
    if out is None:
        sys.stdout.write(text)
        return
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as e:
        die(InputError(str(out), "", f"cannot write ({e.strerror or e})",
                       "check that the directory exists and is writable").line())


def register(app: typer.Typer) -> None:
    """Add the ``render`` command to the CLI ``app``."""
    app.command("render")(render_command)


def main() -> None:
    """``python -m ehatp.tools.render POLICY.json ...`` without the rest of the CLI."""
    app = typer.Typer(add_completion=False, cls=Commands)
    app.command()(render_command)
    app()


if __name__ == "__main__":
    main()
