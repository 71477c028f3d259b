"""Network faults on loopback for the tests and the soak: a TCP relay that can cut its
connections the way a network does (one side never learns of it)."""

from __future__ import annotations

import asyncio
import contextlib


class CuttableRelay:
    """Relays TCP connections from `port` (ephemeral, after `start()`) to `target_port`.

    `cut()` aborts the client side of every relayed connection and leaves the server side
    open and silent: the client sees its connection reset while the server still holds the
    session until its own timeout (a dropped radio link, a NAT timeout, a cable pulled at the
    client's end). Connections made after the cut are relayed normally.
    """

    def __init__(self, target_port: int, host: str = "127.0.0.1") -> None:
        self.target_port = target_port
        self.host = host
        self.port = 0
        self._server: asyncio.Server | None = None
        self._pairs: list[tuple[asyncio.StreamWriter, asyncio.StreamWriter]] = []
        self._tasks: set[asyncio.Task[None]] = set()
        self._stale: list[asyncio.StreamWriter] = []  # server sides kept open after a cut

    async def start(self) -> int:
        self._server = await asyncio.start_server(self._relay, self.host, 0)
        self.port = self._server.sockets[0].getsockname()[1]
        return self.port

    def cut(self) -> None:
        for client, server in self._pairs:
            client.transport.abort()
            self._stale.append(server)
        self._pairs.clear()
        for task in self._tasks:
            task.cancel()

    async def close(self) -> None:
        self.cut()
        for writer in self._stale:
            writer.transport.abort()
        self._stale.clear()
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()

    async def _relay(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            upstream_reader, upstream = await asyncio.open_connection(self.host, self.target_port)
        except OSError:
            writer.transport.abort()
            return
        self._pairs.append((writer, upstream))
        for source, sink in ((reader, upstream), (upstream_reader, writer)):
            task = asyncio.create_task(self._pump(source, sink))
            self._tasks.add(task)
            task.add_done_callback(self._tasks.discard)

    @staticmethod
    async def _pump(source: asyncio.StreamReader, sink: asyncio.StreamWriter) -> None:
        with contextlib.suppress(ConnectionError):
            while data := await source.read(65536):
                sink.write(data)
                await sink.drain()
            sink.close()
