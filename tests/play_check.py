"""What the tests of ``ehatp play`` share: the branches of a policy as the participant's moves,
and the check that a participant was shown nothing the human cannot perceive -- written here
from docs/semantics.md §2-§5, not from ehatp.play's code.

The rule: a fact shown as believed (or seen, or always so) holds in every world the human
entertains; a fact shown as unsure differs between them; a fact shown as seen is visible in the
true state and true there; the robot's actions are shown only when the human witnessed them
(co-present before the move), a robot turn out of sight only as such.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ehatp.epistemic.state import states_of
from ehatp.play.session import policy_hash
from ehatp.run.executor import Executor

PROBLEMS = {
    "p2": "examples/cubes/p2.toml",
    "p4": "examples/cubes/p4.toml",
    "sally-inform": "examples/sally-anne/inform.toml",
    "sally-defer": "examples/sally-anne/defer.toml",
}


def branches(ex: Executor, cap: int = 200) -> list[list[str]]:
    """Return every branch of the policy ``ex`` follows, as the participant's moves in order
    (each a move the policy covers), depth first."""
    ex = ex.copy()
    ex.replay_opening()
    out: list[list[str]] = []

    def walk(e: Executor, path: list[str]) -> None:
        while not e.done and e.next_robot_action() is not None:
            e.robot_action_done()
        if e.done:
            out.append(path)
            return
        for a in e.expected_human_actions():
            if len(out) >= cap:
                return
            f = e.copy()
            f.observe_human_action(a.label)
            walk(f, [*path, a.label])

    walk(ex, [])
    return out


def _bits(ex: Executor, fact: str) -> int | None:
    """The mask of ``fact`` (an atom, or a variable's ``x = v``), None when it is no fluent."""
    i = ex.grounded.atom_index.get(fact)
    if i is not None:
        return 1 << i
    return next((u for u, name in ex.grounded.unit_names.items() if name == fact), None)


def leaks(ex: Executor, shown: list[dict[str, str]], feed: list[dict[str, Any]]) -> list[str]:
    """Return every way ``shown`` (facts as ``{"fact", "status"}``, status ``believed``,
    ``seen``, ``fixed`` or ``unsure``) and ``feed`` (entries ``{"kind", "text"}``) tell the
    participant more than the human of ``ex`` (now) perceives; empty when nothing."""
    es = ex.state
    states = states_of(es.worlds)
    t = es.true
    vis = ex.sem.visible(t)
    bad: list[str] = []
    static = {f"{n}({', '.join(a)})" if a else n for n, a in ex.problem.init}
    for item in shown:
        fact, status = item["fact"], item["status"]
        m = _bits(ex, fact)
        if status in ("believed", "seen", "fixed"):
            if m is None:
                if fact not in static:
                    bad.append(f"{fact} shown as {status} but is no fact of the problem")
            elif not all(s & m for s in states):
                bad.append(f"{fact} shown as {status} but some world of the human denies it")
            if status == "seen" and (m is None or not (vis & m and t & m)):
                bad.append(f"{fact} shown as seen but the human does not see it")
        elif status == "unsure":
            if m is None or len({s & m for s in states}) < 2:
                bad.append(f"{fact} shown as unsure but the human's worlds agree on it")
        else:
            bad.append(f"{fact}: unknown status {status}")
    # the robot's moves: witnessed ones by name, unseen ones only as "out of sight"
    R = ex.robot_name
    want_robot = []
    for step in ex.history:
        a = step.action
        if a.agent == R and a.kind in ("action", "wait"):
            if ex.sem.copresent(step.before.true):
                want_robot.append(f"{R} waits." if a.kind == "wait"
                                  else f"{R}: {a.name}({', '.join(a.args)})" if a.args
                                  else f"{R}: {a.name}")
            else:
                want_robot.append("hidden")
    got_robot = [e["text"] if e["kind"] == "robot" else "hidden" for e in feed
                 if e["kind"] in ("robot", "hidden")]
    if got_robot != want_robot:
        bad.append(f"the robot's moves shown {got_robot}, perceivable {want_robot}")
    return bad


def view_facts(view: dict[str, Any]) -> list[dict[str, str]]:
    """Return the facts of a participant view (the JSON the page receives) as :func:`leaks`
    reads them."""
    out = []
    for g in view["believed"]:
        out += [{"fact": f["text"], "status": "seen" if f["seen"] else "believed"}
                for f in g["facts"]]
    for g in view["fixed"]:
        out += [{"fact": f["text"], "status": "fixed"} for f in g["facts"]]
    out += [{"fact": u["name"], "status": "unsure"} for u in view["unsure"]]
    return out


def make_hub(problem: Path, log_dir: Path, policy_of: Path | None = None) -> Any:
    """Return a server hub whose sessions play ``problem`` (with the policy solved for
    ``policy_of``, default ``problem``'s own), each logging to its file in ``log_dir``."""
    from ehatp.play.files import load_setup, session_log
    from ehatp.play.server import Hub
    from ehatp.play.session import PlaySession

    setup = load_setup(problem, None)
    policy = setup.policy
    if policy_of is not None:
        policy = load_setup(policy_of, None).policy
        setup.source.policy_hash = policy_hash(policy)

    def factory(sid: str) -> PlaySession:
        return PlaySession(setup.problem, policy, setup.source, session_id=sid,
                           log=session_log(log_dir, sid), view=setup.view)

    return Hub(factory, key="k3y")


@contextmanager
def serving(hub: Any) -> Iterator[str]:
    """Serve ``hub`` with a real uvicorn server on a free port, in a thread; yield its
    address (``127.0.0.1:PORT``)."""
    import uvicorn

    from ehatp.play.server import listen, make_app

    sock = listen("127.0.0.1", 0)
    server = uvicorn.Server(uvicorn.Config(make_app(hub), log_level="warning", lifespan="off"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    for _ in range(500):
        if server.started:
            break
        time.sleep(0.02)
    try:
        yield f"127.0.0.1:{sock.getsockname()[1]}"
    finally:
        server.should_exit = True
        thread.join(10)
        sock.close()
