"""Step through one execution of a policy and say, at every step, what happened and what each
agent now believes (``ehatp simulate``, :mod:`ehatp.cli.simulate`). See ``docs/simulation.md``.

The robot's moves come from the policy; the human's from a prompt, a seeded random pick, the
first option, or a script. Exit codes: 0 goal reached, 1 the run left the policy (or the script's
expectation of the robot), 2 bad input.
"""

from __future__ import annotations

import random
import sys
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import TextIO

from ..epistemic.semantics import Move
from ..errors import ExecutionError, InputError, PolicyMismatch, UncoveredHumanAction
from ..formats.policy import label_key
from ..formats.policy_check import read_policy
from ..formats.problem_toml import load
from ..formats.text import print_notes
from ..model.problem import Cost, Problem
from .executor import Executor

MODES = ("ask", "random", "first", "script")

# Chooses the human's move among the moves it can make (Executor.legal_human_moves: the model's
# options, and a pass the fairness rule lets a policy leave out); returns the label played.
Chooser = Callable[[Executor, list[Move]], str]


class Stop(Exception):
    """The run leaves the policy or the script's expectation (exit code 1)."""


@dataclass
class ScriptLine:
    number: int
    agent: str | None  # None: the human (no name given)
    label: str


def read_script(path: Path, robot: str, human: str) -> list[ScriptLine]:
    """One move per line; ``#`` starts a comment; a leading agent name is optional for the
    human's moves and required for the robot's (checked against the policy)."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise InputError(str(path), "", f"cannot read the script ({e.strerror})",
                         "check the path given to --script") from None
    except UnicodeDecodeError as e:
        raise InputError(str(path), "", f"not a UTF-8 text file (byte at offset {e.start})",
                         "give a script of moves, one per line, saved as UTF-8") from None
    out = []
    for i, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        head, _, rest = line.partition(" ")
        if head in (robot, human) and rest.strip():
            out.append(ScriptLine(i, head, rest.strip()))
        else:
            out.append(ScriptLine(i, None, line))
    return out


class ScriptedHuman:
    """Plays the script's human moves in order and checks its robot lines."""

    def __init__(self, path: Path, lines: list[ScriptLine]) -> None:
        self.path, self.lines, self.pos = path, lines, 0

    def check_robot(self, ex: Executor, label: str) -> None:
        if self.pos < len(self.lines) and self.lines[self.pos].agent == ex.robot_name:
            ln = self.lines[self.pos]
            self.pos += 1
            if not label_key(ln.label) == label_key(label):
                raise Stop(f"{self.path}:{ln.number}: the script expects {ex.robot_name} "
                           f"{ln.label}, the policy does {label}")

    def __call__(self, ex: Executor, moves: list[Move]) -> str:
        if self.pos >= len(self.lines):
            raise InputError(str(self.path), "end", f"the script ended but {ex.human_name} "
                             f"must move (options: {', '.join(m.label for m in moves)})",
                             "add a line with the human's move")
        ln = self.lines[self.pos]
        self.pos += 1
        if ln.agent == ex.robot_name:
            raise InputError(str(self.path), str(ln.number),
                             f"{ex.robot_name} {ln.label} is given where {ex.human_name} must "
                             "move", f"give one of: {', '.join(m.label for m in moves)}")
        if not any(label_key(m.label) == label_key(ln.label) for m in moves):
            raise InputError(str(self.path), str(ln.number),
                             f"{ln.label!r} is not a move of {ex.human_name} here",
                             f"give one of: {', '.join(m.label for m in moves)}")
        return ln.label

    def finish(self) -> None:
        if self.pos < len(self.lines):
            ln = self.lines[self.pos]
            raise InputError(str(self.path), str(ln.number),
                             f"the run is over but the script goes on ({ln.label!r})",
                             "remove the extra lines")


def asking_human(stdin: TextIO, out: Callable[[str], None]) -> Chooser:
    """Lists the human's options and reads a number or a label per line of ``stdin``."""

    def choose(ex: Executor, moves: list[Move]) -> str:
        covered = {label_key(a.label) for a in ex.expected_human_actions()}
        out(f"  {ex.human_name} to move; options:")
        for i, m in enumerate(moves, 1):
            note = ""
            if m.child is None:
                note = f"  (fails: {m.failure})"
            elif label_key(m.label) not in covered:
                note = "  (not covered by the policy)"
            out(f"    {i}) {m.label}{note}")
        while True:
            out(f"  choice for {ex.human_name} (number or label)?")
            line = stdin.readline()
            if not line:
                raise InputError("<stdin>", "", f"input ended while {ex.human_name} had to "
                                 "move", "give one choice per line")
            answer = line.strip()
            if answer.isdigit() and 1 <= int(answer) <= len(moves):
                return moves[int(answer) - 1].label
            for m in moves:
                if label_key(m.label) == label_key(ex.strip_agent(answer)):
                    return m.label
            numbers = "1" if len(moves) == 1 else f"a number from 1 to {len(moves)}"
            out(f"  not an option: {answer!r}; type {numbers} or a label")

    return choose


def random_human(seed: int) -> Chooser:
    """A seeded random pick among the model's options (:meth:`Executor.possible_human_moves`)."""
    rng = random.Random(seed)
    return lambda ex, moves: rng.choice(ex.possible_human_moves()).label


def first_human(ex: Executor, moves: list[Move]) -> str:
    return moves[0].label


def _num(c: Cost) -> str:
    if isinstance(c, Fraction) and c.denominator != 1:
        return str(float(c))
    return str(int(c)) if isinstance(c, Fraction) else str(c)


def simulate(ex: Executor, choose: Chooser, out: Callable[[str], None],
             script: ScriptedHuman | None = None) -> int:
    """Run ``ex`` to its end, printing every step; returns the exit code (0 goal, 1 stopped)."""
    R, H = ex.robot_name, ex.human_name
    opening = len(ex.policy.after)
    out("start" + (f" (then the problem's fixed opening of {opening} moves)" if opening else "")
        + (f"; policy node {ex.node.id}" if ex.node is not None else ""))
    for line in ex.start_lines():
        out(f"  {line}")
    try:
        while not ex.done:
            action = ex.next_robot_action()
            if action is not None:
                if script is not None and not ex.in_opening:
                    script.check_robot(ex, action.label)
                step = ex.robot_action_done()
            elif ex.in_opening:
                step = ex.observe_human_action(ex.expected_human_actions()[0])
            else:
                label = choose(ex, ex.legal_human_moves())
                step = ex.observe_human_action(label)
            if step.node is None:
                where = "opening"
            elif step.opening:  # the opening's last move reaches the policy's root
                where = f"end of the opening, policy node {step.node.id}"
            else:
                where = f"policy node {step.node.id}"
            out(f"{step.index}. {step.action.agent} {step.action.label}  "
                f"(cost {_num(step.action.cost)}; {where})")
            for line in ex.explain(step):
                out(f"  {line}")
        if script is not None:
            script.finish()
    except UncoveredHumanAction as e:
        out(f"stopped: {e}")
        return 1
    except Stop as e:
        out(f"stopped: {e}")
        return 1
    opening_cost = sum((s.action.cost for s in ex.history if s.opening), 0)
    total = ex.cost
    detail = (f" (opening {_num(opening_cost)}, then {_num(total - opening_cost)})"
              if opening else "")
    worst = ex.policy.cost
    if ex.goal_reached:
        out(f"outcome: goal reached after {len(ex.history)} steps; total cost {_num(total)}"
            f"{detail}; the policy's worst case"
            f"{' after the opening' if opening else ''} is {_num(worst)}")
        return 0
    out(f"outcome: the policy ended without reaching the goal ({R} and {H} stopped after "
        f"{len(ex.history)} steps, cost {_num(total)})")
    return 1


def run(problem_path: Path, *, policy_path: Path | None = None, human: str = "first",
        script_path: Path | None = None, seed: int = 0, stdin: TextIO | None = None,
        out: Callable[[str], None] = print) -> int:
    """The ``simulate`` command without the CLI: returns the exit code. Bad input raises
    :class:`~ehatp.errors.InputError`."""
    if script_path is not None and human == "first":
        human = "script"
    if human not in MODES:
        raise InputError("--human", "", f"{human!r} is not a mode",
                         f"use one of {', '.join(MODES)}")
    if human == "script" and script_path is None:
        raise InputError("--human script", "", "no script given", "add --script FILE")
    if human != "script" and script_path is not None:
        raise InputError("--script", "", f"a script is only read with --human script, "
                         f"not {human}", "drop --script or use --human script")
    problem: Problem = load(problem_path)
    print_notes(problem)
    policy = read_policy(policy_path) if policy_path is not None else None
    try:
        ex = Executor(problem, policy)
    except PolicyMismatch as e:
        raise InputError(str(policy_path or problem.source), "", str(e)) from None
    except ExecutionError as e:
        out(str(e))
        return 1
    script: ScriptedHuman | None = None
    if human == "script":
        assert script_path is not None
        script = ScriptedHuman(script_path,
                               read_script(script_path, ex.robot_name, ex.human_name))
        choose: Chooser = script
    elif human == "ask":
        choose = asking_human(stdin or sys.stdin, out)
    elif human == "random":
        choose = random_human(seed)
    else:
        choose = first_human
    how = {"ask": "asked on stdin", "random": f"random (seed {seed})", "first": "first option",
           "script": f"script {script_path}"}[human]
    source = f"policy {policy_path}" if policy_path is not None else "policy solved now"
    out(f"simulating {problem.name} ({problem.domain.name}): robot {ex.robot_name}, human "
        f"{ex.human_name}, K={problem.K}; {source}; human moves: {how}")
    try:
        return simulate(ex, choose, out, script)
    except PolicyMismatch as e:
        where = str(policy_path) if policy_path is not None else problem.source
        raise InputError(where, "", str(e)) from None


__all__ = ["MODES", "ScriptLine", "ScriptedHuman", "read_script", "run", "simulate"]
