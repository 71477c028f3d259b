"""Asyncio MOOS V10 (asynchronous) client.

    async with MOOSClient("myapp", port=db.port) as client:     # connects (waits for it)
        client.subscribe("NAV_X")                                # current value comes at once
        client.subscribe_wildcard("NAV_*", app_pattern="*", interval=0.5)
        client.publish("DESIRED_SPEED", 1.5)                     # float -> D, str -> S, bytes -> B
        msg = await client.receive()                             # or `async for msg in client`
        replies = await client.server_request("VAR_SUMMARY")

Behaviour: a `T` timing message leads a packet at least once a second (keep-alive and clock
sync); everything queued is sent in one packet as soon as the event loop runs the writer. The
client reconnects by itself (every `reconnect_interval` s) after a lost connection, sends its
subscriptions again, emits `signal_connect`, then sends publications queued while it
was away (bounded by `outbox_limit`; the oldest are dropped beyond it, with a warning).

A `K` (name already in use) at the first connection ends the client with `MoosRefusedError`
(another process has the name: no retry, as in C++). A `K` on a reconnection means the DB still
holds this client's previous session, which it drops after its client timeout: the client
tries again, backing off from `reconnect_interval` to 10 s, with a warning each time (the C++
client gives up there and leaves a live process disconnected forever).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket
from collections import deque
from collections.abc import AsyncIterator, Callable

from pygoby.moos import protocol as p
from pygoby.moos.errors import MoosProtocolError, MoosRefusedError
from pygoby.moos.protocol import MOOSMessage, Value
from pygoby.util.aiorun import cancel_and_wait
from pygoby.util.clock import Clock, WallClock
from pygoby.util.signal import Signal

log = logging.getLogger(__name__)

TIMING_PERIOD = 1.0
MAX_PACKET_MESSAGES = 4096
HANDSHAKE_TIMEOUT = 5.0  # s for the DB's answer to the handshake
MAX_REFUSED_BACKOFF = 10.0  # s between attempts while the DB refuses the name on reconnect
# A DB that cannot be reached is reported at WARN once attempts have failed for this long (a DB
# launched beside the app by antler is up by then), then once a minute while it stays so.
UNREACHABLE_FIRST_WARNING = 3.0
UNREACHABLE_WARNING_EVERY = 60.0


class UnreachableWarnings:
    """When to say that connection attempts keep failing (sans-I/O: fed loop times):
    `failed(now)` is True when a warning is due; `reset()` on a connection."""

    def __init__(
        self, first: float = UNREACHABLE_FIRST_WARNING, every: float = UNREACHABLE_WARNING_EVERY
    ) -> None:
        self.first, self.every = first, every
        self._since: float | None = None
        self._next = 0.0

    def failed(self, now: float) -> bool:
        if self._since is None:
            self._since, self._next = now, now + self.first
        if now < self._next:
            return False
        self._next = now + self.every
        return True

    def reset(self) -> None:
        self._since = None

    def failing_for(self, now: float) -> float:
        return 0.0 if self._since is None else now - self._since


class MOOSClient:
    """A V10 MOOS client.

    Args: name (the MOOS name), host, port, clock (MOOS local time; see
    `pygoby.moos.timewarp.moos_clock`), on_message (callback for every received message; when
    None, messages go to the inbox read by `receive()`), reconnect_interval (s), outbox_limit,
    inbox_limit (messages), max_packet_size (bytes accepted from the DB).

    Signals (`pygoby.util.signal.Signal`): `signal_connect()` after each (re)connection, once
    the subscriptions are sent again (a raising slot is logged); `signal_disconnect()` when a
    connection is lost; `signal_refused(MoosRefusedError)` when the DB refuses the name at the
    first connection (the client then stops; `failure` holds the error).
    """

    def __init__(
        self,
        name: str,
        host: str = "127.0.0.1",
        port: int = p.DEFAULT_PORT,
        *,
        clock: Clock | None = None,
        on_message: Callable[[MOOSMessage], None] | None = None,
        reconnect_interval: float = 0.5,
        outbox_limit: int = 100_000,
        inbox_limit: int = 100_000,
        max_packet_size: int = p.DEFAULT_MAX_PACKET_SIZE,
    ) -> None:
        if not name:
            raise ValueError("a MOOS client needs a name")
        self.name = name
        self.host = "127.0.0.1" if host.upper() == "LOCALHOST" else host
        self.port = port
        self.clock = clock or WallClock()
        self.on_message = on_message
        # a failing connect slot is logged (the session goes on); disconnect slots' errors propagate
        self.signal_connect: Signal[[]] = Signal(contain_errors=True, logger=log)
        self.signal_disconnect: Signal[[]] = Signal()
        self.signal_refused: Signal[MoosRefusedError] = Signal(contain_errors=True, logger=log)
        self.reconnect_interval = reconnect_interval
        self.unreachable = UnreachableWarnings()
        self.outbox_limit = outbox_limit
        self.inbox_limit = inbox_limit
        self.max_packet_size = max_packet_size
        self.community = ""
        self.db_hostname = ""
        self.skew = p.SkewFilter()
        self.clock_correction = False
        self.throttle = 0.0
        self._next_id = 0
        self._outbox: deque[MOOSMessage] = deque()
        self._inbox: deque[MOOSMessage] = deque()
        self._inbox_ready = asyncio.Event()
        self._subscriptions: dict[str, float] = {}
        self._wildcards: dict[tuple[str, str], float] = {}
        self._wake = asyncio.Event()
        self._connected = asyncio.Event()
        self._stopped = asyncio.Event()
        self._requests: list[asyncio.Future[list[MOOSMessage]]] = []
        self._task: asyncio.Task[None] | None = None
        self._writer: asyncio.StreamWriter | None = None
        self.failure: BaseException | None = None
        self.connections = 0

    # -- life cycle ----------------------------------------------------------------------------

    def start(self) -> None:
        """Start connecting (and reconnecting) in the background."""
        if self._task is None:
            self._task = asyncio.create_task(self._run(), name=f"moos-client-{self.name}")

    async def connect(self, timeout: float | None = 5.0) -> None:
        """Start and wait until connected (TimeoutError after `timeout`; MoosRefusedError on K)."""
        self.start()
        await self.wait_connected(timeout)

    async def wait_connected(self, timeout: float | None = None) -> None:
        waiter = asyncio.ensure_future(self._connected.wait())
        stopper = asyncio.ensure_future(self._stopped.wait())
        try:
            done, _ = await asyncio.wait(
                {waiter, stopper}, timeout=timeout, return_when=asyncio.FIRST_COMPLETED
            )
        finally:
            waiter.cancel()
            stopper.cancel()
        if self.failure is not None:
            raise self.failure
        if not done:
            raise TimeoutError(f"{self.name}: no connection to {self.host}:{self.port}")

    async def close(self) -> None:
        task, self._task = self._task, None
        await cancel_and_wait(task)

    async def __aenter__(self) -> MOOSClient:
        await self.connect()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    @property
    def connected(self) -> bool:
        return self._connected.is_set()

    # -- time ----------------------------------------------------------------------------------

    def local_time(self) -> float:
        """MOOSLocalTime: the clock (warped), without skew."""
        return self.clock.now()

    def time(self) -> float:
        """MOOSTime: local time plus the skew estimate when clock correction is on."""
        return self.clock.now() + (self.skew.skew if self.clock_correction else 0.0)

    # -- publishing and subscribing ------------------------------------------------------------

    def publish(
        self, key: str, value: Value, *, src_aux: str = "", time: float | None = None
    ) -> None:
        """Queue a notification (float/int: double, str: string, bytes: binary)."""
        if not key:
            raise ValueError("cannot publish to an empty variable name")
        msg = p.notify(
            key,
            value,
            time=self.time() if time is None else time,
            src=self.name,
            src_aux=src_aux,
            msg_id=self._take_id(),
        )
        self._queue(msg)

    def subscribe(self, key: str, interval: float = 0.0) -> None:
        """Register for `key` (interval > 0: the DB drops updates closer than that)."""
        if not key:
            raise ValueError("cannot subscribe to an empty variable name")
        self._subscriptions[key] = interval
        if self.connected:
            self._queue(self._register_msg(key, interval))

    def unsubscribe(self, key: str) -> None:
        if self._subscriptions.pop(key, None) is not None and self.connected:
            self._queue(
                MOOSMessage(
                    p.UNREGISTER, p.DOUBLE, key, self.time(), 0.0, src=self.name, id=self._take_id()
                )
            )

    def subscribe_wildcard(
        self, var_pattern: str, app_pattern: str = "*", interval: float = 0.0
    ) -> None:
        """Register every variable whose name matches `var_pattern` (MOOS globs `*`, `?`) and
        whose first writer matches `app_pattern`."""
        if not var_pattern or not app_pattern:
            raise ValueError("wildcard patterns must not be empty")
        self._wildcards[(var_pattern, app_pattern)] = interval
        if self.connected:
            self._queue(self._wildcard_msg(p.WILDCARD_REGISTER, var_pattern, app_pattern, interval))

    def unsubscribe_wildcard(self, var_pattern: str, app_pattern: str = "*") -> None:
        if self._wildcards.pop((var_pattern, app_pattern), None) is not None and self.connected:
            self._queue(self._wildcard_msg(p.WILDCARD_UNREGISTER, var_pattern, app_pattern, 0.0))

    @property
    def subscriptions(self) -> dict[str, float]:
        return dict(self._subscriptions)

    async def server_request(self, name: str, timeout: float = 2.0) -> list[MOOSMessage]:
        """Send a `Q` request (ALL, VAR_SUMMARY, PROC_SUMMARY, DB_CLEAR) and return the replies
        (N messages with id -2) from the first packet that carries any; [] on timeout."""
        if not self.connected:
            raise ConnectionError(f"{self.name}: not connected")
        future: asyncio.Future[list[MOOSMessage]] = asyncio.get_running_loop().create_future()
        self._requests.append(future)
        self._queue(
            MOOSMessage(
                p.SERVER_REQUEST, p.STRING, name, self.time(), src=self.name, id=p.SERVER_REQUEST_ID
            )
        )
        try:
            async with asyncio.timeout(timeout):
                return await future
        except TimeoutError:
            return []
        finally:
            with contextlib.suppress(ValueError):
                self._requests.remove(future)

    async def flush(self, timeout: float = 5.0) -> None:
        """Wait until the outbox has been handed to the socket, or `timeout`. Returns at once
        when disconnected (the outbox then waits for the next connection)."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while self._outbox and self.connected and loop.time() < deadline:
            await asyncio.sleep(0.001)
        if self._writer is not None:
            with contextlib.suppress(ConnectionError):
                await self._writer.drain()

    # -- receiving -----------------------------------------------------------------------------

    async def receive(self, timeout: float | None = None) -> MOOSMessage:
        """The next received message (TimeoutError after `timeout`)."""
        async with asyncio.timeout(timeout):
            while not self._inbox:
                self._inbox_ready.clear()
                await self._inbox_ready.wait()
        return self._inbox.popleft()

    def fetch(self) -> list[MOOSMessage]:
        """All messages received so far (non-blocking)."""
        mail = list(self._inbox)
        self._inbox.clear()
        return mail

    async def __aiter__(self) -> AsyncIterator[MOOSMessage]:
        while True:
            yield await self.receive()

    # -- internals -----------------------------------------------------------------------------

    def _take_id(self) -> int:
        msg_id = self._next_id
        self._next_id += 1
        return msg_id

    def _register_msg(self, key: str, interval: float) -> MOOSMessage:
        return MOOSMessage(
            p.REGISTER, p.DOUBLE, key, self.time(), interval, src=self.name, id=self._take_id()
        )

    def _wildcard_msg(self, kind: str, var: str, app: str, interval: float) -> MOOSMessage:
        return MOOSMessage(
            kind,
            p.STRING,
            self.name,
            self.time(),
            -1.0,
            -1.0,
            p.wildcard_sval(app, var, interval),
            self.name,
            id=self._take_id(),
        )

    def _queue(self, msg: MOOSMessage) -> None:
        self._outbox.append(msg)
        if len(self._outbox) > self.outbox_limit:
            dropped = len(self._outbox) - self.outbox_limit // 2
            for _ in range(dropped):
                self._outbox.popleft()
            log.warning(
                "%s: outbox over %d messages, dropped the %d oldest",
                self.name,
                self.outbox_limit,
                dropped,
            )
        self._wake.set()

    def _to_inbox(self, msg: MOOSMessage) -> None:
        self._inbox.append(msg)
        if len(self._inbox) > self.inbox_limit:
            self._inbox.popleft()
        self._inbox_ready.set()

    async def _run(self) -> None:
        refusals = 0  # in a row, on reconnection
        loop = asyncio.get_running_loop()
        try:
            while True:
                try:
                    reader, writer = await asyncio.open_connection(self.host, self.port)
                except OSError as err:
                    now = loop.time()
                    due = self.unreachable.failed(now)
                    log.log(
                        logging.WARNING if due else logging.DEBUG,
                        "%s: cannot connect to the MOOSDB at %s:%d (ServerHost/ServerPort): "
                        "%s; still trying (for %.0f s)",
                        self.name,
                        self.host,
                        self.port,
                        err.strerror or err,
                        self.unreachable.failing_for(now),
                    )
                    await asyncio.sleep(self.reconnect_interval)
                    continue
                self.unreachable.reset()
                delay = self.reconnect_interval
                connections = self.connections
                try:
                    await self._session(reader, writer)
                except MoosRefusedError as err:
                    if not self.connections:
                        log.error("%s: %s", self.name, err)
                        self.failure = err
                        self.signal_refused.emit(err)
                        return
                    # The DB still holds our previous session (it has not noticed that the
                    # connection is gone): it drops it after its client timeout.
                    refusals += 1
                    delay = min(self.reconnect_interval * 2**refusals, MAX_REFUSED_BACKOFF)
                    log.warning(
                        "%s: %s (the MOOSDB still holds the previous session?); "
                        "trying again in %.1f s",
                        self.name,
                        err,
                        delay,
                    )
                except (OSError, EOFError, TimeoutError, MoosProtocolError) as err:
                    log.warning(
                        "%s: connection to %s:%d lost: %s",
                        self.name,
                        self.host,
                        self.port,
                        err or type(err).__name__,
                    )
                finally:
                    writer.close()
                    self._on_lost()
                if self.connections > connections:
                    refusals = 0
                await asyncio.sleep(delay)
        finally:
            self._on_lost()
            self._stopped.set()

    def _on_lost(self) -> None:
        self._writer = None
        if not self._connected.is_set():
            return
        self._connected.clear()
        # registrations are re-sent on reconnect; keep only publications and requests
        kept = [m for m in self._outbox if m.msg_type == p.NOTIFY]
        self._outbox = deque(kept)
        for future in self._requests:
            if not future.done():
                future.set_result([])
        self.signal_disconnect.emit()

    async def _session(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        sock = writer.get_extra_info("socket")
        if sock is not None:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.skew.skew = 0.0
        writer.write(
            p.PROTOCOL_STRING + p.encode_packet([p.handshake_message(self.name, self.time())])
        )
        await writer.drain()
        framer = p.PacketFramer(self.max_packet_size)
        async with asyncio.timeout(HANDSHAKE_TIMEOUT):
            welcome, early = await self._read_first_packet(reader, framer)
        if welcome.msg_type == p.POISON:
            raise MoosRefusedError(f"MOOSDB refused {self.name!r}: {welcome.string}")
        if welcome.msg_type != p.WELCOME:
            raise MoosProtocolError(f"expected a welcome, got message type {welcome.msg_type!r}")
        self.community = welcome.community
        self.db_hostname = p.welcome_hostname(welcome)
        self.clock_correction = bool(self.db_hostname) and self.db_hostname != socket.gethostname()
        if self.clock_correction:
            self.skew.skew = welcome.dval
        self._writer = writer
        self._resend_registrations()
        self.connections += 1
        self._connected.set()
        log.info(
            "%s: connected to MOOSDB %s at %s:%d", self.name, self.community, self.host, self.port
        )
        self.signal_connect.emit()
        write_task = asyncio.create_task(self._write_loop(writer))
        try:
            await self._read_loop(reader, framer, early)
        finally:
            with contextlib.suppress(OSError):  # a write error is the lost connection itself
                await cancel_and_wait(write_task)

    def _resend_registrations(self) -> None:
        pending = list(self._outbox)
        self._outbox.clear()
        for key, interval in self._subscriptions.items():
            self._outbox.append(self._register_msg(key, interval))
        for (var, app), interval in self._wildcards.items():
            self._outbox.append(self._wildcard_msg(p.WILDCARD_REGISTER, var, app, interval))
        self._outbox.extend(pending)
        self._wake.set()

    async def _read_first_packet(
        self, reader: asyncio.StreamReader, framer: p.PacketFramer
    ) -> tuple[MOOSMessage, list[list[MOOSMessage]]]:
        """The handshake's answer, and the packets that came with it (for the read loop)."""
        while True:
            data = await reader.read(65536)
            if not data:
                raise EOFError("MOOSDB closed the connection during the handshake")
            buf, spans = framer.feed(data)
            packets = [p.decode_packet(buf, start, end) for start, end in spans]
            for i, msgs in enumerate(packets):
                if msgs:
                    return msgs[0], packets[i + 1 :]

    async def _read_loop(
        self, reader: asyncio.StreamReader, framer: p.PacketFramer, early: list[list[MOOSMessage]]
    ) -> None:
        for msgs in early:
            self._on_packet(msgs)
        decode = p.decode_packet
        while True:
            data = await reader.read(262144)
            if not data:
                raise EOFError("MOOSDB closed the connection")
            buf, spans = framer.feed(data)
            for start, end in spans:
                self._on_packet(decode(buf, start, end))

    def _on_packet(self, msgs: list[MOOSMessage]) -> None:
        if msgs and msgs[0].msg_type == p.TIMING:
            echo = msgs[0]
            if echo.dval > 0:
                self.skew.update(echo.time, echo.dval, self.local_time())
            self.throttle = max(echo.dval2, 0.0)
            del msgs[0]
        if self._requests:
            replies = [m for m in msgs if m.id == p.SERVER_REQUEST_ID and m.msg_type == p.NOTIFY]
            if replies:
                future = self._requests.pop(0)
                if not future.done():
                    future.set_result(replies)
        deliver = self.on_message or self._to_inbox
        for msg in msgs:
            kind = msg.msg_type
            if kind == p.NOTIFY:
                if msg.id == p.SERVER_REQUEST_ID:
                    continue
            elif kind == p.NULL:
                continue
            elif kind in (p.WELCOME, p.POISON):
                raise MoosProtocolError(f"unexpected {kind!r} message after the handshake")
            try:
                deliver(msg)
            except Exception:
                log.exception("%s: message handler failed on %s", self.name, msg.key)

    async def _write_loop(self, writer: asyncio.StreamWriter) -> None:
        loop = asyncio.get_running_loop()
        last_timing = -1e9
        while True:
            wait = last_timing + TIMING_PERIOD - loop.time()
            if not self._outbox and wait > 0:
                self._wake.clear()
                # asyncio.timeout, not wait_for: Python 3.11's wait_for can swallow a
                # cancellation that arrives as the wait ends
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(wait):
                        await self._wake.wait()
            batch: list[MOOSMessage] = []
            now = loop.time()
            if now - last_timing >= TIMING_PERIOD:
                batch.append(p.timing_message(self.local_time()))
                last_timing = now
            while self._outbox and len(batch) < MAX_PACKET_MESSAGES:
                batch.append(self._outbox.popleft())
            if not batch:
                continue
            writer.write(p.encode_packet(batch))
            await writer.drain()
            if self.throttle > 0:
                await asyncio.sleep(self.throttle)
            elif not self._outbox:
                await asyncio.sleep(0)
