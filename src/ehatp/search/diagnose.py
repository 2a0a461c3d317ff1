"""Why no policy exists, said in the problem's own terms.

When the search proves a problem unsolvable, the explored graph holds every state the agents can
reach (up to the depth limit). That is enough to name the cause when it is the goal itself: a
goal literal that holds in none of those states, literals that never hold together, or agendas
that never finish where the goal holds. Otherwise (the goal is reachable, but the human can
steer away from it, or the search was cut by the depth limit) one failing line of play is the
best explanation there is.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from ..epistemic.semantics import DEAD_PASSIVE_RUN
from ..model.formula import FALSE, TRUE, And, Formula, GAtom, Not
from ..model.grounded import FINISH, Grounded
from ..model.problem import call_str
from .graph import DEAD, OPEN, Graph

MAX_SHOWN = 120  # characters of a ground goal part; a whole expanded formula would not read


def diagnose(grounded: Grounded, graph: Graph, line_of_play: Callable[[], str]) -> str:
    """Why the problem is unsolvable. If the search explored everything reachable: a goal
    literal no state reaches, goal literals that never hold together, or agendas that never
    finish where the goal holds, each followed by ``line_of_play()`` (one failing line) as an
    example. Otherwise, or when a goal state is reachable, just ``line_of_play()``."""
    if not _complete(graph):  # a cut-off state might reach the goal: claim nothing
        return line_of_play()
    why = _goal_unreached(grounded, graph) or _agendas(grounded, graph)
    # the line of play stays as an example: it shows what stands in the way (a false belief,
    # a deadlock), the diagnosis says what is never reached
    return f"{why}; one failing line: {line_of_play()}" if why is not None else line_of_play()


def _complete(graph: Graph) -> bool:
    """Whether every reachable state was explored: none left open or cut by the depth limit
    (a dead end that is not an inactivity deadlock)."""
    return all(st != OPEN and (st != DEAD or es.passive >= DEAD_PASSIVE_RUN)
               for st, es in zip(graph.status, graph.states, strict=True))


def _goal_unreached(grounded: Grounded, graph: Graph) -> str | None:
    states = graph.states
    n = len(states)
    seen = f"{n} explored state{'s' if n != 1 else ''}"
    trues = sorted({es.true for es in states})
    missing = _missing_literals(grounded, trues)
    if missing:
        return (f"the goal needs {_and(missing)}, which hold{'s' if len(missing) == 1 else ''} "
                f"in none of the {seen}")
    if not any(grounded.goal(t) for t in trues):
        return (f"each part of the goal holds somewhere, but never all at once in the {seen} "
                f"(goal: {_short(_show(grounded.goal_f))})")
    return None


def _missing_literals(grounded: Grounded, trues: Sequence[int]) -> list[str]:
    """Goal literals no explored true state satisfies: the problem's ``goal`` first (a static
    one is fixed by ``[init]``), then the other conjuncts of the ground goal."""
    out: list[str] = []
    covered: set[Formula] = set()
    p = grounded.problem
    for positive, (name, args) in p.goal:
        text = call_str(name, args)
        idx = grounded.atom_index.get(text)
        if idx is None:  # a predicate no action changes: its value is the initial one
            reached = ((name, args) in p.init) == positive
        else:
            reached = any((t >> idx & 1) == positive for t in trues)
            atom = GAtom(idx, text)
            covered.add(atom if positive else Not(atom))
        if not reached:
            out.append(text if positive else f"not {text}")
    if out:
        return out
    parts = grounded.goal_f.args if isinstance(grounded.goal_f, And) else (grounded.goal_f,)
    for part in parts:
        if part == TRUE or part in covered:
            continue
        if part == FALSE or not any(grounded.compile(part)(t) for t in trues):
            out.append(_short(_show(part)))
    return out


def _agendas(grounded: Grounded, graph: Graph) -> str | None:
    """Which agenda never finishes in a state where the goal holds, if one does not."""
    sem = graph.sem
    r_name, h_name = sem.names
    n = len(graph.states)
    seen = f"{n} explored state{'s' if n != 1 else ''}"
    at_goal = [es for es in graph.states if grounded.goal(es.true)]
    robot_done = [es for es in at_goal if sem.robot_done(es)]
    if not robot_done:
        return (f"{r_name} never finishes its agenda "
                f"({_agenda(grounded, grounded.robot_agenda)}) in a state where the goal holds "
                f"({seen})")
    both_done = [es for es in robot_done if sem.human_done(es)]
    if not both_done:
        return (f"{h_name} never finishes its agenda "
                f"({_agenda(grounded, grounded.human_agenda)}) in a state where the goal holds "
                f"and {r_name} has finished ({seen}): the two agendas never finish together")
    if not any(sem.human_believes_robot_done(es) for es in both_done):
        return (f"where both agendas are finished and the goal holds, {h_name} never believes "
                f"{r_name} is done ({seen})")
    return None


def _agenda(grounded: Grounded, agenda: Sequence[int]) -> str:
    names = [grounded.task_names[t] for t in agenda if t != FINISH]
    return ", ".join(names) if names else "empty"


def _show(f: Formula) -> str:
    if f == FALSE:
        return "false (a part of it can never hold)"
    if isinstance(f, Not) and isinstance(f.arg, GAtom):
        return f"not {f.arg}"
    return str(f)


def _short(text: str) -> str:
    return text if len(text) <= MAX_SHOWN else text[:MAX_SHOWN - 1] + "…"


def _and(items: Sequence[str]) -> str:
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} and {items[-1]}"


__all__ = ["diagnose"]
