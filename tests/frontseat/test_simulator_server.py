"""The simulator over real loopback TCP: two clients, replies and NAV to both, mission end."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys

import pytest

from pygoby.frontseat.simulator.protocol import Nav, parse_line
from pygoby.frontseat.simulator.server import SimulatorServer

pytestmark = pytest.mark.e2e


async def read_until(reader: asyncio.StreamReader, prefix: str, timeout: float = 5.0) -> list[str]:
    """Lines up to and including the first that starts with `prefix`."""
    lines: list[str] = []
    async with asyncio.timeout(timeout):
        while True:
            raw = await reader.readuntil(b"\r\n")
            lines.append(raw[:-2].decode())
            if lines[-1].startswith(prefix):
                return lines


async def test_two_clients_share_one_simulator():
    server = SimulatorServer(0, host="127.0.0.1")
    serving = asyncio.create_task(server.serve())
    try:
        port = await server.start()
        reader_a, writer_a = await asyncio.open_connection("127.0.0.1", port)
        # 50 ticks per second of wall time; a mission of 5 s at FREQ 10 = 60 ticks
        writer_a.write(b"START,LAT:42.1234,LON:-72,DURATION:5,FREQ:10,WARP:5\r\n")
        assert await read_until(reader_a, "CTRL") == ["CTRL,STATE:PAYLOAD"]
        reader_b, writer_b = await asyncio.open_connection("127.0.0.1", port)
        for reader in (reader_a, reader_b):  # NAV goes to both
            assert (await read_until(reader, "NAV"))[-1].startswith("NAV,LAT:42.1234,")

        writer_b.write(b"CMD,HEADING:90,SPEED:2,DEPTH:3\r\n")
        for reader in (reader_a, reader_b):
            lines = await read_until(reader, "CMD")
            assert lines[-1] == "CMD,RESULT:OK"
            assert all(line.startswith("NAV,") for line in lines[:-1])

        for reader in (reader_a, reader_b):
            lines = await read_until(reader, "CTRL")
            assert lines[-1] == "CTRL,STATE:IDLE"
            navs = [Nav.from_message(parse_line(line)) for line in lines[:-1]]
            assert navs[-1].depth > 0 and navs[-1].heading > 0 and navs[-1].speed > 0
        assert not server.simulator.running

        writer_a.write(b"garbage,x\r\n")  # logged and skipped; the server carries on
        writer_a.write(b"START,LAT:1,LON:2,WARP:10\r\n")
        assert await read_until(reader_b, "CTRL") == ["CTRL,STATE:PAYLOAD"]
        for writer in (writer_a, writer_b):
            writer.close()
    finally:
        serving.cancel()
        await asyncio.gather(serving, return_exceptions=True)


async def test_ticks_follow_freq_times_warp():
    server = SimulatorServer(0, host="127.0.0.1")
    serving = asyncio.create_task(server.serve())
    try:
        port = await server.start()
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(b"START,LAT:42,LON:-72,FREQ:20,WARP:5\r\n")  # period 10 ms
        await read_until(reader, "CTRL")
        loop = asyncio.get_running_loop()
        start = loop.time()
        for _ in range(50):
            await read_until(reader, "NAV")
        elapsed = loop.time() - start
        assert 0.3 < elapsed < 5.0  # about 0.5 s; loose bounds for a loaded machine
        writer.close()
    finally:
        serving.cancel()
        await asyncio.gather(serving, return_exceptions=True)


async def test_port_in_use_is_an_os_error():
    first = SimulatorServer(0, host="127.0.0.1")
    port = await first.start()
    try:
        with pytest.raises(OSError):
            await SimulatorServer(port, host="127.0.0.1").start()
    finally:
        first.close()


def test_command_line_program_exits_cleanly_on_sigint():
    proc = subprocess.Popen(
        [sys.executable, "-m", "pygoby.frontseat.simulator.server", "0", "--bind", "127.0.0.1"],
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        assert "listening on 127.0.0.1:" in proc.stderr.readline()
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=10) == 0
        assert "Traceback" not in proc.stderr.read()
    finally:
        proc.kill()
        proc.wait()
