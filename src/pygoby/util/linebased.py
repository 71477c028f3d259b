"""Line-based links (serial, TCP client, TCP server) for modem drivers.

A driver sees a `LineLink`: `write(text)`, `read_lines()` (non-blocking: the complete lines
received since the last call) and `is_open`. The asyncio links do their I/O in the running event
loop and buffer lines, so a driver's `do_work()` stays a plain, non-blocking function.
`MemoryLink` is the same interface with no I/O, for sans-I/O tests and simulations.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import os
from collections import deque
from typing import Any, Protocol

from pygoby.util.errors import LinkClosedError

log = logging.getLogger(__name__)

MAX_LINE_BYTES = 65536  # a peer that never sends the delimiter must not grow memory forever


class LineLink(Protocol):
    # connections made so far: a change tells a driver that its peer may have restarted
    connections: int

    @property
    def is_open(self) -> bool: ...

    def open(self) -> None: ...

    def close(self) -> None: ...

    def write(self, text: str) -> None: ...

    def read_lines(self) -> list[str]: ...


class LineSplitter:
    """Splits a byte stream into text lines (delimiter removed, decoded as latin-1).

    A line longer than `max_line_bytes` is dropped whole, up to and including its delimiter (so
    its tail never comes out as a line of its own), and counted in `discarded`. Each byte is
    scanned once, however the stream is cut into chunks.
    """

    def __init__(self, delimiter: str, max_line_bytes: int = MAX_LINE_BYTES) -> None:
        if not delimiter:
            raise ValueError("line delimiter must not be empty")
        self.delimiter = delimiter.encode("latin-1")
        self.max_line_bytes = max_line_bytes
        self.discarded = 0  # over-long lines dropped so far
        self._buffer = bytearray()
        self._scanned = 0  # bytes of _buffer known to hold no delimiter
        self._discarding = False  # inside an over-long line: drop up to the next delimiter

    def feed(self, data: bytes) -> list[str]:
        self._buffer += data
        lines = []
        while True:
            end = self._buffer.find(self.delimiter, self._scanned)
            if end < 0:
                break
            if self._discarding:
                self._discarding = False
            elif end <= self.max_line_bytes:
                lines.append(self._buffer[:end].decode("latin-1"))
            else:
                self._discard()
            del self._buffer[: end + len(self.delimiter)]
            self._scanned = 0
        # (a line at the limit may still be waiting for the rest of a split delimiter)
        if len(self._buffer) >= self.max_line_bytes + len(self.delimiter):
            if not self._discarding:
                self._discard()
                self._discarding = True
            # keep what could be the start of a delimiter split across chunks
            del self._buffer[: len(self._buffer) - len(self.delimiter) + 1]
        self._scanned = max(0, len(self._buffer) - len(self.delimiter) + 1)
        return lines

    def _discard(self) -> None:
        self.discarded += 1
        log.warning("discarding a line longer than %d bytes", self.max_line_bytes)


class LocalLink:
    """The open/closed state of a link without I/O (it counts its openings)."""

    def __init__(self) -> None:
        self._open = False
        self.connections = 0

    @property
    def is_open(self) -> bool:
        return self._open

    def open(self) -> None:
        if not self._open:
            self.connections += 1
        self._open = True

    def close(self) -> None:
        self._open = False


class MemoryLink(LocalLink):
    """A link with no I/O: tests push incoming text with `feed` and inspect `written`."""

    def __init__(self, delimiter: str = "\r\n") -> None:
        super().__init__()
        self._splitter = LineSplitter(delimiter)
        self._lines: deque[str] = deque()
        self.written: list[str] = []

    def feed(self, text: str) -> None:
        self._lines.extend(self._splitter.feed(text.encode("latin-1")))

    def write(self, text: str) -> None:
        if not self._open:
            raise LinkClosedError("memory link is closed")
        self.written.append(text)

    def read_lines(self) -> list[str]:
        lines = list(self._lines)
        self._lines.clear()
        return lines

    def take_written(self) -> list[str]:
        out, self.written = self.written, []
        return out


class _StreamLinkBase:
    """Common part of the asyncio links: a line buffer fed by one or more transports."""

    def __init__(self, delimiter: str) -> None:
        self.delimiter = delimiter
        self._lines: deque[str] = deque()
        self._transports: dict[asyncio.BaseTransport, LineSplitter] = {}
        self._task: asyncio.Task | None = None
        self._closing = False
        self._open_event = asyncio.Event()
        self.connections = 0

    @property
    def is_open(self) -> bool:
        return bool(self._transports)

    async def wait_open(self, timeout: float = 10.0) -> None:
        async with asyncio.timeout(timeout):
            await self._open_event.wait()

    def read_lines(self) -> list[str]:
        lines = list(self._lines)
        self._lines.clear()
        return lines

    def write(self, text: str) -> None:
        if not self._transports:
            raise LinkClosedError(f"{self.describe()} is not connected")
        data = text.encode("latin-1")
        for transport in list(self._transports):
            transport.write(data)  # type: ignore[attr-defined]

    def close(self) -> None:
        self._closing = True
        if self._task is not None:
            self._task.cancel()
            self._task = None
        for transport in list(self._transports):
            transport.close()
        self._transports.clear()
        self._open_event.clear()

    def describe(self) -> str:
        return type(self).__name__

    # protocol callbacks
    def _made(self, transport: asyncio.BaseTransport) -> None:
        self._transports[transport] = LineSplitter(self.delimiter)
        self.connections += 1
        self._open_event.set()
        log.info("%s: connection made", self.describe())

    def _received(self, transport: asyncio.BaseTransport, data: bytes) -> None:
        splitter = self._transports.get(transport)
        if splitter is not None:
            self._lines.extend(splitter.feed(data))

    def _lost(self, transport: asyncio.BaseTransport) -> None:
        if self._transports.pop(transport, None) is not None:
            log.warning("%s: connection lost", self.describe())
        if not self._transports:
            self._open_event.clear()


class _Protocol(asyncio.Protocol):
    def __init__(self, owner: _StreamLinkBase, on_lost: asyncio.Future | None = None) -> None:
        self.owner = owner
        self.on_lost = on_lost
        self.transport: asyncio.BaseTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport
        self.owner._made(transport)

    def data_received(self, data: bytes) -> None:
        assert self.transport is not None
        self.owner._received(self.transport, data)

    def connection_lost(self, exc: Exception | None) -> None:
        if self.transport is not None:
            self.owner._lost(self.transport)
        if self.on_lost is not None and not self.on_lost.done():
            self.on_lost.set_result(None)


class TCPClientLink(_StreamLinkBase):
    """Connects to host:port; reconnects every `reconnect_interval` seconds while down."""

    def __init__(
        self, host: str, port: int, delimiter: str = "\r\n", reconnect_interval: float = 10.0
    ) -> None:
        super().__init__(delimiter)
        self.host, self.port, self.reconnect_interval = host, port, reconnect_interval

    def describe(self) -> str:
        return f"TCP client to {self.host}:{self.port}"

    def open(self) -> None:
        self._closing = False
        if self._task is None:
            self._task = asyncio.get_running_loop().create_task(self._run())

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        while not self._closing:
            lost: asyncio.Future = loop.create_future()
            try:
                await loop.create_connection(
                    functools.partial(_Protocol, self, lost), self.host, self.port
                )
            except OSError as exc:
                log.warning(
                    "%s: %s; retrying in %g s", self.describe(), exc, self.reconnect_interval
                )
            else:
                await lost
            if not self._closing:
                await asyncio.sleep(self.reconnect_interval)


class TCPServerLink(_StreamLinkBase):
    """Serves on port (0 = ephemeral; see `port` after `wait_open` or `wait_listening`).

    Writes go to every connected client; lines from all clients are merged.
    """

    def __init__(self, port: int, host: str = "127.0.0.1", delimiter: str = "\r\n") -> None:
        super().__init__(delimiter)
        self.host, self.port = host, port
        self._server: asyncio.Server | None = None
        self._listening = asyncio.Event()

    def describe(self) -> str:
        return f"TCP server on {self.host}:{self.port}"

    def open(self) -> None:
        self._closing = False
        if self._task is None:
            self._task = asyncio.get_running_loop().create_task(self._serve())

    async def wait_listening(self, timeout: float = 10.0) -> int:
        """The port once listening; raises the server's own error (e.g. port in use) if it failed."""
        listening = asyncio.ensure_future(self._listening.wait())
        waiting = {listening} if self._task is None else {listening, self._task}
        try:
            await asyncio.wait(waiting, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
        finally:
            listening.cancel()
        if self._task is not None and self._task.done() and not self._task.cancelled():
            self._task.result()  # raises the error that ended the server
        if not self._listening.is_set():
            raise TimeoutError(f"{self.describe()}: not listening after {timeout} s")
        return self.port

    async def _serve(self) -> None:
        loop = asyncio.get_running_loop()
        server = await loop.create_server(lambda: _Protocol(self), self.host, self.port)
        self._server = server
        self.port = server.sockets[0].getsockname()[1]
        self._listening.set()
        try:
            await asyncio.Future()  # serve until cancelled
        finally:
            server.close()  # close() may already have dropped self._server

    def drop_connections(self) -> None:
        """Close every client connection and keep listening."""
        for transport in list(self._transports):
            transport.close()

    def close(self) -> None:
        if self._server is not None:
            self._server.close()
            self._server = None
        self._listening.clear()
        super().close()


class SerialLink(_StreamLinkBase):
    """A serial port (pyserial) read through the event loop; RTS forced low on open."""

    def __init__(self, port: str, baud: int, delimiter: str = "\r\n") -> None:
        super().__init__(delimiter)
        self.port, self.baud = port, baud
        self._serial: Any = None  # a serial.Serial once open (pyserial has no type stubs)
        self._transport = _SerialTransport(self)

    def describe(self) -> str:
        return f"serial {self.port}@{self.baud}"

    def open(self) -> None:
        import serial  # pyserial

        self._closing = False
        self._serial = serial.Serial(self.port, self.baud, timeout=0, write_timeout=1)
        with contextlib.suppress(OSError, ValueError):
            self._serial.rts = False
        asyncio.get_running_loop().add_reader(self._serial.fileno(), self._on_readable)
        self._made(self._transport)

    def _on_readable(self) -> None:
        assert self._serial is not None
        try:
            data = self._serial.read(self._serial.in_waiting or 1)
        except OSError as exc:
            log.warning("%s: read failed: %s", self.describe(), exc)
            self._drop()
            return
        if data:
            self._received(self._transport, data)

    def _write_bytes(self, data: bytes) -> None:
        assert self._serial is not None
        try:
            self._serial.write(data)
        except OSError as exc:
            log.warning("%s: write failed: %s", self.describe(), exc)
            self._drop()

    def _drop(self) -> None:
        if self._serial is not None:
            with contextlib.suppress(Exception):
                asyncio.get_running_loop().remove_reader(self._serial.fileno())
            self._serial.close()
            self._serial = None
        self._lost(self._transport)

    def close(self) -> None:
        self._drop()
        super().close()


class _SerialTransport(asyncio.BaseTransport):
    def __init__(self, link: SerialLink) -> None:
        super().__init__()
        self.link = link

    def write(self, data: bytes) -> None:
        self.link._write_bytes(data)

    def close(self) -> None:
        pass


def open_pty_pair() -> tuple[int, str]:
    """A pseudo-terminal: (master fd, slave device path), e.g. to fake a serial modem."""
    import tty

    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    path = os.ttyname(slave)
    os.close(slave)
    return master, path
