"""liaison's web layer: a Starlette application served by uvicorn inside the app's own asyncio
loop. Pages are one static HTML/JS/CSS bundle shipped in the package (no CDN); live data comes
as Server-Sent Events (`feed`: one snapshot per tick, deltas to each page); commands are JSON
POSTs. Every request passes `access.Access` first (Host, Origin and the per-launch token).

The routes and the Commander's operations are the literal tables ROUTES, COMMANDER_ACTIONS and
SPECIALS below; the handlers find the server's parts in `request.app.state.liaison`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import secrets
import socket
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from http.cookies import SimpleCookie
from pathlib import Path
from typing import Any

from pygoby.util.extras import needs_extra

with needs_extra("topside", "liaison"):
    import uvicorn
    from starlette.applications import Starlette
    from starlette.middleware import Middleware
    from starlette.requests import Request
    from starlette.responses import (
        FileResponse,
        JSONResponse,
        PlainTextResponse,
        RedirectResponse,
        Response,
        StreamingResponse,
    )
    from starlette.routing import Mount, Route
    from starlette.staticfiles import StaticFiles
    from starlette.types import ASGIApp, Message, Receive, Scope, Send

from pygoby.errors import ConfigError, PygobyError
from pygoby.protobuf.pygoby.apps.topside_config_pb2 import LiaisonConfig
from pygoby.topside.commander import (
    Commander,
    CommanderError,
    Draft,
    FieldValueError,
    SaveFileError,
)
from pygoby.topside.errors import LogControlError, ScopeFilterError, TooManyStreamsError
from pygoby.topside.liaison.access import Access, SaveFolder, is_loopback
from pygoby.topside.liaison.feed import PAGES, LiveFeed, PageStream, ScopeStream
from pygoby.topside.liaison.log_feed import LogPlayer
from pygoby.topside.liaison.state import LiaisonState, field_view, outgoing_view, record_view
from pygoby.util.aiorun import cancel_and_wait

__all__ = ["WebServer", "is_loopback", "make_app"]

log = logging.getLogger("pygoby.liaison")
STATIC = Path(__file__).parent / "static"


@dataclass
class Parts:
    """What the handlers use, kept in `app.state.liaison`."""

    state: LiaisonState
    feed: LiveFeed
    saves: SaveFolder | None  # None: no saving (log mode)
    player: LogPlayer | None = None  # replaying a log (`pygoby liaison --log`)


def _parts(request: Request) -> Parts:
    return request.app.state.liaison


# ---------------------------------------------------------------------------------- pages
async def index(request: Request) -> Response:
    query = f"?{request.url.query}" if request.url.query else ""
    return RedirectResponse(f"/scope{query}")


async def page(request: Request) -> Response:
    return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})


async def favicon(request: Request) -> Response:
    return FileResponse(STATIC / "favicon.svg", media_type="image/svg+xml")


class EventStream(StreamingResponse):
    """A live page's Server-Sent Events; its place among the feed's streams is given back
    however the response ends (finished, client gone, server stopping)."""

    def __init__(self, feed: LiveFeed, stream: ScopeStream | PageStream) -> None:
        super().__init__(
            feed.stream(stream),
            media_type="text/event-stream",
            headers={"Cache-Control": "no-store"},
        )
        self.feed, self.stream = feed, stream

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        try:
            await super().__call__(scope, receive, send)
        finally:
            self.feed.release(self.stream)


async def events(request: Request) -> Response:
    name = request.query_params.get("page", "scope")
    if name not in PAGES:
        return PlainTextResponse(f"no page {name!r}", 404)
    feed = _parts(request).feed
    try:
        stream = feed.admit(name, request.query_params.get("filter", ""))
    except TooManyStreamsError as err:
        return PlainTextResponse(str(err), 503, headers={"Retry-After": "5"})
    except ScopeFilterError as err:
        return PlainTextResponse(str(err), 400)
    return EventStream(feed, stream)


async def history(request: Request) -> Response:
    key = request.query_params.get("key", "")
    return JSONResponse({"key": key, "points": _parts(request).state.scope.history(key)})


async def types(request: Request) -> Response:
    state = _parts(request).state
    return JSONResponse(
        {
            "types": state.commander_types(),
            "community": state.commander.community,
            "modem_ids": state.commander.modem_ids(),
            "style": state.commander.style,
        }
    )


# ---------------------------------------------------------------------------------- commander
Action = Callable[[Parts, Draft | None, dict], dict[str, Any]]


def _needs_draft(draft: Draft | None) -> Draft:
    if draft is None:
        raise CommanderError("this action needs a message `type`")
    return draft


def _special_time(commander: Commander, draft: Draft, body: dict) -> None:
    commander.insert_time(draft, body["field"])


def _special_xy(commander: Commander, draft: Draft, body: dict) -> None:
    commander.insert_xy(draft, body["field"])


def _special_community(commander: Commander, draft: Draft, body: dict) -> None:
    commander.insert_community(draft, body["field"])


def _special_modem_id(commander: Commander, draft: Draft, body: dict) -> None:
    commander.insert_modem_id(draft, body["field"], int(body["modem_id"]))


SPECIALS: dict[str, Callable[[Commander, Draft, dict], None]] = {
    "time": _special_time,
    "xy": _special_xy,
    "community": _special_community,
    "modem_id": _special_modem_id,
}


def _open(parts: Parts, draft: Draft | None, body: dict) -> dict:
    _needs_draft(draft)
    return {}


def _check(parts: Parts, draft: Draft | None, body: dict) -> dict:
    parts.state.commander.check(
        _needs_draft(draft), body["field"], body.get("text", ""), partial=bool(body.get("partial"))
    )
    return {}


def _set(parts: Parts, draft: Draft | None, body: dict) -> dict:
    parts.state.commander.set_value(_needs_draft(draft), body["field"], body.get("text", ""))
    return {}


def _special(parts: Parts, draft: Draft | None, body: dict) -> dict:
    special = SPECIALS.get(body["special"])
    if special is None:
        raise CommanderError(f"no special {body['special']!r}")
    special(parts.state.commander, _needs_draft(draft), body)
    return {}


def _clear(parts: Parts, draft: Draft | None, body: dict) -> dict:
    parts.state.commander.clear(_needs_draft(draft))
    return {}


def _preview(parts: Parts, draft: Draft | None, body: dict) -> dict:
    return {"preview": outgoing_view(parts.state.commander.preview(_needs_draft(draft)))}


def _send(parts: Parts, draft: Draft | None, body: dict) -> dict:
    return {"record": record_view(parts.state.commander.send(_needs_draft(draft)))}


def _save_folder(parts: Parts) -> SaveFolder:
    if parts.saves is None:
        raise SaveFileError("this liaison has no save folder")
    return parts.saves


def _save(parts: Parts, draft: Draft | None, body: dict) -> dict:
    name = str(body["path"])
    parts.state.commander.save(_save_folder(parts).for_saving(name))
    return {}


def _load(parts: Parts, draft: Draft | None, body: dict) -> dict:
    name = str(body["path"])
    path = _save_folder(parts).path(name)
    if not path.is_file():
        raise SaveFileError(f"no save file {name!r} in the save folder")
    try:
        return {"warnings": parts.state.commander.load(path)}
    except OSError as err:
        raise SaveFileError(f"{name}: cannot read ({err.strerror})") from None


COMMANDER_ACTIONS: dict[str, Action] = {
    "open": _open,
    "check": _check,
    "set": _set,
    "special": _special,
    "clear": _clear,
    "preview": _preview,
    "send": _send,
    "save": _save,
    "load": _load,
}


async def command(request: Request) -> Response:
    """POST {action, type, field?, text?, ...}: one commander operation."""
    parts = _parts(request)
    if parts.player is not None:
        return JSONResponse({"ok": False, "error": LOG_MODE_COMMANDER}, status_code=409)
    try:
        body = await request.json()
        if not isinstance(body, dict):
            raise CommanderError("the request is a JSON object {action, type, ...}")
        action = COMMANDER_ACTIONS.get(body["action"])
        if action is None:
            raise CommanderError(f"no action {body['action']!r}")
        draft = parts.state.commander.open(body["type"]) if "type" in body else None
        result: dict = {"ok": True, **action(parts, draft, body)}
        if draft is not None:
            result["fields"] = field_view(draft)
            result["type"] = draft.type.name
        return JSONResponse(result)
    except (PygobyError, KeyError, ValueError, TypeError, OSError) as err:
        reason = err.args[0] if isinstance(err, KeyError) and err.args else str(err)
        status = 422 if isinstance(err, FieldValueError | SaveFileError) else 400
        return JSONResponse({"ok": False, "error": str(reason)}, status_code=status)


# ---------------------------------------------------------------------------------- log replay
LOG_MODE_COMMANDER = "liaison is replaying a log: the Commander is off (no MOOSDB to post to)"


def _player(request: Request) -> LogPlayer | None:
    return _parts(request).player


def _log_control_seek(player: LogPlayer, body: dict) -> None:
    player.seek(_number(body, "time"))


def _log_control_speed(player: LogPlayer, body: dict) -> None:
    player.set_speed(_number(body, "speed"))


def _number(body: dict, name: str) -> float:
    value = body.get(name)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise LogControlError(f"`{name}` is a number")
    return float(value)


LOG_CONTROLS: dict[str, Callable[[LogPlayer, dict], None]] = {
    "play": lambda player, body: player.play(),
    "pause": lambda player, body: player.pause(),
    "seek": _log_control_seek,
    "speed": _log_control_speed,
}


async def log_status(request: Request) -> Response:
    """GET: where the replay is; `replaying` false when liaison serves a live community (every
    page asks at start, so a live liaison answers too, without an error)."""
    player = _player(request)
    if player is None:
        return JSONResponse({"replaying": False})
    return JSONResponse({"replaying": True, **player.status()})


async def log_control(request: Request) -> Response:
    """POST {action: play|pause|seek|speed, time?, speed?}: the replay's controls; the
    answer is the status. A seek only aims: the pages get there over the next ticks (each
    reads a bounded number of entries), so no request reads the log at length."""
    player = _player(request)
    if player is None:
        return PlainTextResponse("liaison is not replaying a log", 404)
    try:
        body = await request.json()
        if not isinstance(body, dict):
            raise LogControlError("the request is a JSON object {action, ...}")
        control = LOG_CONTROLS.get(str(body.get("action")))
        if control is None:
            raise LogControlError(f"no action {body.get('action')!r} (play, pause, seek, speed)")
        control(player, body)
    except (LogControlError, ValueError) as err:
        return JSONResponse({"ok": False, "error": str(err)}, status_code=400)
    return JSONResponse({"ok": True, "replaying": True, **player.status()})


ROUTES = [
    Route("/", index),
    Route("/scope", page),
    Route("/commander", page),
    Route("/acomms", page),
    Route("/map", page),
    Route("/favicon.ico", favicon),
    Route("/api/events", events),
    Route("/api/scope/history", history),
    Route("/api/commander/types", types),
    Route("/api/commander", command, methods=["POST"]),
    Route("/api/log", log_status),
    Route("/api/log", log_control, methods=["POST"]),
    Mount("/static", StaticFiles(directory=STATIC), name="static"),
]


# ---------------------------------------------------------------------------------- access
class AccessGuard:
    """ASGI middleware: `Access` decides on every HTTP request before any route; a valid
    `?token=` leaves the token as the page's cookie."""

    def __init__(self, app: ASGIApp, access: Access) -> None:
        self.app = app
        self.access = access

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        request = Request(scope)
        headers = dict(request.headers.items())
        query = scope.get("query_string", b"").decode("latin-1")
        refusal = self.access.refusal(scope["method"], headers, query, request.cookies)
        if refusal is not None:
            status, reason = refusal
            await PlainTextResponse(reason, status)(scope, receive, send)
            return
        from_query = request.query_params.get("token", "")
        if not self.access.token_ok(from_query):
            await self.app(scope, receive, send)
            return

        async def send_with_cookie(message: Message) -> None:
            if message["type"] == "http.response.start":
                cookie: SimpleCookie = SimpleCookie()
                cookie[self.access.cookie] = self.access.token
                morsel = cookie[self.access.cookie]
                morsel["httponly"], morsel["samesite"], morsel["path"] = True, "Strict", "/"
                header = (b"set-cookie", morsel.OutputString().encode("latin-1"))
                message = {**message, "headers": [*message.get("headers", []), header]}
            await send(message)

        await self.app(scope, receive, send_with_cookie)


def make_app(
    state: LiaisonState,
    *,
    access: Access,
    feed: LiveFeed,
    saves: SaveFolder | None,
    player: LogPlayer | None = None,
) -> Starlette:
    """The ASGI application: ROUTES behind the AccessGuard."""
    app = Starlette(routes=ROUTES, middleware=[Middleware(AccessGuard, access=access)])
    app.state.liaison = Parts(state, feed, saves, player)
    return app


class _EmbeddedServer(uvicorn.Server):
    """uvicorn without its signal handlers: the application owns SIGINT/SIGTERM and stops the
    server itself."""

    @contextlib.contextmanager
    def capture_signals(self) -> Iterator[None]:
        yield


def listen(address: str, port: int) -> socket.socket:
    """The server's listening socket, bound when the app is configured, so that a taken port or
    an address this host does not have stops the app with a configuration error."""
    family = socket.AF_INET6 if ":" in address else socket.AF_INET
    try:
        return socket.create_server((address, port), family=family)
    except OSError as err:
        raise ConfigError(
            f"cannot serve the pages on {address}:{port}: {err.strerror or err} "
            "(set http_address / http_port)",
            field="liaison",
        ) from None


class WebServer:
    """uvicorn in the running asyncio loop, on a socket bound at construction; `url` once
    started."""

    def __init__(
        self,
        state: LiaisonState,
        cfg: LiaisonConfig,
        save_dir: str | Path | None,
        player: LogPlayer | None = None,
    ) -> None:
        """`cfg`: the LiaisonConfig (address, port, token, update_freq, max_streams,
        allowed_host); `save_dir`: the Commander page's save folder (None: none); `player`:
        the log replay the pages show (`pygoby liaison --log`), moved before every tick."""
        self.address = address = cfg.http_address
        self._socket = listen(address, cfg.http_port)
        self.port = self._socket.getsockname()[1]
        self.token = cfg.token or secrets.token_urlsafe(16)
        self._stopping = asyncio.Event()
        period = 1.0 / cfg.update_freq if cfg.update_freq > 0 else 1.0
        self.feed = LiveFeed(
            state, period, cfg.max_streams, before_tick=player.update if player else None
        )
        access = Access(address, self.token, self.port, cfg.allowed_host)
        saves = SaveFolder(save_dir) if save_dir is not None else None
        app = make_app(state, access=access, feed=self.feed, saves=saves, player=player)
        config = uvicorn.Config(
            app,
            host=address,
            port=self.port,
            log_level="warning",
            lifespan="off",
            access_log=False,
            timeout_graceful_shutdown=1,
        )
        self._server = _EmbeddedServer(config)
        self._task: asyncio.Task | None = None
        self._feed_task: asyncio.Task | None = None

    @property
    def url(self) -> str:
        host = f"[{self.address}]" if ":" in self.address else self.address
        return f"http://{host}:{self.port}/scope?token={self.token}"

    async def start(self) -> None:
        self._feed_task = asyncio.create_task(self.feed.run(self._stopping), name="liaison-feed")
        self._task = asyncio.create_task(
            self._server.serve(sockets=[self._socket]), name="liaison-http"
        )
        while not self._server.started:
            if self._task.done():
                self._task.result()  # the server failed to start: raise its error
                raise PygobyError(f"liaison could not serve on {self.address}:{self.port}")
            await asyncio.sleep(0.01)

    async def stop(self) -> None:
        if self._task is None:
            self._socket.close()  # never served (once served, the server closes it)
            return
        self._stopping.set()
        if self._feed_task is not None:
            await self._feed_task
        self._server.should_exit = True
        task, self._task = self._task, None
        # not wait_for in a suppress(CancelledError): that swallowed our caller's cancellation
        done, _ = await asyncio.wait({task}, timeout=5)
        if not done:
            with contextlib.suppress(Exception):  # the server's own errors are logged by it
                await cancel_and_wait(task)
        elif not task.cancelled():
            task.exception()  # retrieved; the server logs its own errors


def needed(draft: Draft | None) -> Draft:
    """The draft an action works on (a request without "type" has none: a 400)."""
    if draft is None:
        raise KeyError("type")
    return draft
