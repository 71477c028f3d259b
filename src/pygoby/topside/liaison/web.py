"""liaison's web layer: a Starlette application served by uvicorn inside the app's own asyncio
loop. Pages are one static HTML/JS/CSS bundle shipped in the package (no CDN); live data comes
as Server-Sent Events (one JSON snapshot of the open page per update); commands are JSON POSTs.

Access: loopback addresses need nothing. Any other address needs the token (printed at
start-up): `?token=...` on the first page (then a cookie), or `Authorization: Bearer ...`.
Every POST must carry the `X-Liaison` header, which a page from another site cannot add without
a CORS permission this server never gives (so other sites cannot send commands through a
browser that has liaison open).
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import ipaddress
import json
import logging
import secrets
import socket
from collections.abc import AsyncIterator, Callable, Iterator
from pathlib import Path

import uvicorn
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import (
    FileResponse,
    JSONResponse,
    RedirectResponse,
    Response,
    StreamingResponse,
)
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from pygoby.errors import ConfigError, PygobyError
from pygoby.topside.commander import CommanderError, FieldValueError, SaveFileError
from pygoby.topside.commander.commander import Draft
from pygoby.topside.liaison.state import LiaisonState, field_view, outgoing_view, record_view
from pygoby.util.aiorun import cancel_and_wait

log = logging.getLogger("pygoby.liaison")
STATIC = Path(__file__).parent / "static"
PAGES = ("scope", "commander", "acomms", "map")
COOKIE = "liaison_token"


def is_loopback(address: str) -> bool:
    if address in ("localhost", ""):
        return address == "localhost"
    try:
        return ipaddress.ip_address(address).is_loopback
    except ValueError:
        return False


def _json_default(value: object) -> object:
    if isinstance(value, float | int):
        return value
    return str(value)


def make_app(
    state: LiaisonState,
    *,
    token: str | None,
    update_period: float,
    stopping: asyncio.Event | None = None,
) -> Starlette:
    """The ASGI application. `token`: None when no token is needed; `stopping` ends the live
    streams (so that the server can stop while pages are open)."""
    stopping = stopping or asyncio.Event()

    def authorised(request: Request) -> bool:
        if token is None:
            return True
        offered = (
            request.query_params.get("token")
            or request.cookies.get(COOKIE)
            or request.headers.get("authorization", "").removeprefix("Bearer ")
        )
        return bool(offered) and hmac.compare_digest(offered, token)

    def guard(handler: Callable) -> Callable:
        async def guarded(request: Request) -> Response:
            if not authorised(request):
                return Response("liaison: access token required (?token=...)", 401)
            if request.method == "POST" and request.headers.get("x-liaison") != "1":
                return Response("liaison: POST without the X-Liaison header", 403)
            response = await handler(request)
            if token is not None and request.query_params.get("token"):
                response.set_cookie(COOKIE, token, httponly=True, samesite="strict")
            return response

        return guarded

    async def index(request: Request) -> Response:
        return RedirectResponse("/scope")

    async def page(request: Request) -> Response:
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    async def events(request: Request) -> Response:
        name = request.query_params.get("page", "scope")
        pattern = request.query_params.get("filter", "")
        if name not in PAGES:
            return Response(f"no page {name!r}", 404)

        async def stream() -> AsyncIterator[str]:
            while not stopping.is_set() and not await request.is_disconnected():
                data = state.page(name, state.now(), pattern)
                yield f"data: {json.dumps(data, default=_json_default)}\n\n"
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(update_period):
                        await stopping.wait()

        return StreamingResponse(
            stream(), media_type="text/event-stream", headers={"Cache-Control": "no-store"}
        )

    async def history(request: Request) -> Response:
        key = request.query_params.get("key", "")
        return JSONResponse({"key": key, "points": state.scope.history(key)})

    async def types(request: Request) -> Response:
        return JSONResponse(
            {
                "types": state.commander_types(),
                "community": state.commander.community,
                "modem_ids": state.commander.modem_ids(),
                "style": state.commander.style,
            }
        )

    async def command(request: Request) -> Response:
        """POST {action, type, field?, text?, ...}: one commander operation."""
        try:
            body = await request.json()
            action = body["action"]
            commander = state.commander
            draft = commander.open(body["type"]) if "type" in body else None
            result: dict = {"ok": True}
            if action == "open":
                pass
            elif action == "check":
                commander.check(
                    needed(draft),
                    body["field"],
                    body.get("text", ""),
                    partial=bool(body.get("partial")),
                )
            elif action == "set":
                commander.set_value(needed(draft), body["field"], body.get("text", ""))
            elif action == "special":
                special = body["special"]
                if special == "time":
                    commander.insert_time(needed(draft), body["field"])
                elif special == "xy":
                    commander.insert_xy(needed(draft), body["field"])
                elif special == "community":
                    commander.insert_community(needed(draft), body["field"])
                elif special == "modem_id":
                    commander.insert_modem_id(needed(draft), body["field"], int(body["modem_id"]))
                else:
                    raise CommanderError(f"no special {special!r}")
            elif action == "clear":
                commander.clear(needed(draft))
            elif action == "preview":
                result["preview"] = outgoing_view(commander.preview(needed(draft)))
            elif action == "send":
                result["record"] = record_view(commander.send(needed(draft)))
            elif action == "save":
                commander.save(body["path"])
            elif action == "load":
                result["warnings"] = commander.load(body["path"])
            else:
                raise CommanderError(f"no action {action!r}")
            if draft is not None:
                result["fields"] = field_view(draft)
                result["type"] = draft.type.name
            return JSONResponse(result)
        except (PygobyError, KeyError, ValueError, TypeError, OSError) as err:
            reason = err.args[0] if isinstance(err, KeyError) and err.args else str(err)
            status = 400 if not isinstance(err, FieldValueError | SaveFileError) else 422
            return JSONResponse({"ok": False, "error": str(reason)}, status_code=status)

    routes = [
        Route("/", guard(index)),
        *(Route(f"/{name}", guard(page)) for name in PAGES),
        Route("/api/events", guard(events)),
        Route("/api/scope/history", guard(history)),
        Route("/api/commander/types", guard(types)),
        Route("/api/commander", guard(command), methods=["POST"]),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]
    return Starlette(routes=routes)


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
        address: str,
        port: int,
        token: str = "",
        update_period: float = 0.2,
    ) -> None:
        self.address = address
        self.token: str | None = None
        if not is_loopback(address):
            self.token = token or secrets.token_urlsafe(16)
        self._stopping = asyncio.Event()
        app = make_app(
            state, token=self.token, update_period=update_period, stopping=self._stopping
        )
        config = uvicorn.Config(
            app,
            host=address,
            port=port,
            log_level="warning",
            lifespan="off",
            access_log=False,
            timeout_graceful_shutdown=1,
        )
        self._server = _EmbeddedServer(config)
        self._task: asyncio.Task | None = None
        self._socket = listen(address, port)
        self.port = self._socket.getsockname()[1]

    @property
    def url(self) -> str:
        host = f"[{self.address}]" if ":" in self.address else self.address
        suffix = f"/scope?token={self.token}" if self.token else "/scope"
        return f"http://{host}:{self.port}{suffix}"

    async def start(self) -> None:
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
