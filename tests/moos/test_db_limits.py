"""Hostile clients against the embedded MOOSDB over real loopback sockets: no client can freeze
the DB or make it hold memory without bound (issue 16, items 1 and 5; issue 25, items 1-3)."""

from __future__ import annotations

import asyncio
import logging
import socket
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pygoby.moos import dbcore
from pygoby.moos import protocol as p
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.dbcore import (
    MAX_NAME_LENGTH,
    MAX_PATTERN_LENGTH,
    MAX_WILDCARDS,
    VARIABLE_OVERHEAD,
    DBCore,
)
from pygoby.util.clock import VirtualClock
from tests.hypothesis_profiles import examples
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
        _reader, writer = await raw_connect(db.port, "sleeper")
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


# -- issue 25: names, patterns, the number of variables, summaries, held mail ------------------


def _core_with(*names: str, **kwargs) -> DBCore:
    core = DBCore(clock=VirtualClock(1000.0), **kwargs)
    for name in names:
        core.connect(p.handshake_message(name, 1000.0))
    return core


def _send(core: DBCore, name: str, *msgs: p.MOOSMessage) -> None:
    core.process_packet(name, p.encode_packet(list(msgs)))
    for record in core.take_ready():
        record.take_output()


@settings(
    max_examples=examples(50),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    length=st.integers(MAX_NAME_LENGTH - 2, MAX_NAME_LENGTH + 2) | st.integers(1, 40_000),
    pattern_length=st.integers(MAX_PATTERN_LENGTH - 2, MAX_PATTERN_LENGTH + 2),
)
def test_names_and_patterns_beyond_their_caps_are_refused_once_per_client(
    caplog, length, pattern_length
):
    caplog.clear()
    caplog.set_level(logging.WARNING, logger="pygoby.moos.dbcore")
    core = _core_with("poster")
    name = "V" * length
    for _ in range(2):
        _send(core, "poster", p.notify(name, 1.0, time=1000.0, src="poster"))
    assert (name in core.variables) is (length <= MAX_NAME_LENGTH)
    assert caplog.text.count("refused (at most 256)") == (length > MAX_NAME_LENGTH)
    pattern = "*" + "?" * (pattern_length - 3) + "X*"
    wildcard = p.MOOSMessage(
        p.WILDCARD_REGISTER, p.STRING, "", sval=p.wildcard_sval("*", pattern, 0.0), src="poster"
    )
    _send(core, "poster", wildcard)
    registered = ("*", pattern) in core.clients["poster"].filters
    assert registered is (pattern_length <= MAX_PATTERN_LENGTH)


def test_a_client_keeps_at_most_max_wildcards_registrations(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.dbcore")
    core = _core_with("greedy")
    for k in range(MAX_WILDCARDS + 10):
        sval = p.wildcard_sval("*", f"P{k}_*", 0.0)
        _send(
            core,
            "greedy",
            p.MOOSMessage(p.WILDCARD_REGISTER, p.STRING, "", sval=sval, src="greedy"),
        )
    assert len(core.clients["greedy"].filters) == MAX_WILDCARDS
    assert caplog.text.count("wildcard registration refused") == 1


def test_a_long_src_or_client_name_is_refused():
    core = _core_with("ok")
    long_name = "N" * (MAX_NAME_LENGTH + 1)
    assert core.connect(p.handshake_message(long_name, 1000.0)).msg_type == p.POISON
    with pytest.raises(p.MoosProtocolError, match="src of 257 bytes"):
        _send(core, "ok", p.notify("X", 1.0, time=1000.0, src=long_name))


async def test_the_long_name_and_pattern_attack_leaves_the_db_responsive():
    # issue 25, item 1: a 30 kB name, then `*` + 2000 x `?` + `X*`: ~21 s of matching before
    db = subprocess.Popen(
        [PYGOBY, "moosdb", "--port", "0", "--max-variables", "1000", "--memory-budget", "64"],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        port = int(db.stdout.readline().rsplit(":", 1)[1])
        async with MOOSClient("attacker", port=port) as attacker:
            attacker.publish("A" * 30_000, 1.0)
            attacker.subscribe_wildcard("*" + "?" * 2000 + "X*", "*")
            await attacker.flush()
            assert await _delivered(port, "AFTER")
            assert attacker.connected
    finally:
        db.kill()
        db.wait()


async def test_max_variables_refuses_new_ones_and_logs_once(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.dbcore")
    async with (
        MOOSDB(port=0, max_variables=40) as db,
        MOOSClient("many", port=db.port) as many,
    ):
        many.subscribe("MINE")
        for k in range(100):
            many.publish(f"VAR_{k}", float(k))
            many.subscribe(f"REG_{k}")  # a registration creates a variable too
        many.publish("MINE", 1.0)
        await many.flush()
        await asyncio.sleep(0.3)
        assert len(db.core.variables) == 40
        assert caplog.text.count("(max_variables)") == 1
        assert "client many: new variable" in caplog.text
        assert many.connected
        many.publish("VAR_0", 2.0)  # an existing variable is still written
        while (await many.receive(2.0)).key != "MINE":
            pass
        assert await _delivered(db.port, "VAR_1")


def test_summaries_decode_only_the_variables_written_since_the_last_refresh(monkeypatch):
    # issue 25, item 2: every refresh decoded and sorted every variable (0.5-1.9 s at 60k)
    decoded = []
    real = p.decode_message
    monkeypatch.setattr(p, "decode_message", lambda *a: decoded.append(1) or real(*a))
    monkeypatch.setattr(dbcore, "SUMMARY_LINES_PER_REFRESH", 500)
    core = _core_with("poster")
    _send(core, "poster", *(p.notify(f"V{k}", float(k), time=1000.0) for k in range(2000)))
    for refresh in range(5):  # 500 new lines a refresh, until every variable has one
        decoded.clear()
        core.clock.advance(3.0)
        _send(core, "poster", p.notify("V1", 1.5, time=core.clock.now()))
        assert len(decoded) <= 500
        summary = core.variables["DB_VARSUMMARY"].message().string.splitlines()
        assert len(summary) == min(500 * (refresh + 1), len(core.variables))
    decoded.clear()
    core.clock.advance(3.0)
    _send(core, "poster", p.notify("V2", 2.5, time=1006.0))  # a refresh: V2 and the DB's own
    assert 0 < len(decoded) < 20
    summary = core.variables["DB_VARSUMMARY"].message().string.splitlines()
    assert len(summary) == len(core.variables)
    assert next(line for line in summary if line.startswith("V2 ")).endswith(" D 2.5")


@settings(max_examples=examples(40), deadline=None)
@given(
    st.lists(
        st.tuples(st.sampled_from(["A", "B", "C", "Z", "AA"]), st.integers(0, 4), st.booleans()),
        max_size=30,
    )
)
def test_incremental_summaries_equal_summaries_made_afresh(steps):
    # writes, registrations, DB_CLEAR and refreshes in any order: the kept lines stay true
    core = _core_with("poster", "reader")
    for name, action, refresh in steps:
        if action == 3:
            _send(core, "reader", p.MOOSMessage(p.REGISTER, p.DOUBLE, name, dval=0, src="reader"))
        elif action == 4:
            _send(core, "poster", p.MOOSMessage(p.SERVER_REQUEST, p.STRING, "DB_CLEAR", src="x"))
        else:
            _send(core, "poster", p.notify(name, float(action), time=core.clock.now()))
        core.clock.advance(2.5 if refresh else 0.1)
    incremental = core._var_summary(), core._rw_summary()
    for var in core.variables.values():
        var.summary_of = var  # every line out of date
    for record in core.clients.values():
        record.rw_summary = None
    assert (core._var_summary(), core._rw_summary()) == incremental


async def test_a_synchronous_client_that_never_reads_is_dropped_at_the_memory_budget(caplog):
    # issue 25, item 3: mail held for a synchronous `*` subscriber was outside the budget
    caplog.set_level(logging.WARNING, logger="pygoby.moos.db")
    budget = 4 << 20
    async with MOOSDB(port=0, memory_budget=budget) as db:
        _reader, writer = await raw_connect(db.port, "sleeper", asynchronous=False)
        writer.write(
            p.encode_packet(
                [
                    p.MOOSMessage(
                        p.WILDCARD_REGISTER,
                        p.STRING,
                        "",
                        sval=p.wildcard_sval("*", "*", 0.0),
                        src="sleeper",
                    )
                ]
            )
        )
        await writer.drain()
        await asyncio.sleep(0.1)
        async with MOOSClient("flooder", port=db.port) as flooder:
            for k in range(400):  # 40 MB the sleeper never asks for
                flooder.publish(f"BULK_{k % 10}", b"\0" * 100_000)
                await flooder.flush()
                if "sleeper" not in db.client_names:
                    break
            await asyncio.sleep(0.2)
            assert "sleeper" not in db.client_names
            assert db.buffered + db.core.stored_bytes <= budget
            assert flooder.connected
        assert "memory budget" in caplog.text
        writer.close()


def test_stored_values_count_in_the_memory_budget(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.dbcore")
    core = _core_with("poster", store_budget=1 << 20)
    for k in range(30):  # 3 MB of distinct variables
        _send(core, "poster", p.notify(f"BIG_{k}", b"\0" * 100_000, time=1000.0))
    assert core.stored_bytes <= 1 << 20
    assert sum(1 for var in core.variables.values() if var.written) < 15
    assert caplog.text.count("exceed the memory budget") == 1
    before = core.stored_bytes
    _send(core, "poster", p.notify("BIG_0", b"\0" * 10, time=1000.0))  # smaller: room again
    assert core.stored_bytes == before - 99_990
    _send(core, "poster", p.MOOSMessage(p.SERVER_REQUEST, p.STRING, "DB_CLEAR", src="poster"))
    # the variables remain, their values are gone
    assert core.stored_bytes == sum(VARIABLE_OVERHEAD + len(v.key) for v in core.variables.values())


async def test_stored_variables_take_at_most_half_the_memory_budget(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.dbcore")
    budget = 2 << 20
    async with (
        MOOSDB(port=0, memory_budget=budget) as db,
        MOOSClient("filler", port=db.port) as filler,
    ):
        for k in range(30):  # 3 MB of values, 100 kB a packet
            filler.publish(f"FILL_{k}", b"\0" * 100_000)
            await filler.flush()
            await asyncio.sleep(0.01)
        await asyncio.sleep(0.3)
        assert db.core.stored_bytes <= budget // 2
        assert "would exceed the memory budget" in caplog.text
        assert filler.connected
        assert await _delivered(db.port, "ROOM_LEFT")  # the other half serves the clients
