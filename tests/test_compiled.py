"""The optional compiled core (docs/compiled.md): built from this checkout's source as a user
builds it (a wheel with the ``mypyc`` build hook enabled), it must give the very policies the
pure Python core gives, and each of them must execute on every branch.

The build takes about two minutes of CPU, so the whole file is ``slow`` (``make test`` and CI
run it) and builds once. It is skipped only where no C compiler or no Python headers exist.
Both cores run in their own fresh process, the compiled one with the installed build first on
``sys.path`` and the pure Python one with this checkout's ``src``, and each reports the files
its modules came from, so a build that silently fell back to the sources fails.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import zipfile
from collections.abc import Iterator
from importlib.machinery import EXTENSION_SUFFIXES
from pathlib import Path
from typing import Any

import pytest

from .conftest import EXAMPLES, ROOT

pytestmark = pytest.mark.slow

# the modules the hook compiles: its include list in pyproject.toml
HOOK = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))[
    "tool"]["hatch"]["build"]["targets"]["wheel"]["hooks"]["mypyc"]
COMPILED = tuple(sorted(".".join(Path(f).with_suffix("").parts[1:]) for f in HOOK["include"]))
RANDOM_SEEDS = range(60)  # about 20 of them have a policy
# Table 1's instances (benchmarks/joint_steps.py), to be solved in joint steps too
TABLE1 = ("cubes/p1", "cubes/p2", "cubes/p3", "cubes/p4", "cubes/p5", "cubes/p6",
          "cooking/cooking1", "cooking/cooking2", "cooking/cooking3")
# joint steps (docs/concurrent.md C4, C8) besides the examples' own: [first, witness]
JOINT = (("human", "whole"), ("robot", "start"))
MAX_STATES = 20_000  # as the agreement benchmark: a random problem past it is left out

# One core's answers, in a fresh process: sys.argv[1] goes first on sys.path; the jobs come on
# stdin. Every policy's JSON is returned whole (statistics included: the same search counts
# the same states) and walked through the Executor on every branch (run/walk.py).
CHILD = r"""
import importlib, json, sys
sys.path.insert(0, sys.argv[1])
import ehatp
from ehatp.experiments import randomgen
from ehatp.run.walk import walk_policy
jobs = json.load(sys.stdin)
out = {"files": {m: importlib.import_module(m).__file__ for m in jobs["modules"]}, "runs": {}}
for label, what, symmetry in jobs["runs"]:
    if isinstance(what, list):  # [path, first, witness]: the problem in joint steps
        import dataclasses
        from ehatp import StepFirst, StepMode, Steps, Witness
        p = dataclasses.replace(ehatp.load(what[0]), steps=Steps(
            StepMode.CONCURRENT, first=StepFirst(what[1]), witness=Witness(what[2])))
    else:
        p = randomgen.problem(what) if isinstance(what, int) else ehatp.load(what)
    kw = ({} if symmetry is None else {"world_classes": True} if symmetry == "classes"
          else {"symmetry": symmetry})
    r = ehatp.solve(p, max_states=jobs["max_states"], timeout=3600, **kw)
    if r.policy is None:
        out["runs"][label] = {"status": r.status, "reason": r.reason}
        continue
    w = walk_policy(p, r.policy, cap=100_000)
    out["runs"][label] = {"status": r.status, "policy": r.policy.to_json(), "walk_ok": w.ok,
                          "branches": w.branches, "capped": w.capped, "message": w.message}
print(json.dumps(out))
"""

# The executor's copies (Executor.copy, which every walk makes at each branch): from each
# problem's start, every branch of its policy played depth first, a copy taken before each
# move; the copy must be of the same class, share the problem, the memo tables and the joint
# steps' settings, hold its own equal copy of what assessment saw, and read the subclass's
# class attribute; each step's explanation (which reads what assessment saw) is returned.
COPIES = r"""
import dataclasses, importlib, json, sys
sys.path.insert(0, sys.argv[1])
import ehatp
from ehatp import StepFirst, StepMode, Steps, Witness
from ehatp.run.executor import Executor
jobs = json.load(sys.stdin)
out = {"file": importlib.import_module("ehatp.epistemic.semantics").__file__, "runs": {}}
for label, path, steps in jobs:
    p = ehatp.load(path)
    if steps:
        p = dataclasses.replace(p, steps=Steps(StepMode.CONCURRENT, first=StepFirst(steps[0]),
                                               witness=Witness(steps[1])))
    start = Executor(p)
    start.replay_opening()
    lines, bad, stack = [], [], [start]
    while stack:
        ex = stack.pop()
        if ex.done:
            lines.append("goal" if ex.goal_reached else "stopped")
            continue
        other = ex.copy()
        a, b = ex.sem, other.sem
        same = {"class": type(b) is type(a), "grounded": b.grounded is a.grounded,
                "memo": b._succ is a._succ,
                "steps": getattr(b, "steps", 0) is getattr(a, "steps", 0),
                "held": getattr(b, "_held", 0) is getattr(a, "_held", 0),
                "seen": b.seen == a.seen and b.seen is not a.seen,
                "passive_carried": b.passive_carried is (not p.steps.concurrent)}
        bad += [f"{label}: {k}" for k, v in same.items() if not v]
        action = other.next_robot_action()
        if action is not None:
            lines += [f"R {action.label}", *other.explain(other.robot_action_done(action.label))]
            stack.append(other)
            continue
        for move in ex.node.moves:
            nxt = ex.copy()
            lines += [f"H {move.action}", *nxt.explain(nxt.observe_human_action(move.action))]
            stack.append(nxt)
    out["runs"][label] = {"lines": lines, "bad": bad, "class": type(start.sem).__name__}
print(json.dumps(out))
"""

# Pickling and deep copies: each kind of formula, and whole problems (which hold formulas),
# pickled and deep-copied; each problem's copies solved to its policy JSON.
PICKLES = r"""
import copy, hashlib, importlib, json, pickle, sys
sys.path.insert(0, sys.argv[1])
import ehatp
from ehatp.experiments import randomgen
from ehatp.model.formula import (FALSE, TRUE, And, Atom, Cmp, Eq, Exists, Forall, GAtom,
                                 GTest, Is, Not, Or, Var)
jobs = json.load(sys.stdin)
out = {"file": importlib.import_module("ehatp.model.formula").__file__, "formulas": [],
       "problems": {}}
x, c = Var("x", "cube"), "c1"
for f in (x, Atom("on", (x, c)), Is("loc", (x, "mt")), Eq(x, c), Cmp("balls", (c,), ">=", 2),
          Not(Atom("p", ())), And((Atom("p", ()), GAtom(3, "q"))), Or((TRUE, FALSE)),
          Exists((x,), Atom("on", (x, c))), Forall((x,), GTest(GAtom(1, "a"), "a"))):
    p, d = pickle.loads(pickle.dumps(f)), copy.deepcopy(f)
    out["formulas"].append([str(f), type(p) is type(f) and p == f,
                            type(d) is type(f) and d == f])
for label, what in jobs:
    p = randomgen.problem(what) if isinstance(what, int) else ehatp.load(what)
    row = []
    for q in (p, pickle.loads(pickle.dumps(p)), copy.deepcopy(p)):
        r = ehatp.solve(q)
        text = r.policy.to_json() if r.policy is not None else r.status
        row.append(hashlib.sha256(text.encode()).hexdigest())
    out["problems"][label] = row
print(json.dumps(out))
"""

WOODWORKING = r"""
import hashlib, json, sys
sys.path.insert(0, sys.argv[1])
from ehatp.experiments.hddl_report import domains_shipped
from ehatp.formats.hddl import import_hddl
from ehatp.formats.hddl_sidecar import Sidecar
from ehatp.search import andor
from ehatp.search.planner import solve
_, dom, prob = next(d for d in domains_shipped() if d[0].endswith("to-Woodworking"))
problem = import_hddl(dom, prob, sidecar=Sidecar(expects="nothing")).problem()
r = solve(problem, timeout=3600)
print(json.dumps({"andor": andor.__file__, "status": r.status, "distinct": r.stats["distinct"],
                  "cost": None if r.policy is None else str(r.policy.cost),
                  "sha256": None if r.policy is None else
                  hashlib.sha256(r.policy.to_json().encode()).hexdigest()}))
"""


def _why_not_buildable() -> str | None:
    """Why a C extension cannot be built here (None: it can)."""
    cc = (sysconfig.get_config_var("CC") or "cc").split()[0]
    if shutil.which(cc) is None and shutil.which("cc") is None:
        return f"no C compiler ({cc}) to build the compiled core"
    headers = Path(sysconfig.get_paths()["include"]) / "Python.h"
    if not headers.exists():
        return f"no Python headers ({headers}) to build the compiled core"
    return None


def _copy_source(dest: Path) -> None:
    """What a source checkout builds a wheel from, without any compiled module left in
    ``src`` by an earlier build (the hook writes them beside the sources)."""
    skip = shutil.ignore_patterns("__pycache__", "*.so", "*.pyd", "*.c", "*.egg-info")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, dest / name)
    for name in ("src", "examples"):
        shutil.copytree(ROOT / name, dest / name, ignore=skip)
    for lic in ROOT.glob("LICENSE*"):
        shutil.copy2(lic, dest / lic.name)


@pytest.fixture(scope="module")
def compiled(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The compiled core, built as docs/compiled.md says and installed into a directory of
    its own (``pip install --no-deps --target``); that directory."""
    why = _why_not_buildable()
    if why is not None:
        pytest.skip(why)
    tmp = tmp_path_factory.mktemp("compiled")
    source, dist, target = tmp / "source", tmp / "dist", tmp / "site"
    source.mkdir()
    _copy_source(source)
    env = {**os.environ, "HATCH_BUILD_HOOK_ENABLE_MYPYC": "true",
           "PIP_DISABLE_PIP_VERSION_CHECK": "1"}
    env.pop("PYTHONPATH", None)
    build = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", str(source), "-w", str(dist)],
        env=env, capture_output=True, text=True)
    assert build.returncode == 0, build.stdout + build.stderr
    wheels = list(dist.glob("ehatp-*.whl"))
    assert len(wheels) == 1, wheels
    # a compiled wheel is tagged for this interpreter and platform, not py3-none-any
    assert "-none-any" not in wheels[0].name, wheels[0].name
    install = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(target),
         str(wheels[0])], env=env, capture_output=True, text=True)
    assert install.returncode == 0, install.stdout + install.stderr
    yield target


def test_a_plain_build_stays_pure_python_beside_a_compiled_one(compiled: Path) -> None:
    """Without the hook enabled the wheel is pure Python (py3-none-any, no extension module),
    even from a source tree where the compiled build left its modules beside the sources."""
    source, dist = compiled.parent / "source", compiled.parent / "dist-pure"
    assert list((source / "src" / "ehatp" / "search").glob("andor.*.so")), "no leftover to test"
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "HATCH_BUILD_HOOK_ENABLE_MYPYC", "HATCH_BUILD_HOOKS_ENABLE")}
    build = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", str(source), "-w", str(dist)],
        env=env, capture_output=True, text=True)
    assert build.returncode == 0, build.stdout + build.stderr
    wheels = list(dist.glob("ehatp-*.whl"))
    assert len(wheels) == 1 and wheels[0].name.endswith("-py3-none-any.whl"), wheels
    with zipfile.ZipFile(wheels[0]) as z:
        names = z.namelist()
    assert "ehatp/search/andor.py" in names
    assert not [n for n in names if n.endswith((".so", ".pyd"))], names


def _script(code: str, path: Path, jobs: Any = None) -> dict[str, Any]:
    """Run ``code`` in a fresh process whose ``sys.path`` starts with ``path`` (its first
    argument), ``jobs`` as JSON on its standard input; the JSON its last line prints."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    r = subprocess.run([sys.executable, "-c", code, str(path)],
                       input=None if jobs is None else json.dumps(jobs),
                       env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    out: dict[str, Any] = json.loads(r.stdout.strip().splitlines()[-1])
    return out


def _both(code: str, compiled: Path, jobs: Any = None) -> tuple[dict[str, Any], dict[str, Any]]:
    """Return what ``code`` (:func:`_script`) answers with the compiled core, then with the
    pure Python core of this checkout."""
    return _script(code, compiled, jobs), _script(code, ROOT / "src", jobs)


def _core(path: Path, runs: list[tuple[str, Any, Any]]) -> dict[str, Any]:
    """Run ``runs`` (label, an example's path or a random seed, symmetry: None, a bool, or
    ``"classes"`` for the worlds kept as classes) in a fresh process whose ``sys.path`` starts
    with ``path``; its answers."""
    return _script(CHILD, path, {"modules": list(COMPILED), "runs": runs,
                                 "max_states": MAX_STATES})


def _is_compiled(file: str) -> bool:
    return any(file.endswith(s) for s in EXTENSION_SUFFIXES)


def test_the_compiled_wheel_holds_an_extension_for_each_module_it_compiles(
        compiled: Path) -> None:
    """The wheel installs an extension module beside each source the hook lists (and the
    ``ehatp --core`` line lists exactly those)."""
    for mod in COMPILED:
        rel = Path(*mod.split("."))
        found = [s for s in EXTENSION_SUFFIXES if (compiled / rel.parent / f"{rel.name}{s}")
                 .exists()]
        assert found, f"no extension module for {mod} in {compiled}"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    code = ("import sys; sys.path.insert(0, sys.argv[1]); sys.argv[1:] = ['--core']\n"
            "from ehatp.cli.app import main; main()")
    r = subprocess.run([sys.executable, "-c", code, str(compiled)], env=env,
                       capture_output=True, text=True)
    assert r.stdout.splitlines() == ["compiled core:", *sorted(COMPILED)], r.stdout + r.stderr


def test_the_compiled_core_writes_the_pure_python_policies_byte_for_byte(
        compiled: Path) -> None:
    """Every example and the first 60 random problems, each with and without the symmetry
    reduction: the compiled core (its modules really the extension ones) solves each to the
    same status and the same policy JSON, statistics included, as the pure Python core, and
    each of its policies executes to the goal on every branch."""
    runs: list[tuple[str, Any, bool | None]] = []
    for e in EXAMPLES:
        runs += [(f"{e.name}", str(e.path), None), (f"{e.name} --no-symmetry", str(e.path), False)]
    runs += [(f"random {seed}{flag}", seed, symmetry) for seed in RANDOM_SEEDS
             for flag, symmetry in (("", None), (" --no-symmetry", False))]
    fast, pure = _core(compiled, runs), _core(ROOT / "src", runs)
    assert all(_is_compiled(f) for f in fast["files"].values()), fast["files"]
    assert not any(_is_compiled(f) for f in pure["files"].values()), pure["files"]
    assert fast["runs"].keys() == pure["runs"].keys()
    solved = 0
    for label, run in fast["runs"].items():
        assert run == pure["runs"][label], label
        if run["status"] == "solved":
            solved += 1
            assert run["walk_ok"] and not run["capped"], (label, run["message"])
            assert run["branches"] >= 1, label
    # every example solves both ways, and about a third of the random problems
    assert solved >= 2 * len(EXAMPLES) + 30, solved


def test_the_compiled_core_keeps_worlds_as_classes_as_pure_python_does(
        compiled: Path, tmp_path: Path) -> None:
    """With the human's worlds kept as classes (docs/semantics.md §3, "Worlds as classes";
    ``search/worldclasses.py`` and ``search/classsemantics.py`` compiled, the container
    ``epistemic/classworlds.py`` a Python class): every example, the first 60 random problems
    and two K=8 grid points give, compiled, the policies pure Python gives with the worlds
    listed, statistics included, and each executes on every branch."""
    from ehatp.experiments.bench import GridPoint

    runs: list[tuple[str, Any, Any]] = [(e.name, str(e.path), "classes") for e in EXAMPLES]
    runs += [(f"random {seed}", seed, "classes") for seed in RANDOM_SEEDS]
    for point in (GridPoint("cubes", 8, 6, 3), GridPoint("cubes", 8, 8, 2)):
        path = tmp_path / f"{point.name}.toml"
        path.write_text(point.toml(), encoding="utf-8")
        runs.append((point.name, str(path), "classes"))
    fast = _core(compiled, runs)
    pure = _core(ROOT / "src", [(label, what, None) for label, what, _ in runs])
    assert all(_is_compiled(f) for f in fast["files"].values()), fast["files"]
    for label, run in fast["runs"].items():
        assert run == pure["runs"][label], label
        if run["status"] == "solved":
            assert run["walk_ok"] and not run["capped"], (label, run["message"])


def _joint_runs() -> list[tuple[str, Any, bool | None]]:
    """Joint steps (docs/concurrent.md): Table 1's instances under each setting of
    :data:`JOINT`, with and without symmetry, and the joint-step examples with the robot
    deciding first (their own files have the human first)."""
    runs: list[tuple[str, Any, bool | None]] = []
    for name in TABLE1:
        path = str(ROOT / "examples" / f"{name}.toml")
        runs += [(f"{name} joint {first}/{witness}{flag}", [path, first, witness], symmetry)
                 for first, witness in JOINT
                 for flag, symmetry in (("", None), (" --no-symmetry", False))]
    for e in EXAMPLES:
        if "concurrent" in e.path.parts:
            runs.append((f"{e.name} joint robot/whole", [str(e.path), "robot", "whole"], None))
    return runs


def test_the_compiled_core_writes_the_pure_python_policies_in_joint_steps(
        compiled: Path) -> None:
    """Joint steps (docs/concurrent.md, C1-C12): ``ConcurrentSemantics``, compiled too,
    subclasses ``Semantics``, overriding methods the compiled ones call, and the executor's
    Python class ``_TracingJoint`` subclasses both it and the tracing semantics. On
    Table 1's instances (human first and whole witnessing; robot first and witnessing at the
    start), with and without symmetry, and on the stacking examples with the robot first, the
    compiled core solves each to the pure Python core's status and policy JSON, and each
    policy executes on every branch. (No joint-step state counts passive moves, so no policy
    depends on the class attribute ``passive_carried`` it overrides: the copies' test reads
    it.)"""
    runs = _joint_runs()
    fast, pure = _core(compiled, runs), _core(ROOT / "src", runs)
    assert all(_is_compiled(f) for f in fast["files"].values()), fast["files"]
    assert fast["runs"].keys() == pure["runs"].keys() == {label for label, _, _ in runs}
    for label, run in fast["runs"].items():
        assert run == pure["runs"][label], label
        assert run["status"] == "solved", (label, run)
        assert run["walk_ok"] and not run["capped"] and run["branches"] >= 1, (label, run)


def test_the_executor_copies_a_compiled_semantics_whole(compiled: Path) -> None:
    """``Executor.copy`` copies the tracing semantics, a Python subclass of the compiled
    ``Semantics`` (of ``ConcurrentSemantics`` too in joint steps): compiled, a plain
    ``copy.copy`` kept only the attributes ``Semantics`` declares and dropped the
    subclass's (the joint steps' settings, what assessment saw). Played on every branch
    from a copy at each move, in turns (Sally-Anne, P3, Cooking 1) and in joint steps (two
    stacking examples, P3 with the robot first), each copy is whole and every step's
    explanation is the pure Python core's, line for line."""
    ex = ROOT / "examples"
    jobs = [("sally-anne", str(ex / "sally-anne/inform.toml"), None),
            ("p3", str(ex / "cubes/p3.toml"), None),
            ("cooking1", str(ex / "cooking/cooking1.toml"), None),
            ("stack4", str(ex / "concurrent/stack4.toml"), None),
            ("stack-prefs", str(ex / "concurrent/stack-prefs.toml"), None),
            ("p3 joint robot/start", str(ex / "cubes/p3.toml"), ["robot", "start"])]
    fast, pure = _both(COPIES, compiled, jobs)
    assert _is_compiled(fast["file"]) and not _is_compiled(pure["file"])
    for label, *_ in jobs:
        assert fast["runs"][label]["bad"] == [], label
        assert fast["runs"][label] == pure["runs"][label], label
        assert "goal" in fast["runs"][label]["lines"], label
    assert fast["runs"]["stack4"]["class"] == "_TracingJoint"


def test_formulas_and_problems_pickle_and_copy_with_the_compiled_core(compiled: Path) -> None:
    """The formulas are frozen dataclasses; compiled, pickle and ``copy.deepcopy`` rebuilt one
    by assigning its fields after creating it, which a frozen class refuses
    (``FrozenInstanceError``), so a problem (which holds its domain's formulas) could not be
    pickled. Each kind of formula comes back equal and of its class, and each problem
    pickled or deep-copied solves to the original's policy JSON, as in pure Python."""
    ex = ROOT / "examples"
    jobs = [("p3", str(ex / "cubes/p3.toml")), ("cooking1", str(ex / "cooking/cooking1.toml")),
            ("stack4", str(ex / "concurrent/stack4.toml")), *[(f"random {s}", s) for s in range(4)]]
    fast, pure = _both(PICKLES, compiled, jobs)
    assert _is_compiled(fast.pop("file")) and not _is_compiled(pure.pop("file"))
    assert fast == pure
    assert len(fast["formulas"]) == 10 and all(p and d for _, p, d in fast["formulas"]), fast
    assert fast["problems"].keys() == {label for label, _ in jobs}
    for label, (original, pickled, copied) in fast["problems"].items():
        assert original == pickled == copied, label


def test_the_compiled_core_solves_ipc_woodworking_as_pure_python_does(compiled: Path) -> None:
    """IPC 2020 to-Woodworking, the robot alone, grounded on demand: a compiled build that
    typed the model's tables ``dict`` skipped the on-demand grounding and answered
    unsolvable after 116,644 states (docs/compiled.md). Both cores must find the same policy
    (cost 13 over 126,569 states, docs/benchmarks.md)."""
    pytest.importorskip("unified_planning", reason="ehatp[hddl] (unified-planning) not installed")
    fast, pure = _both(WOODWORKING, compiled)
    assert _is_compiled(fast.pop("andor")) and not _is_compiled(pure.pop("andor"))
    assert fast == pure
    assert fast["status"] == "solved" and fast["cost"] == "13", fast
