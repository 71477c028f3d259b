"""Hostile clients against the embedded MOOSDB over real loopback sockets: no client can freeze
the DB or make it hold memory without bound (issue 16, items 1 and 5)."""

from __future__ import annotations

import asyncio
import logging
import socket
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from pygoby.moos import protocol as p
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from tests.moos.rawclient import closed_by_peer, raw_connect

pytestmark = pytest.mark.e2e

PYGOBY = str(Path(sys.executable).with_name("pygoby"))


async def _delivered(port: int, key: str) -> bool:
    """A fresh client publishes and gets its own notification back within 2 s."""
    async with MOOSClient(f"probe_{key}", port=port) as probe:
        probe.subscribe(key)
        probe.publish(key, 1.0)
        try:
            while (await probe.receive(2.0)).key != key:
                pass
        except TimeoutError:
            return False
    return True


async def test_hostile_wildcard_does_not_freeze_the_db():
    # the DB runs in its own process: a frozen DB must not freeze the test's event loop too
    db = subprocess.Popen([PYGOBY, "moosdb", "--port", "0"], stdout=subprocess.PIPE, text=True)
    try:
        port = int(db.stdout.readline().rsplit(":", 1)[1])
        async with MOOSClient("greedy", port=port) as greedy:
            greedy.subscribe_wildcard("*a*a*a*a*a*a*a*a*a*a*b", "*")
            await greedy.flush()
            async with MOOSClient("poster", port=port) as poster:
                poster.publish("a" * 200, 1.0)  # a backtracking matcher took hours on this
                await poster.flush()
            assert await _delivered(port, "AFTER")
    finally:
        db.kill()
        db.wait()


async def test_trickled_packet_dropped_at_its_deadline(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.db")
    async with MOOSDB(port=0, packet_timeout=1.0, client_timeout=30.0) as db:
        reader, writer = await raw_connect(db.port, "trickler")
        writer.write(struct.pack("<iiB", 1 << 20, 1, 0) + b"\0" * 1000)  # 1 MB announced
        for _ in range(10):  # a byte every 0.2 s: never silent, never finished
            await asyncio.sleep(0.2)
            if writer.is_closing() or reader.at_eof():
                break
            writer.write(b"\0")
        assert await closed_by_peer(reader, 2)
        assert "took more than 1 s to arrive" in caplog.text
        assert db.buffered == 0
        assert await _delivered(db.port, "STILL_SERVING")
        writer.close()


async def test_partial_packets_stay_within_the_memory_budget(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.db")
    budget = 1 << 20
    async with MOOSDB(port=0, memory_budget=budget) as db:
        hogs = [await raw_connect(db.port, f"hog{i}") for i in range(3)]
        # each announces a 4 MB packet; two send 300 kB of it, then the third 600 kB: when the
        # budget is exceeded the third holds more than 1 MB - 600 kB, the most
        for (_, writer), size in zip(hogs, (300 << 10, 300 << 10, 600 << 10), strict=True):
            writer.write(struct.pack("<iiB", 4 << 20, 1, 0) + b"\0" * size)
            await writer.drain()
            await asyncio.sleep(0.2)
        assert db.buffered <= budget
        dropped = [await closed_by_peer(reader, 0.5) for reader, _ in hogs]
        assert dropped == [False, False, True]
        assert "memory budget" in caplog.text
        assert await _delivered(db.port, "STILL_SERVING")
        for _, writer in hogs:
            writer.close()


async def test_unread_output_stays_within_the_memory_budget(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.db")
    budget = 1 << 20
    async with MOOSDB(port=0, memory_budget=budget) as db:
        reader, writer = await raw_connect(db.port, "sleeper")
        sock = writer.get_extra_info("socket")
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        writer.write(
            p.encode_packet([p.MOOSMessage(p.REGISTER, p.DOUBLE, "BULK", dval=0, src="sleeper")])
        )
        await writer.drain()
        async with MOOSClient("flooder", port=db.port) as flooder:
            await asyncio.sleep(0.1)
            for _ in range(400):  # 40 MB in 100 kB packets, never read by the sleeper
                flooder.publish("BULK", b"\0" * 100_000)
                await flooder.flush()
                if "sleeper" not in db.client_names:
                    break
            await flooder.flush()
            await asyncio.sleep(0.2)
            assert "sleeper" not in db.client_names
            assert db.buffered <= budget
            assert flooder.connected
        assert "memory budget" in caplog.text
        writer.close()


async def test_connection_limit(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.db")
    async with MOOSDB(port=0, max_clients=3) as db:
        first = [await raw_connect(db.port, f"c{i}") for i in range(2)]
        _, idle_writer = await asyncio.open_connection("127.0.0.1", db.port)
        await asyncio.sleep(0.1)  # handshaking connections count too
        extra_reader, extra_writer = await asyncio.open_connection("127.0.0.1", db.port)
        assert await closed_by_peer(extra_reader, 2)
        assert "max_clients" in caplog.text
        idle_writer.close()
        await asyncio.sleep(0.2)
        assert await _delivered(db.port, "ROOM_AGAIN")  # a slot was freed
        for _, writer in first:
            writer.close()
        extra_writer.close()


async def test_console_script_limits():
    db = subprocess.Popen(
        [PYGOBY, "moosdb", "--port", "0", "--max-clients", "1", "--packet-timeout", "0.5"],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        port = int(db.stdout.readline().rsplit(":", 1)[1])
        reader, writer = await raw_connect(port, "only")
        extra_reader, extra_writer = await asyncio.open_connection("127.0.0.1", port)
        assert await closed_by_peer(extra_reader, 2)  # one client at most
        writer.write(struct.pack("<iiB", 1000, 1, 0))  # a packet that never completes
        assert await closed_by_peer(reader, 3)
        writer.close()
        extra_writer.close()
    finally:
        db.kill()
        db.wait()
