"""Client side of the netsim_manager interface (what upstream's ``netsim::tcp_client`` does).

`RequestTracker` is the sans-I/O core: it numbers requests (0, 1, 2, ..., wrapping from
2147483647 to 0, one counter for the client's lifetime), encodes them as lines, decodes response
lines and matches them to requests by ``request_id`` (not by order).

`NetSimClient` runs it over asyncio TCP with automatic reconnection (capped exponential
back-off). Requests built while disconnected are not queued: their ids are used up (as upstream),
and for position updates only the newest navs are kept and sent right after the next connect.

    client = NetSimClient("127.0.0.1", 61999, on_response=print)
    await client.start()
    future = client.send_navs([nav])      # None while not connected
    response = await future if future else None
    await client.close()
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Iterable
from typing import cast

from pygoby.netsim.errors import LineError
from pygoby.netsim.manager.protocol import (
    LEGACY_REQUEST_NAME,
    REQUEST_NAME,
    LineDecoder,
    NavUpdate,
    NetSimManagerRequest,
    NetSimManagerResponse,
    ReceiveStats,
    encode_line,
    request_class,
    response_names,
)
from pygoby.util.aiorun import cancel_and_wait
from pygoby.util.signal import Signal

log = logging.getLogger(__name__)

MAX_REQUEST_ID = 2**31 - 1

ResponseCallback = Callable[[NetSimManagerResponse], None]


def status_name(response: NetSimManagerResponse) -> str:
    return response.Status.Name(response.status)


class RequestTracker:
    """Request numbering, encoding and response matching for one client. `first_id`: the id
    of the first request (0, as upstream; another value continues a sequence)."""

    def __init__(self, legacy_names: bool = False, first_id: int = 0) -> None:
        if not 0 <= first_id <= MAX_REQUEST_ID:
            raise ValueError(f"a request id is within 0..{MAX_REQUEST_ID}, not {first_id}")
        self.request_name = LEGACY_REQUEST_NAME if legacy_names else REQUEST_NAME
        self._next_id = first_id
        self._decoder = LineDecoder(response_names())
        self._waiting: dict[int, asyncio.Future[NetSimManagerResponse]] = {}

    def take_id(self) -> int:
        request_id = self._next_id
        self._next_id = 0 if request_id >= MAX_REQUEST_ID else request_id + 1
        return request_id

    def build(
        self, navs: Iterable[NavUpdate] = (), stats: Iterable[ReceiveStats] = ()
    ) -> NetSimManagerRequest:
        """A request with the next id (the id is used up even if the request is never sent)."""
        request = request_class()(id=self.take_id())
        request.nav.extend(navs)
        request.stats.extend(stats)
        return request

    def encode(self, request: NetSimManagerRequest) -> bytes:
        return encode_line(request, self.request_name)

    def expect(self, request_id: int, future: asyncio.Future[NetSimManagerResponse]) -> None:
        self._waiting[request_id] = future

    def feed(self, data: bytes) -> list[NetSimManagerResponse]:
        """Responses decoded from `data`; waiting futures for their ids are resolved."""
        responses: list[NetSimManagerResponse] = []
        for event in self._decoder.feed(data):
            if isinstance(event, LineError):
                log.warning("netsim client: dropped line from manager: %s", event)
                continue
            if event.parse_error:
                log.warning("netsim client: %s", event.parse_error)
            # (the decoder was made with the response class: every message is one)
            response = cast(NetSimManagerResponse, event.message)
            future = self._waiting.pop(response.request_id, None)
            if future is not None and not future.done():
                future.set_result(response)
            responses.append(response)
        return responses

    def fail_waiting(self, exc: Exception) -> None:
        for future in self._waiting.values():
            if not future.done():
                future.set_exception(exc)
        self._waiting.clear()


class NetSimClient:
    """asyncio client for netsim_manager with reconnection."""

    def __init__(
        self,
        host: str,
        port: int,
        *,
        on_response: ResponseCallback | None = None,
        legacy_names: bool = False,
        backoff_initial: float = 1.0,
        backoff_max: float = 30.0,
    ) -> None:
        self.host, self.port = host, port
        self.tracker = RequestTracker(legacy_names)
        self.signal_response: Signal[NetSimManagerResponse] = (
            Signal()
        )  # every response received, in arrival order
        if on_response is not None:
            self.signal_response.connect(on_response)
        self.backoff_initial, self.backoff_max = backoff_initial, backoff_max
        self._writer: asyncio.StreamWriter | None = None
        self._connected = asyncio.Event()
        self._pending_navs: list[NavUpdate] = []
        self._task: asyncio.Task | None = None
        self.connections = 0  # successful connects so far

    @property
    def connected(self) -> bool:
        return self._writer is not None

    async def start(self) -> None:
        if self._task is None:
            self._task = asyncio.create_task(self._run(), name="netsim-client")

    async def wait_connected(self, timeout: float | None = None) -> None:
        async with asyncio.timeout(timeout):
            await self._connected.wait()

    async def close(self) -> None:
        task, self._task = self._task, None
        await cancel_and_wait(task)

    def send_request(
        self, request: NetSimManagerRequest
    ) -> asyncio.Future[NetSimManagerResponse] | None:
        """Write a request built with `tracker.build`; a future for its response, or None if
        not connected (the request is dropped, not queued)."""
        if self._writer is None:
            return None
        future = asyncio.get_running_loop().create_future()
        self.tracker.expect(request.id, future)
        self._writer.write(self.tracker.encode(request))
        return future

    def send_navs(
        self, navs: Iterable[NavUpdate], stats: Iterable[ReceiveStats] = ()
    ) -> asyncio.Future[NetSimManagerResponse] | None:
        """Report positions (and optionally stats). While disconnected only the newest navs
        are kept, and sent as soon as the connection is back."""
        navs = list(navs)
        request = self.tracker.build(navs, stats)
        future = self.send_request(request)
        if future is None:
            self._pending_navs = navs
        return future

    def send_stats(
        self, stats: Iterable[ReceiveStats]
    ) -> asyncio.Future[NetSimManagerResponse] | None:
        return self.send_request(self.tracker.build(stats=stats))

    @staticmethod
    def nav(**fields) -> NavUpdate:
        """Convenience: a NavUpdate from keyword fields."""
        return NavUpdate(**fields)

    async def _run(self) -> None:
        delay = self.backoff_initial
        while True:
            try:
                reader, writer = await asyncio.open_connection(self.host, self.port)
            except OSError as exc:
                log.info("netsim client: cannot connect to %s:%d: %s", self.host, self.port, exc)
                await asyncio.sleep(delay)
                delay = min(delay * 2, self.backoff_max)
                continue
            delay = self.backoff_initial
            await self._session(reader, writer)
            await asyncio.sleep(delay)

    async def _session(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self._writer = writer
        self.connections += 1
        self._connected.set()
        if self._pending_navs:
            navs, self._pending_navs = self._pending_navs, []
            self.send_navs(navs)
        try:
            while data := await reader.read(65536):
                for response in self.tracker.feed(data):
                    if response.status != response.UPDATE_ACCEPTED:
                        log.warning(
                            "netsim request %d: %s", response.request_id, status_name(response)
                        )
                    self.signal_response.emit(response)
        except OSError as exc:
            log.info("netsim client: connection lost: %s", exc)
        finally:
            self._writer = None
            self._connected.clear()
            self.tracker.fail_waiting(ConnectionError("connection to netsim_manager lost"))
            writer.close()
            with contextlib.suppress(OSError):
                await writer.wait_closed()
