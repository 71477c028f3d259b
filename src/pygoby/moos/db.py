"""The embedded MOOSDB: an asyncio TCP server around the sans-I/O `DBCore`.

    async with MOOSDB(port=0, community="alpha") as db:   # port 0: an ephemeral port
        print(db.port)

Unlike the C++ DB, each connection does its own handshake with timeouts, so a connection that
never completes its handshake blocks nobody. The server binds 127.0.0.1 unless `host` says
otherwise ("0.0.0.0" opens it to the network). A client that sends bytes that are not MOOS
packets, or a packet above `max_packet_size`, is dropped with a log line; the others carry on.

Mail for a client is collected in one outgoing buffer and written once per event-loop
iteration, so a burst of notifications leaves in a few large packets (as libMOOS packs its
outbox). Resources are bounded: at most `max_clients` connections; a packet must arrive whole
within `packet_timeout` of its first byte; at most `max_variables` variables; the stored
variables, partial packets, mail held for a client (a synchronous client's until it next
writes) and unsent output together stay within `memory_budget` bytes (a write that would take
the stored variables beyond half of it is refused, so that the clients' buffers always have the
other half; beyond it the connection holding the most is dropped), and one client's unsent
output within MAX_WRITE_BUFFER.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket

from pygoby.moos import protocol as p
from pygoby.moos.dbcore import DEFAULT_MAX_VARIABLES, DBCore
from pygoby.moos.errors import MoosProtocolError
from pygoby.util.aiorun import cancel_and_wait
from pygoby.util.clock import Clock

log = logging.getLogger(__name__)

DEFAULT_CLIENT_TIMEOUT = 5.0
DEFAULT_HANDSHAKE_TIMEOUT = 5.0
DEFAULT_PACKET_TIMEOUT = 30.0
DEFAULT_MAX_CLIENTS = 512
DEFAULT_MEMORY_BUDGET = 256 * 1024 * 1024
MAX_WRITE_BUFFER = 64 * 1024 * 1024


class _Connection(asyncio.Protocol):
    """One client connection: preamble, handshake, then packets into the core."""

    def __init__(self, server: MOOSDB) -> None:
        self.server = server
        self.transport: asyncio.Transport | None = None
        self.name: str | None = None
        self.peer = "?"
        self._preamble = b""
        self._framer = p.PacketFramer(server.max_packet_size)
        self.pending = 0  # bytes of an incomplete packet (as last counted in the budget)
        self.packet_since: float | None = None  # loop time the incomplete packet began
        self.unsent = 0  # the transport's write buffer, as last seen
        self.last_rx = 0.0
        self._handshake_timer: asyncio.TimerHandle | None = None
        self._closed = False

    # asyncio.Protocol ---------------------------------------------------------------------------

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]  # uvloop's is no asyncio.Transport
        self.peer = str(transport.get_extra_info("peername"))
        server = self.server
        if len(server._connections) >= server.max_clients:
            self._closed = True
            log.warning(
                "refusing a connection from %s: %d connections already (max_clients)",
                self.peer,
                len(server._connections),
            )
            transport.abort()  # type: ignore[attr-defined]  # (a stream transport)
            return
        sock = transport.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        loop = server._loop
        self.last_rx = loop.time()
        self._handshake_timer = loop.call_later(
            server.handshake_timeout, self._drop, "handshake not completed in time"
        )
        server._connections.add(self)

    def data_received(self, data: bytes) -> None:
        if self._closed:
            return
        server = self.server
        now = self.last_rx = server._loop.time()
        try:
            if len(self._preamble) < p.PROTOCOL_STRING_SIZE:
                need = p.PROTOCOL_STRING_SIZE - len(self._preamble)
                self._preamble += data[:need]
                data = data[need:]
                if len(self._preamble) < p.PROTOCOL_STRING_SIZE:
                    return
                if not p.check_protocol_string(self._preamble):
                    self._drop("wrong protocol string", quiet=True)
                    return
            if data:
                self._consume(data, now)
        except MoosProtocolError as err:
            self._drop(f"protocol error: {err}")
        except Exception:  # a bug must cost one connection, never the DB
            log.exception("error while serving client %s", self.name)
            self._drop("internal error")
        server._schedule_flush()

    def connection_lost(self, exc: Exception | None) -> None:
        self._closed = True
        self._release_buffers()
        if self._handshake_timer is not None:
            self._handshake_timer.cancel()
        server = self.server
        server._connections.discard(self)
        if self.name is not None and server._clients.get(self.name) is self:
            del server._clients[self.name]
            log.info("client %s disconnected", self.name)
            server.core.disconnect(self.name)
            server._schedule_flush()

    # ------------------------------------------------------------------------------------------

    def _consume(self, data: bytes, now: float) -> None:
        """Process every packet that `data` completes; the rest waits in the framer."""
        framer = self._framer
        buf, spans = framer.feed(data)
        core = self.server.core
        for start, end in spans:
            if self.name is None:
                self._handshake(buf[start:end])
            else:
                core.process_packet(self.name, buf, start, end)
            if self._closed:
                return
        if not framer.buffered:
            self.packet_since = None
        elif framer.began_packet:
            self.packet_since = now
        self._set_pending(framer.buffered)
        if framer.buffered:
            self.server._check_budget()

    def _handshake(self, packet: bytes) -> None:
        msgs = p.decode_packet(packet)
        if not msgs:
            raise MoosProtocolError("empty handshake packet")
        reply = self.server.core.connect(msgs[0])
        self.write(p.encode_packet([reply]))
        if reply.msg_type == p.POISON:
            self._drop(f"refused: {reply.string}")
            return
        if self._handshake_timer is not None:
            self._handshake_timer.cancel()
        self.name = msgs[0].string
        self.server._clients[self.name] = self
        log.info("client %s connected from %s", self.name, self.peer)

    def write(self, data: bytes) -> None:
        if self._closed or self.transport is None:
            return
        transport = self.transport
        transport.write(data)
        self.update_unsent()
        if self.unsent > MAX_WRITE_BUFFER:
            self._drop("not reading its mail (write buffer full)")

    def update_unsent(self) -> None:
        assert self.transport is not None
        size = self.transport.get_write_buffer_size()
        self.server._unsent_total += size - self.unsent
        self.unsent = size

    def _set_pending(self, size: int) -> None:
        self.server._pending_total += size - self.pending
        self.pending = size

    def _release_buffers(self) -> None:
        self._framer = p.PacketFramer(self.server.max_packet_size)
        self._set_pending(0)
        self.server._unsent_total -= self.unsent
        self.unsent = 0

    def _drop(self, reason: str, quiet: bool = False) -> None:
        if self._closed:
            return
        self._closed = True
        self._release_buffers()
        (log.debug if quiet else log.warning)(
            "dropping client %s (%s): %s", self.name or "<handshaking>", self.peer, reason
        )
        if self.transport is not None:
            if reason.startswith("refused"):
                self.transport.close()  # let the poison reach the client
            else:
                self.transport.abort()


class MOOSDB:
    """An embedded MOOSDB server.

    Args: host (default 127.0.0.1), port (default 9000; 0 = ephemeral, read `port` after
    start), community (default "#1"), clock (MOOS time; see `pygoby.moos.timewarp`),
    client_timeout (s of silence before a client is dropped), handshake_timeout,
    packet_timeout (s from a packet's first byte to its last), max_packet_size (bytes; larger
    packets are refused from their header), max_clients (connections, handshaking ones
    included), max_variables, memory_budget (bytes of stored variables, partial packets, held
    mail and unsent output, all clients).
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = p.DEFAULT_PORT,
        community: str = p.DEFAULT_COMMUNITY,
        *,
        clock: Clock | None = None,
        client_timeout: float = DEFAULT_CLIENT_TIMEOUT,
        handshake_timeout: float = DEFAULT_HANDSHAKE_TIMEOUT,
        packet_timeout: float = DEFAULT_PACKET_TIMEOUT,
        max_packet_size: int = p.DEFAULT_MAX_PACKET_SIZE,
        max_clients: int = DEFAULT_MAX_CLIENTS,
        memory_budget: int = DEFAULT_MEMORY_BUDGET,
        max_variables: int = DEFAULT_MAX_VARIABLES,
        hostname: str | None = None,
    ) -> None:
        self.host = host
        self._requested_port = port
        self.client_timeout = client_timeout
        self.handshake_timeout = handshake_timeout
        self.packet_timeout = packet_timeout
        self.max_packet_size = max_packet_size
        self.max_clients = max_clients
        self.memory_budget = memory_budget
        self.core = DBCore(
            community,
            clock,
            hostname or socket.gethostname(),
            max_variables=max_variables,
            store_budget=memory_budget // 2,
        )
        self._server: asyncio.Server | None = None
        self._sweeper: asyncio.Task[None] | None = None
        self._connections: set[_Connection] = set()
        self._clients: dict[str, _Connection] = {}
        self._pending_total = 0
        self._unsent_total = 0
        self._flush_scheduled = False
        self._loop: asyncio.AbstractEventLoop = None  # type: ignore[assignment]  # start() sets it

    @property
    def community(self) -> str:
        return self.core.community

    @property
    def port(self) -> int:
        if self._server is None:
            return self._requested_port
        return self._server.sockets[0].getsockname()[1]

    @property
    def client_names(self) -> list[str]:
        return list(self._clients)

    @property
    def buffered(self) -> int:
        """Bytes of partial packets, held mail and unsent output for all clients (as last
        seen); with the stored variables (`core.stored_bytes`), what `memory_budget` bounds."""
        return self._pending_total + self._unsent_total + self._held_total()

    def _held_total(self) -> int:
        return sum(record.held_size() for record in self.core.clients.values())

    def _holding(self, conn: _Connection) -> int:
        record = self.core.clients.get(conn.name) if conn.name is not None else None
        held = record.held_size() if record is not None else 0
        return conn.pending + conn.unsent + held

    async def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._server = await self._loop.create_server(
            lambda: _Connection(self), self.host, self._requested_port, reuse_address=True
        )
        self._sweeper = asyncio.create_task(self._sweep(), name="moosdb-timeouts")
        log.info("MOOSDB %s listening on %s:%d", self.community, self.host, self.port)

    async def stop(self) -> None:
        sweeper, self._sweeper = self._sweeper, None
        await cancel_and_wait(sweeper)
        if self._server is not None:
            self._server.close()
            for conn in list(self._connections):
                if conn.transport is not None:
                    conn.transport.abort()
            await self._server.wait_closed()
            self._server = None

    async def serve_forever(self) -> None:
        if self._server is None:
            await self.start()
        assert self._server is not None
        try:
            await self._server.serve_forever()
        finally:
            await self.stop()

    async def __aenter__(self) -> MOOSDB:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    # ------------------------------------------------------------------------------------------

    def _schedule_flush(self) -> None:
        if not self._flush_scheduled:
            self._flush_scheduled = True
            self._loop.call_soon(self._flush)

    def _flush(self) -> None:
        """Write every client's due mail: once per loop iteration, however many packets came."""
        self._flush_scheduled = False
        clients = self._clients
        for record in self.core.take_ready():
            data = record.take_output()
            conn = clients.get(record.name)
            if conn is not None and data:
                conn.write(data)
        self._check_budget()

    def _check_budget(self) -> None:
        while self.buffered + self.core.stored_bytes > self.memory_budget:
            biggest = max(self._connections, key=self._holding, default=None)
            holding = self._holding(biggest) if biggest is not None else 0
            if biggest is None or holding == 0:
                return
            biggest._drop(
                f"holding {holding} bytes while the stored variables and all clients' "
                f"buffers exceed the memory budget of {self.memory_budget} bytes"
            )
            if biggest.name is not None and biggest.name in self.core.clients:
                # its held mail goes with it now, not when the transport reports the loss
                self.core.clients[biggest.name].drop_held()

    async def _sweep(self) -> None:
        loop = self._loop
        while True:
            await asyncio.sleep(min(0.5, self.client_timeout / 4, self.packet_timeout / 4))
            try:
                self._enforce_deadlines(loop.time())
            except Exception:  # the timeouts must outlive any bug
                log.exception("error while checking client deadlines")

    def _enforce_deadlines(self, now: float) -> None:
        for conn in list(self._connections):
            if conn.name is not None and conn.last_rx < now - self.client_timeout:
                conn._drop(f"silent for more than {self.client_timeout:g} s")
            elif conn.packet_since is not None and conn.packet_since < now - self.packet_timeout:
                conn._drop(f"a packet took more than {self.packet_timeout:g} s to arrive")
            elif conn.transport is not None and not conn.transport.is_closing():
                conn.update_unsent()
        self._check_budget()
