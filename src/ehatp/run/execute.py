"""Run a policy live over JSON lines (``ehatp execute``, :mod:`ehatp.cli.execute`): the protocol a
robot process speaks with ehatp running as its subprocess.

A robot process (a ROS node, a C++ controller) starts ``ehatp execute PROBLEM --policy P.json``
and talks to it through stdin and stdout, one JSON object a line. In: what the human did
(``{"human": "pick(w)"}``) and that the robot is done (``{"robot_done": "pick(r)"}`` or
``{"robot_done": true}``). Out: what the robot should do (``{"robot": {...}}``), that the human
is to act (``{"waiting": {...}}``), what the human now believes (``{"beliefs": {...}}``), the goal
(``{"goal": true, ...}``) and errors (``{"error": KIND, ...}``). With ``--replan`` a human action
the policy does not cover, but the human model allows, is applied and the robot replans from
there (``{"replanned": {...}}``): a move the model allows, or a ``pass`` the fairness rule lets
a policy leave out (docs/semantics.md §4); only an impossible move is an error. See
``docs/execution.md``.

Exit codes (:func:`run` returns them): 0 the goal is reached; 1 the input ended before the goal,
or replanning found no policy; 2 a policy that turns out not to fit the problem (a
``policy-mismatch`` line).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any, TextIO

from ..errors import ExecutionError, PolicyMismatch, UncoveredHumanAction
from ..formats.policy import label_key, num
from .executor import Action, Executor, Step

EXIT_GOAL, EXIT_STOPPED, EXIT_BAD = 0, 1, 2

Emit = Callable[[dict[str, Any]], None]


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
                 save: Path | None = None) -> None:
        self.ex, self.emit, self.replan, self.save = ex, emit, replan, save
        self.exit: int | None = None  # set when the session is over
        self.replans = 0

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
            self.emit({"waiting": {"human": ex.human_name,
                                   "expected": [a.label for a in ex.expected_human_actions()]}})

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
        if not isinstance(msg, dict) or len(msg) != 1 or next(iter(msg)) not in (
                "human", "robot_done"):
            self.error("bad-request", 'expected one of {"human": "ACTION"}, '
                       '{"robot_done": "ACTION"} or {"robot_done": true}', line)
            return
        key, value = next(iter(msg.items()))
        try:
            if key == "robot_done":
                if value is not True and not isinstance(value, str):
                    self.error("bad-request", "robot_done takes the action's label or true",
                               line)
                    return
                self.robot_done(None if value is True else value, line)
            else:
                if not isinstance(value, str):
                    self.error("bad-request", "human takes the action's label, e.g. "
                               '{"human": "pick(w)"}', line)
                    return
                self.human(value, line)
        except PolicyMismatch as e:
            self.error("policy-mismatch", str(e), line)
            self.exit = EXIT_BAD

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
            result = ex.replan(label)
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
        assert result.policy is not None
        self.replans += 1
        stats = result.stats
        info: dict[str, Any] = {
            "action": label, "after": len(ex.history), "status": result.status,
            "cost": num(result.policy.cost), "nodes": len(result.policy.nodes),
            "distinct": stats.get("distinct"), "generated": stats.get("generated"),
            "time_ms": stats.get("time_ms")}
        if self.save is not None:
            path = self.save / f"replan-{self.replans}.json"
            try:
                result.policy.write(path)
                info["policy"] = str(path)
            except OSError as e:
                info["policy_error"] = f"{path}: cannot write ({e.strerror or e})"
        self.emit({"replanned": info})
        self.stepped(ex.history[-1])


def run(ex: Executor, stdin: TextIO, emit: Emit, *, replan: bool = False,
        source: str = "solved now", save: Path | None = None) -> int:
    """The protocol without the CLI: read ``stdin`` to the goal or its end; returns the exit
    code. ``save``: a folder where each replanned policy is written (``replan-N.json``)."""
    session = Session(ex, emit, replan=replan, save=save)
    try:
        session.start(source)
    except PolicyMismatch as e:
        emit({"error": "policy-mismatch", "message": str(e), "line": 0})
        return EXIT_BAD
    number = 0
    while session.exit is None:
        text = stdin.readline()
        if not text:
            emit({"error": "end-of-input", "message": "the input ended before the goal",
                  "line": number})
            return EXIT_STOPPED
        number += 1
        session.handle(text, number)
    return session.exit


def json_lines(out: TextIO) -> Emit:
    """Write each message as one JSON line and flush (the reader is waiting for it)."""
    def emit(message: dict[str, Any]) -> None:
        out.write(json.dumps(message, ensure_ascii=False) + "\n")
        out.flush()
    return emit


__all__ = ["EXIT_BAD", "EXIT_GOAL", "EXIT_STOPPED", "Session", "beliefs", "json_lines", "run"]
