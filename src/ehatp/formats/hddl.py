"""Import an HTN domain and problem written in HDDL (the format of the IPC 2020 HTN track) as
one agent's task model (docs/hddl.md).

HDDL says nothing about a second agent, what the human perceives or when the two are together;
a small *sidecar* (TOML, or Python) says it. The result is readable data: a Python domain module
(``@domain_factory def make_domain()``, the same statements a person would write) and a problem
TOML, or the :class:`~ehatp.Domain` and :class:`~ehatp.Problem` in memory::

    imported = import_hddl("domain.hddl", "p01.hddl", agent="robot")
    problem = imported.problem()          # the HDDL agent's agenda; the other's empty
    imported.write("transport.py")        # transport.py and transport.toml

Reading HDDL needs the optional dependency ``unified-planning`` (``pip install
'ehatp[hddl]'``), whose :class:`PDDLReader` parses it. What ehatp cannot express is refused
with one line naming it (:class:`HddlUnsupported`): numeric fluents, numeric conditions or
effects, temporal constraints between subtasks, anything that is not a boolean formula. The
sidecar is read by :mod:`ehatp.formats.hddl_sidecar`.
"""

from __future__ import annotations

import importlib.util
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import HddlMissing, HddlUnsupported, control_char
from ..model.domain import Domain
from ..model.problem import BeliefWorld, Limits, Problem
from .hddl_sidecar import AGENTS, Sidecar, check_metrics, literal, read_sidecar
from .hddl_source import _call, _ident, _isort, _Names, _py, _q

if TYPE_CHECKING:  # unified-planning is optional (ehatp[hddl])
    from unified_planning.model import FNode


# --- the converter ---------------------------------------------------------------------------


@dataclass
class Imported:
    """An HDDL domain and problem as ehatp sees them: the module's text, and the problem's
    data. :meth:`domain` and :meth:`problem` build them in memory; :meth:`write` writes the
    module and the problem TOML."""

    name: str  # the HDDL domain's
    agent: str
    source: str  # the domain module
    objects: dict[str, list[str]]
    init: list[str]
    agenda: list[str]  # the HDDL agent's
    other_agenda: list[str]
    goal: list[str]  # literals; a goal that is not a conjunction of literals is in the module
    sidecar: Sidecar
    notes: list[str] = field(default_factory=list)  # what the import changed, one line each
    module_file: str = "domain.py"
    problem_name: str = ""  # default: domain/problem file stem

    def domain(self, module_path: str | Path | None = None) -> Domain:
        """Run the module's ``make_domain()`` (``module_path``: where it would be, for a
        Python sidecar's relative path; default beside the sidecar)."""
        where = Path(module_path or self._default_path())
        ns: dict[str, Any] = {"__name__": f"ehatp_hddl_{_ident(self.name)}",
                              "__file__": str(where)}
        exec(compile(self._text(where), str(where), "exec"), ns)  # noqa: S102 - our own text
        d = ns["make_domain"]()
        assert isinstance(d, Domain)
        return d

    def _text(self, module: Path) -> str:
        """The module's text as it is at ``module``: a Python sidecar named by its path
        relative to the module's folder."""
        if self.sidecar.customize is None:
            return self.source
        rel = os.path.relpath(self.sidecar.customize, module.resolve().parent)
        return self.source.replace(_SIDE_MARK, _q(Path(rel).as_posix()))

    def _default_path(self) -> Path:
        base = self.sidecar.customize.parent if self.sidecar.customize else Path.cwd()
        return base / self.module_file

    def problem(self, domain: Domain | None = None) -> Problem:
        """The problem in memory: the HDDL agent's agenda, the other's from the sidecar."""
        d = domain or self.domain()
        from ..model.problem import parse_call  # one reader for task calls and atoms

        def calls(xs: Iterable[str]) -> tuple[tuple[str, tuple[str, ...]], ...]:
            out = []
            for x in xs:
                c = parse_call(x)
                assert c is not None, x
                out.append(c)
            return tuple(out)

        mine, other = tuple(self.agenda), tuple(self.other_agenda)
        robot, human = (mine, other) if self.agent == "robot" else (other, mine)
        side = self.sidecar.problem
        lim = self.sidecar.limits
        limits = Limits(**{k: v for k, v in lim.items() if k != "max_memory"})
        return Problem(
            name=str(side.get("name", self.problem_name or self.name)), domain=d,
            objects=dict(self.objects),
            init=frozenset(calls(self.init)), robot_agenda=calls(robot),
            human_agenda=calls(human), beliefs=(self._belief(),),
            starts=str(side.get("starts", self.agent)), K=int(side.get("K", 2)),
            limits=limits, description=str(side.get("description", "")),
            goal=tuple((not g.startswith("not "), calls([g.removeprefix("not ")])[0])
                       for g in self.goal),
            source=f"<hddl {self.name}>")

    def _belief(self) -> BeliefWorld:
        """The world the human starts in: the truth, and the robot's own agenda, or none
        when it expects nothing of the robot (``[other] expects``)."""
        return BeliefWorld(robot_agenda=() if self.sidecar.expects == "nothing" else None)

    def problem_toml(self, module_file: str | None = None) -> str:
        """The problem file naming ``module_file`` (beside it) as its domain."""
        side = self.sidecar.problem
        mine = self.agenda
        robot, human = (mine, self.other_agenda) if self.agent == "robot" else (
            self.other_agenda, mine)

        def arr(xs: Sequence[str], indent: str = "  ") -> str:
            if not xs:
                return "[]"
            return "[\n" + "".join(f"{indent}{_q(x)},\n" for x in xs) + "]"

        lines = [f"# Generated by `ehatp import-hddl` from HDDL ({self.agent}: the HDDL model)."]
        if self.notes:
            lines += [f"# {' '.join(n.split())}" for n in self.notes]  # one line each
        if self.goal:
            lines.append(f"goal = {arr(self.goal)}")
        lines += ["", "[problem]",
                  f"name = {_q(str(side.get('name', self.problem_name or self.name)))}"]
        if "description" in side:
            lines.append(f"description = {_q(str(side['description']))}")
        lines += [f"starts = {_q(str(side.get('starts', self.agent)))}",
                  f"K = {int(side.get('K', 2))}", "", "[domain]",
                  f"name = {_q((module_file or self.module_file) + ':make_domain')}", "",
                  "[objects]"]
        lines += [f"{_q(t)} = {arr(os_)}" for t, os_ in sorted(self.objects.items()) if os_]
        lines += ["", "[init]", f"true = {arr(self.init)}", "", "[agenda]",
                  f"robot = {arr(robot)}", f"human = {arr(human)}"]
        if self.sidecar.expects == "nothing":
            lines += ["", "[[beliefs.world]]  # the human expects nothing of the robot",
                      "robot_agenda = []"]
        if self.sidecar.limits:
            lines += ["", "[limits]"]
            for k, v in sorted(self.sidecar.limits.items()):
                lines.append(f"{k} = {_q(v) if isinstance(v, str) else v}")
        return "\n".join(lines) + "\n"

    def write(self, module: str | Path, problem: str | Path | None = None) -> tuple[Path, Path]:
        """Write the domain module and, beside it (default: same name, ``.toml``), the
        problem. A Python sidecar is referred to by its path relative to the module."""
        mod = Path(module)
        prob = Path(problem) if problem is not None else mod.with_suffix(".toml")
        mod.write_text(self._text(mod), encoding="utf-8")
        rel_mod = os.path.relpath(mod.resolve(), prob.resolve().parent)
        prob.write_text(self.problem_toml(Path(rel_mod).as_posix()), encoding="utf-8")
        return mod, prob


_SIDE_MARK = "__SIDECAR_PATH__"


def run_sidecar(d: Domain, module_file: str, relative: str) -> None:
    """Run ``customize(d)`` of the Python sidecar at ``relative`` (to the module's folder)."""
    path = Path(module_file).resolve().parent / relative
    spec = importlib.util.spec_from_file_location(f"_ehatp_sidecar_{abs(hash(path))}", path)
    if spec is None or spec.loader is None:
        raise HddlUnsupported(f"{path}: cannot load the Python sidecar")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.customize(d)


def import_hddl(domain_file: str | Path, problem_file: str | Path, *, agent: str = "robot",
                sidecar: Sidecar | str | Path | None = None,
                module_file: str | None = None) -> Imported:
    """Read ``domain_file`` and ``problem_file`` (HDDL) as the HTN of ``agent`` ("robot" or
    "human"). Raise :class:`HddlUnsupported` (one line) when they use something ehatp
    cannot express, :class:`HddlMissing` without unified-planning."""
    if agent not in AGENTS:
        raise HddlUnsupported(f"--agent {agent!r}: use robot or human")
    side = sidecar if isinstance(sidecar, Sidecar) else read_sidecar(sidecar)
    try:
        from unified_planning.io import PDDLReader
    except ImportError:
        raise HddlMissing("reading HDDL needs unified-planning: pip install 'ehatp[hddl]'"
                          ) from None
    try:
        up_problem = PDDLReader().parse_problem(str(domain_file), str(problem_file))
    except Exception as e:  # noqa: BLE001 - the reader's own errors are many and untyped
        raise _unreadable(PDDLReader, e, domain_file, problem_file) from None
    _printable_names(up_problem, domain_file)
    name = _domain_name(domain_file)
    module = module_file or f"{_ident(name)}.py"
    imported = _Converter(up_problem, agent, side, name, module, domain_file).run()
    imported.problem_name = f"{name}/{Path(problem_file).name.removesuffix('.hddl')}"
    return imported


def _unreadable(reader: Any, e: Exception, domain_file: str | Path,
                problem_file: str | Path) -> HddlUnsupported:
    """Return the one-line error for HDDL unified-planning cannot read: at the file that fails
    (the domain read alone tells which one), with the line and column of a parse error."""
    where: str | Path = problem_file
    try:
        reader().parse_problem(str(domain_file))
    except Exception as alone:  # noqa: BLE001 - as above
        where, e = domain_file, alone
    first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
    at = re.search(r"\(line:(\d+), col:(\d+)\)", first)
    if at:
        where = f"{where}:{at.group(1)}:{at.group(2)}"
        first = first[:at.start()].rstrip(" ,")
    return HddlUnsupported(f"{where}: unified-planning cannot read it ({type(e).__name__}: "
                           f"{first}); see docs/hddl.md for the HDDL ehatp reads")


def _printable_names(p: Any, where: str | Path) -> None:
    """Refuse a name of the HDDL files that holds a control character (ESC included): the
    names reach a terminal and the files ehatp writes."""
    named = [p, *p.user_types, *p.fluents, *p.actions, *p.all_objects,
             *getattr(p, "tasks", ()), *getattr(p, "methods", ())]
    for x in named:
        name = str(getattr(x, "name", ""))
        if (ch := control_char(name)) is not None:
            raise HddlUnsupported(f"{where}: the name {name!r} holds the control character "
                                  f"{ch!r}; rename it with letters, digits, - and _")


def _domain_name(path: str | Path) -> str:
    """The name after ``(define (domain``, else the file's folder."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError:
        text = ""
    m = re.search(r"\(\s*define\s*\(\s*domain\s+([^\s()]+)", text, re.IGNORECASE)
    name = m.group(1) if m else Path(path).parent.name or "hddl"
    return re.sub(r"[^\w\-]", "_", name) or "hddl"


class _Converter:
    def __init__(self, p: Any, agent: str, side: Sidecar, name: str, module_file: str,
                 domain_file: str | Path) -> None:
        self.p = p
        self.domain_file = domain_file
        self.agent = agent
        self.side = side
        self.name = name
        self.module_file = module_file
        self.names = _Names()
        self.vars: dict[tuple[str, str], str] = {}  # (name, type) -> identifier
        self.action_env: dict[str, dict[str, str]] = {}  # action -> its parameters' idents
        self.lines: list[str] = []
        self.notes: list[str] = []

    # -- helpers --
    def unsupported(self, what: str, place: str | Path | None = None) -> HddlUnsupported:
        """Return the one-line error for ``what`` ehatp cannot express, at ``place`` (by
        default the domain file)."""
        return HddlUnsupported(f"{place or self.domain_file}: {what}")

    def var(self, name: str, type_: str) -> str:
        key = (name, type_)
        v = self.vars.get(key)
        if v is None:
            v = self.vars[key] = self.names.get("var", f"{name}:{type_}", hint=type_,
                                                base=name)
        return v

    def tname(self, t: Any) -> str:
        """A UP type as the ehatp type name (HDDL's own name)."""
        if not t.is_user_type():
            raise self.unsupported(f"a parameter of type {t} (only object types map)")
        return str(t.name)

    # -- formulas --
    def expr(self, f: FNode, env: Mapping[str, str]) -> str:
        """A UP boolean expression as Python source over the module's names; ``env`` maps
        parameter and variable names to identifiers."""
        if f.is_bool_constant():
            return "TRUE" if f.bool_constant_value() else "FALSE"
        if f.is_fluent_exp():
            fl = f.fluent()
            if not fl.type.is_bool_type():
                raise self.unsupported(f"numeric fluent {fl.name} in a condition")
            return _py(self.names.get("pred", fl.name), [self.term(a, env) for a in f.args])
        if f.is_not():
            return f"~{self.atomic(f.args[0], env)}"
        if f.is_and() or f.is_or():
            if not f.args:
                return "TRUE" if f.is_and() else "FALSE"
            if len(f.args) == 1:
                return self.expr(f.args[0], env)
            op = " & " if f.is_and() else " | "
            return op.join(self.atomic(a, env) for a in f.args)
        if f.is_implies():
            return f"{self.atomic(f.args[0], env)} >> {self.atomic(f.args[1], env)}"
        if f.is_iff():
            a, b = self.atomic(f.args[0], env), self.atomic(f.args[1], env)
            return f"({a} >> {b}) & ({b} >> {a})"
        if f.is_equals():
            a, b = f.args
            if not (a.type.is_user_type() and b.type.is_user_type()):
                raise self.unsupported(f"a numeric comparison ({f})")
            return f"eq({self.term(a, env)}, {self.term(b, env)})"
        if f.is_exists() or f.is_forall():
            inner = dict(env)
            vs = []
            for v in f.variables():
                inner[v.name] = self.var(v.name, self.tname(v.type))
                vs.append(inner[v.name])
            q = "exists" if f.is_exists() else "forall"
            return f"{q}([{', '.join(vs)}], {self.expr(f.args[0], inner)})"
        raise self.unsupported(f"a condition of kind {f.node_type.name.lower()} ({f})")

    def atomic(self, f: FNode, env: Mapping[str, str]) -> str:
        s = self.expr(f, env)
        simple = f.is_fluent_exp() or f.is_bool_constant() or f.is_equals() or f.is_not() or (
            (f.is_and() or f.is_or()) and len(f.args) <= 1) or f.is_exists() or f.is_forall()
        return s if simple else f"({s})"

    def term(self, a: FNode, env: Mapping[str, str]) -> str:
        if a.is_parameter_exp():
            return env[a.parameter().name]
        if a.is_variable_exp():
            return env[a.variable().name]
        if a.is_object_exp():
            return _q(a.object().name)
        raise self.unsupported(f"an argument {a} that is not an object or a parameter")

    def effects(self, effs: Iterable[Any], env: Mapping[str, str]) -> list[str]:
        out = []
        for e in effs:
            if e.is_increase() or e.is_decrease() or not e.value.is_bool_constant():
                raise self.unsupported(f"a numeric effect ({e})")
            inner = dict(env)
            vs = []
            for v in e.forall:
                inner[v.name] = self.var(v.name, self.tname(v.type))
                vs.append(inner[v.name])
            atom = self.expr(e.fluent, inner)
            s = atom if e.value.bool_constant_value() else f"~{atom}"
            if e.is_conditional():
                s = f"when({self.expr(e.condition, inner)}, {s})"
            if vs:
                s = f"for_each([{', '.join(vs)}], {s})"
            out.append(s)
        return out

    # -- the parts --
    def run(self) -> Imported:
        p, side = self.p, self.side
        for f in p.fluents:
            if not f.type.is_bool_type():
                raise self.unsupported(f"numeric fluent {f.name} (ehatp states are sets of "
                                       "true atoms)")
        for q in getattr(p, "quality_metrics", []):
            if type(q).__name__ not in ("MinimizeActionCosts", "MinimizeSequentialPlanLength"):
                raise self.unsupported(f"the metric {type(q).__name__}")
        objects: dict[str, list[str]] = {}
        for o in p.all_objects:
            objects.setdefault(self.tname(o.type), []).append(o.name)
        taken = {o.name for o in p.all_objects}
        for a in (side.robot, side.human):
            if a in taken:
                raise self.unsupported(f"an object is named {a!r} like an agent; name the "
                                       "agents otherwise in the sidecar ([agents])")
        L = self.lines
        model = "d.robot" if self.agent == "robot" else "d.human"
        L += [f"    d = Domain({_q(self.name)}, robot={_q(side.robot)}, human={_q(side.human)})",
              "", "    # types (HDDL's hierarchy)"]
        self.types()
        L += ["", "    # parameters and quantified variables"]
        var_at = len(L)
        L += ["", "    # predicates: what the human perceives of each (the sidecar, else "
              f"{side.default})"]
        self.predicates()
        if side.copresence:
            L += ["", "    # the agents are together when (the sidecar)",
                  f"    d.copresence = {self.ground_lits(side.copresence, 'copresence')}"]
        else:
            L += ["", "    # always together (no [copresence] in the sidecar)"]
        L += ["", f"    # {self.agent}: actions", f"    m = {model}"]
        unknown = sorted(set(side.resources) - {a.name for a in p.actions})
        if unknown:
            raise self.unsupported(f"[resources] names {unknown[0]!r}, which is not an action "
                                   "of the domain", side.source)
        cost = self.costs()
        for a in sorted(p.actions, key=lambda a: a.name):
            self.action(a, cost.get(a.name, 1))
        L += ["", f"    # {self.agent}: tasks"]
        for t in sorted(p.tasks, key=lambda t: t.name):
            params = [self.var(x.name, self.tname(x.type)) for x in t.parameters]
            L.append(f"    {self.names.get('task', t.name)} = m.task("
                     f"{', '.join([_q(t.name), *params])})")
        agenda = self.initial_network()
        L += ["", f"    # {self.agent}: methods"]
        for me in sorted(p.methods, key=lambda me: (me.achieved_task.task.name, me.name)):
            self.method(me)
        if agenda is None:  # the initial task network became the task "top"
            agenda = [self.top_name]
        if side.other == "same":
            other = "human" if self.agent == "robot" else "robot"
            L += ["", f"    # {other}: the same model (the sidecar)",
                  f"    d.{other} = {model}.copy(d.{other}_name)"]
        if side.expects == "nothing":
            if self.agent != "robot":
                raise HddlUnsupported(f"{side.source}: [other] expects is what the human "
                                      "expects of the robot; import the robot's model to use it")
            L += ["", "    # the human expects nothing of the robot (the sidecar): it sees what "
                  "the robot does,", "    # and follows no plan of it",
                  "    d.robot_seen_by_human = AgentModel(d.robot_name)"]
        if side.metrics:
            L += ["", "    # metrics a preference profile may name (the sidecar)"]
            self.metrics()
        goal = self.goal()
        if side.customize is not None:
            L += ["", "    # the Python sidecar's customize(d)",
                  f"    run_sidecar(d, __file__, {_SIDE_MARK})"]
        L += ["    return d"]
        decls = [f"    {ident} = Var({_q(n)}, {self.names.get('type', t)})"
                 for (n, t), ident in sorted(self.vars.items(), key=lambda kv: kv[1])]
        L[var_at:var_at] = decls
        self.drop_unused()
        source = self.header() + "\n".join(L) + "\n"
        init = sorted(_call(f.fluent().name, [a.object().name for a in f.args])
                      for f, v in p.explicit_initial_values.items()
                      if v.is_bool_constant() and v.bool_constant_value())
        other_agenda = list(side.other_agenda)
        return Imported(self.name, self.agent, source, objects, init, agenda, other_agenda,
                        goal, side, self.notes, self.module_file)

    def drop_unused(self) -> None:
        """``x = d.type(...)`` for an ``x`` nothing else uses becomes ``d.type(...)``: the
        module reads cleanly (and passes a linter)."""
        body = "\n".join(self.lines)
        for k, ln in enumerate(self.lines):
            m = re.match(r"^    (\w+) = (?!Var\()", ln)
            if m and m.group(1) != "d" and m.group(1) != "m" and len(
                    re.findall(rf"\b{m.group(1)}\b", body)) == 1:
                self.lines[k] = "    " + ln[m.end():]
        if not any(re.search(r"\bm\.", ln) for ln in self.lines):
            self.lines[:] = [ln for ln in self.lines if not re.match(r"^    m = ", ln)]

    def header(self) -> str:
        imports = ["Domain", "Var", "domain_factory"]
        body = "\n".join(ln.split("#")[0] for ln in self.lines)  # code, not comments
        for name in ("TRUE", "FALSE", "eq", "exists", "forall", "when", "for_each",
                     "observable", "HIDDEN", "INFERABLE", "AgentModel"):
            if re.search(rf"\b{name}\b", body):
                imports.append(name)
        lines = [f'"""The HDDL domain {self.name} as ehatp data (generated by `ehatp import-hddl`;',
                 f'the HDDL model is the {self.agent}\'s, docs/hddl.md)."""', "",
                 "from __future__ import annotations", "",
                 f"from ehatp import {', '.join(sorted(imports, key=_isort))}"]
        if "run_sidecar" in body:
            lines.append("from ehatp.formats.hddl import run_sidecar")
        return "\n".join(lines) + "\n\n\n@domain_factory\ndef make_domain() -> Domain:\n"

    def types(self) -> None:
        ts = {t.name: t for t in self.p.user_types}
        done: set[str] = set()

        def emit(n: str) -> None:
            if n in done:
                return
            t = ts[n]
            father = t.father.name if t.father is not None else None
            if father is not None:
                emit(father)
            done.add(n)
            ident = self.names.get("type", n)
            parent = f", parent={self.names.get('type', father)}" if father else ""
            self.lines.append(f"    {ident} = d.type({_q(n)}{parent})")

        if "agent" in ts:
            raise self.unsupported("a type named agent (ehatp's own type of R and H)")
        for n in sorted(ts):
            emit(n)

    def predicates(self) -> None:
        side = self.side
        known = {f.name for f in self.p.fluents}
        for what in (*side.classes, *side.when):
            if what not in known:
                raise self.unsupported(f"[observability] names {what!r}, not a predicate of "
                                       f"the domain ({', '.join(sorted(known))})", side.source)
        for f in self.visibility_order():
            params = [self.var(x.name, self.tname(x.type)) for x in f.signature]
            env = {x.name: v for x, v in zip(f.signature, params, strict=True)}
            cls = side.classes.get(f.name, side.default)
            obs = ""
            if f.name in side.when:
                obs = f", observability=observable({self.lits(side.when[f.name], env, f.name)})"
            elif cls != "observable":
                obs = f", observability={cls.upper()}"
            self.lines.append(f"    {self.names.get('pred', f.name)} = d.predicate("
                              f"{', '.join([_q(f.name), *params])}{obs})")

    def visibility_order(self) -> list[Any]:
        """The predicates by name, each after those its visibility condition reads."""
        fl = {f.name: f for f in self.p.fluents}
        reads = {n: {literal(t, n)[1] for t in self.side.when.get(n, [])} - {"="}
                 for n in fl}
        out: list[Any] = []
        state: dict[str, int] = {}

        def visit(n: str, path: list[str]) -> None:
            if state.get(n) == 2:
                return
            if state.get(n) == 1:
                raise self.unsupported(f"[observability.when] {' -> '.join([*path, n])}: a "
                                       "visibility condition cannot read its own predicate",
                                       self.side.source)
            state[n] = 1
            for r in sorted(reads[n] & set(fl)):
                visit(r, [*path, n])
            state[n] = 2
            out.append(fl[n])

        for n in sorted(fl):
            visit(n, [])
        return out

    def lits(self, texts: Sequence[str], env: Mapping[str, str], where: str) -> str:
        known = {f.name: f for f in self.p.fluents}
        parts = []
        for text in texts:
            pos, pred, args = literal(text, f"{self.side.source}: {where}")
            if pred != "=" and pred not in known:
                raise self.unsupported(f"{where}: {pred!r} is not a predicate of the domain",
                                       self.side.source)
            terms = []
            for a in args:
                if a.startswith("?"):
                    if a[1:] not in env:
                        raise self.unsupported(f"{where}: {a} is not a parameter of {where}",
                                               self.side.source)
                    terms.append(env[a[1:]])
                else:
                    terms.append(_q(a))
            atom = (f"eq({terms[0]}, {terms[1]})" if pred == "="
                    else _py(self.names.get("pred", pred), terms))
            parts.append(atom if pos else f"~{atom}")
        return " & ".join(parts) if parts else "TRUE"

    def ground_lits(self, texts: Sequence[str], where: str) -> str:
        return self.lits(texts, {}, where)

    def costs(self) -> dict[str, int | float]:
        out: dict[str, int | float] = {}
        for q in getattr(self.p, "quality_metrics", []):
            for a, c in getattr(q, "costs", {}).items():
                if c is None:
                    continue
                if not (c.is_int_constant() or c.is_real_constant()):
                    raise self.unsupported(f"the cost of {a.name} depends on the state ({c})")
                v = c.constant_value()
                if v <= 0:
                    self.notes.append(f"{a.name} costs {v} in HDDL; ehatp costs are positive: 1")
                    v = 1
                out[a.name] = int(v) if float(v).is_integer() else float(v)
        return out

    def action(self, a: Any, cost: int | float) -> None:
        if type(a).__name__ != "InstantaneousAction":
            raise self.unsupported(f"action {a.name} is not instantaneous")
        params = [self.var(x.name, self.tname(x.type)) for x in a.parameters]
        env = {x.name: v for x, v in zip(a.parameters, params, strict=True)}
        pre = self.conj(a.preconditions, env)
        effs = self.effects(a.effects, env)
        args = [_q(a.name), *params]
        if pre and pre != ["TRUE"]:
            args.append(f"pre={' & '.join(pre)}")
        args.append(f"effects=[{', '.join(effs)}]")
        if cost != 1:
            args.append(f"cost={cost}")
        self.action_env[a.name] = env
        held = self.side.resources.get(a.name)
        if held:
            args.append(f"resources=[{', '.join(self.resource(a.name, x, env) for x in held)}]")
        self.lines.append(self.wrap(f"    {self.names.get('task', a.name)} = m.action(", args))

    def metrics(self) -> None:
        """The sidecar's ``[metrics]`` (checked: :func:`~.hddl_sidecar.check_metrics`) as
        ``d.metric(...)`` lines (docs/concurrent.md C11)."""
        check_metrics(self.side, self.agent, self.action_env)
        for name, m in sorted(self.side.metrics.items()):
            args = [_q(name), f"agent={_q(m.agent)}",
                    f"actions=[{', '.join(_q(a) for a in m.actions)}]"]
            if m.when:  # over the parameters the actions share (check_metrics)
                env = self.action_env[m.actions[0]]
                args.append(f"when={self.lits(m.when, env, f'[metrics.{name}]')}")
            if m.doc:
                args.append(f"doc={_q(m.doc)}")
            self.lines.append(self.wrap("    d.metric(", args))

    def resource(self, action: str, x: str, env: dict[str, str]) -> str:
        """A ``[resources]`` entry of the sidecar as the DSL writes it: ``?x`` the action's
        parameter, anything else a name (docs/concurrent.md, C3 c)."""
        if not x.startswith("?"):
            return _q(x)
        if x[1:] not in env:
            raise self.unsupported(f"[resources] {action}: {x} is not a parameter of "
                                   f"{action} ({', '.join('?' + n for n in env) or 'none'})",
                                   self.side.source)
        return env[x[1:]]

    def wrap(self, head: str, args: Sequence[str], tail: str = ")") -> str:
        """``head`` + the arguments, filled into lines of at most 99 characters where they
        fit, continuation lines aligned after the opening parenthesis."""
        pad = " " * len(head)
        lines: list[str] = []
        cur = head
        for k, a in enumerate(args):
            piece = a + ("," if k < len(args) - 1 else tail)
            sep = "" if cur in (head, pad) else " "
            if cur not in (head, pad) and len(cur) + len(sep) + len(piece) > 99:
                lines.append(cur)
                cur, sep = pad, ""
            cur += sep + piece
        lines.append(cur)
        return "\n".join(lines)

    def conj(self, conds: Sequence[FNode], env: Mapping[str, str]) -> list[str]:
        """Conditions to be joined with ``&``: one as it is, several each parenthesised."""
        if len(conds) == 1:
            return [self.expr(conds[0], env)]
        return [self.atomic(c, env) for c in conds]

    def network(self, net: Any, env: dict[str, str], where: str) -> tuple[list[str], str | None]:
        """A task network's subtasks (as calls) and its ``order=`` argument (None: listed)."""
        subs = list(net.subtasks)
        total = net.total_order()
        if total is not None:
            by_id = {s.identifier: s for s in subs}
            subs = [by_id[i] for i in total]
            order = None
        else:
            po = net.partial_order()
            if po is None:
                raise self.unsupported(f"{where}: temporal constraints between subtasks (only "
                                       "orderings map)")
            pos = {s.identifier: k for k, s in enumerate(subs)}
            order = "[" + ", ".join(f"({pos[a]}, {pos[b]})" for a, b in sorted(
                po, key=lambda ab: (pos[ab[0]], pos[ab[1]]))) + "]"
        calls = [_py(self.names.get("task", s.task.name), [self.term(x, env)
                                                               for x in s.parameters])
                 for s in subs]
        return calls, order

    def method(self, me: Any) -> None:
        task = me.achieved_task.task
        where = f"method {me.name}"
        tvars = [self.var(x.name, self.tname(x.type)) for x in task.parameters]
        env: dict[str, str] = {}
        own: list[str] = []
        pre: list[str] = []
        bound: dict[str, int] = {}  # method parameter -> the task position it fills
        for i, x in enumerate(me.achieved_task.parameters):
            bound.setdefault(x.name, i)
        for x in me.parameters:
            t = self.tname(x.type)
            at = bound.get(x.name)
            if at is not None and t == self.tname(task.parameters[at].type):
                env[x.name] = tvars[at]  # the task's own variable
                continue
            v = self.var(x.name, t)
            if v in tvars:  # a free parameter named like another position of the task
                v = self.var(f"{x.name}_", t)
            env[x.name] = v
            own.append(v)
            if at is not None:  # a narrower type than the task's: chosen, and equal to it
                pre.append(f"eq({v}, {tvars[at]})")
        for i, x in enumerate(me.achieved_task.parameters):  # a parameter used twice
            if bound[x.name] != i:
                pre.append(f"eq({env[x.name]}, {tvars[i]})")
        conds = [*me.preconditions, *me.non_temporal_constraints()]
        pre += self.conj(conds, env) if not pre else [self.atomic(c, env) for c in conds]
        calls, order = self.network(me, env, where)
        self.lines.append(self.method_line(self.names.get("task", task.name), me.name, own,
                                           pre, calls, order))

    def method_line(self, task: str, name: str, params: list[str], pre: list[str],
                    calls: list[str], order: object) -> str:
        """One ``m.method(...)`` line of the written module."""
        args = [task, _q(name)]
        if params:
            args.append(f"params=[{', '.join(params)}]")
        if pre:
            args.append(f"pre={' & '.join(pre)}")
        args.append(f"subtasks=[{', '.join(calls)}]")
        if order is not None:
            args.append(f"order={order}")
        return self.wrap("    m.method(", args)

    def initial_network(self) -> list[str] | None:
        """The agenda: the initial task network's calls when totally ordered and ground, else
        None after declaring a task ``top`` whose one method is that network."""
        net = self.p.task_network
        if net.total_order() is not None and not net.variables and not (
                net.non_temporal_constraints()):
            calls, _ = self.network(net, {}, "the initial task network")
            return [self.plain(c) for c in calls]
        names = {t.name for t in self.p.tasks} | {a.name for a in self.p.actions}
        top = "top"
        while top in names:
            top += "_"
        self.top_name = top
        env = {v.name: self.var(v.name, self.tname(v.type)) for v in net.variables}
        calls, order = self.network(net, env, "the initial task network")
        pre = [self.atomic(c, env) for c in net.non_temporal_constraints()]
        ident = self.names.get("task", top)
        self.notes.append(f"the initial task network is the one method of task {top} (it is "
                          + ("partially ordered" if order is not None else "not ground") + ")")
        self.lines += [f"    {ident} = m.task({_q(top)})  # the initial task network",
                       self.method_line(ident, top, list(env.values()), pre, calls, order)]
        return None

    def plain(self, call: str) -> str:
        """A ground call of the module (``get_to("truck-0", "l1")``) as a problem's task call
        (``get-to(truck-0, l1)``)."""
        head, _, rest = call.partition("(")
        name = next(n for (k, n), i in self.names.of.items() if k == "task" and i == head)
        inner = rest[:-1] if rest.endswith(")") else rest
        args = [a.strip().strip('"') for a in inner.split(",")] if inner.strip() else []
        return _call(name, args)

    def goal(self) -> list[str]:
        goals = list(self.p.goals)
        lits: list[str] = []
        rest: list[FNode] = []
        flat: list[FNode] = []
        for g in goals:
            flat.extend(g.args if g.is_and() else [g])
        for g in flat:
            neg = g.is_not()
            a = g.args[0] if neg else g
            if a.is_fluent_exp() and all(x.is_object_exp() for x in a.args):
                atom = _call(a.fluent().name, [x.object().name for x in a.args])
                lits.append(f"not {atom}" if neg else atom)
            elif g.is_bool_constant() and g.bool_constant_value():
                continue
            else:
                rest.append(g)
        if rest:
            self.lines += ["", "    # the problem's goal (not only literals)",
                           f"    d.goal = {' & '.join(self.atomic(g, {}) for g in rest)}"]
        return lits


__all__ = ["HddlMissing", "HddlUnsupported", "Imported", "Sidecar", "import_hddl", "read_sidecar",
           "run_sidecar"]
