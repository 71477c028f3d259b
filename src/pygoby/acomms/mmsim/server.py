"""asyncio front ends for the modem model: a TCP server, a pseudo-terminal or a serial device.

Text is made here, at the edge: the model's sentences are printed with their checksum and CRLF;
host lines (CR and/or LF) are parsed by the model. The model's timed events and the channel's
deliveries run in one loop that wakes for the next of them (at most `work_period` apart).

Output never waits for a reader: a TCP client that reads nothing is not read either once its
pending output passes asyncio's high-water mark (so its own commands cannot grow it), and is
disconnected when the modem's own output (receptions) passes `MAX_CLIENT_BACKLOG` bytes; the
pseudo-terminal (or serial device) drops what its reader leaves unread.
"""

from __future__ import annotations

import asyncio
import logging
import os
import re

from pygoby.acomms.mmsim.channel import ModemChannel
from pygoby.acomms.mmsim.model import MicroModemModel
from pygoby.util.linebased import open_pty_pair
from pygoby.util.pty import PtyEnd, open_serial

log = logging.getLogger(__name__)

_LINE_END = re.compile(rb"[\r\n]+")
MAX_PENDING = 65536  # bytes of a host line without its end
MAX_CLIENT_BACKLOG = 1 << 20  # bytes of unread output before a TCP client is dropped
ANONYMOUS_PTY = ""  # `pty_path` value for a pty without a stable link


class _HostLines:
    """Host text split on CR and/or LF (hosts differ: goby sends CRLF, some send CR)."""

    def __init__(self) -> None:
        self.buffer = b""

    def feed(self, data: bytes) -> list[str]:
        *lines, self.buffer = _LINE_END.split(self.buffer + data)
        if len(self.buffer) > MAX_PENDING:
            self.buffer = b""
        return [line.decode("latin-1") for line in lines if line]


class MMSimServer:
    """Serves one emulated modem on TCP (every client sees the modem's output) and optionally
    on a pty: `pty_path` a path to link it at (e.g. /tmp/ttyLOOPA1), or ANONYMOUS_PTY; after
    `start`, `pty_path` is where a host opens it. Or on a serial device (`serial_path`: a tty,
    e.g. one end of a pygoby.util.pty.PtyPair). `port=None`: no TCP server."""

    def __init__(
        self,
        model: MicroModemModel,
        channel: ModemChannel,
        host: str = "127.0.0.1",
        port: int | None = 0,
        pty_path: str | None = None,
        work_period: float = 0.01,
        serial_path: str | None = None,
    ) -> None:
        if pty_path is not None and serial_path is not None:
            raise ValueError("a pty or a serial device, not both")
        self.model, self.channel = model, channel
        self.host, self.port = host, port
        self.pty_path = pty_path
        self.serial_path = serial_path
        self.work_period = work_period
        self.pty_dropped = 0  # bytes the pty's reader left unread
        self._pty: PtyEnd | None = None
        self._pty_master: int | None = None
        self._writers: set[asyncio.StreamWriter] = set()
        self._server: asyncio.Server | None = None
        self._tasks: list[asyncio.Task] = []
        self._client_tasks: set[asyncio.Task] = set()
        model.on_output = self._broadcast

    async def start(self) -> int | None:
        if self.port is not None:
            self._server = await asyncio.start_server(self._client, self.host, self.port)
            self.port = self._server.sockets[0].getsockname()[1]
            log.info(
                "Micro-Modem emulator id %d on %s:%d", self.model.modem_id, self.host, self.port
            )
        if self.serial_path is not None:
            self._pty_master = open_serial(self.serial_path)
        elif self.pty_path is not None:
            if self.pty_path:
                self._pty = PtyEnd(self.pty_path).open()
                self._pty_master = self._pty.master
            else:
                self._pty_master, self.pty_path = open_pty_pair()
                os.set_blocking(self._pty_master, False)
        if self._pty_master is not None:
            asyncio.get_running_loop().add_reader(self._pty_master, self._pty_readable)
            self._pty_lines = _HostLines()
        self._tasks.append(asyncio.create_task(self._work()))
        return self.port

    async def close(self) -> None:
        for task in self._tasks:
            task.cancel()
        if self._server is not None:
            self._server.close()
        self.drop_clients()
        if self._client_tasks:  # let them see their end of file: a client task cancelled at
            # the loop's shutdown makes asyncio's stream callback log a CancelledError traceback
            await asyncio.wait(set(self._client_tasks), timeout=1.0)
        if self._pty_master is not None:
            asyncio.get_running_loop().remove_reader(self._pty_master)
            if self._pty is not None:
                self._pty.close()
            else:
                os.close(self._pty_master)
            self._pty_master = None
        self.channel.detach(self.model)

    def drop_clients(self) -> None:
        """Close every client connection (fault injection: the modem link drops)."""
        for writer in list(self._writers):
            writer.close()
        self._writers.clear()

    async def _work(self) -> None:
        clock = self.model.clock
        while True:
            self.model.do_work()
            self.channel.do_work()
            wait = self.work_period
            for when in (self.model.next_event_time(), self.channel.next_event_time()):
                if when is not None:
                    wait = min(wait, max(0.0, when - clock.now()))
            await asyncio.sleep(wait)

    def _broadcast(self, sentence) -> None:
        data = (sentence.message() + "\r\n").encode("latin-1")
        for writer in list(self._writers):
            if writer.is_closing():
                self._writers.discard(writer)
            elif writer.transport.get_write_buffer_size() > MAX_CLIENT_BACKLOG:
                log.warning("dropping a client that has not read %d bytes", MAX_CLIENT_BACKLOG)
                self._writers.discard(writer)
                writer.close()
            else:
                writer.write(data)
        if self._pty_master is not None:
            try:
                written = os.write(self._pty_master, data)
            except OSError:  # (full, or nobody has the line open)
                written = 0
            self.pty_dropped += len(data) - written

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        if task is not None:
            self._client_tasks.add(task)
            task.add_done_callback(self._client_tasks.discard)
        self._writers.add(writer)
        lines = _HostLines()
        try:
            while data := await reader.read(4096):
                for line in lines.feed(data):
                    self.model.handle_line(line)
                await writer.drain()  # a client that does not read is not read either
        except ConnectionError:
            pass
        finally:
            self._writers.discard(writer)
            writer.close()

    def _pty_readable(self) -> None:
        assert self._pty_master is not None
        try:
            data = os.read(self._pty_master, 4096)
        except OSError:
            return  # no process has the slave open right now
        for line in self._pty_lines.feed(data):
            self.model.handle_line(line)
