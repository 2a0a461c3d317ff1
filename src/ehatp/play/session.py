"""One session of ``ehatp play``: a person plays the human against the robot's policy.

Pure Python, no web: :class:`PlaySession` follows the policy with an
:class:`~ehatp.run.executor.Executor` (the robot's side), and says what the participant sees --
the human's perspective only (:func:`perspective`; docs/semantics.md §2-§5): the facts true in
every world the human entertains, the units its worlds disagree on, what it sees now, what the
robot says, and the robot's actions only when they are co-present -- and what the experimenter
sees (the truth, the policy node, the worlds, the robot's hypotheses). A participant's move the
policy does not cover, but the human can make, is applied and the robot plans again from there
with :meth:`Executor.replan`, as ``ehatp execute --replan`` does (docs/execution.md). On a
preferences problem (docs/concurrent.md C11) the experimenter may switch the robot's profile
mid-session (:meth:`PlaySession.switch_profile`): the explored graph kept at the start (and a
replan's own) is relabelled from the current state, without a new search, at a step's start;
a switch asked in the middle of a step waits for its end.

Every session writes a log, one JSON object a line, flushed line by line (docs/play.md, "The
log"): its start (session id, problem and policy hashes), every move, every message the
participant was shown, every replan, every profile switch, the participant's beliefs after
every step, its end.
:func:`replay` plays a log's choices again and compares every record: the same problem and
policy give the same records, apart from times and session ids.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import threading
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, Protocol

from .. import __version__
from ..epistemic.semantics import (
    ACTION,
    ANNOUNCE,
    ANSWER,
    ASK,
    INFORM,
    PASS,
    SILENCE,
    WAIT,
    Move,
)
from ..epistemic.state import states_of
from ..errors import ExecutionError, InputError, UncoveredHumanAction
from ..formats.policy import Policy, label_key, num
from ..model.options import ObjectiveKind, StepFirst
from ..model.problem import Problem, call_str
from ..model.vocabulary import HUMAN
from ..run.execute import beliefs
from ..run.executor import Executor
from ..run.step import Step
from .views import Perspective, Scene, Unsure, ViewHook, check_scene, predicate_of

if TYPE_CHECKING:
    from ..search.planner import Relabeler

LOG_TAIL = 200  # the records an experimenter view carries
# what the robot signals at the start of a joint step (docs/play.md, "Joint steps"), by key
SIGNALS = {"parallel": "You can act in parallel", "act": "Act if you will",
           "passive": "I will be passive this step"}
# what differs between a session and its replay (``played`` is derived from the move, and
# logs written before it was recorded replay all the same)
IGNORED_IN_REPLAY = ("t", "session", "played")
NOT_REPLAYED = ("connection",)  # records of the browser, not of the play


def sha256(data: bytes | str) -> str:
    """Return ``sha256:<hex>`` of ``data`` (text as UTF-8)."""
    raw = data.encode("utf-8") if isinstance(data, str) else data
    return "sha256:" + hashlib.sha256(raw).hexdigest()


def policy_hash(policy: Policy) -> str:
    """Return the hash of ``policy``'s JSON as ehatp writes it (the same for a policy read
    from a file and the one ``ehatp solve`` wrote there)."""
    return sha256(policy.to_json())


def now() -> str:
    """Return the time now, UTC, to the millisecond (ISO 8601)."""
    return datetime.now(UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z")


# --- the log -----------------------------------------------------------------------------------


class Log(Protocol):
    def write(self, record: dict[str, Any]) -> None: ...


class FileLog:
    """A session's log file: one JSON object a line, each flushed as it is written, so a
    crash loses nothing already logged. The file is created (never overwritten)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._f: IO[str] | None = path.open("x", encoding="utf-8")

    def write(self, record: dict[str, Any]) -> None:
        if self._f is None:
            return
        self._f.write(json.dumps(record, ensure_ascii=False) + "\n")
        self._f.flush()

    def close(self) -> None:
        if self._f is not None:
            self._f.close()
            self._f = None


class MemoryLog:
    """A log kept in memory (replays, tests)."""

    def __init__(self) -> None:
        self.records: list[dict[str, Any]] = []

    def write(self, record: dict[str, Any]) -> None:
        self.records.append(record)


# --- what the human perceives ------------------------------------------------------------------


def perspective(ex: Executor, objects: dict[str, list[str]] | None = None) -> Perspective:
    """Return the situation as the human perceives it now (docs/semantics.md §2-§3): the facts
    true in every world it entertains, the units its worlds disagree on with the values they
    take, the facts it sees in the true state (visible units, its value; only what the worlds
    already agree on after situation assessment), the facts no action changes, and whether the
    robot is in sight."""
    g, sem, es = ex.grounded, ex.sem, ex.state
    states = states_of(es.worlds)
    first, every, some = states[0], -1, 0
    for s in states:
        every &= s
        some |= s
    differ = every ^ some
    full = (1 << len(g.atoms)) - 1
    believed: list[str] = []
    unsure: list[Unsure] = []
    seeing: list[str] = []
    t, vis = es.true, sem.visible(es.true)
    for u in g.units(full):
        whole = u in g.unit_names  # a state variable or a counter
        if differ & u:
            if whole:
                unsure.append(Unsure(g.unit_names[u], tuple(sorted({g.fact(s, u)
                                                                     for s in states}))))
            else:
                atom = g.atoms[u.bit_length() - 1]
                unsure.append(Unsure(atom, (atom, f"not {atom}")))
            continue
        if whole:
            believed.append(g.fact(first, u))
        elif first & u:
            believed.append(g.atoms[u.bit_length() - 1])
        if g.is_counter(u):  # seen whole (§2)
            if vis & u == u:
                seeing.append(g.fact(t, u))
        elif vis & u & t:  # an atom, or a variable's value, true and in sight
            seeing.append(g.fact(t, u) if whole else g.atoms[u.bit_length() - 1])
    return Perspective(ex.human_name, ex.robot_name, tuple(believed), tuple(unsure),
                       tuple(seeing), fixed_facts(ex), sem.copresent(t),
                       objects if objects is not None else ex.problem.all_objects())


def fixed_facts(ex: Executor) -> tuple[str, ...]:
    """Return the initial facts of predicates no action changes (folded away by grounding,
    docs/semantics.md §1): every world holds them, so the human believes them."""
    g = ex.grounded
    fluent = {predicate_of(a) for a in g.atoms} | {predicate_of(n)
                                                   for n in g.unit_names.values()}
    d = ex.problem.domain
    out = []
    for name, args in ex.problem.init:
        if name in fluent:
            continue
        if name in d.variables or name in d.counters:
            out.append(f"{call_str(name, args[:-1])} = {args[-1]}")
        else:
            out.append(call_str(name, args))
    return tuple(sorted(out))


def grouped(facts: Iterable[str], seeing: Iterable[str] = ()) -> list[dict[str, Any]]:
    """Return facts grouped by predicate, in order of first appearance, each marked ``seen``
    when it is among ``seeing``."""
    seen = set(seeing)
    out: dict[str, list[dict[str, Any]]] = {}
    for f in facts:
        out.setdefault(predicate_of(f), []).append({"text": f, "seen": f in seen})
    return [{"predicate": p, "facts": fs} for p, fs in out.items()]


def move_text(m: Move, label: str, robot: str) -> str:
    """Return a human move as the participant's button says it."""
    if m.kind == PASS:
        return "Wait (do nothing)"
    if m.kind == ASK:
        return f"Ask {robot}: {label[len('ask('):-1]}?"
    if m.kind == ANSWER:
        inner = label[label.find("(") + 1:-1] if "(" in label else ""
        return f"Tell {robot} you will do: {inner or 'nothing more'}"
    return label


def robot_signal(ex: Executor) -> str | None:
    """Return the key of :data:`SIGNALS` the robot shows at the start of a joint step where the
    human decides first (None elsewhere: turns, the robot first, the opening, the robot to
    move, done), derived from the policy's replies at the node (docs/concurrent.md, C4):

    - ``parallel``: the robot acts beside some action of the human (a reply that is an action
      to a human move that is not ``pass``);
    - ``act``: otherwise, the robot acts only if the human passes (it yields to any action);
    - ``passive``: every reply is ``wait`` (the robot will not act this step)."""
    st = ex.problem.steps
    if (not st.concurrent or st.first != StepFirst.HUMAN or ex.node is None
            or ex.done or ex.state.turn != HUMAN):
        return None
    beside = after_pass = False
    for a in ex.expected_human_actions():
        other = ex.copy()
        other.observe_human_action(a)
        reply = other.next_robot_action()
        if reply is None or reply.kind != ACTION:
            continue
        if a.kind == PASS:
            after_pass = True
        else:
            beside = True
    return "parallel" if beside else "act" if after_pass else "passive"


# --- a session ---------------------------------------------------------------------------------


@dataclass
class FeedEntry:
    """One thing the participant was shown happening."""

    step: int | None
    kind: str  # you | robot | hidden | speech | answer | question | end
    text: str

    def to_dict(self) -> dict[str, Any]:
        return {"step": self.step, "kind": self.kind, "text": self.text}


@dataclass
class Source:
    """Where a session's problem and policy come from, as its log records it."""

    problem_file: str
    problem_hash: str
    policy_file: str | None
    policy_hash: str
    view: str = "default"
    extra: dict[str, Any] = field(default_factory=dict)


class PlaySession:
    """One participant playing the human of ``problem`` against ``policy``; every record
    goes to ``log``. Call :meth:`start` first, then :meth:`robot_step` while
    :attr:`robot_to_move`, and :meth:`choose` with the participant's moves.
    ``decision_timeout`` (seconds; joint steps only): the participant's page counts it down at
    each decision where the human may pass, and :meth:`timeout` plays ``pass`` when it ends.
    ``graph`` (a preferences problem, docs/concurrent.md C11): the explored graph
    ``solve(problem, keep_graph=True)`` kept, which :meth:`switch_profile` relabels; a replan
    keeps its own."""

    def __init__(self, problem: Problem, policy: Policy, source: Source, *, session_id: str,
                 log: Log, view: ViewHook | None = None,
                 clock: Callable[[], str] = now, decision_timeout: float | None = None,
                 graph: Relabeler | None = None) -> None:
        if decision_timeout is not None and not decision_timeout > 0:
            raise ValueError(f"decision_timeout is a number of seconds above 0, "
                             f"got {decision_timeout!r}")
        self.decision_timeout = decision_timeout if problem.steps.concurrent else None
        self.ex = Executor(problem, policy)
        self.problem, self.policy = problem, policy  # as given: a replan changes the executor's
        self.source, self.id, self.log, self.view, self.clock = source, session_id, log, view, clock
        self.objects = problem.all_objects()
        self.task = [call_str(n, a) for n, a in problem.human_agenda]
        self.feed: list[FeedEntry] = []
        self.outcome: str | None = None  # goal | failed | no-policy | dead-end
        self.replans = 0
        self.graph = graph
        self.switches = 0  # profile switches made
        self.queued: str | None = None  # a switch asked mid-step, made at the step's end
        self.seq = 0
        self.tail: deque[dict[str, Any]] = deque(maxlen=LOG_TAIL)
        self.started = False
        self._write = threading.Lock()  # the server logs connections from another thread

    # -- where we are ---------------------------------------------------------------------------
    @property
    def over(self) -> bool:
        return self.outcome is not None

    @property
    def robot_to_move(self) -> bool:
        return not self.over and self.ex.next_robot_action() is not None

    @property
    def human_to_move(self) -> bool:
        return not self.over and self.started and self.ex.to_move == self.ex.human_name

    # -- the log --------------------------------------------------------------------------------
    def record(self, type_: str, /, **fields: Any) -> dict[str, Any]:
        """Write one record to the log: time, session id, sequence number, type, fields."""
        with self._write:
            self.seq += 1
            rec = {"t": self.clock(), "session": self.id, "seq": self.seq, "type": type_,
                   **fields}
            self.log.write(rec)
            self.tail.append(rec)
        return rec

    def connection(self, event: str, role: str) -> None:
        """Log that a page opened or closed (not replayed: the browser's, not the play's)."""
        self.record("connection", event=event, role=role)

    def _say(self, entry: FeedEntry) -> None:
        self.feed.append(entry)
        self.record("message", to="participant", step=entry.step, kind=entry.kind,
                    text=entry.text)

    def _beliefs(self) -> None:
        p = perspective(self.ex, self.objects)
        self.record("beliefs", step=len(self.ex.history), believed=list(p.believed),
                    unsure=[{"name": u.name, "options": list(u.options)} for u in p.unsure],
                    seeing=list(p.seeing), robot_here=p.robot_here,
                    robot_tasks=self._robot_tasks())

    # -- playing --------------------------------------------------------------------------------
    def start(self) -> None:
        """Log the start, play the problem's fixed opening as moves already made, and say
        what the human perceives."""
        ex, src = self.ex, self.source
        self.record("start", ehatp=__version__, problem=ex.problem.name,
                    domain=ex.problem.domain.name, problem_file=src.problem_file,
                    problem_hash=src.problem_hash, policy_file=src.policy_file,
                    policy_hash=src.policy_hash, policy_cost=num(ex.policy.cost),
                    policy_nodes=len(ex.policy.nodes), human=ex.human_name,
                    robot=ex.robot_name, task=self.task, view=src.view, **src.extra,
                    **({"decision_timeout": self.decision_timeout}
                       if ex.problem.steps.concurrent else {}))
        self.started = True
        for step in ex.replay_opening():
            self._stepped(step, covered=True)
        if not ex.history:
            self._beliefs()
        self._next()

    def robot_step(self) -> Step | None:
        """Play the robot's next move (None when it is not the robot's turn)."""
        if not self.robot_to_move:
            return None
        step = self.ex.robot_action_done()
        self._stepped(step, covered=True)
        self._next()
        return step

    def run_robot(self) -> None:
        """Play the robot's moves until the participant is to move or the session is over."""
        while self.robot_step() is not None:
            pass

    def timed_pass(self) -> str | None:
        """The label of the ``pass`` a decision timeout would play now (None: no timer now --
        not joint steps, no timeout set, not the participant's decision, or it may not pass)."""
        if self.decision_timeout is None or not self.human_to_move:
            return None
        return next((m.label for m in self.ex.legal_human_moves() if m.kind == PASS), None)

    def timeout(self, step: int) -> str:
        """The participant's decision at ``step`` (moves played so far) timed out: play
        ``pass`` as :meth:`choose` does and return what it returns; ``stale`` (nothing
        logged, nothing changes) when the decision at ``step`` is not the current one or has
        no timer."""
        label = self.timed_pass()
        if label is None or step != len(self.ex.history):
            return "stale"
        self.record("timeout", step=step, seconds=self.decision_timeout)
        return self.choose(label, timeout=True)

    def choose(self, label: str, *, timeout: bool = False) -> str:
        """Play the participant's move ``label`` (one of :meth:`moves`); return ``played``,
        ``replanned``, ``failed``, ``no-policy`` or ``rejected`` (not a move of the human now:
        nothing changes). ``timeout``: the move is a timed-out decision's ``pass``."""
        self.record("choice", move=label, **({"timeout": True} if timeout else {}))
        ex = self.ex
        if not self.human_to_move:
            self.record("rejected", move=label, reason="it is not the participant's turn")
            return "rejected"
        try:
            step = ex.observe_human_action(label)
        except UncoveredHumanAction as e:
            move = next((m for m in ex.legal_human_moves()
                         if label_key(m.label) == label_key(e.action)), None)
            if move is None:
                self.record("rejected", move=label, reason=e.reason)
                return "rejected"
            if move.child is None:  # acting on a false belief (§4): the branch fails
                self._say(FeedEntry(len(ex.history) + 1, "end",
                                    f"You try {move.label}, but it cannot be done."))
                self._end("failed", move=move.label, reason=move.failure)
                return "failed"
            return self._replan(move.label)
        self._stepped(step, covered=True)
        self._next()
        return "played"

    def _replan(self, label: str) -> str:
        ex = self.ex
        try:
            # as `ehatp execute --replan` does (docs/execution.md); a preferences problem's
            # replan keeps its own graph, which holds the states from here (C11)
            result = ex.replan(label, **({"keep_graph": True} if self.preferences else {}))
        except ExecutionError as e:
            self.record("replan", move=label, after=len(ex.history), status="no-policy",
                        reason=str(e))
            self._end("no-policy", move=label)
            return "no-policy"
        assert result.policy is not None
        if result.graph is not None:
            self.graph = result.graph
        self.replans += 1
        stats = result.stats
        self.record("replan", move=label, after=len(ex.history), status=result.status,
                    cost=num(result.policy.cost), nodes=len(result.policy.nodes),
                    distinct=stats.get("distinct"), generated=stats.get("generated"),
                    policy_hash=policy_hash(result.policy))
        self._stepped(ex.history[-1], covered=False)
        self._next()
        return "replanned"

    def _stepped(self, step: Step, covered: bool) -> None:
        ex = self.ex
        a = step.action
        witnessed = a.agent == ex.human_name or ex.sem.copresent(step.before.true)
        self.record("step", index=step.index, agent=a.agent, move=a.label, played=step.played,
                    kind=str(a.kind),
                    cost=num(a.cost), total=num(ex.cost),
                    node=None if step.node is None else step.node.id, opening=step.opening,
                    covered=covered, replanned=step.replanned, witnessed=witnessed)
        for entry in self._feed_of(step, witnessed):
            self._say(entry)
        self._beliefs()

    def _feed_of(self, step: Step, witnessed: bool) -> list[FeedEntry]:
        """What the participant perceives of ``step`` (docs/semantics.md §4-§5): its own
        moves; the robot's actions and waits only when co-present; what the robot says,
        always (it is said only where the human hears it)."""
        ex, a, n = self.ex, step.action, step.index
        R = ex.robot_name
        out: list[FeedEntry] = []
        if a.agent == ex.human_name:
            if a.kind == ASK:
                out.append(FeedEntry(n, "you", f"You ask {R}: {a.args[0]}?"))
                answer = ex.answer(step.before, a.label)
                if answer is not None:
                    out.append(FeedEntry(n, "answer", f"{R} answers: "
                                         + ("yes" if answer else "no")))
            elif a.kind == PASS:
                out.append(FeedEntry(n, "you", "You wait."))
            elif a.kind == ANSWER:
                out.append(FeedEntry(n, "you", "You tell " + R + " you will do: "
                                     + (", ".join(ex.sem.net.names_of(
                                         step.after.human_agendas[0])) or "nothing more")))
            else:
                out.append(FeedEntry(n, "you", f"You: {a.label}"))
            return out
        if a.kind in (ACTION, WAIT):
            if witnessed:
                out.append(FeedEntry(n, "robot", f"{R} waits." if a.kind == WAIT
                                     else f"{R}: {a.name}" + (f"({', '.join(a.args)})"
                                                              if a.args else "")))
            else:
                out.append(FeedEntry(n, "hidden", f"{R} is out of sight."))
            if a.told:
                out.append(FeedEntry(n, "speech", f"{R} says: {', '.join(a.told)}"))
        elif a.kind == INFORM:
            out.append(FeedEntry(n, "speech", f"{R} says: {', '.join(a.args)}"))
        elif a.kind == ANNOUNCE:
            out.append(FeedEntry(n, "speech", f"{R} says it will do: "
                                 + (", ".join(ex.sem.net.names_of(step.before.robot_agenda))
                                    or "nothing more")))
        elif a.kind == ASK:
            out.append(FeedEntry(n, "question", f"{R} asks: what are you about to do?"))
        elif a.kind != SILENCE:
            out.append(FeedEntry(n, "robot", f"{R}: {a.label}"))
        return out

    def _next(self) -> None:
        """After a move: a switch asked mid-step, now that the step is over; then the end, or
        the participant's options when it is its turn."""
        ex = self.ex
        if self.queued is not None and not ex.state.pending:
            name, self.queued = self.queued, None
            if ex.done:
                self.record("switch-refused", profile=name, step=len(ex.history),
                            reason="the task is done: there is nothing left to relabel")
            else:
                self._switch(name)
        if ex.done:
            self._end("goal" if ex.goal_reached else "dead-end")
        elif ex.state.turn == HUMAN:
            expected = {label_key(a.label) for a in ex.expected_human_actions()}
            joint: dict[str, Any] = {}
            if ex.problem.steps.concurrent:  # turns' records stay as they were
                joint = {"signal": robot_signal(ex),
                         "timeout": self.decision_timeout if self.timed_pass() else None}
            self.record("offer", step=len(ex.history),
                        moves=[m.label for m in ex.legal_human_moves()],
                        covered=[m.label for m in ex.legal_human_moves()
                                 if label_key(m.label) in expected], **joint)

    def _end(self, outcome: str, **fields: Any) -> None:
        ex = self.ex
        self.outcome = outcome
        if outcome == "goal":
            self._say(FeedEntry(None, "end", "The task is done."))
        elif outcome != "failed":
            self._say(FeedEntry(None, "end", "The session is over."))
        self.record("end", outcome=outcome, steps=len(ex.history), cost=num(ex.cost),
                    truth=ex.truth(), worlds=len(ex.state.worlds), **fields)

    # -- the robot's preference profile (docs/concurrent.md C11) ------------------------------
    @property
    def preferences(self) -> bool:
        """Whether the problem is a preferences problem (its robot's profile can switch)."""
        return self.problem.objective.kind == ObjectiveKind.PREFERENCES

    def profile(self) -> str | None:
        """The profile the robot follows now (None: no preferences problem)."""
        return self.ex.problem.objective.profile if self.preferences else None

    def switch_profile(self, name: str) -> str:
        """The experimenter switches the robot to preference profile ``name`` (the
        participant's true one, learnt during the task; C11): from the next decision on, the
        robot follows the policy ``name`` prefers, relabelled from the current state on the
        kept graph (:meth:`Executor.switch_profile`; no new search). The participant is told
        nothing; only the robot's replies, and its signals, may change.

        Returns ``switched``; ``queued`` when it comes in the middle of a joint step (the
        human's reply to the robot's move is due, steps where the robot decides first): the
        step's first move was chosen under the old profile and its reply is due, so the switch
        is made when the step ends, before the next one; or ``refused`` (one record with the
        reason, nothing changes): not a preferences problem, no such profile, no graph kept,
        the session not started or over. The request is logged (``switch``) and replayed;
        the switch made is logged (``profile``: the profile, the step, the new policy's hash,
        its root vector)."""
        self.record("switch", profile=name)
        why = self._cannot_switch(name)
        if why is not None:
            self.record("switch-refused", profile=name, step=len(self.ex.history), reason=why)
            return "refused"
        if self.ex.state.pending:
            self.queued = name
            self.record("switch-queued", profile=name, step=len(self.ex.history))
            return "queued"
        return "switched" if self._switch(name) else "refused"

    def _cannot_switch(self, name: str) -> str | None:
        """Why the robot cannot switch to profile ``name`` now (None: it can, now or at the
        step's end)."""
        obj = self.ex.problem.objective
        if not self.preferences:
            return (f"cannot switch to profile {name!r}: the problem's [objective] kind is "
                    f'"{obj.kind.value}", not "preferences" with [objective.profiles]')
        if name not in obj.profiles:
            return f"no profile {name!r}: the problem names " + ", ".join(sorted(obj.profiles))
        if self.graph is None:
            return ("no explored graph is kept (the search at the start stopped at a limit, "
                    "or the session was given none): the profile cannot be relabelled")
        if not self.started:
            return "the session has not started"
        if self.over:
            return f"the session is over ({self.outcome})"
        return None

    def _switch(self, name: str) -> bool:
        """Switch now (at a step's start); log it; False (logged as refused) when the executor
        refuses (e.g. the current state is not in the kept graph)."""
        ex = self.ex
        assert self.graph is not None
        try:
            policy = ex.switch_profile(self.graph, name)
        except ExecutionError as e:
            self.record("switch-refused", profile=name, step=len(ex.history), reason=str(e))
            return False
        self.switches += 1
        self.record("profile", profile=name, step=len(ex.history),
                    policy_hash=policy_hash(policy), cost=num(policy.cost),
                    nodes=len(policy.nodes), metrics=list(policy.objective["metrics"]),
                    value=list(policy.objective["value"]))
        return True

    # -- what each side sees ------------------------------------------------------------------
    def _robot_tasks(self) -> list[list[str]]:
        """The robot agendas the human's worlds attribute to the robot (one when it is sure)."""
        net = self.ex.sem.net
        return [list(x) for x in sorted({tuple(net.names_of(ag)) for _, ag in
                                         self.ex.state.worlds})]

    def moves(self) -> list[dict[str, str]]:
        """Return the participant's moves now: every move the human can make
        (:meth:`Executor.legal_human_moves`), covered by the policy or not."""
        if not self.human_to_move:
            return []
        return [{"label": m.label, "kind": str(m.kind),
                 "text": move_text(m, m.label, self.ex.robot_name)}
                for m in self.ex.legal_human_moves()]

    def status(self) -> str:
        if self.over:
            return "goal" if self.outcome == "goal" else "over"
        return "your-turn" if self.human_to_move else "robot-turn"

    def scene(self, p: Perspective) -> Scene | None:
        return None if self.view is None else check_scene(self.view(p))

    def participant_view(self) -> dict[str, Any]:
        """Return what the participant's page shows: the human's perspective only."""
        p = perspective(self.ex, self.objects)
        return {"session": self.id, "you": p.human, "robot": p.robot, "task": self.task,
                "status": self.status(), "outcome": self.outcome, "robot_here": p.robot_here,
                "step": len(self.ex.history),
                "believed": grouped(p.believed, p.seeing), "fixed": grouped(p.fixed),
                "unsure": [{"predicate": predicate_of(u.name), "name": u.name,
                            "options": list(u.options)} for u in p.unsure],
                "robot_tasks": self._robot_tasks(), "scene": self.scene(p),
                "feed": [e.to_dict() for e in self.feed], "moves": self.moves(),
                **self._joint_view()}

    def _joint_view(self) -> dict[str, Any]:
        """Joint steps only: the robot's signal at the participant's decision (its key and
        text; None elsewhere) and the decision's timer (seconds; None: no timer now)."""
        if not self.ex.problem.steps.concurrent:
            return {}
        key = robot_signal(self.ex) if self.human_to_move else None
        return {"signal": None if key is None else {"key": key, "text": SIGNALS[key]},
                "timer": self.decision_timeout if self.timed_pass() else None}

    def experimenter_view(self) -> dict[str, Any]:
        """Return what the experimenter's page shows: the truth, the policy node, the human's
        worlds, the robot's hypotheses about the human, every move and the log's tail."""
        ex = self.ex
        es = ex.state
        net = ex.sem.net
        expected = {label_key(a.label) for a in ex.expected_human_actions()}
        return {
            "session": self.id, "problem": ex.problem.name, "source": self.source.__dict__,
            "policy": {"cost": num(ex.policy.cost), "nodes": len(ex.policy.nodes),
                       "replans": self.replans},
            "node": None if ex.node is None else ex.node.id, "status": self.status(),
            "outcome": self.outcome, "to_move": ex.to_move, "k": es.k, "K": ex.sem.K,
            "copresent": ex.sem.copresent(es.true), "truth": ex.truth(),
            "beliefs": beliefs(ex), "robot_agenda": net.names_of(es.robot_agenda),
            "hypotheses": [net.names_of(h) for h in es.human_agendas],
            "moves": [{"label": m.label, "covered": label_key(m.label) in expected,
                       "fails": m.child is None} for m in ex.legal_human_moves()],
            "robot_next": (None if (a := ex.next_robot_action()) is None else a.label),
            "history": [{"index": s.index, "agent": s.action.agent, "move": s.action.label,
                         "node": None if s.node is None else s.node.id,
                         "opening": s.opening, "replanned": s.replanned}
                        for s in ex.history],
            "profiles": None if not self.preferences else {
                "current": self.profile(), "names": sorted(ex.problem.objective.profiles),
                "queued": self.queued, "switches": self.switches,
                "can_switch": self.graph is not None and not self.over},
            "log": list(self.tail), "participant": self.participant_view()}


# --- replay --------------------------------------------------------------------------------------


def read_log(path: Path) -> list[dict[str, Any]]:
    """Return the records of a session log; :class:`InputError` (``file:line``) on a line
    that is not a JSON object, or a log with no ``start`` record first."""
    out = []
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(str(path), "", f"cannot read ({getattr(e, 'strerror', None) or e})",
                         "give the log file of an `ehatp play` session") from None
    for i, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
        except json.JSONDecodeError as e:
            if i == len(text.splitlines()):  # a last line cut short by a crash
                break
            raise InputError(str(path), f"line {i}", f"not JSON ({e.msg})",
                             "give the log file of an `ehatp play` session") from None
        if not isinstance(rec, dict) or not isinstance(rec.get("type"), str):
            raise InputError(str(path), f"line {i}", "not a log record",
                             "give the log file of an `ehatp play` session")
        out.append(rec)
    if not out or out[0]["type"] != "start":
        raise InputError(str(path), "line 1", "no start record",
                         "give the log file of an `ehatp play` session")
    return out


def comparable(records: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """Return the records a replay must reproduce: all but the browser's, without times,
    session ids and the files' paths (their hashes are compared)."""
    out = []
    for r in records:
        if r.get("type") in NOT_REPLAYED:
            continue
        c = {k: v for k, v in r.items() if k not in IGNORED_IN_REPLAY and k != "seq"}
        if c.get("type") == "start":
            c.pop("problem_file", None)
            c.pop("policy_file", None)
        out.append(c)
    return out


@dataclass
class ReplayReport:
    """What :func:`replay` found: ``ok`` when the replay wrote the log's records again;
    ``mismatch`` the first record that differs (its number among the compared records, the
    log's, the replay's); ``session`` the replayed session, at its end."""

    ok: bool
    session: PlaySession
    records: int
    mismatch: tuple[int, dict[str, Any] | None, dict[str, Any] | None] | None = None

    def __str__(self) -> str:
        s = self.session
        end = (f"{s.outcome} after {len(s.ex.history)} steps, cost {num(s.ex.cost)}"
               if s.outcome else f"not over, {len(s.ex.history)} steps")
        if self.ok:
            return f"replay matches the log ({self.records} records): {end}"
        assert self.mismatch is not None
        i, old, new = self.mismatch
        return (f"replay differs from the log at record {i + 1}: the log has "
                f"{json.dumps(old, ensure_ascii=False)}, the replay "
                f"{json.dumps(new, ensure_ascii=False)}")


def replay(records: list[dict[str, Any]], problem: Problem, policy: Policy, source: Source,
           view: ViewHook | None = None, graph: Relabeler | None = None) -> ReplayReport:
    """Play the participant's choices of ``records`` (a session's log) again, on ``problem``
    and ``policy`` (those of the log: the caller checks the hashes), with the experimenter's
    profile switches where the log asked them (``graph``: the kept graph, searched again as
    the session did), and compare every record the replay writes with the log's
    (:func:`comparable`)."""
    start = records[0]
    source = dataclasses.replace(source, view=str(start.get("view", source.view)))
    log = MemoryLog()
    timeout = start.get("decision_timeout")
    session = PlaySession(problem, policy, source, session_id=str(start.get("session", "")),
                          log=log, view=view,
                          decision_timeout=float(timeout) if timeout is not None else None,
                          graph=graph)
    session.start()
    session.run_robot()
    for r in records:
        if r["type"] == "timeout":
            session.timeout(int(r.get("step", -1)))
            session.run_robot()
        elif r["type"] == "choice" and not r.get("timeout"):  # a timeout's is replayed above
            session.choose(str(r.get("move", "")))
            session.run_robot()
        elif r["type"] == "switch":
            session.switch_profile(str(r.get("profile", "")))
            session.run_robot()
    want, got = comparable(records), comparable(log.records)
    for i, (a, b) in enumerate(zip(want, got, strict=False)):
        if a != b:
            return ReplayReport(False, session, len(want), (i, a, b))
    if len(want) != len(got):
        i = min(len(want), len(got))
        return ReplayReport(False, session, len(want),
                            (i, want[i] if i < len(want) else None,
                             got[i] if i < len(got) else None))
    return ReplayReport(True, session, len(want))


__all__ = ["FeedEntry", "FileLog", "Log", "MemoryLog", "PlaySession", "ReplayReport",
           "Source", "comparable", "fixed_facts", "grouped", "perspective", "policy_hash",
           "SIGNALS", "read_log", "replay", "robot_signal", "sha256"]
