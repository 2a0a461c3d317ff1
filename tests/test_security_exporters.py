"""A file must never run code: every string of a policy reaches what an exporter writes only
as an escaped literal (docs/security.md). Hostile names -- quotes that end a docstring, markup
that ends a script, DOT syntax, newlines, backslashes, line separators -- go through every
exporter as the problem, the domain, the agents' labels and the state; the py_trees module
imports without running them and gives them back as data, the XML attributes parse back to
them, the DOT parses with no node of theirs, the HTML holds no tag of theirs."""

from __future__ import annotations

import ast
import importlib.util
import json
import re
import shutil
import subprocess
import sys
import tomllib
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from ehatp import Policy
from ehatp.cli.app import app
from ehatp.errors import printable
from ehatp.formats import bt, render
from ehatp.formats.hddl_source import _q
from ehatp.formats.text import plain, policy_lines

from .conftest import solved_v2

MARK = "MARKER_PATH"  # replaced by the path of a file that injected code would create


def hostile_names() -> list[str]:
    """Names that would run or render as code if pasted raw (``MARK`` stands for a file the
    injected code creates)."""
    touch = f"import pathlib; pathlib.Path({MARK!r}).touch()"
    return [
        # valid Python both raw in a docstring and as a repr in one: this one ran before
        'P"""; import pathlib; pathlib.Path(__file__).with_suffix(chr(46)+chr(120)).touch(); """',
        f'P"""\n{touch}\n"""',
        f"P'''\n{touch}\n'''",
        f'P" + str(__import__("pathlib").Path({MARK!r}).touch()) + "',
        f"P\\\"\"\"; {touch}; x = '",
        "</script><script>document.title='pwned'</script>",
        '"]; evil [shape=box label="injected"]; x ["',
        "<<b>html label</b>>",
        "<!-- comment --> -- -->",
        "a & b &amp; c <d>",
        "new\nline\r\tand tab",
        "back\\slash \\N \\G \\l \\",
        "{{title}} {policy_json} {}",
        "line\u2028separator\u2029paragraph",
        "https://example.com/x",
        "ünïcödé 名前 ✓",
    ]


def marked(name: str, marker: Path) -> str:
    return name.replace(MARK, str(marker))


def for_bt(name: str) -> str:
    """``name`` with its statement separators ``;`` made newlines: still code if pasted raw,
    and a name a behaviour tree can carry (``;`` separates the items of a list port, so a
    name holding it is refused: test_a_name_holding_the_list_separator_...)."""
    return name.replace(";", "\n")


def hostile_policy(name: str) -> Policy:
    """P4's policy (informs and human choices included) with ``name`` as its problem, domain,
    in every move label, argument and literal told, and as a fact of every state."""
    d = solved_v2("cubes/p4").policy.to_dict()
    d["problem"] = d["domain"] = name
    for node in d["nodes"]:
        node["state"] = [*node["state"], name]
        for m in node["moves"]:
            m["action"] = f"{m['action']} {name}"
            m["args"] = [*m["args"], name]
            if m["told"]:
                m["told"] = [*m["told"], name]
    return Policy.from_dict(d)


def hostile_file(tmp_path: Path, name: str) -> Path:
    f = tmp_path / "hostile.policy.json"
    f.write_text(json.dumps(hostile_policy(name).to_dict()), encoding="utf-8")
    return f


@pytest.fixture(params=range(len(hostile_names())), ids=lambda i: f"name{i}")
def name_and_marker(request: pytest.FixtureRequest, tmp_path: Path) -> tuple[str, Path]:
    marker = tmp_path / "INJECTED-CODE-RAN"
    return marked(hostile_names()[request.param], marker), marker


# --- py_trees: a module -----------------------------------------------------------------------


def import_file(path: Path) -> Any:
    spec = importlib.util.spec_from_file_location(f"hostile_{abs(hash(path))}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def string_constants(source: str) -> set[str]:
    return {n.value for n in ast.walk(ast.parse(source))
            if isinstance(n, ast.Constant) and isinstance(n.value, str)}


def test_the_py_trees_module_imports_without_running_a_name_and_gives_it_back(
        tmp_path: Path, name_and_marker: tuple[str, Path]) -> None:
    pytest.importorskip("py_trees", reason="py_trees is not installed (pip install 'ehatp[bt]')")
    name, marker = for_bt(name_and_marker[0]), name_and_marker[1]
    policy = hostile_policy(name)
    source = bt.to_py_trees_source(bt.from_policy(policy))
    tree = ast.parse(source)
    docstrings = [ast.get_docstring(n) or "" for n in ast.walk(tree)
                  if isinstance(n, ast.Module | ast.FunctionDef)]
    assert not any(name in doc for doc in docstrings)
    path = tmp_path / "hostile_tree.py"
    path.write_text(source, encoding="utf-8")
    module = import_file(path)
    assert not marker.exists(), "a name ran as code when the module was imported"
    assert not path.with_suffix(".x").exists(), "a name ran as code when the module was imported"
    assert module.POLICY["problem"] == name and module.POLICY["domain"] == name
    labels = {m.action for _, m in policy.edges()}
    assert labels <= string_constants(source)
    commands: list[Any] = []
    root = module.make_tree(lambda c: commands.append(c) or True,
                            lambda turn: policy.nodes[turn.node].moves[0].action)
    for _ in range(100):
        root.tick_once()
    assert not marker.exists()
    acted = [c for c in commands if c.kind == "action"]
    assert acted and all(c.action.endswith(" " + name) for c in acted)


# --- BehaviorTree.CPP: XML ------------------------------------------------------------------


def test_the_xml_parses_and_every_label_is_an_attribute_equal_to_it(
        name_and_marker: tuple[str, Path]) -> None:
    name = for_bt(name_and_marker[0])
    policy = hostile_policy(name)
    xml = bt.to_btcpp(bt.from_policy(policy))
    root = ET.fromstring(xml, parser=ET.XMLParser(target=ET.TreeBuilder(insert_comments=True)))
    values = {v for e in root.iter() for v in e.attrib.values()}
    human_labels = {m.action for _, m in policy.edges() if m.agent == policy.agents["human"]}
    assert human_labels and human_labels <= values
    did = [e.attrib["action"] for e in root.iter("HumanDid")]
    assert did and all(a.endswith(" " + name) for a in did)
    robot = [e.attrib["action"] for e in root.iter("RobotAction")]
    assert robot and all(a.endswith(" " + name) for a in robot)
    tags = {e.tag for e in root.iter() if isinstance(e.tag, str)}
    assert tags <= bt.CUSTOM_IDS | {"root", "BehaviorTree", "Sequence", "Fallback", "SubTree",
                                    "AlwaysFailure", "TreeNodesModel", "Action", "Condition",
                                    "input_port", "output_port"}
    comments = [e.text or "" for e in root.iter() if e.tag is ET.Comment]
    assert comments and not any("--" in c or c.endswith("-") for c in comments)


def test_a_character_xml_cannot_carry_is_refused_not_written() -> None:
    with pytest.raises(ValueError, match="control character"):
        bt.to_btcpp(bt.from_policy(hostile_policy("P\x1b[31m")))


# --- DOT, SVG -----------------------------------------------------------------------------


def dot_json(source: str) -> dict[str, Any]:
    r = subprocess.run(["dot", "-Tjson"], input=source, capture_output=True, text=True,
                       timeout=60, check=False)
    assert r.returncode == 0, r.stderr
    out: dict[str, Any] = json.loads(r.stdout)
    return out


def test_the_dot_parses_with_no_node_of_a_name_and_shows_it_as_text(
        name_and_marker: tuple[str, Path]) -> None:
    name, _ = name_and_marker
    policy = hostile_policy(name)
    dot = render.to_dot(policy)
    if shutil.which("dot") is None:
        pytest.skip("Graphviz's dot is not installed (make system-deps): the DOT is not parsed")
    graph = dot_json(dot.source)
    names = {o["name"] for o in graph.get("objects", [])}
    assert names == {f"n{i}" for i in range(len(policy.nodes))}
    assert len(graph.get("edges", [])) == sum(1 for _ in policy.edges())
    # dot keeps a label's backslash escapes until it draws: ours double every backslash
    shown = printable(name).replace("\\", "\\\\").replace("&", "&amp;")
    assert shown in graph["label"]
    tooltips = [o.get("tooltip", "") for o in graph["objects"]]
    assert all(shown in t for t in tooltips)
    svg = render.to_svg(dot)
    drawn = "".join(ET.fromstring(svg).itertext())
    assert printable(name).splitlines()[0][:20] in drawn


def test_a_label_written_like_an_html_label_is_drawn_as_text() -> None:
    if shutil.which("dot") is None:
        pytest.skip("Graphviz's dot is not installed (make system-deps): nothing is drawn")
    d = solved_v2("cubes/p4").policy.to_dict()
    for node in d["nodes"]:  # every move its own label: each shared node's edges are labelled
        for j, m in enumerate(node["moves"]):
            m["action"] = f"<<b>bold{node['id']}_{j}</b>>"
    policy = Policy.from_dict(d)
    dot = render.to_dot(policy)
    assert any(attrs.startswith("[label=\"<<b>") for attrs in
               re.findall(r"n\d+ -> n\d+ (\[.*\])", dot.source))
    drawn = "".join(ET.fromstring(render.to_svg(dot)).itertext())
    assert "<<b>bold" in drawn  # as written: no bold text, no HTML-like label


# --- the HTML explorer ----------------------------------------------------------------------


class Page(HTMLParser):
    """The tags, the script bodies and the title of a page as a browser's tokenizer sees them."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[str] = []
        self.scripts: dict[str, str] = {}
        self.title = ""
        self._in: tuple[str, str] | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append(tag)
        if tag in ("script", "title", "iframe"):
            self._in = (tag, dict(attrs).get("id") or "")
            if tag == "iframe":
                self.scripts["srcdoc"] = dict(attrs).get("srcdoc") or ""

    def handle_endtag(self, tag: str) -> None:
        self._in = None

    def handle_data(self, data: str) -> None:
        if self._in is None:
            return
        if self._in[0] == "title":
            self.title += data
        elif self._in[0] == "script":
            self.scripts[self._in[1]] = self.scripts.get(self._in[1], "") + data


def parse(page: str) -> Page:
    p = Page()
    p.feed(page)
    p.close()
    return p


TEMPLATE_TAGS = ["html", "head", "meta", "meta", "meta", "meta", "title", "style", "body"]


def test_the_html_holds_no_tag_of_a_name_and_gives_it_back_as_data(
        name_and_marker: tuple[str, Path]) -> None:
    name, _ = name_and_marker
    policy = hostile_policy(name)
    page = render.to_html(policy)
    plain_page = render.to_html(hostile_policy("P"))
    assert parse(page).tags == parse(plain_page).tags  # the same elements, none injected
    p = parse(page)
    assert p.tags.count("script") == 3
    assert json.loads(p.scripts["policy-data"])["problem"] == name
    assert p.title == f"{name} — ehatp policy"
    for bad in ("</script", "<!--", "<script>document", "\u2028", "\u2029"):
        assert page.count(bad) == plain_page.count(bad)
    frame = parse(render.notebook_html(policy))
    assert frame.tags == ["iframe"] and frame.scripts["srcdoc"] == page


# --- text for a terminal --------------------------------------------------------------------


def test_show_prints_a_name_with_its_control_characters_escaped() -> None:
    text = plain(policy_lines(hostile_policy("P\x1b]0;title\x07\x9b31m")))
    assert "\x1b" not in text and "\x07" not in text and "\x9b" not in text
    assert "P\\x1b]0;title\\x07\\x9b31m" in text


# --- the files import-hddl writes ----------------------------------------------------------


@pytest.mark.parametrize("text", [*hostile_names(), "esc\x1b[31m", "nul\x00", "del\x7f\x9b"])
def test_a_string_import_hddl_writes_is_the_same_string_in_python_and_in_toml(
        text: str) -> None:
    literal = _q(text)
    assert ast.literal_eval(literal) == text
    assert tomllib.loads(f"x = {literal}")["x"] == text
    assert "\n" not in literal and "\r" not in literal


# --- through the command line -------------------------------------------------------------


runner = CliRunner()


@pytest.mark.parametrize("command", [
    ["export", "bt", "--format", "py_trees"], ["export", "bt", "--format", "btcpp4"],
    ["render", "--format", "dot"], ["render", "--format", "html"], ["show"],
])
def test_every_exporter_writes_a_hostile_policy_file_without_running_it(
        tmp_path: Path, command: list[str]) -> None:
    marker = tmp_path / "INJECTED-CODE-RAN"
    name = hostile_names()[0]  # valid Python both raw and as a repr in a docstring
    if command[0] == "export":  # no ';' (refused by export bt), still code if pasted raw
        name = 'P"""+__import__("pathlib").Path(__file__).with_suffix(chr(46)+chr(120)).touch()+"""'
    f = hostile_file(tmp_path, name)
    out = tmp_path / "out.txt"
    args = [*command, str(f)] + ([] if command == ["show"] else ["--out", str(out)])
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.output
    if command[-1] == "py_trees":
        pytest.importorskip("py_trees", reason="py_trees is not installed")
        module = import_file(out.rename(tmp_path / "tree.py"))
        assert module.POLICY["problem"] == name
        assert not (tmp_path / "tree.x").exists()
    assert not marker.exists()


@pytest.mark.parametrize("fmt", ["btcpp4", "py_trees"])
def test_a_name_holding_the_list_separator_is_refused_by_export_bt_in_one_line(
        tmp_path: Path, fmt: str) -> None:
    """BehaviorTree.CPP splits a list port (``args``, ``literals``, ``expected``) on every
    ``;`` with no escape: a tree holding ``pick(a;b)`` would hand the robot's program the
    arguments ``a`` and ``b``. So ``export bt`` refuses it, naming the item and the fix."""
    f = hostile_file(tmp_path, "a;b")
    r = subprocess.run([sys.executable, "-m", "ehatp.cli", "export", "bt", str(f),
                        "--format", fmt, "--out", str(tmp_path / "t")],
                       capture_output=True, text=True, timeout=120, check=False)
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.splitlines()) == 1, r.stderr
    assert "holds ';', which BehaviorTree.CPP's list ports split on" in r.stderr
    assert "rename the object or literal without ';'" in r.stderr
    assert not (tmp_path / "t").exists()


def test_a_policy_file_holding_a_terminal_escape_code_is_refused_in_one_line(
        tmp_path: Path) -> None:
    f = hostile_file(tmp_path, "P\x1b]0;pwned\x07")
    for command in (["show"], ["render", "--format", "dot"], ["export", "bt"]):
        r = subprocess.run([sys.executable, "-m", "ehatp.cli", *command, str(f)],
                           capture_output=True, text=True, timeout=120, check=False)
        assert r.returncode == 2, r.stderr
        assert "\x1b" not in r.stderr + r.stdout and "\x07" not in r.stderr
        assert re.fullmatch(r"error: \S+:\d+:\d+: a string holds the control character "
                            r"'\\x1b'.*; remove it from the file\n", r.stderr), r.stderr


def test_import_hddl_writes_hostile_sidecar_strings_as_data(tmp_path: Path) -> None:
    pytest.importorskip("unified_planning", reason="unified-planning is not installed "
                                                   "(pip install 'ehatp[hddl]')")
    hddl = Path(__file__).parent / "data" / "hddl"
    marker = tmp_path / "INJECTED-CODE-RAN"
    name = marked(hostile_names()[1], marker).replace("\n", " ")  # a sidecar holds no newline
    description = marked(hostile_names()[2], marker)
    text = (hddl / "transport-sidecar.toml").read_text(encoding="utf-8")
    assert "\n[problem]\n" in text
    side = tmp_path / "side.toml"
    side.write_text(text.replace("\n[problem]\n", f"\n[problem]\nname = {json.dumps(name)}\n"
                                 f"description = {json.dumps(description)}\n"), encoding="utf-8")
    r = runner.invoke(app, ["import-hddl", str(hddl / "transport-domain.hddl"),
                            str(hddl / "transport-p1.hddl"), "--sidecar", str(side),
                            "--out", str(tmp_path / "transport.py")])
    assert r.exit_code == 0, r.output
    problem = tomllib.loads((tmp_path / "transport.toml").read_text(encoding="utf-8"))
    assert problem["problem"]["name"] == name
    assert problem["problem"]["description"] == description
    import_file(tmp_path / "transport.py").make_domain()
    assert not marker.exists()
