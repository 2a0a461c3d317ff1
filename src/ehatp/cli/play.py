"""``ehatp play``: a person plays the human against the robot's policy, in a browser, for demos
and user studies (the sessions are :mod:`ehatp.play.session`, the server
:mod:`ehatp.play.server`; docs/play.md)."""

from __future__ import annotations

import importlib.util
import threading
import webbrowser
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import typer

from ..errors import printable
from .common import EXIT_BAD_INPUT, command_app, die, user_errors

app = command_app()

INSTALL = ("ehatp play needs Starlette and uvicorn, which are not installed; install them "
           "with: pip install 'ehatp[play]'")


@app.command("play")
def play_cmd(
    problem: Path | None = typer.Argument(
        None, help="Problem TOML file (with --replay: default, the log's).", show_default=False),
    policy: Path | None = typer.Option(
        None, "--policy", "-p", help="Policy JSON from `ehatp solve` (default: solve now).",
        show_default=False),
    port: int = typer.Option(8765, "--port", help="Port to listen on (0: any free port)."),
    host: str = typer.Option("127.0.0.1", "--host",
                             help="Address to listen on (0.0.0.0: every network)."),
    log_dir: Path = typer.Option(Path("play-logs"), "--log-dir",
                                 help="Folder of the session logs, one file per session "
                                      "(created)."),
    view: str | None = typer.Option(
        None, "--view", help="How the page draws the scene: module:function (a view hook), "
        "or none (facts only); default: the domain's own hook, if any.", show_default=False),
    robot_delay: float = typer.Option(0.8, "--robot-delay", min=0.0,
                                      help="Seconds between the robot's moves on the page."),
    decision_timeout: float | None = typer.Option(
        None, "--decision-timeout", min=0.1, metavar="SECONDS",
        help="Joint steps: the seconds the participant has to decide at each step where the "
        "human may pass; when they run out, the human passes (default: no timer).",
        show_default=False),
    no_browser: bool = typer.Option(False, "--no-browser", help="Do not open a browser."),
    keep_graph: bool = typer.Option(
        True, "--keep-graph/--no-keep-graph", help="Preferences problems: keep the explored "
        "graph (searched at the start, also with --policy) so that the experimenter can "
        "switch the robot's profile; --no-keep-graph: no search with --policy, no switching."),
    replay_log: Path | None = typer.Option(
        None, "--replay", metavar="LOG", help="Replay a session's log instead: print it, "
        "play its moves again and check that every record is the same (exit 1 if not).",
        show_default=False),
) -> None:
    """Play the human against the robot's policy in a browser: the participant's page shows
    only what the human perceives, an experimenter's page shows the truth and the policy, and
    every session is logged as JSON lines. See docs/play.md.

    Exit code 0: served until Ctrl-C, or the replay matches its log; 1: the replay differs;
    2: bad input."""
    from ..play.files import load_setup, log_folder

    if replay_log is not None:
        _replay(replay_log, problem, policy, view)
        return
    if problem is None:
        die("missing argument PROBLEM; give a problem TOML file, or --replay LOG")
    if not all(importlib.util.find_spec(m) for m in ("starlette", "uvicorn")):
        die(INSTALL)
    with user_errors(problem):
        setup = load_setup(problem, policy, view, keep_graph=keep_graph)
        folder = log_folder(log_dir)
    from ..play.server import Hub, listen, serve
    from ..play.session import PlaySession

    def factory(sid: str) -> PlaySession:
        from ..play.files import session_log

        return PlaySession(setup.problem, setup.policy, setup.source, session_id=sid,
                           log=session_log(folder, sid), view=setup.view,
                           decision_timeout=decision_timeout, graph=setup.graph)

    hub = Hub(factory, robot_delay=robot_delay)
    try:
        sock = listen(host, port)
    except OSError as e:
        die(f"--port {port}: cannot listen on {host}:{port} ({e.strerror or e}); choose "
            "another port with --port, or --port 0 for any free one", EXIT_BAD_INPUT)
    bound = sock.getsockname()[1]
    shown = "localhost" if host in ("127.0.0.1", "0.0.0.0") else host
    base = f"http://{shown}:{bound}"
    typer.echo(f"ehatp play: {printable(setup.problem.name)}, policy cost "
               f"{setup.policy.cost}; logs in {folder}/")
    typer.echo(f"  participant (a new session per visit): {base}/")
    typer.echo(f"  experimenter: {base}/experimenter?key={hub.key}")
    typer.echo("  Ctrl-C stops the server")
    if not no_browser:
        threading.Timer(0.5, webbrowser.open, (f"{base}/",)).start()
    serve(hub, sock)


def _replay(log: Path, problem: Path | None, policy: Path | None, view: str | None) -> None:
    from ..play.files import load_setup
    from ..play.session import read_log, replay

    with user_errors(log):
        records = read_log(log)
    start = records[0]
    where = problem or Path(str(start.get("problem_file", "")))
    pol = policy or (Path(start["policy_file"]) if start.get("policy_file") else None)
    with user_errors(where):
        setup = load_setup(where, pol, "none" if view is None else view, want=start)
        report = replay(records, setup.problem, setup.policy, setup.source, setup.view,
                        setup.graph)
    for line in timeline(records):
        typer.echo(printable(line))
    typer.echo(printable(str(report)))
    raise typer.Exit(0 if report.ok else 1)


def timeline(records: Iterable[dict[str, Any]]) -> list[str]:
    """Return a session's log as text: each move (agent, move, policy node, whether it was
    witnessed, covered or replanned), what the participant was shown, each replan, the end."""
    out: list[str] = []
    for r in records:
        kind = r.get("type")
        if kind == "start":
            out.append(f"session {r.get('session')}: problem {r.get('problem')} "
                       f"({r.get('problem_hash')}), policy {r.get('policy_file') or 'solved'}"
                       f" ({r.get('policy_hash')}), {r.get('human')} played by a person")
        elif kind == "step":
            notes = [f"node {r.get('node')}"] + (["opening"] if r.get("opening") else []) + (
                ["unseen by the human"] if not r.get("witnessed") else []) + (
                ["not covered: replanned"] if r.get("replanned") else [])
            out.append(f"{r.get('index')}. {r.get('agent')} {r.get('move')}  "
                       f"({'; '.join(notes)})")
        elif kind == "message":
            out.append(f"     shown: {r.get('text')}")
        elif kind == "replan":
            out.append(f"   replan after {r.get('move')}: {r.get('status')}, cost "
                       f"{r.get('cost')}, {r.get('nodes')} nodes")
        elif kind == "timeout":
            out.append(f"   the decision timed out after {r.get('seconds')} s: pass")
        elif kind == "rejected":
            out.append(f"   rejected {r.get('move')}: {r.get('reason')}")
        elif kind == "profile":
            out.append(f"   the robot switched to profile {r.get('profile')} at step "
                       f"{r.get('step')}: {r.get('metrics')} {r.get('value')} "
                       f"({r.get('policy_hash')})")
        elif kind == "switch-queued":
            out.append(f"   switch to profile {r.get('profile')} asked mid-step: at its end")
        elif kind == "switch-refused":
            out.append(f"   switch to profile {r.get('profile')} refused: {r.get('reason')}")
        elif kind == "end":
            out.append(f"end: {r.get('outcome')} after {r.get('steps')} steps, cost "
                       f"{r.get('cost')}")
    return out
