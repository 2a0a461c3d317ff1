"""A structural check of BehaviorTree.CPP v4 XML, written from its documented format
(behaviortree.dev, "XML format") and from what its own parser checks and its own schema requires
(``VerifyXML`` and ``writeTreeXSD`` in BehaviorTree.CPP 4's ``src/xml_parsing.cpp``):

- ``<root BTCPP_format="4">``, with ``main_tree_to_execute`` naming one of its trees; as
  children ``<include>`` and ``<BehaviorTree>`` elements, then at most one ``<TreeNodesModel>``,
  last;
- a ``<BehaviorTree>`` has a unique ``ID`` (a model name: no space, ``<>&"'/\\:*?|.`` nor
  control character, not ``Root``), no other attribute, exactly one child;
- a node is a registered node -- one of BehaviorTree.CPP's own that the export uses, or one
  the ``TreeNodesModel`` declares, as a program registering it with those ports would: a port
  with no ``default`` is required (``use="required"`` in the generated schema), an output port
  takes a blackboard entry ``{key}``, and no attribute other than its ports, ``name`` and the
  pre- and post-condition scripts is allowed; an action or a condition has no child, a control
  node at least one, a decorator exactly one; ``<SubTree ID=...>`` has no child and names a
  tree of the file, with no tree reaching itself;
- no tree is nested deeper than 256 elements below its ``<BehaviorTree>`` (the parser's limit);
- the ``TreeNodesModel``: ``Action``, ``Condition``, ``Control`` or ``Decorator`` elements with
  an ``ID``, each holding ``input_port`` (``name``, optional ``type`` and ``default``) and
  ``output_port`` (``name``, optional ``type``) elements, then at most one ``description``; port
  names start with a letter and are not reserved.

:func:`problems` returns what is wrong, one line each (empty: the file passes).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

MAX_DEPTH = 256
RESERVED = {"name", "ID", "_autoremap", "_failureIf", "_skipIf", "_successIf", "_while",
            "_onSuccess", "_onFailure", "_post", "_onHalted"}
COMMON = {"name", "_failureIf", "_skipIf", "_successIf", "_while", "_onSuccess", "_onFailure",
          "_post", "_onHalted"}
FORBIDDEN = re.compile(r"[ \t\n\r<>&\"'/\\:*?|.\x00-\x1f\x7f]")
BLACKBOARD = re.compile(r"\{.*\}", re.DOTALL)


@dataclass
class Model:
    """A registered node: its kind, its ports (name: (direction, default or None))."""

    kind: str
    ports: dict[str, tuple[str, str | None]] = field(default_factory=dict)


# BehaviorTree.CPP's own nodes the export uses (none of them has a port)
BUILT_IN = {"Sequence": Model("Control"), "Fallback": Model("Control"),
            "AlwaysFailure": Model("Action"), "AlwaysSuccess": Model("Action")}


def _model_name(name: str) -> str | None:
    if not name:
        return "is empty"
    if name in ("Root", "root"):
        return "is reserved"
    if (m := FORBIDDEN.search(name)) is not None:
        return f"holds the forbidden character {m.group()!r}"
    return None


def _models(model: ET.Element, out: list[str]) -> dict[str, Model]:
    found: dict[str, Model] = {}
    for e in model:
        where = f"TreeNodesModel <{e.tag} ID={e.get('ID')!r}>"
        if e.tag not in ("Action", "Condition", "Control", "Decorator"):
            out.append(f"TreeNodesModel: <{e.tag}> is not a node model; use Action, Condition, "
                       "Control or Decorator")
            continue
        nid = e.get("ID")
        if nid is None:
            out.append(f"{where}: no ID; give one")
            continue
        if set(e.attrib) != {"ID"}:
            out.append(f"{where}: attributes {sorted(set(e.attrib) - {'ID'})}; only ID")
        m = Model(e.tag)
        kids = list(e)
        for i, p in enumerate(kids):
            if p.tag == "description":
                if i != len(kids) - 1:
                    out.append(f"{where}: <description> before a port; put it last")
                continue
            allowed = {"input_port": {"name", "type", "default"},
                       "output_port": {"name", "type"}}.get(p.tag)
            if allowed is None:
                out.append(f"{where}: <{p.tag}> is not a port; use input_port or output_port")
                continue
            name = p.get("name")
            if name is None or set(p.attrib) - allowed:
                out.append(f"{where}: <{p.tag}> attributes {sorted(p.attrib)}; name required, "
                           f"{sorted(allowed - {'name'})} optional")
                continue
            if not name[:1].isalpha() or name in RESERVED or FORBIDDEN.search(name):
                out.append(f"{where}: port name {name!r} is not allowed; start with a letter, "
                           "no reserved name")
            if name in m.ports:
                out.append(f"{where}: port {name!r} declared twice; once")
            m.ports[name] = ("input" if p.tag == "input_port" else "output", p.get("default"))
        if nid in found or nid in BUILT_IN or nid == "SubTree":
            out.append(f"{where}: declared twice or a built-in node; one model per ID")
        found[nid] = m
    return found


def problems(text: str) -> list[str]:
    """Return what keeps ``text`` from being a BehaviorTree.CPP v4 file its parser loads and its
    generated schema accepts, for a program that registers the nodes of its TreeNodesModel
    with those ports; one line each, ``place: problem; fix``."""
    out: list[str] = []
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        return [f"XML: {e}; write well-formed XML"]
    if root.tag != "root":
        return [f"<{root.tag}>: the root element must be <root>; rename it"]
    if root.get("BTCPP_format") != "4":
        out.append(f"<root>: BTCPP_format is {root.get('BTCPP_format')!r}; write \"4\"")
    if extra := set(root.attrib) - {"BTCPP_format", "main_tree_to_execute"}:
        out.append(f"<root>: attributes {sorted(extra)}; only BTCPP_format, "
                   "main_tree_to_execute")
    kids = list(root)
    models_at = [i for i, e in enumerate(kids) if e.tag == "TreeNodesModel"]
    if len(models_at) > 1:
        out.append("<root>: several <TreeNodesModel>; one")
    if models_at and models_at[-1] != len(kids) - 1:
        out.append("<root>: <TreeNodesModel> is not the last child; move it to the end")
    for e in kids:
        if e.tag not in ("include", "BehaviorTree", "TreeNodesModel"):
            out.append(f"<root>: child <{e.tag}>; only include, BehaviorTree, TreeNodesModel")
    registry = dict(BUILT_IN)
    if models_at:
        registry.update(_models(kids[models_at[0]], out))
    trees: dict[str, ET.Element] = {}
    for t in root.findall("BehaviorTree"):
        tid = t.get("ID", "")
        if (why := _model_name(tid)) is not None:
            out.append(f"<BehaviorTree ID={tid!r}>: the ID {why}; give a model name")
        if tid in trees:
            out.append(f"<BehaviorTree ID={tid!r}>: defined twice; one tree per ID")
        if tid in registry or tid == "SubTree":
            out.append(f"<BehaviorTree ID={tid!r}>: the name of a registered node; rename it")
        if set(t.attrib) != {"ID"}:
            out.append(f"<BehaviorTree ID={tid!r}>: attributes {sorted(t.attrib)}; ID only")
        if len(t) != 1:
            out.append(f"<BehaviorTree ID={tid!r}>: {len(t)} children; exactly 1")
        trees[tid] = t
    main = root.get("main_tree_to_execute")
    if main is not None and main not in trees:
        out.append(f"<root>: main_tree_to_execute={main!r} names no tree; name one")
    calls: dict[str, set[str]] = {tid: set() for tid in trees}

    def node(e: ET.Element, tid: str, depth: int) -> None:
        where = f"tree {tid!r}, <{e.tag}> at depth {depth}"
        if depth > MAX_DEPTH:
            out.append(f"{where}: nested deeper than {MAX_DEPTH}; split the tree into SubTrees")
            return
        if e.tag == "SubTree":
            sid = e.get("ID")
            if sid is None or sid not in trees:
                out.append(f"{where}: ID={sid!r} names no tree of the file; define it")
            else:
                calls[tid].add(sid)
            if len(e):
                out.append(f"{where}: a SubTree has children; none")
            return
        model = registry.get(e.tag)
        if model is None:
            out.append(f"{where}: not a registered node; declare it in the TreeNodesModel")
            return
        for k, v in e.attrib.items():
            if k in COMMON:
                continue
            port = model.ports.get(k)
            if port is None:
                out.append(f"{where}: attribute {k!r} is not a port of {e.tag}; declare it or "
                           "remove it")
            elif port[0] == "output" and not BLACKBOARD.fullmatch(v):
                out.append(f"{where}: output port {k}={v!r}; write a blackboard entry {{key}}")
        for k, (_, default) in model.ports.items():
            if default is None and k not in e.attrib:
                out.append(f"{where}: the port {k!r} has no default and is not given; give it "
                           "or declare a default")
        n = len(e)
        if model.kind in ("Action", "Condition") and n:
            out.append(f"{where}: {n} children; an {model.kind.lower()} has none")
        elif model.kind == "Control" and not n:
            out.append(f"{where}: no child; a control node has one or more")
        elif model.kind == "Decorator" and n != 1:
            out.append(f"{where}: {n} children; a decorator has exactly 1")
        for c in e:
            node(c, tid, depth + 1)

    for tid, t in trees.items():
        for c in t:
            node(c, tid, 1)
    # no tree reaches itself through SubTrees (the parser refuses a cycle)
    state: dict[str, int] = {}

    def visit(tid: str) -> None:
        state[tid] = 1
        for s in sorted(calls[tid]):
            if state.get(s) == 1:
                out.append(f"tree {tid!r}: reaches itself through SubTree {s!r}; break the cycle")
            elif s not in state:
                visit(s)
        state[tid] = 2

    for tid in trees:
        if tid not in state:
            visit(tid)
    return out


def depth(text: str) -> int:
    """Return the deepest nesting of an element below its ``<BehaviorTree>`` (which is 0)."""

    def down(e: ET.Element) -> int:
        return 1 + max((down(c) for c in e), default=0)

    return max((down(t) - 1 for t in ET.fromstring(text).findall("BehaviorTree")), default=0)
