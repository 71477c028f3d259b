"""asyncio front ends for the modem model: a TCP server, a pseudo-terminal or a serial device."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import re

from pygoby.acomms.mmsim.channel import Channel
from pygoby.acomms.mmsim.model import MicroModemModel
from pygoby.util.linebased import open_pty_pair
from pygoby.util.pty import open_serial

log = logging.getLogger(__name__)

_LINE_END = re.compile(rb"[\r\n]+")
MAX_PENDING = 65536


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
    on a pty (`pty_path` after `start`) or on a serial device (`serial_path`: a tty, e.g. one end
    of a pygoby.util.pty.PtyPair). `port=None`: no TCP server. Runs `channel.do_work()` every
    `work_period` s."""

    def __init__(
        self,
        model: MicroModemModel,
        channel: Channel,
        host: str = "127.0.0.1",
        port: int | None = 0,
        use_pty: bool = False,
        work_period: float = 0.05,
        serial_path: str | None = None,
    ) -> None:
        self.model, self.channel = model, channel
        self.host, self.port = host, port
        self.use_pty = use_pty
        self.serial_path = serial_path
        self.work_period = work_period
        self.pty_path: str | None = None
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
            log.info("Micro-Modem emulator id %d on %s:%d", self.model.modem_id, self.host, self.port)
        if self.use_pty or self.serial_path:
            if self.serial_path:
                self._pty_master = open_serial(self.serial_path)
            else:
                self._pty_master, self.pty_path = open_pty_pair()
            asyncio.get_running_loop().add_reader(self._pty_master, self._pty_readable)
            self._pty_lines = _HostLines()
        self._tasks.append(asyncio.create_task(self._work()))
        return self.port

    async def close(self) -> None:
        for task in self._tasks:
            task.cancel()
        if self._server is not None:
            self._server.close()
        for writer in list(self._writers):
            writer.close()
        self._writers.clear()
        if self._client_tasks:  # let them see their end of file: a client task cancelled at
            # the loop's shutdown makes asyncio's stream callback log a CancelledError traceback
            await asyncio.wait(set(self._client_tasks), timeout=1.0)
        if self._pty_master is not None:
            asyncio.get_running_loop().remove_reader(self._pty_master)
            os.close(self._pty_master)
            self._pty_master = None
        self.channel.detach(self.model)

    def drop_clients(self) -> None:
        """Close every client connection (fault injection: the modem link drops)."""
        for writer in list(self._writers):
            writer.close()
        self._writers.clear()

    async def _work(self) -> None:
        while True:
            self.channel.do_work()
            await asyncio.sleep(self.work_period)

    def _broadcast(self, text: str) -> None:
        data = text.encode("latin-1")
        for writer in list(self._writers):
            if writer.is_closing():
                self._writers.discard(writer)
            else:
                writer.write(data)
        if self._pty_master is not None:
            with contextlib.suppress(OSError):
                os.write(self._pty_master, data)

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
