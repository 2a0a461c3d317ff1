"""The problem options that choose a human model, a communication model and an objective
(docs/semantics.md §4-§7, docs/problem-format.md): explicit, documented choices with the
defaults that give the policies a user would draw by hand.

Reading them from TOML is here too, so the problem loader stays one table per concern.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from enum import StrEnum
from fractions import Fraction
from typing import Any, Protocol

from ..errors import InputError


class Passes(StrEnum):
    """When the human's ``pass`` right after a robot ``wait`` need not be covered (§4)."""

    FAIR = "fair"  # only after a wait the robot could not avoid (nothing real to do)
    PROTOTYPE = "prototype"  # after any robot wait (the authors' prototype)
    IDLE = "idle"  # only when it has nothing it could do (the HATP/EHDA predecessor's human)


class Intentions(StrEnum):
    """Whether the robot sees which method the human chose (§3-§4)."""

    HIDDEN = "hidden"  # it sees actions only: one AND branch per distinct action label
    VISIBLE = "visible"  # every method choice is announced: one branch per refinement


class InformWhere(StrEnum):
    """Where the robot may inform (§5)."""

    COPRESENT = "copresent"
    ANYWHERE = "anywhere"  # a call, a screen: heard while apart, nothing else witnessed


class Speech(StrEnum):
    """What an inform takes (§5)."""

    TURN = "turn"  # the robot's whole turn
    WITH_ACTION = "with-action"  # said while acting (or waiting), in the same turn


class Relevance(StrEnum):
    """Which divergences make an inform worth offering (§5)."""

    NEXT = "next"  # those that change the next options
    PLAN = "plan"  # also those that make a later step of the human's agenda fail or differ


class StepMode(StrEnum):
    """How the agents move (docs/concurrent.md): in turns (§4), or in joint steps (C1-C12)."""

    TURNS = "turns"  # one agent acts, then the other (the paper)
    CONCURRENT = "concurrent"  # both act in every step, the robot compliant (C1-C12)


class StepFirst(StrEnum):
    """Who decides first in a joint step (C4)."""

    HUMAN = "human"  # AND over the human's options, then OR over the robot's replies
    ROBOT = "robot"  # OR over the robot's options, then AND over the human's


class Witness(StrEnum):
    """When the human witnesses the robot's action of a joint step (C8)."""

    WHOLE = "whole"  # co-present before and after the human's action
    START = "start"  # co-present before the step


class Commute(StrEnum):
    """What makes two actions of a step admissible together (C3 b)."""

    STATE = "state"  # both orders reach the same state
    LABEL = "label"  # each action is still an option after the other (the authors' planner)


class ObjectiveKind(StrEnum):
    """What the policy's cost is (§6-§7)."""

    WORST_CASE = "worst-case"
    EXPECTED = "expected"
    PREFERENCES = "preferences"  # C11: a named lexicographic profile (joint steps only)


class Metric(StrEnum):
    """A built-in per-branch metric a preference profile orders (C11, docs/concurrent.md
    "Preferences"); a profile may also name the metrics its domain declares
    (:meth:`~ehatp.model.domain.Domain.metric`)."""

    MAKESPAN = "makespan"  # the steps' cost ([steps] cost each)
    HUMAN_END = "human_end"  # steps until the human's last action ([steps] cost each)
    HUMAN_EFFORT = "human_effort"  # steps in which the human acts (an action of its model)
    EFFORT = "effort"  # actions of both agents
    COMMUNICATIONS = "communications"  # inform and ask moves


class Estimate(StrEnum):
    """How a preference profile aggregates the human's branches (C11)."""

    WORST_CASE = "worst-case"  # the lexicographically worst branch (the default)
    OPTIMISTIC = "optimistic"  # the best branch: the authors' best-pair value



# the keys of each options table, for the loader's checks
OPTION_KEYS: dict[str, frozenset[str]] = {
    "options": frozenset({"human_passes_when_blocked", "inform_max_atoms"}),
    "human": frozenset({"passes", "passes_when_blocked", "anticipates", "intentions"}),
    "communication": frozenset({"inform", "speech", "relevance", "ask", "inform_max_atoms",
                                "plan_horizon", "robot_asks", "announce"}),
    "objective": frozenset({"kind", "weights", "ties", "profile", "profiles", "estimate"}),
    "steps": frozenset({"mode", "first", "witness", "commute", "cost"}),
}


class TieKey(StrEnum):
    """A tie-break among robot options of equal value (§7, "Ties"), as ``[objective] ties``
    names it."""

    COMMUNICATIONS = "communications"  # fewer inform/ask/announce moves, and moves said with one
    WAITS = "waits"  # fewer human passes made waiting
    LENGTH = "length"  # a shorter average branch
    WORST_CASE = "worst-case"  # a smaller worst-case cost
    EXPECTED = "expected"  # a smaller expected cost


TIE_KEYS = tuple(TieKey)
DEFAULT_TIES = (TieKey.COMMUNICATIONS, TieKey.WAITS, TieKey.LENGTH)


@dataclass(frozen=True)
class HumanModel:
    """``[human]``: how the uncontrollable agent behaves and reasons."""

    passes: Passes = Passes.FAIR
    # a human blocked by uncertainty may silently pass after a robot wait (the paper's trace b)
    passes_when_blocked: bool = True
    # the human imagines what the robot does unseen (the product of anticipated events)
    anticipates: bool = True
    # whether the robot sees the human's method choices (§3): hidden by default
    intentions: Intentions = Intentions.HIDDEN


@dataclass(frozen=True)
class Communication:
    """``[communication]``: how the robot may talk and the human may ask."""

    inform: InformWhere = InformWhere.COPRESENT
    speech: Speech = Speech.TURN
    relevance: Relevance = Relevance.NEXT
    ask: bool = True
    inform_max_atoms: int = 3  # largest informing set tried (subsets by increasing size)
    plan_horizon: int = 8  # human steps looked ahead by relevance = "plan"
    robot_asks: bool = False  # the robot may ask the human what it is about to do (§5)
    announce: bool = False  # the robot may announce its own agenda (§5)


@dataclass(frozen=True)
class Steps:
    """``[steps]``: turn-taking (the default) or joint, compliant steps (docs/concurrent.md)."""

    mode: StepMode = StepMode.TURNS
    first: StepFirst = StepFirst.HUMAN  # C4
    witness: Witness = Witness.WHOLE  # C8
    commute: Commute = Commute.STATE  # C3 b
    cost: Fraction | int = 1  # C11: c_step, what one joint step costs

    @property
    def concurrent(self) -> bool:
        """Return whether the agents move in joint steps (C1-C12)."""
        return self.mode == StepMode.CONCURRENT


@dataclass(frozen=True)
class Objective:
    """``[objective]``: the cost a policy minimises, and the tie-breaks after it."""

    kind: ObjectiveKind = ObjectiveKind.WORST_CASE
    # relative weights of human moves for "expected", keyed by move label or action name
    weights: Mapping[str, Fraction] = field(default_factory=dict)
    ties: tuple[TieKey, ...] = DEFAULT_TIES
    # kind = "preferences" (C11): the chosen profile, every named profile, the aggregation
    profile: str = ""
    # each profile's metrics, most important first: a built-in :class:`Metric` or the name of
    # a metric the domain declares (C11)
    profiles: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    estimate: Estimate = Estimate.WORST_CASE

    @property
    def metrics(self) -> tuple[str, ...]:
        """C11: the chosen profile's metrics, most important first (empty unless
        ``kind = "preferences"``): built-in ones as :class:`Metric`, the domain's by name."""
        return tuple(self.profiles.get(self.profile, ()))

    def with_profile(self, name: str) -> Objective:
        """This objective with another of its named profiles chosen (relabelling, C11);
        :class:`KeyError` naming the known ones when ``name`` is not one."""
        if name not in self.profiles:
            raise KeyError(f"no profile {name!r}: the problem names "
                           + (", ".join(sorted(self.profiles)) or "none"))
        return replace(self, profile=name)

    def weight(self, label: str, name: str) -> Fraction:
        """A human move's relative weight: by its label, else its action name, else 1."""
        w = self.weights.get(label)
        if w is None:
            w = self.weights.get("".join(label.split()))
        if w is None:
            w = self.weights.get(name, Fraction(1))
        return w


class _Reader(Protocol):
    def err(self, place: str, problem: str, fix: str = "",
            needle: str | None = None) -> InputError: ...

    def table(self, data: Mapping[str, Any], key: str, allowed: Iterable[str] | None,
              required: bool = False) -> dict[str, Any]: ...


def _choice(r: _Reader, table: str, t: Mapping[str, Any], key: str,
            enum: type[StrEnum], default: StrEnum) -> Any:
    v = t.get(key, default.value)
    values = [e.value for e in enum]
    if v not in values:
        raise r.err(f"[{table}] {key}", f"unknown value {v!r}",
                    "use one of " + ", ".join(f'"{x}"' for x in values), key)
    return enum(v)


def _flag(r: _Reader, place: str, key: str, v: Any) -> bool:
    if not isinstance(v, bool):
        raise r.err(place, f"expected true or false, got {v!r}", "write true or false", key)
    return v


def _count(r: _Reader, place: str, key: str, v: Any) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise r.err(place, f"expected a whole number of at least 1, got {v!r}",
                    "write e.g. 3", key)
    return v


def metric(name: str) -> str:
    """C11: a profile's metric name as the objective keeps it: a built-in :class:`Metric`, or
    the name of one the domain declares."""
    return Metric(name) if name in _BUILT_IN else name


_BUILT_IN = frozenset(m.value for m in Metric)


def known_metrics(domain_metrics: Iterable[str]) -> str:
    """C11: the metrics a profile may name, for a message: the built-in ones, then the
    domain's (``"makespan", ... (built in); "shared_taken" (the domain's)``)."""
    own = sorted(domain_metrics)
    return (", ".join(f'"{m.value}"' for m in Metric) + " (built in)"
            + ("; " + ", ".join(f'"{m}"' for m in own) + " (the domain's)" if own
               else "; the domain declares none"))


def read_options(r: _Reader, data: Mapping[str, Any], domain_metrics: Iterable[str] = ()
                 ) -> tuple[HumanModel, Communication, Objective, tuple[str, ...]]:
    """The ``[human]``, ``[communication]`` and ``[objective]`` tables (and the deprecated
    ``[options]`` spellings, with a one-line note each); a preference profile may name the
    built-in metrics and ``domain_metrics`` (C11)."""
    notes: list[str] = []
    old = r.table(data, "options", OPTION_KEYS["options"])
    h = r.table(data, "human", OPTION_KEYS["human"])
    c = r.table(data, "communication", OPTION_KEYS["communication"])
    o = r.table(data, "objective", OPTION_KEYS["objective"])
    for key, new_table, new_key, target in (
            ("human_passes_when_blocked", "human", "passes_when_blocked", h),
            ("inform_max_atoms", "communication", "inform_max_atoms", c)):
        if key in old:
            if new_key in target:
                raise r.err(f"[options] {key}", f"given twice (also as [{new_table}] "
                            f"{new_key})", "keep only the new spelling", key)
            target[new_key] = old[key]
            notes.append(f"[options] {key} is deprecated: write [{new_table}] {new_key}")
    human = HumanModel(
        _choice(r, "human", h, "passes", Passes, Passes.FAIR),
        _flag(r, "[human] passes_when_blocked", "passes_when_blocked",
              h.get("passes_when_blocked", True)),
        _flag(r, "[human] anticipates", "anticipates", h.get("anticipates", True)),
        _choice(r, "human", h, "intentions", Intentions, Intentions.HIDDEN))
    comm = Communication(
        _choice(r, "communication", c, "inform", InformWhere, InformWhere.COPRESENT),
        _choice(r, "communication", c, "speech", Speech, Speech.TURN),
        _choice(r, "communication", c, "relevance", Relevance, Relevance.NEXT),
        _flag(r, "[communication] ask", "ask", c.get("ask", True)),
        _count(r, "[communication] inform_max_atoms", "inform_max_atoms",
               c.get("inform_max_atoms", 3)),
        _count(r, "[communication] plan_horizon", "plan_horizon", c.get("plan_horizon", 8)),
        _flag(r, "[communication] robot_asks", "robot_asks", c.get("robot_asks", False)),
        _flag(r, "[communication] announce", "announce", c.get("announce", False)))
    weights_t = o.get("weights", {})
    if not isinstance(weights_t, dict):
        raise r.err("[objective] weights", "weights must be a table",
                    "write [objective.weights] with e.g. pass = 0.5", "weights")
    weights: dict[str, Fraction] = {}
    for k, v in weights_t.items():
        if isinstance(v, bool) or not isinstance(v, int | float) or v <= 0:
            raise r.err(f"[objective.weights] {k}", f"expected a positive number, got {v!r}",
                        "give a relative weight greater than 0, e.g. 0.5", k)
        weights["".join(k.split())] = Fraction(str(v))
    ties = o.get("ties", list(DEFAULT_TIES))
    if (not isinstance(ties, list) or not all(isinstance(t, str) for t in ties)
            or any(t not in TIE_KEYS for t in ties) or len(set(ties)) != len(ties)):
        raise r.err("[objective] ties", f"bad tie-breaks {ties!r}",
                    "give distinct names from " + ", ".join(f'"{t}"' for t in TIE_KEYS),
                    "ties")
    kind = _choice(r, "objective", o, "kind", ObjectiveKind, ObjectiveKind.WORST_CASE)
    objective = Objective(kind, weights, tuple(TieKey(t) for t in ties),
                          *_read_profiles(r, data, o, kind, frozenset(domain_metrics)))
    return human, comm, objective, tuple(notes)


def _read_profiles(r: _Reader, data: Mapping[str, Any], o: Mapping[str, Any],
                   kind: ObjectiveKind, domain_metrics: frozenset[str]
                   ) -> tuple[str, dict[str, tuple[str, ...]], Estimate]:
    """C11: ``[objective] profile``, ``estimate`` and ``[objective.profiles]`` (each a list of
    distinct metric names: built in, or ``domain_metrics``); only with ``kind =
    "preferences"``, which needs joint steps."""
    if kind != ObjectiveKind.PREFERENCES:
        for key in ("profile", "profiles", "estimate"):
            if key in o:
                raise r.err(f"[objective] {key}", f'{key} is read only with kind = '
                            '"preferences"', 'write kind = "preferences", or leave '
                            f"{key} out", key)
        return "", {}, Estimate.WORST_CASE
    steps = data.get("steps", {})
    if not isinstance(steps, dict) or steps.get("mode") != "concurrent":
        raise r.err("[objective] kind", 'preference profiles are built for joint steps only',
                    'add [steps] mode = "concurrent", or use kind = "worst-case"', "kind")
    table = o.get("profiles", {})
    if not isinstance(table, dict) or not table:
        raise r.err("[objective] profiles", "no profiles given",
                    'write [objective.profiles] with e.g. hurry = ["makespan", '
                    '"communications"]', "profiles")
    profiles: dict[str, tuple[str, ...]] = {}
    for name, ms in table.items():
        if (not isinstance(ms, list) or not ms or not all(isinstance(m, str) for m in ms)
                or len(set(ms)) != len(ms)):
            raise r.err(f"[objective.profiles] {name}", f"expected a list of distinct metric "
                        f"names, got {ms!r}", 'write e.g. ["makespan", "communications"]',
                        name)
        for m in ms:
            if m not in _BUILT_IN and m not in domain_metrics:
                raise r.err(f"[objective.profiles] {name}", f"unknown metric {m!r}",
                            "use one of " + known_metrics(domain_metrics), m)
        profiles[name] = tuple(metric(m) for m in ms)
    profile = o.get("profile")
    if not isinstance(profile, str) or profile not in profiles:
        raise r.err("[objective] profile", f"expected one of the profiles' names, got "
                    f"{profile!r}", "write e.g. profile = "
                    + repr(sorted(profiles)[0]).replace("'", '"'), "profile")
    return profile, profiles, _choice(r, "objective", o, "estimate", Estimate,
                                      Estimate.WORST_CASE)


# [communication] and [problem] settings joint steps do not read (docs/concurrent.md)
_NOT_CONCURRENT = (
    ("communication", "speech", "with-action",
     "speech is part of a joint step already: leave [communication] speech out"),
    ("communication", "robot_asks", True, "leave [communication] robot_asks out"),
    ("communication", "announce", True, "leave [communication] announce out"),
)


def read_steps(r: _Reader, data: Mapping[str, Any]) -> Steps:
    """Return the ``[steps]`` table (docs/concurrent.md: mode, first, witness, commute, cost);
    a setting joint steps do not support is one error naming it."""
    t = r.table(data, "steps", OPTION_KEYS["steps"])
    cost = t.get("cost", 1)
    if isinstance(cost, bool) or not isinstance(cost, int | float) or cost <= 0:
        raise r.err("[steps] cost", f"expected a positive number, got {cost!r}",
                    "write e.g. cost = 1", "cost")
    steps = Steps(_choice(r, "steps", t, "mode", StepMode, StepMode.TURNS),
                  _choice(r, "steps", t, "first", StepFirst, StepFirst.HUMAN),
                  _choice(r, "steps", t, "witness", Witness, Witness.WHOLE),
                  _choice(r, "steps", t, "commute", Commute, Commute.STATE),
                  cost if isinstance(cost, int) else Fraction(str(cost)))
    if steps.concurrent:
        for table, key, bad, fix in _NOT_CONCURRENT:
            if data.get(table, {}).get(key) == bad:
                raise r.err(f"[{table}] {key}", f"{key} = {bad!r} is not supported with "
                            '[steps] mode = "concurrent"', fix, key)
    return steps


__all__ = ["DEFAULT_TIES", "OPTION_KEYS", "TIE_KEYS", "Commute", "Communication", "Estimate",
           "HumanModel", "InformWhere", "Intentions", "Metric", "Objective", "ObjectiveKind",
           "Passes", "Relevance", "Speech", "StepFirst", "StepMode", "Steps", "TieKey",
           "Witness", "known_metrics", "metric", "read_options", "read_steps"]
