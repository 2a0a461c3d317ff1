"""An execution in words, for people: what a step changed and what each agent believes, in the
domain's vocabulary (the text of ``ehatp simulate``, the worlds ``ehatp execute`` reports).

Everything here reads the problem's :class:`~ehatp.epistemic.semantics.Semantics` and the
epistemic states of an execution, and changes nothing;
:class:`~ehatp.run.executor.Executor`'s ``explain``, ``start_lines``, ``belief_lines``,
``human_worlds`` and ``uncertain_atoms`` say it of the execution they follow. Worlds are
docs/semantics.md §3, situation assessment §2, what is told and asked §5.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..epistemic.semantics import ACTION, ANNOUNCE, ANSWER, ASK, INFORM, WAIT, Semantics, bits_of
from ..epistemic.state import EState, Worlds, states_of
from ..model.agenda import Agenda
from .step import Step

MAX_WORLDS_LISTED = 8


@dataclass(frozen=True)
class WorldView:
    """One world the human entertains: its true atoms, how it differs from the truth, and the
    agenda the human attributes to the robot there."""

    atoms: tuple[str, ...]
    true: tuple[str, ...]  # true here, false in reality
    false: tuple[str, ...]  # false here, true in reality
    robot_agenda: tuple[str, ...]

    @property
    def is_truth(self) -> bool:
        return not self.true and not self.false


def human_agendas(es: EState) -> tuple[Agenda, ...]:
    """Return the human agendas the robot cannot tell apart at ``es`` (docs/semantics.md §3,
    "What the robot observes"): the one place the executor and its narrative read them."""
    return es.human_agendas


def _agenda(sem: Semantics, ag: Agenda) -> list[str]:  # a partially ordered block as {a | b}
    return sem.net.names_of(ag)


def world_views(sem: Semantics, es: EState) -> list[WorldView]:
    """§3: the worlds the human entertains in ``es``, in the domain's vocabulary."""
    g, t = sem.grounded, es.true
    return [WorldView(tuple(g.state_atoms(s)), tuple(g.mask_atoms(s & ~t)),
                      tuple(g.mask_atoms(t & ~s)), tuple(_agenda(sem, ag)))
            for s, ag in es.worlds]


def disputed_atoms(sem: Semantics, es: EState) -> list[str]:
    """§3: the atoms on which the human's worlds in ``es`` disagree."""
    states = states_of(es.worlds)
    m = 0
    for s in states:
        m |= s ^ states[0]
    return sem.grounded.mask_atoms(m)


def step_lines(sem: Semantics, step: Step,
               answer: Callable[[EState, str], bool | None]) -> list[str]:
    """What ``step`` changed, in the domain's vocabulary: the truth, co-presence, and how the
    human's worlds were added, ruled out (§2) or told (§5); ``answer`` is the robot's answer
    to a question the human asks (:meth:`~ehatp.run.executor.Executor.answer`)."""
    g = sem.grounded
    R, H = sem.names
    b, a, act = step.before, step.after, step.action
    lines: list[str] = []
    gained, lost = g.mask_atoms(a.true & ~b.true), g.mask_atoms(b.true & ~a.true)
    if gained or lost:
        parts = ([f"now true: {', '.join(gained)}"] if gained else []) + (
            [f"no longer true: {', '.join(lost)}"] if lost else [])
        lines.append("; ".join(parts))
    n0 = len(b.worlds)
    mid = step.assessed if step.assessed is not None else a.worlds
    cop = sem.copresent(b.true)
    if act.agent == R and act.kind in (ACTION, WAIT) and not cop:
        if act.kind == ACTION or b.k < sem.K:
            lines.append(f"{H} did not see it: imagining what {R} may have done meanwhile, "
                         f"{H} goes from {n0} to {_worlds(len(mid))}")
        else:
            lines.append(f"{H} did not see it and imagines nothing more "
                         f"({R} has had its K={sem.K} unseen turns)")
    elif act.agent == R and act.kind == ACTION and len(mid) != n0:
        lines.append(f"{H} saw it: {n0} -> {_worlds(len(mid))}")
    elif act.kind == INFORM:
        lines.append(f"{R} tells {H}: {', '.join(act.args)} ({n0} -> {_worlds(len(mid))})")
    elif act.kind == ASK and act.agent == R:
        lines.append(f"{R} asks {H} what {H} is about to do")
    elif act.kind == ANSWER:
        lines.append(f"{H} answers {R}: " + (", ".join(_agenda(sem, human_agendas(a)[0]))
                                             or "nothing more to do")
                     + f"; {R} now knows {H}'s intention")
    elif act.kind == ANNOUNCE:
        lines.append(f"{R} tells {H} what it is doing: "
                     + (", ".join(_agenda(sem, b.robot_agenda)) or "nothing more")
                     + f" ({n0} -> {_worlds(len(mid))})")
    elif act.kind == ASK:
        said_yes = answer(b, act.label)
        said = "" if said_yes is None else f"; {R} answers {'yes' if said_yes else 'no'}"
        lines.append(f"{H} asks whether {act.args[0]}{said} ({n0} -> {_worlds(len(mid))})")
    if step.assessed is not None and step.assessed != a.worlds:
        lines.append(_assessment(sem, a.true, step.assessed, a.worlds))
    if sem.copresent(a.true) != cop:
        lines.append(f"{H} and {R} are now " + ("together" if sem.copresent(a.true)
                                                 else "apart"))
    if not sem.copresent(a.true) and a.k != b.k:
        lines.append(f"{R} has had {a.k} of its K={sem.K} turns unseen by {H}")
    lines.extend(belief_lines(sem, a))
    return lines


def start_lines(sem: Semantics, es: EState, assessed: Worlds | None) -> list[str]:
    """The situation ``es`` before the first move; ``assessed``: the human's worlds before
    the situation assessment of the start (§2), when it ran."""
    R, H = sem.names
    lines = [f"{H} and {R} are " + ("together" if sem.copresent(es.true) else "apart")]
    if assessed is not None and assessed != es.worlds:
        lines.append(_assessment(sem, es.true, assessed, es.worlds))
    return lines + belief_lines(sem, es)


def belief_lines(sem: Semantics, es: EState) -> list[str]:
    """What each agent believes in ``es``: the human's worlds, and the human's intentions the
    robot cannot tell apart (§3)."""
    R, H = sem.names
    hyps = human_agendas(es)
    intentions = [] if len(hyps) < 2 else [  # what the robot cannot see (§3)
        f"{R} cannot tell which of {len(hyps)} intentions {H} follows: "
        + " / ".join(", ".join(_agenda(sem, h)) or "nothing" for h in hyps)]
    return _world_lines(sem, es) + intentions


def _world_lines(sem: Semantics, es: EState) -> list[str]:
    g, t = sem.grounded, es.true
    R, H = sem.names
    ws = es.worlds
    head = f"{R} knows the truth; {H} now entertains {_worlds(len(ws))}"
    if len(ws) == 1 and ws[0][0] == t and ws[0][1] == es.robot_agenda:
        return [head + ": the truth"]
    states = states_of(ws)
    m = 0
    for s in states:
        m |= s ^ states[0]
    differ = g.mask_atoms(m)
    if len({ag for _, ag in ws}) > 1:
        differ.append(f"{R}'s agenda")
    if differ:
        head += f"; they differ on {', '.join(differ)}"
    if all(s != t for s in states):
        head += "; none of them is the truth"
    lines = [head + ":"]
    for i, (s, ag) in enumerate(ws[:MAX_WORLDS_LISTED], 1):
        lits = g.mask_atoms(s & ~t) + [f"not {x}" for x in g.mask_atoms(t & ~s)]
        text = f"differs from the truth: {', '.join(lits)}" if lits else "the true state"
        if ag != es.robot_agenda:
            text += f"; {H} thinks {R} still has to do: " + (
                ", ".join(_agenda(sem, ag)) or "nothing")
        lines.append(f"  world {i}: {text}")
    if len(ws) > MAX_WORLDS_LISTED:
        lines.append(f"  ... and {len(ws) - MAX_WORLDS_LISTED} more")
    return lines


def _assessment(sem: Semantics, t: int, pre: Worlds, post: Worlds) -> str:
    g, H = sem.grounded, sem.names[1]
    vis = sem.visible(t)
    removed = [w for w in pre if w not in post]
    m = 0
    for s, _ in removed:
        m |= (s ^ t) & vis
    seen = ", ".join(g.atoms[i] if t >> i & 1 else f"not {g.atoms[i]}" for i in bits_of(m))
    if set(post) <= set(pre):
        return (f"situation assessment: {H} sees {seen or 'the scene'}, which rules out "
                f"{_worlds(len(removed))} ({len(pre)} -> {len(post)})")
    return (f"situation assessment: no world fits what {H} sees ({seen}); {H} revises its "
            f"worlds ({len(pre)} -> {len(post)})")


def _worlds(n: int) -> str:
    return f"{n} world" + ("" if n == 1 else "s")
