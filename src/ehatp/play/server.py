"""The web server of ``ehatp play`` (Starlette, served by uvicorn; ``pip install 'ehatp[play]'``).

Routes (docs/play.md):

- ``GET /`` starts a new session and sends the browser to its page, ``/s/<id>``: one session per
  tab, each with its own log, isolated from the others;
- ``GET /s/<id>`` the participant's page; ``WS /ws/<id>`` its socket: the server sends the
  participant's view (``{"type": "view", "view": {...}}``, the human's perspective only), the
  page sends the participant's moves (``{"move": LABEL}``), and in joint steps a decision whose
  timer ran out (``{"timeout": STEP}``, STEP the moves played when it started: a ``pass``);
- ``GET /experimenter?key=K`` the sessions; ``GET /experimenter/<id>?key=K`` one session as the
  experimenter sees it, ``WS /ws/<id>/experimenter?key=K`` its socket. ``K`` is made when the
  server starts and printed with the URLs: a participant cannot open these pages. On a
  preferences problem the experimenter switches the robot's profile with ``{"profile": NAME}``
  on that socket (the page's control), or ``POST /api/s/<id>/profile?key=K`` with the body
  ``{"profile": NAME}`` (a script's); a switch refused is one message with the reason.

Data from a problem or a policy reaches the pages as JSON over the socket only, and the pages
insert it as text (never as markup); every page is served with a content security policy that
allows the page's own scripts and nothing else.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import secrets
import socket
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import anyio.to_thread
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, RedirectResponse, Response
from starlette.routing import Route, WebSocketRoute
from starlette.websockets import WebSocket, WebSocketDisconnect

from .session import PlaySession

STATIC = Path(__file__).parent / "static"
ASSETS = {"play.js": "text/javascript", "experimenter.js": "text/javascript",
          "play.css": "text/css"}
HEADERS = {
    "Content-Security-Policy": "default-src 'none'; script-src 'self'; style-src 'self'; "
                               "connect-src 'self'; img-src 'self'; base-uri 'none'; "
                               "form-action 'none'; frame-ancestors 'none'",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",  # the experimenter's key is in its pages' addresses
    "Cache-Control": "no-store",
}
MAX_MESSAGE = 4096  # a move's label is short; anything longer is not a move


@dataclass
class Live:
    """A session on the server: the play, a lock (one move at a time), the open sockets."""

    session: PlaySession
    lock: asyncio.Lock = field(default_factory=asyncio.Lock)
    participants: set[WebSocket] = field(default_factory=set)
    experimenters: set[WebSocket] = field(default_factory=set)


@contextlib.contextmanager
def _connected(live: Live, ws: WebSocket, role: str, group: set[WebSocket]) -> Iterator[None]:
    """Keep ``ws`` in ``group`` (the session's participants or experimenters) while the body
    runs, logging the connection's opening and closing as ``role``'s; a page that goes away
    ends the body quietly."""
    group.add(ws)
    live.session.connection("open", role)
    try:
        yield
    except WebSocketDisconnect:
        pass
    finally:
        group.discard(ws)
        live.session.connection("close", role)


class Hub:
    """Every session of one server. ``factory(session_id)`` makes a session (logging to its
    own file); ``robot_delay`` is the pause in seconds after each robot move, so that a
    participant sees them one by one."""

    def __init__(self, factory: Callable[[str], PlaySession], *, key: str | None = None,
                 robot_delay: float = 0.0) -> None:
        self.factory = factory
        self.key = key or secrets.token_urlsafe(16)
        self.robot_delay = robot_delay
        self.sessions: dict[str, Live] = {}

    def new(self) -> Live:
        sid = secrets.token_urlsafe(12)
        live = self.sessions[sid] = Live(self.factory(sid))
        live.session.start()
        return live

    async def push(self, live: Live) -> None:
        """Send each open page of ``live`` its view now."""
        s = live.session
        if live.participants:
            await _send_all(live.participants, {"type": "view", "view": s.participant_view()})
        if live.experimenters:
            await _send_all(live.experimenters,
                            {"type": "experimenter", "view": s.experimenter_view()})

    async def robot(self, live: Live) -> None:
        """Play the robot's moves, one by one, each shown before the next (lock held)."""
        while live.session.robot_to_move:
            await anyio.to_thread.run_sync(live.session.robot_step)
            await self.push(live)
            if self.robot_delay and live.session.robot_to_move:
                await asyncio.sleep(self.robot_delay)

    async def move(self, live: Live, label: str) -> None:
        async with live.lock:
            await anyio.to_thread.run_sync(live.session.choose, label)
            await self.push(live)
            await self.robot(live)

    async def timeout(self, live: Live, step: int) -> None:
        async with live.lock:
            await anyio.to_thread.run_sync(live.session.timeout, step)
            await self.push(live)
            await self.robot(live)

    async def switch(self, live: Live, name: str) -> dict[str, Any]:
        """The experimenter switches ``live``'s robot to profile ``name``
        (:meth:`PlaySession.switch_profile`), once the robot's moves due are played (as a
        replay plays them before the next record); returns ``{"result": switched | queued |
        refused, "profile": ..., "reason": ...}`` (the reason when refused)."""
        async with live.lock:
            await self.robot(live)
            s = live.session
            result = await anyio.to_thread.run_sync(s.switch_profile, name)
            out: dict[str, Any] = {"result": result, "profile": s.profile()}
            if result == "refused":
                out["reason"] = next(r for r in reversed(s.tail)
                                     if r["type"] == "switch-refused")["reason"]
            await self.push(live)
            await self.robot(live)
            return out

    async def advance(self, live: Live) -> None:
        async with live.lock:
            await self.robot(live)


async def _send_all(sockets: set[WebSocket], message: dict[str, Any]) -> None:
    text = json.dumps(message, ensure_ascii=False)
    for ws in list(sockets):
        try:
            await ws.send_text(text)
        except Exception:  # a page closed meanwhile: it reconnects and gets the view then
            sockets.discard(ws)


def _page(name: str) -> Response:
    return FileResponse(STATIC / name, media_type="text/html", headers=HEADERS)


def _same_origin(ws: WebSocket) -> bool:
    """Whether the socket comes from a page of this server (a browser always says its
    origin; another site's page must not drive a session)."""
    origin = ws.headers.get("origin")
    return origin is None or urlsplit(origin).netloc == ws.headers.get("host")


def make_app(hub: Hub) -> Starlette:
    """Return the web application of ``hub``'s sessions."""

    def keyed(request: Request | WebSocket) -> bool:
        return secrets.compare_digest(request.query_params.get("key", ""), hub.key)

    async def index(request: Request) -> Response:
        live = hub.new()
        return RedirectResponse(f"/s/{live.session.id}", status_code=303, headers=HEADERS)

    async def participant(request: Request) -> Response:
        if request.path_params["sid"] not in hub.sessions:
            return Response("no such session; open / for a new one", 404, headers=HEADERS,
                            media_type="text/plain")
        return _page("participant.html")

    async def asset(request: Request) -> Response:
        name = request.path_params["name"]
        if name not in ASSETS:
            return Response("not found", 404, headers=HEADERS, media_type="text/plain")
        return FileResponse(STATIC / name, media_type=ASSETS[name], headers=HEADERS)

    async def experimenter_index(request: Request) -> Response:
        if not keyed(request):
            return Response("forbidden", 403, headers=HEADERS, media_type="text/plain")
        return _page("experimenter.html")

    async def experimenter(request: Request) -> Response:
        if not keyed(request) or request.path_params["sid"] not in hub.sessions:
            return Response("forbidden", 403, headers=HEADERS, media_type="text/plain")
        return _page("experimenter.html")

    async def sessions(request: Request) -> Response:
        if not keyed(request):
            return Response("forbidden", 403, headers=HEADERS, media_type="text/plain")
        rows = [{"session": sid, "status": live.session.status(),
                 "outcome": live.session.outcome, "steps": len(live.session.ex.history),
                 "replans": live.session.replans, "open": len(live.participants)}
                for sid, live in hub.sessions.items()]
        return JSONResponse({"sessions": rows}, headers=HEADERS)

    async def socket(ws: WebSocket) -> None:
        live = hub.sessions.get(ws.path_params["sid"])
        if live is None or not _same_origin(ws):
            await ws.close(code=1008)
            return
        await ws.accept()
        with _connected(live, ws, "participant", live.participants):
            await ws.send_text(json.dumps({"type": "view",
                                           "view": live.session.participant_view()},
                                          ensure_ascii=False))
            if live.session.robot_to_move and not live.lock.locked():
                asyncio.get_running_loop().create_task(hub.advance(live))
            while True:
                text = await ws.receive_text()
                label = _move(text)
                if label is None:
                    step = _timeout(text)
                    if step is not None:
                        await hub.timeout(live, step)
                        continue
                    await ws.send_text(json.dumps({"type": "error",
                                                   "message": 'send {"move": LABEL}'}))
                    continue
                await hub.move(live, label)

    async def experimenter_socket(ws: WebSocket) -> None:
        live = hub.sessions.get(ws.path_params["sid"])
        if live is None or not keyed(ws) or not _same_origin(ws):
            await ws.close(code=1008)
            return
        await ws.accept()
        with _connected(live, ws, "experimenter", live.experimenters):
            await ws.send_text(json.dumps({"type": "experimenter",
                                           "view": live.session.experimenter_view()},
                                          ensure_ascii=False))
            while True:  # the experimenter's page listens, and may switch the profile
                name = _field(await ws.receive_text(), "profile")
                if not isinstance(name, str):
                    await ws.send_text(json.dumps({"type": "error",
                                                   "message": 'send {"profile": NAME}'}))
                    continue
                out = await hub.switch(live, name)
                await ws.send_text(json.dumps({"type": "switch", **out}, ensure_ascii=False))

    async def profile(request: Request) -> Response:
        if not keyed(request):
            return JSONResponse({"result": "refused", "reason": "forbidden: the experimenter's "
                                 "key is missing or wrong; give ?key=K as the server printed "
                                 "it"}, 403, headers=HEADERS)
        live = hub.sessions.get(request.path_params["sid"])
        if live is None:
            return JSONResponse({"result": "refused", "reason": "no such session"}, 404,
                                headers=HEADERS)
        name = _field((await request.body()).decode("utf-8", "replace"), "profile")
        if not isinstance(name, str):
            return JSONResponse({"result": "refused", "reason": 'send {"profile": NAME}'},
                                400, headers=HEADERS)
        out = await hub.switch(live, name)
        return JSONResponse(out, 409 if out["result"] == "refused" else 200, headers=HEADERS)

    async def favicon(request: Request) -> Response:
        return Response(status_code=204, headers=HEADERS)

    return Starlette(routes=[
        Route("/", index),
        Route("/favicon.ico", favicon),
        Route("/s/{sid}", participant),
        Route("/static/{name}", asset),
        Route("/experimenter", experimenter_index),
        Route("/experimenter/{sid}", experimenter),
        Route("/api/sessions", sessions),
        Route("/api/s/{sid}/profile", profile, methods=["POST"]),
        WebSocketRoute("/ws/{sid}", socket),
        WebSocketRoute("/ws/{sid}/experimenter", experimenter_socket),
    ])


def _field(text: str, key: str) -> Any:
    """Return the value of a participant's message ``{KEY: value}`` (exactly that one key), or
    None for anything else: too long, not JSON, nested too deeply, other keys."""
    if len(text) > MAX_MESSAGE:
        return None
    try:
        msg = json.loads(text)
    except (json.JSONDecodeError, RecursionError):
        return None
    if not isinstance(msg, dict) or set(msg) != {key}:
        return None
    return msg[key]


def _move(text: str) -> str | None:
    """Return the move a participant's message names, None when it is not ``{"move": str}``."""
    move = _field(text, "move")
    return move if isinstance(move, str) else None


def _timeout(text: str) -> int | None:
    """Return the step a participant's ``{"timeout": STEP}`` names, None for anything else."""
    step = _field(text, "timeout")
    return step if isinstance(step, int) and not isinstance(step, bool) else None


def listen(host: str, port: int) -> socket.socket:
    """Return a socket listening on ``host``:``port`` (0: a free port); OSError when it
    cannot."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
        sock.listen(128)
    except OSError:
        sock.close()
        raise
    return sock


def serve(hub: Hub, sock: socket.socket) -> None:
    """Serve ``hub``'s sessions on ``sock`` until interrupted (Ctrl-C)."""
    import uvicorn

    config = uvicorn.Config(make_app(hub), log_level="warning", ws="auto",
                            lifespan="off")
    uvicorn.Server(config).run(sockets=[sock])


__all__ = ["Hub", "Live", "listen", "make_app", "serve"]
