"""Run a policy live over JSON lines (``ehatp execute``, :mod:`ehatp.cli.execute`): the protocol a
robot process speaks with ehatp running as its subprocess.

A robot process (a ROS node, a C++ controller) starts ``ehatp execute PROBLEM --policy P.json``
and talks to it through stdin and stdout, one JSON object a line. In: what the human did
(``{"human": "pick(w)"}``), that the robot is done (``{"robot_done": "pick(r)"}`` or
``{"robot_done": true}``), or that its action failed (``{"robot_failed": "pick(r)"}``: it did
not happen; ``{"robot_failed": {"action": "pick(r)", "observed": [...]}}``: it had another
outcome, the facts observed), and, for a preferences problem, that the human's preferences are
learnt to be another profile (``{"profile": "lazy_human"}``: the kept graph relabelled from the
current state at a step's start, C11: ``{"switched": {...}}``). Out: what the robot should do
(``{"robot": {...}}``), that the human is to act (``{"waiting": {...}}``), what the human now
believes (``{"beliefs": {...}}``), the goal (``{"goal": true, ...}``) and errors (``{"error":
KIND, ...}``), each with its number (``"seq"``: 1, 2, ...). With ``--replan`` a human action the
policy does not cover, but the human model allows, is applied and the robot replans from there
(``{"replanned": {...}}``): a move the model allows, or a ``pass`` the fairness rule lets a
policy leave out (docs/semantics.md §4); only an impossible move is an error. A failed robot
action is always replanned from: from the same state when it did not happen, else after the
robot's action whose outcome the observed facts describe. See ``docs/execution.md``.

Exit codes (:func:`run` returns them): 0 the goal is reached; 1 the input ended before the goal,
or replanning found no policy; 2 a policy that turns out not to fit the problem (a
``policy-mismatch`` line).
"""

from __future__ import annotations

import dataclasses
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from ..epistemic.semantics import Move
from ..errors import ExecutionError, InputError, PolicyMismatch, UncoveredHumanAction
from ..formats.policy import label_key, num
from ..model.options import ObjectiveKind
from ..model.vocabulary import MoveKind
from .executor import Action, Executor, Step

if TYPE_CHECKING:
    from ..search.planner import Relabeler, Result

EXIT_GOAL, EXIT_STOPPED, EXIT_BAD = 0, 1, 2

Emit = Callable[[dict[str, Any]], None]
REQUESTS = ("human", "robot_done", "robot_failed", "profile")
SHOWN = 60  # characters of a bad label an error line repeats in its message
NOTHING = object()  # a failed robot action's outcome: it did not happen


def beliefs(ex: Executor) -> dict[str, Any]:
    """What the human believes now, in the domain's vocabulary: each world as its differences
    from the truth (and the robot agenda the human attributes there), the atoms the worlds
    disagree on, and the human's false beliefs (literals that hold in every world but not in
    reality: ``empty(box1)`` believed but false, ``not in(r, box1)`` when it is true)."""
    views = ex.human_worlds()
    wrong_true = set.intersection(*(set(w.true) for w in views)) if views else set()
    wrong_false = set.intersection(*(set(w.false) for w in views)) if views else set()
    return {"worlds": [{"true": list(w.true), "false": list(w.false),
                        "robot_agenda": list(w.robot_agenda)} for w in views],
            "uncertain": ex.uncertain_atoms(),
            "false": sorted(wrong_true) + [f"not {a}" for a in sorted(wrong_false)]}


def robot_line(a: Action) -> dict[str, Any]:
    return {"action": a.label, "kind": a.kind, "name": a.name, "args": list(a.args),
            "told": list(a.told), "cost": num(a.cost)}


def step_line(ex: Executor, s: Step) -> dict[str, Any]:
    return {"index": s.index, "agent": s.action.agent, "action": s.action.label,
            "cost": num(s.action.cost), "node": None if s.node is None else s.node.id,
            "total": num(ex.cost)}


class Session:
    """One execution driven by JSON lines; :meth:`handle` answers one input line."""

    def __init__(self, ex: Executor, emit: Emit, *, replan: bool,
                 save: Path | None = None, timeout: float | None = None,
                 max_memory: int | None = None,
                 timing: dict[str, float | None] | None = None,
                 graph: Relabeler | None = None, relabel: bool = True) -> None:
        self.ex, self.out, self.replan, self.save = ex, emit, replan, save
        # a preferences problem (C11): the explored graph kept, for {"profile": NAME} lines;
        # each replan keeps its own (it holds the states the execution now reaches), unless
        # relabelling is off (`ehatp execute --no-keep-graph`)
        self.graph = graph
        self.relabel = relabel
        # joint steps: the step's timing the waiting lines carry (docs/execution.md)
        self.timing = timing or {"decision_timeout": None, "recognition_latency": None}
        # each replan's limits (None: the problem's [limits])
        self.limits: dict[str, Any] = {"timeout": timeout, "max_memory": max_memory}
        self.exit: int | None = None  # set when the session is over
        self.replans = 0
        self.switches = 0  # profile switches so far
        self.seq = 0  # output lines so far

    def emit(self, message: dict[str, Any]) -> None:
        """Write ``message`` as the next output line, numbered last (``"seq"``: 1, 2, ...), so
        that a reader that names a line by its first key still can."""
        self.seq += 1
        self.out({**message, "seq": self.seq})

    def start(self, source: str) -> None:
        ex = self.ex
        opening = ex.replay_opening()
        p = ex.policy
        self.emit({"start": {
            "problem": ex.problem.name, "domain": ex.problem.domain.name,
            "robot": ex.robot_name, "human": ex.human_name, "policy": source,
            "cost": num(p.cost), "nodes": len(p.nodes), "replan": self.replan,
            "opening": [s.played for s in opening]}})
        self.emit({"beliefs": beliefs(ex)})
        self.prompt()

    def prompt(self) -> None:
        """The last line of every answer that moved the execution: what happens next."""
        ex = self.ex
        if ex.done:
            if ex.goal_reached:
                self.emit({"goal": True, "steps": len(ex.history), "cost": num(ex.cost)})
                self.exit = EXIT_GOAL
            else:
                self.emit({"error": "dead-end", "message": "the policy ended without reaching "
                           "the goal"})
                self.exit = EXIT_STOPPED
            return
        action = ex.next_robot_action()
        if action is not None:
            self.emit({"robot": robot_line(action)})
        else:
            waiting: dict[str, Any] = {
                "human": ex.human_name,
                "expected": [a.label for a in ex.expected_human_actions()]}
            if ex.problem.steps.concurrent:  # turns' lines stay as they were
                waiting["step"] = dict(self.timing)
            self.emit({"waiting": waiting})

    def error(self, kind: str, message: str, line: int, **extra: Any) -> None:
        self.emit({"error": kind, "message": message, "line": line, **extra})

    def stepped(self, step: Step) -> None:
        self.emit({"step": step_line(self.ex, step)})
        self.emit({"beliefs": beliefs(self.ex)})
        self.prompt()

    def handle(self, text: str, line: int) -> None:
        """Answer one input line (blank lines are ignored)."""
        if not text.strip():
            return
        try:
            msg = json.loads(text)
        except (json.JSONDecodeError, RecursionError) as e:
            self.error("bad-json", f"not a JSON object: {getattr(e, 'msg', e)}", line)
            return
        if not isinstance(msg, dict) or len(msg) != 1 or next(iter(msg)) not in REQUESTS:
            self.error("bad-request", 'expected one of {"human": "ACTION"}, '
                       '{"robot_done": "ACTION"} or {"robot_done": true}, '
                       '{"robot_failed": "ACTION"} or {"robot_failed": {"action": "ACTION", '
                       '"observed": ["FACT", "not FACT"]}}, {"profile": "NAME"}', line)
            return
        key, value = next(iter(msg.items()))
        try:
            if key == "profile":
                self.profile(value, line)
            elif key == "robot_done":
                if value is not True and not isinstance(value, str):
                    self.error("bad-request", "robot_done takes the action's label or true",
                               line)
                    return
                if self.malformed(value, line):
                    return
                self.robot_done(None if value is True else value, line)
            elif key == "robot_failed":
                self.robot_failed(value, line)
            else:
                if not isinstance(value, str):
                    self.error("bad-request", "human takes the action's label, e.g. "
                               '{"human": "pick(w)"}', line)
                    return
                if self.malformed(value, line):
                    return
                self.human(value, line)
        except PolicyMismatch as e:
            self.error("policy-mismatch", str(e), line)
            self.exit = EXIT_BAD

    def malformed(self, label: object, line: int) -> bool:
        """Answer ``bad-request`` and return True when ``label`` is a string that is no move
        label at all (``pick(w``), as opposed to a label that names no move here."""
        if not isinstance(label, str):
            return False
        why = label_syntax(label)
        if why is None:
            return False
        shown = label if len(label) <= SHOWN else label[:SHOWN] + "..."
        self.error("bad-request", f"{shown!r} is not a move label: {why}; write it as the "
                   "policy prints it, e.g. place(w, box2)", line, action=label)
        return True

    def profile(self, name: object, line: int) -> None:
        """``{"profile": NAME}`` (C11, a preferences problem): the human's preferences are
        learnt to be profile ``NAME``; the robot follows from now on the policy that profile
        prefers, relabelled from the current state on the kept graph (no new search,
        :meth:`Executor.switch_profile`), at the start of a step only."""
        ex = self.ex
        obj = ex.problem.objective
        if not isinstance(name, str):
            self.error("bad-request", 'profile takes a profile\'s name, e.g. {"profile": '
                       '"lazy_human"}', line)
            return
        if obj.kind != ObjectiveKind.PREFERENCES:
            self.error("bad-request", f"profile {name[:SHOWN]!r}: this problem has no "
                       'preference profiles ([objective] kind = "preferences" with '
                       "[objective.profiles])", line)
            return
        if name not in obj.profiles:
            self.error("bad-request", f"no profile {name[:SHOWN]!r}: the problem names "
                       + ", ".join(sorted(obj.profiles)), line, profiles=sorted(obj.profiles))
            return
        if ex.state.pending:
            self.error("wrong-turn", f"in the middle of a step ({ex.to_move}'s reply is due):"
                       " send the profile at the start of a step", line)
            return
        if self.graph is None:
            why = ("its search stopped at a limit" if self.relabel
                   else "ehatp execute was started with --no-keep-graph")
            self.error("no-relabel", f"no explored graph is kept ({why}): the profile cannot "
                       "be relabelled", line)
            return
        try:
            policy = ex.switch_profile(self.graph, name)
        except PolicyMismatch:
            raise
        except ExecutionError as e:
            self.error("no-relabel", str(e), line)
            return
        self.switches += 1
        info: dict[str, Any] = {
            "profile": name, "after": len(ex.history), "cost": num(policy.cost),
            "nodes": len(policy.nodes), "metrics": list(policy.objective["metrics"]),
            "value": list(policy.objective["value"])}
        if self.save is not None:
            path = self.save / f"profile-{self.switches}.json"
            try:
                self.save.mkdir(parents=True, exist_ok=True)
                policy.write(path)
                info["policy"] = str(path)
            except OSError as e:
                info["policy_error"] = f"{path}: cannot write ({e.strerror or e})"
        self.emit({"switched": info})
        self.prompt()

    def keep(self) -> dict[str, Any]:
        """The option that keeps a replan's graph: a preferences problem's only (C11)."""
        kind = self.ex.problem.objective.kind
        return ({"keep_graph": True} if self.relabel and kind == ObjectiveKind.PREFERENCES
                else {})

    def kept(self, result: Result) -> None:
        """Keep the graph of a replan's search (C11), which holds the states from here."""
        if result.graph is not None:
            self.graph = result.graph

    def robot_done(self, label: str | None, line: int) -> None:
        ex = self.ex
        if ex.next_robot_action() is None:
            self.error("wrong-turn", f"it is not {ex.robot_name}'s turn: {ex.human_name} is to "
                       "move", line)
            return
        try:
            step = ex.robot_action_done(label)
        except PolicyMismatch:
            raise
        except ExecutionError as e:
            self.error("wrong-action", str(e), line)
            return
        self.stepped(step)

    def human(self, label: str, line: int) -> None:
        ex = self.ex
        if ex.next_robot_action() is not None:
            self.error("wrong-turn", f"it is not {ex.human_name}'s turn: {ex.robot_name} is to "
                       "move", line)
            return
        try:
            step = ex.observe_human_action(label)
        except UncoveredHumanAction as e:
            # any move the human can make, the policy's or not (a pass the fairness rule lets a
            # policy leave out included, docs/semantics.md §4), is replanned from; only a move
            # that is impossible here (or fails) is an error
            replannable = self.replan and any(
                label_key(m.label) == label_key(e.action) and m.child is not None
                for m in ex.legal_human_moves())
            if not replannable:
                self.error("uncovered", str(e), line, action=e.action, expected=e.expected,
                           possible=e.possible)
                return
            self.replan_after(e.action, line)
            return
        self.stepped(step)

    def replan_after(self, label: str, line: int) -> None:
        ex = self.ex
        try:
            result = ex.replan(label, **self.keep(), **self.limits)
        except UncoveredHumanAction as e:
            self.error("uncovered", str(e), line, action=e.action, expected=e.expected,
                       possible=e.possible)
            return
        except PolicyMismatch:
            raise
        except ExecutionError as e:
            self.error("no-policy", str(e), line, action=label)
            self.exit = EXIT_STOPPED
            return
        self.kept(result)
        self.replanned(result, {"action": label, "agent": ex.human_name, "failed": False})
        self.stepped(ex.history[-1])

    def replanned(self, result: Result, about: dict[str, Any]) -> None:
        """The ``replanned`` line of a new policy (written to the --save-replans folder)."""
        assert result.policy is not None
        self.replans += 1
        stats = result.stats
        info: dict[str, Any] = {
            **about, "after": len(self.ex.history), "status": result.status,
            "cost": num(result.policy.cost), "nodes": len(result.policy.nodes),
            "distinct": stats.get("distinct"), "generated": stats.get("generated"),
            "time_ms": stats.get("time_ms")}
        if self.save is not None:
            path = self.save / f"replan-{self.replans}.json"
            try:
                self.save.mkdir(parents=True, exist_ok=True)
                result.policy.write(path)
                info["policy"] = str(path)
            except OSError as e:
                info["policy_error"] = f"{path}: cannot write ({e.strerror or e})"
        self.emit({"replanned": info})

    # -- the robot's action failed -------------------------------------------------------------
    def robot_failed(self, value: Any, line: int) -> None:
        """``{"robot_failed": LABEL | true}``: the robot's action did not happen, plan again
        from the same state; ``{"robot_failed": {"action": LABEL | true, "observed":
        [LITERAL, ...]}}``: it had another outcome, the state the literals describe among the
        robot's actions here, and plan again after that action."""
        label: Any = value
        observed: list[str] | None = None
        if isinstance(value, dict):
            label = value.get("action", True)
            observed = value.get("observed")
            if set(value) - {"action", "observed"} or not isinstance(observed, list) or not \
                    observed or not all(isinstance(x, str) for x in observed):
                self.error("bad-request", 'robot_failed with facts is {"action": "ACTION", '
                           '"observed": ["FACT", "not FACT", ...]}: at least one observed '
                           "fact, as strings", line)
                return
        if label is not True and not isinstance(label, str):
            self.error("bad-request", "robot_failed takes the action's label or true, or "
                       '{"action": ..., "observed": [...]}', line)
            return
        if self.malformed(label, line):
            return
        ex = self.ex
        intended = ex.next_robot_action()
        if intended is None:
            self.error("wrong-turn", f"it is not {ex.robot_name}'s turn: "
                       + ("the task is done" if ex.done else f"{ex.human_name} is to move"),
                       line)
            return
        if isinstance(label, str) and label_key(ex.strip_agent(label)) != label_key(
                intended.label):
            self.error("wrong-action", f"{ex.robot_name} reports {label!r} but the policy says "
                       f"{intended.label}", line)
            return
        if observed is None:
            self.replan_in_place(intended, line)
            return
        found = self.outcome(intended, observed, line)
        if found is NOTHING:
            self.replan_in_place(intended, line, observed)
        elif isinstance(found, Move):
            self.replan_outcome(intended, found, observed, line)

    def outcome(self, intended: Action, observed: list[str], line: int
                ) -> Move | object | None:
        """What happened, by the facts ``observed``: the robot's action here (a move of its
        own, the policy's or another) whose result fits them, or :data:`NOTHING` when only the
        state before fits; an error line and None when the facts are not atoms, or fit no
        outcome or several."""
        ex = self.ex
        actions = [m for m in ex.sem.moves(ex.state) if m.kind == MoveKind.ACTION
                   and m.child is not None]
        facts = {t: {label_key(a) for a in ex.grounded.state_atoms(t)}
                 for t in {ex.state.true, *(m.child.true for m in actions if m.child)}}
        g = ex.grounded
        known = {label_key(a) for a in g.atoms}.union(  # and every value of every counter
            *facts.values(), (label_key(f"{g.unit_names[u]} = {v}") for u, top in
                              g.counter_max.items() for v in range(top + 1)))
        wanted: list[tuple[str, bool]] = []
        for fact in observed:
            negative = fact.strip().startswith("not ")
            atom = label_key(fact.strip()[4:] if negative else fact)
            if atom not in known:
                self.error("bad-request", f"{fact[:SHOWN]!r} is not a fact that can change in "
                           f"this problem; observed facts are atoms as the beliefs lines "
                           "write them, or 'not ATOM'", line)
                return None
            wanted.append((atom, not negative))

        def fits(true: int) -> bool:
            return all((atom in facts[true]) == positive for atom, positive in wanted)

        nothing = fits(ex.state.true)
        moves = [m for m in actions if m.child is not None and fits(m.child.true)]
        labels = sorted({m.label for m in moves})
        if nothing and not labels:
            return NOTHING
        if len(labels) == 1 and not nothing:
            node = ex.node
            if label_key(labels[0]) == label_key(intended.label) and node is not None \
                    and len(node.moves) == 1:  # the policy's own edge
                return ex.edge_move(node, node.moves[0])
            return moves[0]
        outcomes: list[str | None] = [*([None] if nothing else []), *labels]
        if outcomes:
            listed = ", ".join(o or "nothing happened" for o in outcomes)
            why = (f"the observed facts fit more than one outcome of {ex.robot_name}'s actions "
                   f"here ({listed}); observe more facts")
        else:
            why = (f"the observed facts fit no outcome of {ex.robot_name}'s actions here; "
                   "replanning needs a state the problem's model can reach")
        self.error("unexplained", why, line, action=intended.label, observed=observed,
                   outcomes=outcomes)
        return None

    def replan_in_place(self, intended: Action, line: int,
                        observed: list[str] | None = None) -> None:
        """The robot's action did not happen: plan again from the same state."""
        ex = self.ex
        try:
            result = ex.replan(**self.keep(), **self.limits)
        except PolicyMismatch:
            raise
        except ExecutionError as e:
            self.error("no-policy", str(e), line, action=intended.label)
            self.exit = EXIT_STOPPED
            return
        self.kept(result)
        self.replanned(result, {"action": intended.label, "agent": ex.robot_name,
                                "failed": True, "outcome": None,
                                **({} if observed is None else {"observed": observed})})
        self.prompt()

    def replan_outcome(self, intended: Action, move: Move, observed: list[str],
                       line: int) -> None:
        """The robot's action had the outcome of ``move``: play it after the execution so
        far, as the fixed opening of a new problem, plan after it and follow the new policy
        (the executor replays the whole execution: the same state, K and beliefs)."""
        from ..search.planner import solve  # as the executor does: loaded when planning

        ex = self.ex
        played = (*(s.played for s in ex.history),
                  f"{ex.robot_name} {ex.sem.trace_label(ex.state, move)}")
        problem = dataclasses.replace(ex.as_problem(), after=played)
        try:
            result = solve(problem, **self.keep())
        except InputError as e:  # the planner cannot replay the execution as an opening
            result = None
            why = f"the planner does not replay the execution ({e.problem})"
        if result is None or result.policy is None:
            reason = why if result is None else result.reason or result.status
            self.error("no-policy", f"no policy from here: {reason}", line,
                       action=intended.label)
            self.exit = EXIT_STOPPED
            return
        new = Executor(problem, result.policy)
        new.replay_opening()
        self.ex = new
        self.kept(result)
        self.replanned(result, {"action": intended.label, "agent": new.robot_name,
                                "failed": True, "outcome": new.history[-1].action.label,
                                "observed": observed})
        self.stepped(new.history[-1])


def run(ex: Executor, stdin: TextIO, emit: Emit, *, replan: bool = False,
        source: str = "solved now", save: Path | None = None, timeout: float | None = None,
        max_memory: int | None = None, decision_timeout: float | None = None,
        recognition_latency: float | None = None, graph: Relabeler | None = None,
        relabel: bool = True) -> int:
    """The protocol without the CLI: read ``stdin`` to the goal or its end; returns the exit
    code. ``save``: a folder where each replanned policy is written (``replan-N.json``);
    ``timeout`` (seconds) and ``max_memory`` (bytes): each replan's limits (None: the
    problem's). ``decision_timeout`` and ``recognition_latency`` (seconds; joint steps): the
    timing every ``waiting`` line of a joint-step problem carries (docs/execution.md).
    ``graph``: a preferences problem's explored graph (``solve(..., keep_graph=True).graph``),
    relabelled when a ``{"profile": NAME}`` line comes (C11); ``relabel`` False: replans keep
    no graph either, and a profile line is refused."""
    session = Session(ex, emit, replan=replan, save=save, timeout=timeout,
                      max_memory=max_memory, graph=graph, relabel=relabel,
                      timing={"decision_timeout": decision_timeout,
                              "recognition_latency": recognition_latency})
    try:
        session.start(source)
    except PolicyMismatch as e:
        session.emit({"error": "policy-mismatch", "message": str(e), "line": 0})
        return EXIT_BAD
    number = 0
    while session.exit is None:
        text = stdin.readline(MAX_LINE + 1)
        if not text:
            session.emit({"error": "end-of-input", "message": "the input ended before the "
                          "goal", "line": number})
            return EXIT_STOPPED
        number += 1
        if len(text) > MAX_LINE and not text.endswith("\n"):
            while text and not text.endswith("\n"):  # the rest of the line, unread
                text = stdin.readline(MAX_LINE)
            session.error("bad-request", f"the line is longer than {MAX_LINE:,} characters; "
                          "send one JSON object per line, as the protocol says", number)
            continue
        session.handle(text, number)
    return session.exit


MAX_LINE = 1 << 16
"""The longest input line :func:`run` reads (characters, the newline included): a longer one
is a ``bad-request``, read to its end in pieces and never held or echoed whole."""


def replans_folder(path: Path) -> Path:
    """Return ``path``, created with its parents if missing: where ``--save-replans`` writes;
    :class:`InputError` when it cannot be a folder."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(str(path), "", f"cannot create the folder ({e.strerror or e})",
                         "give --save-replans a folder ehatp may create and write") from None
    return path


# --- move labels -------------------------------------------------------------------------------

_TOKEN = re.compile(r"\s*(?:([\w\-]+)|(.))", re.UNICODE)


def label_syntax(label: str) -> str | None:
    """Return why ``label`` is not a move label (``pick(w``: a ``(`` is not closed), None
    when it is one. A label is an optional agent name, then calls joined by ``+`` (what is
    said with an action): ``NAME`` or ``NAME(ARG, ...)``, an argument being a name, a call,
    ``not`` and a call, or a value ``CALL = NAME``; then, optionally, the agenda it leaves in
    brackets (``fetch [shelve]``). Whether it names a move here is the executor's question."""
    tokens: list[str] = []
    for m in _TOKEN.finditer(label):
        if m.group(1) is not None:
            tokens.append("NAME:" + m.group(1))
        elif m.group(2) is not None and not m.group(2).isspace():  # trailing blanks
            tokens.append(m.group(2))
    if not tokens:
        return "it is empty"
    return _Labels(tokens).label()


class _Labels:
    """A recursive-descent reader of :func:`label_syntax`'s grammar over its tokens."""

    def __init__(self, tokens: list[str]) -> None:
        self.tokens, self.i = tokens, 0

    def peek(self, k: int = 0) -> str:
        j = self.i + k
        return self.tokens[j] if j < len(self.tokens) else "END"

    def name(self) -> bool:
        if self.peek().startswith("NAME:"):
            self.i += 1
            return True
        return False

    def expect(self, token: str) -> str | None:
        if self.peek() == token:
            self.i += 1
            return None
        return self.unexpected(f"{token} expected")

    def unexpected(self, what: str) -> str:
        got = self.peek()
        if got == "END":
            return f"it ends early ({what})"
        return f"{what}, found {got.removeprefix('NAME:')!r}"

    def label(self) -> str | None:
        if self.peek().startswith("NAME:") and self.peek(1).startswith("NAME:"):
            self.i += 1  # the agent's name
        why = self.call()
        while why is None and self.peek() == "+":
            self.i += 1
            why = self.call()
        if why is None and self.peek() == "[":
            self.i += 1
            if self.peek() != "]":
                why = self.args()
            why = why or self.expect("]")
        if why is None and self.peek() != "END":
            why = self.unexpected("nothing more expected")
        return why

    def call(self) -> str | None:
        if not self.name():
            return self.unexpected("a name expected")
        if self.peek() != "(":
            return None
        self.i += 1
        if self.peek() == "END":
            return "a ( is not closed"
        why = self.args()
        if why is None and self.peek() == "END":
            return "a ( is not closed"
        return why or self.expect(")")

    def args(self) -> str | None:
        why = self.arg()
        while why is None and self.peek() == ",":
            self.i += 1
            why = self.arg()
        return why

    def arg(self) -> str | None:
        if self.peek() == "NAME:not" and self.peek(1).startswith("NAME:"):
            self.i += 1
        why = self.call()
        if why is None and self.peek() == "=":
            self.i += 1
            if not self.name():
                return self.unexpected("a value expected after =")
        return why


def json_lines(out: TextIO) -> Emit:
    """Write each message as one JSON line and flush (the reader is waiting for it)."""
    def emit(message: dict[str, Any]) -> None:
        out.write(json.dumps(message, ensure_ascii=False) + "\n")
        out.flush()
    return emit


__all__ = ["EXIT_BAD", "EXIT_GOAL", "EXIT_STOPPED", "Session", "beliefs", "json_lines",
           "label_syntax", "replans_folder", "run"]
