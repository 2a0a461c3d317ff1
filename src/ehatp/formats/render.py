"""Draw a robot policy as Graphviz DOT / SVG or as an offline HTML explorer (``ehatp render``),
also inline in a notebook.

DOT is always available (built with the ``graphviz`` Python package, which needs no binary);
SVG pipes that DOT through Graphviz's ``dot`` program. The policy is a graph
(docs/policy-format.md) and is drawn as one: each node once, with an edge per move, so a node
reached by several paths has several parents. Big policies are collapsed by :func:`plan_view`:
distinct nodes with identical content all the way down are drawn once, and a depth cap and a
node budget fold what is left into "… N more" stubs. The HTML explorer is one file: the
template, CSS and JS under ``explorer/`` are inlined and the policy JSON embedded, so it works
offline. :class:`Explorer` shows that page inline in a Jupyter notebook (``ehatp.explore``; a
policy displays itself so once ``ehatp`` is imported in IPython). See ``docs/rendering.md`` and
``docs/notebook.md``.

Neither typer nor graphviz load with this module: the ``graphviz`` package when a drawing is
made, the command line never (it is :mod:`ehatp.cli.render`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import re
import shutil
import subprocess
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from enum import StrEnum
from html import escape as html_escape
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import DotMissing, PolicyTooLarge, printable
from ..model.problem import call_str
from .lifted import EXPAND_LIMIT, Perm, content, expanded, renamings
from .policy import COMM_KINDS, Policy, PolicyMove, PolicyNode
from .policy_check import read_policy

if TYPE_CHECKING:
    import graphviz  # type: ignore[import-untyped]

    from ..model.problem import Problem

DEFAULT_MAX_NODES = 400  # more than this and a drawing stops being readable
IDLE_KINDS = ("wait", "pass")
INSTALL_DOT = ("--format svg needs Graphviz's `dot` program, which was not found; install "
               "Graphviz (Debian/Ubuntu: apt-get install graphviz; macOS: brew install graphviz) "
               "or use --format dot or --format html")


class Format(StrEnum):
    dot = "dot"
    svg = "svg"
    html = "html"


# --------------------------------------------------------------------------- collapsing


@dataclass
class View:
    """What to draw: policy node ids (a representative for merged identical subgraphs) and
    moves as edges."""

    nodes: list[int]  # drawn node ids, breadth-first
    edges: list[tuple[int, int, int]]  # (from, to, index of the move in the from node's moves)
    folded: dict[int, int] = field(default_factory=dict)  # drawn id -> nodes not drawn below
    stands_for: dict[int, int] = field(default_factory=dict)  # drawn id -> its copies in the tree
    notes: list[str] = field(default_factory=list)
    # drawn id -> the moves into it, from anywhere in the policy (into the nodes it stands for)
    entering: dict[int, list[PolicyMove]] = field(default_factory=dict)
    # a lifted policy drawn without its expansion (lifted_view): ``folded`` counts canonical
    # nodes, ``entering`` only the moves drawn, and the title says how far the drawing went
    lifted: str = ""

    @property
    def collapsed(self) -> bool:
        return bool(self.notes)


def subgraph_hashes(policy: Policy) -> list[str]:
    """A content hash per node covering everything below it (nodes and moves) except the ids,
    children before parents: linear in the graph."""
    out = [""] * len(policy.nodes)
    for i in reversed(policy.topological_order()):
        node = policy.nodes[i]
        own = {k: v for k, v in node.to_dict().items() if k not in ("id", "moves")}
        h = hashlib.sha256(json.dumps(own, sort_keys=True, default=str).encode())
        for m in node.moves:
            move = {k: v for k, v in m.to_dict().items() if k != "to"}
            h.update(json.dumps(move, sort_keys=True, default=str).encode())
            h.update(out[m.to].encode())
        out[i] = h.hexdigest()
    return out


def _below(policy: Policy, canon: list[int], start: int, drawn: set[int]) -> int:
    """Distinct (representative) nodes below ``start`` that are not drawn."""
    seen: set[int] = set()
    stack = [start]
    while stack:
        for m in policy.nodes[stack.pop()].moves:
            k = canon[m.to]
            if k not in seen and k not in drawn:
                seen.add(k)
                stack.append(k)
    return len(seen)


def _breadth_first(has_moves: Callable[[int], bool], kids: Callable[[int], list[int]],
                   max_depth: int | None, max_nodes: int | None
                   ) -> tuple[list[int], list[tuple[int, int, int]], list[int], list[str]]:
    """The breadth-first walk that decides what is drawn, from node 0: ``kids(i)`` gives the
    nodes node ``i``'s moves lead to (asked only of a node with moves, within the depth cap).
    A node below ``max_depth``, or whose new children would pass ``max_nodes``, is cut (all
    its children or none). Return the nodes drawn in the walk's order, the edges drawn (from,
    to, move index), the nodes cut, and the notes saying why."""
    depth = {0: 0}
    order = [0]
    edges: list[tuple[int, int, int]] = []
    cut: list[int] = []
    cut_depth = cut_budget = 0
    queue = deque([0])
    while queue:
        i = queue.popleft()
        if not has_moves(i):
            continue
        if max_depth is not None and depth[i] >= max_depth:
            cut.append(i)
            cut_depth += 1
            continue
        below = kids(i)
        new = list(dict.fromkeys(k for k in below if k not in depth))
        if max_nodes is not None and len(order) + len(new) > max_nodes:
            cut.append(i)
            cut_budget += 1
            continue
        edges.extend((i, k, j) for j, k in enumerate(below))
        for k in new:
            depth[k] = depth[i] + 1
            order.append(k)
            queue.append(k)
    notes = []
    if cut_depth:
        notes.append(f"cut at depth {max_depth} ({cut_depth} node(s) folded)")
    if cut_budget:
        notes.append(f"node budget {max_nodes} reached ({cut_budget} node(s) folded)")
    return order, edges, cut, notes


def plan_view(policy: Policy, *, max_depth: int | None = None,
              max_nodes: int | None = DEFAULT_MAX_NODES, share: bool | None = None) -> View:
    """Decide what to draw.

    ``share`` None merges distinct nodes with identical subgraphs only when the policy is over
    ``max_nodes``. Then a breadth-first walk draws nodes down to ``max_depth`` and while the
    budget lasts; a node whose children do not all fit is drawn with a stub counting the nodes
    folded below it (all children or none, so a human choice is never shown half-expanded).
    A lifted policy (format version 3) is drawn expanded.
    """
    policy = expanded(policy)
    total = len(policy.nodes)
    if share is None:
        share = max_nodes is not None and total > max_nodes
    canon = list(range(total))
    notes: list[str] = []
    if share:
        first: dict[str, int] = {}
        for i, h in enumerate(subgraph_hashes(policy)):
            canon[i] = first.setdefault(h, i)
        if len(first) < total:
            notes.append(f"identical subgraphs drawn once ({total} policy nodes, "
                         f"{len(first)} distinct)")
    copies: dict[int, int] = {}
    for i, n in enumerate(policy.path_counts()):
        copies[canon[i]] = copies.get(canon[i], 0) + n
    order, edges, cut, cuts = _breadth_first(
        lambda i: bool(policy.nodes[i].moves),
        lambda i: [canon[m.to] for m in policy.nodes[i].moves], max_depth, max_nodes)
    notes += cuts
    drawn = set(order)
    # a folded node may have children drawn through another parent: it still gets its stub
    folded = {i: _below(policy, canon, i, drawn) for i in cut}
    stands_for = {i: copies[i] for i in order if copies.get(i, 1) > 1}
    entering: dict[int, list[PolicyMove]] = {}
    for _, m in policy.edges():
        if canon[m.to] in drawn:
            entering.setdefault(canon[m.to], []).append(m)
    return View(order, edges, folded, stands_for, notes, entering)


def lifted_view(policy: Policy, too_large: PolicyTooLarge, *, max_depth: int | None = None,
                max_nodes: int | None = DEFAULT_MAX_NODES) -> tuple[Policy, View]:
    """Decide what to draw of a lifted policy too large to expand (``too_large``), realising
    only what is drawn (docs/policy-format.md, "Version 3"): the breadth-first walk of
    :func:`plan_view` over the real nodes, each a canonical node seen through the renaming of
    the path that first reached it (two paths to one real state give one node, as
    :func:`~ehatp.formats.lifted.expand` merges them), down to ``max_depth`` and while the
    budget lasts (all children or none). Return the drawn nodes as a policy (ids in the walk's
    order; a folded node's moves are not followed) and the view. Unlike :func:`plan_view`, no
    identical subgraphs are merged, a stub counts the canonical nodes below, and a node's
    entering moves are those drawn."""
    ren = renamings(policy)
    assert ren is not None
    nodes = policy.nodes
    budget = DEFAULT_MAX_NODES if max_nodes is None else max_nodes
    ids: dict[tuple[int, str], int] = {}
    real: list[tuple[int, Perm]] = []
    views: list[PolicyNode] = []

    def realise(n: int, tau: Perm) -> int:
        view = ren.node(tau, nodes[n])
        key = (n, content(view))
        i = ids.get(key)
        if i is None:
            i = ids[key] = len(views)
            real.append((n, tau))
            views.append(view)
        return i

    kids_of: dict[int, list[int]] = {}

    def kids(i: int) -> list[int]:
        tau = real[i][1]
        kids_of[i] = [realise(m.to, ren.child(tau, m.renaming)) for m in views[i].moves]
        return kids_of[i]

    realise(0, ren.root)
    order, edges, cut, cuts = _breadth_first(lambda i: bool(views[i].moves), kids, max_depth,
                                             budget)
    drawn_nodes: list[PolicyNode] = []
    for i, view in enumerate(views):
        below = kids_of.get(i)
        moves = (view.moves if below is None else
                 [replace(m, to=k, renaming=0) for m, k in zip(view.moves, below, strict=True)])
        drawn_nodes.append(replace(view, id=i, moves=moves))
    drawn = replace(policy, nodes=drawn_nodes, symmetry=None)
    identity = list(range(len(nodes)))  # canonical nodes counted as they are
    folded = {i: _below(policy, identity, real[i][0], set()) for i in cut}
    notes = [f"lifted, drawn without its expansion: {too_large}", *cuts]
    entering: dict[int, list[PolicyMove]] = {}
    for a, b, j in edges:
        entering.setdefault(b, []).append(drawn_nodes[a].moves[j])
    return drawn, View(order, edges, folded, {}, notes, entering,
                       lifted=f"{len(policy.nodes):,} canonical nodes, {len(order):,} drawn")


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
    """Return ``s`` for a DOT string that dot shows as written: control characters as their
    Python escapes, then backslashes and quotes escaped, so that neither dot's label escapes
    (``\\N``, ``\\l``, ...) nor a quote in a name can change the drawing, and ``&`` as
    ``&amp;`` (dot reads entities in every string). (:func:`to_dot` also marks every value as
    not HTML-like, so that ``<...>`` stays text.)"""
    return printable(s).replace("\\", "\\\\").replace('"', '\\"').replace("&", "&amp;")


def worlds_text(n: PolicyNode) -> str:
    return f"{n.worlds} world" + ("" if n.worlds == 1 else "s")


def k_text(policy: Policy, n: PolicyNode) -> str:
    """The K-counter against the bound: ``k=1/2`` is one robot turn unseen of K = 2."""
    return f"k={n.k}/{policy.K}"


def entry_move(moves: list[PolicyMove]) -> PolicyMove | None:
    """The move a node is drawn with: the one every path takes into it, or None when they
    differ (then each edge is labelled with its own move)."""
    if not moves:
        return None
    first = moves[0]
    same = all((m.agent, m.kind, m.action) == (first.agent, first.kind, first.action)
               for m in moves)
    return first if same else None


def node_attrs(policy: Policy, n: PolicyNode, entered: list[PolicyMove],
               copies: int = 1) -> dict[str, str]:
    """Shape, colours, label and tooltip of one drawn policy node, reached by the moves
    ``entered`` (none at the root)."""
    move = entry_move(entered)
    agent = entered[0].agent if entered else None
    kinds = {m.kind for m in entered}
    kind = kinds.pop() if len(kinds) == 1 else None  # styled by the moves' kind, if one
    human = agent == policy.agents["human"]
    if n.id == 0:
        attrs = dict(_START_STYLE)
    elif kind in COMM_KINDS:
        attrs = dict(_COMM_STYLE)
    else:
        attrs = dict(_HUMAN_STYLE if human else _ROBOT_STYLE)
        if kind in IDLE_KINDS:
            attrs["style"] += ",dashed"
            attrs["fillcolor"] = "#f3f3f3"
    if n.id == 0:
        head = "start"
    elif move is None:  # reached by different moves: each labels its edge
        head = f"{agent}: one of {len(entered)} moves (on the edges)"
    else:
        head = f"{move.agent}: {move.action}"
    info = [worlds_text(n), k_text(policy, n)]
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
    cost = "" if move is None and n.id else f"cost {0 if move is None else move.cost}, "
    attrs["tooltip"] = _dot_text(
        f"node {n.id}: {cost}cost to go {n.value}, "
        f"{'together' if n.copresent else 'apart'}; true: {', '.join(n.state)}")
    attrs["id"] = f"policy_node_{n.id}"  # Graphviz escapes "-" in SVG ids
    return attrs


def to_dot(policy: Policy, view: View | None = None) -> graphviz.Digraph:
    """The policy (or the part ``view`` keeps) as a Graphviz digraph: one node per policy node,
    one edge per move (a lifted policy expanded, as :func:`plan_view` draws it)."""
    import graphviz

    policy = expanded(policy)
    view = view or plan_view(policy, max_nodes=None, share=False)
    kind = "expected" if policy.objective.get("kind") == "expected" else "worst-case"
    size = view.lifted or f"{len(policy.nodes)} nodes"
    title = (f"{policy.problem} ({policy.domain}): {kind} cost {policy.cost}, "
             f"{policy.leaves} branches, {policy.communications} communication(s); {size}")
    label = "\\l".join(_dot_text(x) for x in [title, *(f"collapsed: {t}" for t in view.notes)])
    text = graphviz.nohtml  # every value is text: "<b>x</b>" is not an HTML-like label
    g = graphviz.Digraph(name=re.sub(r"\W", "_", policy.problem) or "policy")
    g.attr(rankdir="TB", labelloc="t", labeljust="l", label=text(label + "\\l"),
           fontname="Helvetica", fontsize="12")
    g.attr("node", fontname="Helvetica", fontsize="10", margin="0.08,0.04")
    g.attr("edge", color="#666666", arrowsize="0.6", fontname="Helvetica", fontsize="9")
    into = view.entering
    for i in view.nodes:
        shown = node_attrs(policy, policy.nodes[i], into.get(i, []), view.stands_for.get(i, 1))
        g.node(f"n{i}", **{k: text(v) for k, v in shown.items()})
        if i in view.folded:
            more = (f"… more below ({view.folded[i]} canonical nodes)" if view.lifted
                    else f"… {view.folded[i]} more")
            g.node(f"more{i}", label=more, shape="note",
                   style="dashed", color="#888888", fontcolor="#555555")
            g.edge(f"n{i}", f"more{i}", style="dashed", color="#888888")
    human = policy.agents["human"]
    for a, b, j in view.edges:
        m = policy.nodes[a].moves[j]
        attrs: dict[str, str] = {}
        if m.agent == human:  # human moves are the uncontrollable branches: dashed, orange
            attrs.update(style="dashed", color="#a35200")
        if entry_move(into.get(b, [])) is None:
            attrs["label"] = text(_dot_text(m.action))
        g.edge(f"n{a}", f"n{b}", **attrs)
    return g


def to_svg(dot: graphviz.Digraph) -> str:
    """Lay out with Graphviz's ``dot``; :class:`DotMissing` when it is not installed."""
    import graphviz

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
    return (resources.files("ehatp.formats") / "explorer" / name).read_text(encoding="utf-8")


def explorer_script(lifted: bool) -> str:
    """The explorer page's one script: the code both pages share (``explorer/explorer.js``,
    which defines ``ehatpExplorer``: drawing, folding, details, timeline), then the page's
    model of the policy, which calls it: the eager one over the embedded version 2 graph
    (``explorer/explorer-eager.js``) or, for a ``lifted`` policy, the lazy one
    (``explorer/explorer-lifted.js``). See docs/rendering.md."""
    return _asset("explorer.js") + "\n" + _asset(
        "explorer-lifted.js" if lifted else "explorer-eager.js")


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
            max_nodes: int | None = DEFAULT_MAX_NODES, static: list[str] | None = None,
            expand_limit: int | None = EXPAND_LIMIT) -> str:
    """Return the self-contained explorer page; depth cap and budget only set what starts
    folded; ``static`` (:func:`static_facts`) are listed with the truth of every node, marked
    static. The script is :func:`explorer_script`. A lifted policy (format version 3) is
    drawn expanded (:func:`~ehatp.formats.lifted.expanded`) by the eager model
    (``explorer/explorer-eager.js``), as a version 2 policy is, while it stands for at most
    ``expand_limit`` real nodes (0: never expanded); past that it is embedded as it is and
    realised in the page, a branch when it is unfolded (``explorer/explorer-lifted.js``,
    docs/rendering.md): the page grows with the lifted file, never with its expansion."""
    if policy.symmetry is not None:
        with contextlib.suppress(PolicyTooLarge):
            policy = expanded(policy, expand_limit)
    lifted = policy.symmetry is not None
    data = policy.to_dict()
    config = {"maxDepth": max_depth, "maxNodes": max_nodes, "staticFacts": static or []}
    parts = {
        # entities for ":" and "/" keep a URL-like problem name from reading as a link
        "title": html_escape(f"{policy.problem} — ehatp policy").replace(":", "&#58;")
        .replace("/", "&#47;").replace("\u2028", "&#8232;").replace("\u2029", "&#8233;"),
        "css": _asset("explorer.css"),
        "js": explorer_script(lifted),
        "policy_json": _script_json(data),
        "config_json": _script_json(config),
    }
    # one pass so that nothing inserted is scanned for tokens again
    return _TOKEN.sub(lambda m: parts[m.group(1)], _asset("explorer.html"))


# --------------------------------------------------------------------------- any format


def render(path: str | Path | Policy, fmt: Format = Format.dot, *, max_depth: int | None = None,
           max_nodes: int | None = DEFAULT_MAX_NODES, share: bool | None = None,
           static: list[str] | None = None, expand_limit: int | None = EXPAND_LIMIT,
           too_large: PolicyTooLarge | None = None) -> tuple[str, list[str]]:
    """Return the rendered text and the collapse notes (empty when drawn whole). A path is
    read with its structure checked (:func:`~ehatp.formats.policy_check.read_policy`); a
    lifted policy (format version 3) is drawn expanded
    (:func:`~ehatp.formats.lifted.expanded`), or, past ``expand_limit`` nodes over the real
    objects (``too_large``: known already, not tried again), realised only as far as it is
    drawn (:func:`lifted_view`, :func:`to_html`). ``static``: the explorer's static facts
    (:func:`to_html`)."""
    policy = path if isinstance(path, Policy) else read_policy(path)
    if too_large is None and policy.symmetry is not None:
        try:
            policy = expanded(policy, expand_limit)
        except PolicyTooLarge as e:
            too_large = e
    if fmt is Format.html:  # expanded above, or drawn lifted
        return to_html(policy, max_depth=max_depth, max_nodes=max_nodes, static=static,
                       expand_limit=0), []
    if too_large is not None and policy.symmetry is not None:
        policy, view = lifted_view(policy, too_large, max_depth=max_depth, max_nodes=max_nodes)
    else:
        view = plan_view(policy, max_depth=max_depth, max_nodes=max_nodes, share=share)
    dot = to_dot(policy, view)
    return (dot.source if fmt is Format.dot else to_svg(dot)), view.notes


def static_facts(problem: Problem) -> list[str]:
    """Return the facts of the problem's ``[init]`` that no action and no belief world changes
    (docs/semantics.md §2): true in every state and every world, so a policy file, which
    records only what can change, does not hold them. Sorted, written as in ``[init]``."""
    from ..model.grounding import ground_problem

    fluent = ground_problem(problem).atom_index
    return sorted(call_str(name, args) for name, args in problem.init
                  if call_str(name, args) not in fluent)


# --------------------------------------------------------------------------- notebooks


def notebook_html(policy: Policy, expand_limit: int | None = EXPAND_LIMIT) -> str:
    """The offline explorer (``ehatp render --format html``) inline in a Jupyter notebook: the
    page in a sandboxed ``<iframe srcdoc>``, so that its styles and scripts stay out of the
    notebook's. ``expand_limit`` as in :func:`to_html`. See ``docs/notebook.md``."""
    page = html_escape(to_html(policy, expand_limit=expand_limit), quote=True)
    return (f'<iframe srcdoc="{page}" sandbox="allow-scripts" title="ehatp policy '
            f'{html_escape(policy.problem, quote=True)}" style="width: 100%; height: 640px; '
            'border: 1px solid #ccc;"></iframe>')


class Explorer:
    """A policy as notebooks show it: the explorer (:func:`notebook_html`). ``ehatp.explore``
    returns one; Jupyter displays it wherever a cell shows it."""

    def __init__(self, policy: Policy) -> None:
        self.policy = policy

    def _repr_html_(self) -> str:
        return notebook_html(self.policy)


__all__ = ["DEFAULT_MAX_NODES", "INSTALL_DOT", "DotMissing", "Explorer", "Format", "View",
           "entry_move", "explorer_script", "k_text", "node_attrs", "notebook_html",
           "plan_view", "render", "static_facts", "subgraph_hashes", "to_dot", "to_html",
           "to_svg", "worlds_text"]
