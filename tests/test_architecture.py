"""The layout is the architecture (docs/architecture.md) and stays so: no import cycle between
ehatp's modules, the document names every module, the policy format loads no command line and no
drawing library, and ``ehatp --help`` imports no command."""

from __future__ import annotations

import ast
import inspect
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "ehatp"
DOC = ROOT / "docs" / "architecture.md"


def run_python(code: str) -> str:
    """Run ``code`` in a fresh interpreter (nothing imported yet); return its stdout."""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    return r.stdout


# --- the modules and their imports -----------------------------------------------------------


def modules() -> dict[str, Path]:
    """Every module of the package by dotted name (a package by its own name)."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def imports_of(name: str, path: Path, known: set[str]) -> set[str]:
    """The ehatp modules ``name`` imports, wherever the import statement is: inside functions
    and under ``if TYPE_CHECKING:`` too. ``from pkg import mod`` counts as importing
    ``pkg.mod``."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()

    def nearest(dotted: str) -> str | None:
        while dotted and dotted not in known:
            dotted = dotted.rpartition(".")[0]
        return dotted or None

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "ehatp" and (m := nearest(alias.name)):
                    out.add(m)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] == "ehatp":
                for alias in node.names:
                    full = f"{target}.{alias.name}"
                    m = full if full in known else nearest(target)
                    if m:
                        out.add(m)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8")))
    out.discard(name)
    return out


def import_graph() -> dict[str, set[str]]:
    mods = modules()
    known = set(mods)
    return {name: imports_of(name, path, known) for name, path in mods.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle (its modules in order, the first repeated at the end), or None."""
    state: dict[str, int] = {}  # 1 on the current path, 2 done
    path: list[str] = []

    def dfs(m: str) -> list[str] | None:
        state[m] = 1
        path.append(m)
        for n in sorted(graph.get(m, ())):
            if state.get(n) == 1:
                return path[path.index(n):] + [n]
            if n not in state and (found := dfs(n)):
                return found
        path.pop()
        state[m] = 2
        return None

    for m in sorted(graph):
        if m not in state and (found := dfs(m)):
            return found
    return None


def test_the_import_graph_is_read_right() -> None:
    g = import_graph()
    assert "ehatp.formats.policy" in g["ehatp.check.validator"] | g["ehatp.policy_format"]
    assert "ehatp.cli.common" in g["ehatp.cli.solve"]
    # an import inside a function counts, and one for type checkers
    assert "ehatp.search.planner" in g["ehatp.cli.solve"]
    assert "ehatp.formats.render" in g["ehatp"]
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_no_import_cycle_between_modules() -> None:
    """Counting the imports inside functions (a lazy import is still a dependency) and those
    for type checkers."""
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_the_layers_import_only_downwards() -> None:
    """model imports nothing of the layers above it; the search and the validator no format
    but the policy file; formats no command line; nothing but the command line (and the old
    paths) imports the command line."""
    g = import_graph()

    def uses(prefix: str, layer: str) -> list[str]:
        return sorted(f"{m} -> {n}" for m, deps in g.items() if m.startswith(prefix)
                      for n in deps if n.startswith(layer))

    above_model = ("ehatp.epistemic", "ehatp.search", "ehatp.check", "ehatp.formats",
                   "ehatp.run", "ehatp.experiments", "ehatp.cli")
    assert [x for layer in above_model for x in uses("ehatp.model", layer)] == []
    for core in ("ehatp.model", "ehatp.epistemic", "ehatp.search", "ehatp.check"):
        for layer in ("ehatp.run", "ehatp.experiments", "ehatp.cli"):
            assert uses(core, layer) == []
        assert [x for x in uses(core, "ehatp.formats")
                if not x.endswith("ehatp.formats.policy")] == []
    assert uses("ehatp.formats", "ehatp.cli") == uses("ehatp.run", "ehatp.cli") == []
    assert uses("ehatp.experiments", "ehatp.cli") == []


# --- the document names every module ---------------------------------------------------------


def documented_modules() -> dict[str, str]:
    """The modules the folder list of docs/architecture.md (its first code block) names, as
    paths under src/ehatp, each with its description. A line names one or more ``x.py`` (or a
    ``folder/``) and says what they are for; indentation puts a name in its folder."""
    text = DOC.read_text(encoding="utf-8")
    block = text.split("```", 2)[1]
    out: dict[str, str] = {}
    folders: list[tuple[int, str]] = []  # (indent, path) of the open folders
    last: list[str] = []  # the names of the line above
    for line in block.splitlines()[1:]:
        if not line.strip():
            continue
        indent = len(line) - len(line.lstrip())
        words = line.split()
        names = []
        while words and (words[0].rstrip(",").endswith(".py") or words[0].endswith("/")):
            names.append(words.pop(0).rstrip(","))
        if not names:  # a description going on from the line above
            for name in last:
                out[name] = f"{out[name]} {' '.join(words)}".strip()
            continue
        while folders and folders[-1][0] >= indent:
            folders.pop()
        where = folders[-1][1] if folders else ""
        last = [where + name for name in names]
        for path in last:
            out[path] = " ".join(words)
            if path.endswith("/"):
                folders.append((indent, path))
    return out


def test_the_architecture_document_names_every_module() -> None:
    named = documented_modules()
    assert named.pop("src/ehatp/", None) is not None, "the list starts at src/ehatp/"
    named = {k.removeprefix("src/ehatp/"): v for k, v in named.items()}
    actual = {"__init__.py"}  # the package's own module: its public API
    for path in PACKAGE.rglob("*.py"):
        rel = path.relative_to(PACKAGE)
        if rel.name == "__init__.py":
            if rel.parent != Path("."):
                actual.add(f"{rel.parent.as_posix()}/")  # a package: named by its folder
        else:
            actual.add(rel.as_posix())
    missing = sorted(actual - set(named))
    assert missing == [], f"docs/architecture.md does not name {missing}"
    gone = sorted(n for n in set(named) - actual if not (PACKAGE / n).is_dir())
    assert gone == [], f"docs/architecture.md names modules that do not exist: {gone}"
    for name, job in named.items():
        if not name.endswith("/") or name.count("/") == 1:
            assert job, f"docs/architecture.md names {name} without saying its job"


# --- module size -----------------------------------------------------------------------------


def size_rule() -> tuple[int, set[str]]:
    """The "Module size" paragraph of docs/architecture.md: the most lines a module may have,
    and the modules it names as exceptions (paths under src/ehatp, in backquotes)."""
    text = DOC.read_text(encoding="utf-8")
    para = text[text.index("**Module size.**"):].split("\n- ", 1)[0]
    limit = re.search(r"No module is over (\d+) lines except", para)
    assert limit, "docs/architecture.md's Module size paragraph says no limit"
    before = para.split("A module that grows")[0]  # the exceptions, not the examples after
    return int(limit.group(1)), set(re.findall(r"`([\w/]+\.py)`", before))


def lines_of(path: Path) -> int:
    """The lines of a file as ``wc -l`` counts them."""
    return path.read_bytes().count(b"\n")


def test_no_module_is_longer_than_the_document_allows() -> None:
    """docs/architecture.md, "Module size": at most 800 lines a module, but for the two it
    names (model/domain.py, experiments/randomgen.py); each exception still exists and is
    still long (else the document would name one that needs no excuse)."""
    limit, exceptions = size_rule()
    assert (limit, exceptions) == (800, {"model/domain.py", "experiments/randomgen.py"})
    sizes = {p.relative_to(PACKAGE).as_posix(): lines_of(p) for p in PACKAGE.rglob("*.py")}
    over = sorted(f"src/ehatp/{m} has {n} lines" for m, n in sizes.items()
                  if n > limit and m not in exceptions)
    assert over == [], (f"over {limit} lines: {'; '.join(over)} -- split it along a seam "
                        "(docs/architecture.md, \"Module size\") and list the new module")
    for m in sorted(exceptions):
        assert m in sizes, f"docs/architecture.md excuses src/ehatp/{m}, which does not exist"
        assert sizes[m] > limit, (f"src/ehatp/{m} has {sizes[m]} lines, no longer over {limit}:"
                                  " take it out of docs/architecture.md's exceptions")


# --- what loads with what --------------------------------------------------------------------


def test_the_policy_format_loads_neither_typer_nor_graphviz() -> None:
    out = run_python(
        "import sys, ehatp.formats.policy, ehatp.formats.policy_check, ehatp.formats.text\n"
        "p = ehatp.formats.policy.Policy\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in "
        "('typer', 'click', 'graphviz', 'rich', 'IPython') "
        "or m.startswith(('ehatp.formats.render', 'ehatp.cli', 'ehatp.tools'))))")
    assert out.strip() == "[]"


def test_import_ehatp_loads_no_command_line_and_no_renderer() -> None:
    out = run_python("import sys, ehatp\n"
                     "print(sorted(m for m in sys.modules if m.split('.')[0] in "
                     "('typer', 'graphviz', 'IPython') or m.startswith(('ehatp.formats.render', "
                     "'ehatp.cli', 'ehatp.tools', 'ehatp.run', 'ehatp.experiments'))))")
    assert out.strip() == "[]"


_HELP_RUNNER = """
import json, sys
sys.argv = ["ehatp", *{args!r}]
from ehatp.cli.app import main
try:
    main()
except SystemExit:
    pass
sys.stdout = sys.__stdout__
print("\\n" + json.dumps(sorted(sys.modules)))
"""


def modules_after(*args: str) -> set[str]:
    out = run_python(_HELP_RUNNER.format(args=list(args)))
    return set(json.loads(out.strip().splitlines()[-1]))


def _third_party(mods: set[str]) -> set[str]:
    tops = {m.split(".")[0] for m in mods}
    return {t for t in tops if t not in sys.stdlib_module_names and not t.startswith("_")}


def test_ehatp_help_imports_no_command() -> None:
    """``ehatp --help`` costs ``import ehatp`` and typer: the command line's own three modules
    (the backstop's is light: it imports nothing until armed), and none of a command's (they
    are listed from ehatp.cli.app.COMMANDS)."""
    after_help = modules_after("--help")
    base = set(json.loads(run_python(
        "import json, sys, ehatp, typer.main, typer.rich_utils\n"
        "print(json.dumps(sorted(sys.modules)))").strip()))
    ours = sorted(m for m in after_help - base if m.startswith("ehatp"))
    assert ours == ["ehatp.cli", "ehatp.cli.app", "ehatp.cli.common", "ehatp.cli.limits",
                    "ehatp.formats.policy_check", "ehatp.formats.schema"], ours
    assert _third_party(after_help) <= _third_party(base), _third_party(after_help - base)


def test_a_command_imports_its_own_module_only() -> None:
    after = modules_after("validate", "--help")
    assert "ehatp.cli.validate" in after
    assert not any(m.startswith(("ehatp.cli.solve", "ehatp.cli.sweep", "ehatp.cli.render",
                                 "ehatp.experiments", "ehatp.formats.render")) for m in after)


def test_every_command_is_one_module_listed_with_its_own_help() -> None:
    """One registration convention: each module under ehatp.cli that defines a command makes
    its app with command_app() and is listed in COMMANDS with the first paragraph of its
    help, word for word (that is what `ehatp --help` shows before importing it)."""
    import typer

    from ehatp.cli.app import COMMANDS, load_command

    command_modules = {p.stem for p in (PACKAGE / "cli").glob("*.py")} - {
        "__init__", "__main__", "app", "common", "limits"}  # the commands' shared modules
    assert {e.module for e in COMMANDS.values()} == command_modules
    for name, entry in COMMANDS.items():
        command = load_command(name)
        assert command.name == name
        first = inspect.cleandoc(command.help or "").split("\n\n")[0].replace("\n", " ")
        assert entry.help == first, name
        module = sys.modules[f"ehatp.cli.{entry.module}"]
        assert isinstance(module.app, typer.Typer)
        assert module.app.rich_markup_mode == "markdown" and not module.app._add_completion


# --- notebooks -------------------------------------------------------------------------------


def test_a_policy_shows_itself_as_the_explorer_in_ipython() -> None:
    """Inside IPython, ``import ehatp`` registers an HTML formatter for Policy by name (nothing
    is imported for it until a policy is shown); the HTML is the explorer in an iframe."""
    code = """
import sys, types
registered = []
class Formatter:
    def for_type_by_name(self, module, name, func):
        registered.append((module, name, func))
shell = types.SimpleNamespace(display_formatter=types.SimpleNamespace(
    formatters={"text/html": Formatter()}))
fake = types.ModuleType("IPython")
fake.get_ipython = lambda: shell
sys.modules["IPython"] = fake
import ehatp
(module, name, show), = registered
assert (module, name) == ("ehatp.formats.policy", "Policy"), registered
assert "ehatp.formats.render" not in sys.modules
p = ehatp.solve(ehatp.load("examples/cubes/p1.toml")).policy
html = show(p)
assert html == ehatp.explore(p)._repr_html_()
print(html[:7], "typer" in sys.modules)
"""
    assert run_python(code).split() == ["<iframe", "False"]


def test_the_explorer_in_a_notebook_is_sandboxed_and_escaped() -> None:
    import ehatp
    from ehatp.formats.render import notebook_html

    policy = ehatp.solve(ehatp.load(ROOT / "examples" / "cubes" / "p1.toml")).policy
    assert policy is not None
    html = ehatp.explore(policy)._repr_html_()
    assert html == notebook_html(policy)
    assert html.startswith("<iframe") and html.rstrip().endswith("</iframe>")
    assert 'sandbox="allow-scripts"' in html and "<script" not in html
    assert "&lt;script" in html


# --- the old paths ---------------------------------------------------------------------------


OLD_PATHS = sorted(["ehatp.policy_format", *(
    f"ehatp.tools.{p.stem}" for p in (PACKAGE / "tools").glob("*.py") if p.stem != "__init__")])


def test_no_module_imports_an_old_path() -> None:
    g = import_graph()
    old = {*OLD_PATHS, "ehatp.tools"}
    assert sorted(f"{m} -> {n}" for m, deps in g.items() if m not in old
                  for n in deps & old) == []


@pytest.mark.parametrize("old", OLD_PATHS)
def test_an_old_path_warns_and_stands_for_its_new_home(old: str) -> None:
    code = f"""
import warnings
import ehatp
warnings.filterwarnings("error", "{old} is deprecated", DeprecationWarning)
try:
    import {old}
except DeprecationWarning as e:
    print(e)
"""
    line = run_python(code).strip()
    assert re.fullmatch(rf"{re.escape(old)} is deprecated and goes in the next release: "
                        r"import ehatp\.\w+\.\w+.* instead", line), line


def test_old_names_are_the_new_objects() -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        from ehatp.formats.policy import Policy
        from ehatp.policy_format import Policy as OldPolicy
        from ehatp.run.executor import Executor
        from ehatp.tools import cli, render
        from ehatp.tools.executor import Executor as OldExecutor
    assert OldPolicy is Policy and OldExecutor is Executor
    from ehatp.cli import app, solve
    from ehatp.formats import render as new_render

    assert cli.app is app.app and cli.solve is solve.solve  # what tests patch
    assert render.render is new_render.render
    assert (Path(render.__file__).parent / "explorer" / "explorer.html").is_file()


def test_no_benchmark_script_shadows_a_standard_library_module() -> None:
    """A script runs with its own folder first on ``sys.path``: ``benchmarks/concurrent.py``
    once hid ``concurrent.futures`` from every other script there."""
    import sys

    scripts = {p.stem for p in (PACKAGE.parent.parent / "benchmarks").glob("*.py")}
    assert scripts and not scripts & set(sys.stdlib_module_names), scripts & set(
        sys.stdlib_module_names)
