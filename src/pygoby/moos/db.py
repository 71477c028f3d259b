"""The embedded MOOSDB: an asyncio TCP server around the sans-I/O `DBCore`.

    async with MOOSDB(port=0, community="alpha") as db:   # port 0: an ephemeral port
        print(db.port)

Unlike the C++ DB, each connection does its own handshake with timeouts, so a connection that
never completes its handshake blocks nobody. The server binds 127.0.0.1 unless `host` says
otherwise ("0.0.0.0" opens it to the network). A client that sends bytes that are not MOOS
packets, or a packet above `max_packet_size`, is dropped with a log line; the others carry on.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket

from pygoby.moos import protocol as p
from pygoby.moos.dbcore import DBCore
from pygoby.moos.errors import MoosProtocolError
from pygoby.util.clock import Clock

log = logging.getLogger(__name__)

DEFAULT_CLIENT_TIMEOUT = 5.0
DEFAULT_HANDSHAKE_TIMEOUT = 5.0
MAX_WRITE_BUFFER = 64 * 1024 * 1024


class _Connection(asyncio.Protocol):
    """One client connection: preamble, handshake, then packets into the core."""

    def __init__(self, server: MOOSDB) -> None:
        self.server = server
        self.transport: asyncio.Transport | None = None
        self.name: str | None = None
        self.peer = "?"
        self._preamble = bytearray()
        self._framer = p.PacketFramer(server.max_packet_size)
        self.last_rx = 0.0
        self._handshake_timer: asyncio.TimerHandle | None = None
        self._closed = False

    # asyncio.Protocol ---------------------------------------------------------------------------

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        sock = transport.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.peer = str(transport.get_extra_info("peername"))
        loop = asyncio.get_running_loop()
        self.last_rx = loop.time()
        self._handshake_timer = loop.call_later(
            self.server.handshake_timeout, self._drop, "handshake not completed in time"
        )
        self.server._connections.add(self)

    def data_received(self, data: bytes) -> None:
        self.last_rx = asyncio.get_running_loop().time()
        try:
            if len(self._preamble) < p.PROTOCOL_STRING_SIZE:
                need = p.PROTOCOL_STRING_SIZE - len(self._preamble)
                self._preamble += data[:need]
                data = data[need:]
                if len(self._preamble) < p.PROTOCOL_STRING_SIZE:
                    return
                if not p.check_protocol_string(bytes(self._preamble)):
                    self._drop("wrong protocol string", quiet=True)
                    return
            if data:
                self._framer.feed(data)
            for packet in self._framer.packets():
                if self._closed:
                    return
                msgs = p.decode_packet(packet)
                if self.name is None:
                    self._handshake(msgs)
                else:
                    self.server._dispatch(self.server.core.process_packet(self.name, msgs))
        except MoosProtocolError as err:
            self._drop(f"protocol error: {err}")
        except Exception:  # a bug must cost one connection, never the DB
            log.exception("error while serving client %s", self.name)
            self._drop("internal error")

    def connection_lost(self, exc: Exception | None) -> None:
        self._closed = True
        if self._handshake_timer is not None:
            self._handshake_timer.cancel()
        self.server._connections.discard(self)
        if self.name is not None and self.server._clients.get(self.name) is self:
            del self.server._clients[self.name]
            log.info("client %s disconnected", self.name)
            self.server._dispatch(self.server.core.disconnect(self.name))

    # ------------------------------------------------------------------------------------------

    def _handshake(self, msgs: list[p.MOOSMessage]) -> None:
        if not msgs:
            raise MoosProtocolError("empty handshake packet")
        reply = self.server.core.connect(msgs[0])
        self.send([reply])
        if reply.msg_type == p.POISON:
            self._drop(f"refused: {reply.string}")
            return
        if self._handshake_timer is not None:
            self._handshake_timer.cancel()
        self.name = msgs[0].string
        self.server._clients[self.name] = self
        log.info("client %s connected from %s", self.name, self.peer)
        self.server._dispatch(self.server.core.collect_pushes(exclude=self.name))

    def send(self, msgs: list[p.MOOSMessage], cache: dict[int, bytes] | None = None) -> None:
        if self._closed or self.transport is None:
            return
        self.transport.write(p.encode_packet(msgs, cache))
        if self.transport.get_write_buffer_size() > MAX_WRITE_BUFFER:
            self._drop("not reading its mail (write buffer full)")

    def _drop(self, reason: str, quiet: bool = False) -> None:
        if self._closed:
            return
        self._closed = True
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
    max_packet_size (bytes; larger packets are refused from their header).
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
        max_packet_size: int = p.DEFAULT_MAX_PACKET_SIZE,
        hostname: str | None = None,
    ) -> None:
        self.host = host
        self._requested_port = port
        self.client_timeout = client_timeout
        self.handshake_timeout = handshake_timeout
        self.max_packet_size = max_packet_size
        self.core = DBCore(community, clock, hostname or socket.gethostname())
        self._server: asyncio.Server | None = None
        self._sweeper: asyncio.Task[None] | None = None
        self._connections: set[_Connection] = set()
        self._clients: dict[str, _Connection] = {}

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

    async def start(self) -> None:
        loop = asyncio.get_running_loop()
        self._server = await loop.create_server(
            lambda: _Connection(self), self.host, self._requested_port, reuse_address=True
        )
        self._sweeper = asyncio.create_task(self._sweep(), name="moosdb-timeouts")
        log.info("MOOSDB %s listening on %s:%d", self.community, self.host, self.port)

    async def stop(self) -> None:
        if self._sweeper is not None:
            self._sweeper.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._sweeper
            self._sweeper = None
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

    def _dispatch(self, outgoing: dict[str, list[p.MOOSMessage]]) -> None:
        cache: dict[int, bytes] = {}  # a notification routed to many clients is encoded once
        for name, msgs in outgoing.items():
            conn = self._clients.get(name)
            if conn is not None and msgs:
                conn.send(msgs, cache)

    async def _sweep(self) -> None:
        loop = asyncio.get_running_loop()
        while True:
            await asyncio.sleep(min(0.5, self.client_timeout / 4))
            limit = loop.time() - self.client_timeout
            for conn in list(self._clients.values()):
                if conn.last_rx < limit:
                    conn._drop(f"silent for more than {self.client_timeout:g} s")
