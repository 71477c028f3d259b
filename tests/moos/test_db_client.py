"""The embedded MOOSDB and the asyncio client against each other over real loopback sockets,
including the faults: DB restart under a connected client, garbage, oversized packets, silent
and half-open connections."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import socket
import struct

import pytest

from pygoby.moos import protocol as p
from pygoby.moos.client import MOOSClient, MoosRefusedError
from pygoby.moos.db import MOOSDB
from tests.faults import CuttableRelay
from tests.moos.rawclient import closed_by_peer, raw_connect


async def _expect(client: MOOSClient, key: str, timeout: float = 2.0) -> p.MOOSMessage:
    while True:
        msg = await client.receive(timeout)
        if msg.key == key:
            return msg


async def test_publish_subscribe_all_types():
    async with (
        MOOSDB(port=0, community="alpha") as db,
        MOOSClient("pub", port=db.port) as pub,
        MOOSClient("sub", port=db.port) as sub,
    ):
        assert sub.community == "alpha"
        sub.subscribe("D")
        sub.subscribe("S")
        sub.subscribe("B")
        await sub.flush()
        await asyncio.sleep(0.05)
        pub.publish("D", 3.5)
        pub.publish("S", "hello", src_aux="aux")
        pub.publish("B", b"\x00\xff\x10")
        got = {}
        for _ in range(3):
            msg = await sub.receive(2)
            got[msg.key] = msg
        assert got["D"].value == 3.5 and got["D"].src == "pub"
        assert got["S"].value == "hello" and got["S"].src_aux == "aux"
        assert got["B"].value == b"\x00\xff\x10" and got["B"].is_binary
        assert got["D"].community == "alpha"
        # type lock: a string write to a double variable is dropped silently
        pub.publish("D", "nope")
        pub.publish("D", 4.0)
        assert (await _expect(sub, "D")).value == 4.0


async def test_current_value_on_subscribe_and_unsubscribe():
    async with MOOSDB(port=0) as db, MOOSClient("a", port=db.port) as a:
        a.publish("X", 1.0)
        await a.flush()
        async with MOOSClient("b", port=db.port) as b:
            b.subscribe("X")
            snap = await _expect(b, "X")
            assert snap.value == 1.0 and snap.id == -1 and snap.src == "a"
            b.unsubscribe("X")
            await b.flush()
            await asyncio.sleep(0.05)
            a.publish("X", 2.0)
            a.publish("Y", 0.0)
            b.subscribe("Y")
            msg = await b.receive(2)
            assert msg.key == "Y"  # no X after the unsubscribe


async def test_wildcard_subscribe_and_interval():
    async with (
        MOOSDB(port=0) as db,
        MOOSClient("nav", port=db.port) as nav,
        MOOSClient("watch", port=db.port) as watch,
    ):
        watch.subscribe_wildcard("NAV_*", "n*")
        watch.subscribe("FAST", interval=10.0)
        await watch.flush()
        await asyncio.sleep(0.05)
        nav.publish("NAV_X", 1.0)
        nav.publish("OTHER", 1.0)
        nav.publish("FAST", 1.0)
        nav.publish("FAST", 2.0)  # within the interval: dropped
        nav.publish("NAV_Y", 2.0)
        keys = [(await watch.receive(2)).key for _ in range(3)]
        assert keys == ["NAV_X", "FAST", "NAV_Y"]
        with pytest.raises(TimeoutError):
            await watch.receive(0.2)


async def test_server_requests():
    async with MOOSDB(port=0, community="c") as db, MOOSClient("probe", port=db.port) as c:
        c.subscribe("FOO")
        c.publish("FOO", 1.0)
        await c.flush()
        summary = await c.server_request("VAR_SUMMARY")
        assert summary[0].key == "VAR_SUMMARY" and "FOO" in summary[0].string.split(",")
        procs = await c.server_request("PROC_SUMMARY")
        assert procs[0].string == "probe:SUBSCRIBED=,FOO,PUBLISHED=,FOO"
        everything = await c.server_request("ALL")
        names = [m.key for m in everything]
        assert names == sorted(names, reverse=True) and "FOO" in names
        assert all(m.id == p.SERVER_REQUEST_ID for m in everything)
        assert await c.server_request("DB_CLEAR", timeout=0.3) == []
        assert not db.core.variables["FOO"].written


async def test_name_collision_is_refused():
    async with MOOSDB(port=0) as db, MOOSClient("dup", port=db.port):
        second = MOOSClient("dup", port=db.port)
        with pytest.raises(MoosRefusedError, match="already exists"):
            await second.connect(timeout=3)
        await second.close()


async def test_refused_on_reconnect_keeps_trying_until_the_stale_session_is_gone(caplog):
    # The link to the DB breaks without the DB noticing: it keeps the client's session until its
    # client timeout and refuses the name meanwhile. The client must not give up.
    async with (
        MOOSDB(port=0, client_timeout=1.5) as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        relay = CuttableRelay(db.port)
        await relay.start()
        app = MOOSClient("app", port=relay.port, reconnect_interval=0.1)
        try:
            await app.connect()
            app.subscribe("CMD")
            await app.flush()
            relay.cut()
            async with asyncio.timeout(3):
                while app.connected:
                    await asyncio.sleep(0.01)
            app.publish("STATUS", "after the cut")
            tester.subscribe("STATUS")
            await app.wait_connected(
                10
            )  # refused at first, accepted once the DB dropped the old one
            assert (await _expect(tester, "STATUS", 3)).string == "after the cut"
            assert "already exists" in caplog.text and "trying again in" in caplog.text
            assert app.failure is None and app.connections == 2
            tester.publish("CMD", 1.0)  # subscriptions made again
            assert (await _expect(app, "CMD", 3)).dval == 1.0
        finally:
            await app.close()
            await relay.close()


async def test_close_ends_the_client_at_any_moment_of_a_lost_connection():
    # close() landing in the few loop iterations in which the client wound up a lost session
    # had its cancellation swallowed: the client went on reconnecting forever (and the app
    # owning it ignored SIGTERM). Try every iteration of that window.
    for turns in range(12):
        db = MOOSDB(port=0)
        await db.start()
        client = MOOSClient("app", port=db.port, reconnect_interval=0.05)
        await client.connect()
        await db.stop()
        for _ in range(turns):
            await asyncio.sleep(0)
        closing = asyncio.ensure_future(client.close())
        done, _ = await asyncio.wait({closing}, timeout=2)
        assert done, f"close() {turns} loop iterations after the drop never returned"


async def test_reconnect_resubscribe_and_queue_while_away():
    db = MOOSDB(port=0)
    await db.start()
    port = db.port
    got: list[p.MOOSMessage] = []
    app = MOOSClient("app", port=port, on_message=got.append)
    await app.connect()
    app.subscribe("CMD")
    await app.flush()
    await db.stop()
    async with asyncio.timeout(3):
        while app.connected:
            await asyncio.sleep(0.01)
    app.publish("STATUS", "while-away")  # queued on the app's side
    db2 = MOOSDB(port=port)
    await db2.start()
    loop = asyncio.get_running_loop()
    t0 = loop.time()
    async with MOOSClient("other", port=port) as other:
        other.subscribe("STATUS")
        await app.wait_connected(timeout=2.0)
        assert loop.time() - t0 < 2.0
        msg = await _expect(other, "STATUS")
        assert msg.value == "while-away"
        other.publish("CMD", 7.0)  # reaches app only if it re-subscribed
        for _ in range(100):
            if any(m.key == "CMD" for m in got):
                break
            await asyncio.sleep(0.02)
        assert [m.value for m in got if m.key == "CMD"] == [7.0]
    await app.close()
    await db2.stop()


async def test_garbage_client_is_dropped_and_others_served(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.db")
    async with MOOSDB(port=0) as db, MOOSClient("good", port=db.port) as good:
        reader, writer = await raw_connect(db.port, "bad")
        writer.write(struct.pack("<iiB", 20, 1, 0) + b"\xff" * 11)
        await writer.drain()
        assert await closed_by_peer(reader, 2)
        assert "dropping client bad" in caplog.text and "protocol error" in caplog.text
        good.subscribe("Z")
        good.publish("Z", 1.0)
        assert (await _expect(good, "Z")).value == 1.0
        writer.close()


async def test_oversized_packet_refused_from_header(caplog):
    caplog.set_level(logging.WARNING, logger="pygoby.moos.db")
    async with MOOSDB(port=0, max_packet_size=4096) as db:
        reader, writer = await raw_connect(db.port, "big")
        writer.write(struct.pack("<iiB", 1 << 30, 1, 0))
        await writer.drain()
        assert await closed_by_peer(reader, 2)
        assert "exceeds the limit" in caplog.text
        writer.close()


async def test_silent_client_dropped_after_timeout():
    async with MOOSDB(port=0, client_timeout=1.5) as db:
        reader, writer = await raw_connect(db.port, "quiet")
        # a real client keeps itself alive with T messages
        async with MOOSClient("chatty", port=db.port, reconnect_interval=5) as c:
            assert "quiet" in db.client_names
            assert await closed_by_peer(reader, 3)
            assert "quiet" not in db.client_names
            await asyncio.sleep(1.0)
            assert c.connected and c.connections == 1
        writer.close()


async def test_half_open_handshake_does_not_block_others():
    async with MOOSDB(port=0, handshake_timeout=1.0) as db:
        idle_reader, idle_writer = await raw_connect(db.port)  # connects, sends nothing
        async with MOOSClient("after", port=db.port) as c:
            assert c.connected
        assert await closed_by_peer(idle_reader, 3)  # and the idle one is closed in time
        idle_writer.close()


async def test_wrong_protocol_string_closed_silently():
    async with MOOSDB(port=0) as db:
        reader, writer = await raw_connect(db.port)
        writer.write(b"HELLO".ljust(32, b"\0"))
        await writer.drain()
        assert await asyncio.wait_for(reader.read(100), 2) == b""
        writer.close()


async def test_time_warp_stamps(vectors_dir):
    from pygoby.moos.timewarp import moos_clock

    clock = moos_clock(10.0)
    async with MOOSDB(port=0, clock=clock) as db, MOOSClient("w", port=db.port, clock=clock) as c:
        c.subscribe("WARP_X")
        c.publish("WARP_X", 1.0)
        msg = await _expect(c, "WARP_X")
        assert msg.time > 1.7e10  # the whole epoch is warped, as in vector seq 148


async def test_cpp_client_bytes_replayed_over_a_socket(vectors_dir):
    """uPokeDB's recorded bytes (session poke_create) sent to our DB: same answers."""
    text = (vectors_dir / "moos" / "sessions.jsonl").read_text()
    units = [json.loads(line) for line in text.splitlines()]
    session = [u for u in units if u["session"] == "poke_create"]
    async with MOOSDB(port=0, community="alpha") as db:
        reader, writer = await asyncio.open_connection("127.0.0.1", db.port)
        framer = p.PacketFramer()
        received: list[list[p.MOOSMessage]] = []

        async def read_some():
            with contextlib.suppress(TimeoutError):
                buf, spans = framer.feed(await asyncio.wait_for(reader.read(65536), 0.1))
                received.extend(p.decode_packet(buf, *span) for span in spans)

        for u in session:
            if u["dir"] == "client_to_db" and u["unit"] in ("protocol_string", "packet"):
                writer.write(bytes.fromhex(u["hex"]))
                await writer.drain()
                await read_some()
        async with asyncio.timeout(5):
            while not received or received[-1][0].key != "FOO":
                await read_some()
        writer.close()
    kinds = [[(m.msg_type, m.key) for m in pk] for pk in received]
    assert kinds[0] == [("W", "")]
    assert kinds[1][0] == ("T", "_async_timing")  # no DB_* yet: our DB is younger than 2 s
    assert kinds[-1] == [("N", "FOO"), ("N", "BAR")]  # pushed back to the publisher
    assert received[-1][0].dval == 3.5 and received[-1][1].value == "hello"
    assert received[0][0].src_aux == f"hostname={socket.gethostname()}"


async def _scripted_db(units: list[dict]):
    """A server that answers any client with the recorded DB-to-client packets of one conn."""
    packets = [bytes.fromhex(u["hex"]) for u in units if u["unit"] == "packet"]

    async def serve(reader, writer):
        await reader.readexactly(p.PROTOCOL_STRING_SIZE)
        header = await reader.readexactly(9)
        total, _ = p.parse_packet_header(header)
        await reader.readexactly(total - 9)
        for packet in packets:
            writer.write(packet)
            await writer.drain()
            await asyncio.sleep(0.01)
        await asyncio.sleep(0.5)
        writer.close()

    return await asyncio.start_server(serve, "127.0.0.1", 0)


async def test_client_against_recorded_cpp_db(vectors_dir):
    text = (vectors_dir / "moos" / "sessions.jsonl").read_text()
    units = [json.loads(line) for line in text.splitlines()]
    listener = [u for u in units if u["conn"] == 3 and u["dir"] == "db_to_client"]
    server = await _scripted_db(listener)
    port = server.sockets[0].getsockname()[1]
    expected = [
        m
        for u in listener
        if u["unit"] == "packet"
        for m in p.decode_packet(bytes.fromhex(u["hex"]))
        if m.msg_type not in (p.WELCOME, p.TIMING)
    ]
    got: list[p.MOOSMessage] = []
    client = MOOSClient("nav_listener", port=port, on_message=got.append, reconnect_interval=5)
    try:
        await client.connect()
        assert client.community == "alpha" and client.db_hostname == "localhost"
        async with asyncio.timeout(5):
            while len(got) < len(expected):
                await asyncio.sleep(0.01)
        assert got == expected  # T echoes dropped, every N delivered in order
        assert client.skew.skew != 0.0  # the echoes fed the skew filter
    finally:
        await client.close()
        server.close()


async def test_client_raises_on_recorded_poison(vectors_dir):
    text = (vectors_dir / "moos" / "sessions.jsonl").read_text()
    units = [json.loads(line) for line in text.splitlines()]
    server = await _scripted_db([u for u in units if u["seq"] == 110])
    client = MOOSClient("dup", port=server.sockets[0].getsockname()[1])
    try:
        with pytest.raises(
            MoosRefusedError, match='A client of this name \\("dup"\\) already exists'
        ):
            await client.connect()
    finally:
        await client.close()
        server.close()


async def test_legacy_synchronous_client_is_polled_not_pushed():
    async with MOOSDB(port=0) as db, MOOSClient("pub", port=db.port) as pub:
        reader, writer = await asyncio.open_connection("127.0.0.1", db.port)
        hs = p.handshake_message("old", 0.0, asynchronous=False)
        writer.write(p.PROTOCOL_STRING + p.encode_packet([hs]))
        framer = p.PacketFramer()
        queued: list[list[p.MOOSMessage]] = []

        async def next_packet(timeout=2.0):
            while not queued:
                buf, spans = framer.feed(await asyncio.wait_for(reader.read(4096), timeout))
                queued.extend(p.decode_packet(buf, *span) for span in spans)
            return queued.pop(0)

        assert (await next_packet())[0].msg_type == p.WELCOME
        writer.write(p.encode_packet([p.MOOSMessage(p.REGISTER, p.DOUBLE, "V", dval=0, src="old")]))
        assert [m.msg_type for m in await next_packet()] == [p.NULL]
        pub.publish("V", 1.0)
        await pub.flush()
        with pytest.raises(TimeoutError):
            await next_packet(timeout=0.3)  # never pushed to a polling client
        writer.write(p.encode_packet([p.MOOSMessage(p.NULL, src="old")]))
        reply = await next_packet()
        assert [(m.msg_type, m.key) for m in reply] == [(p.NULL, ""), (p.NOTIFY, "V")]
        assert reply[0].time == -1.0 and reply[0].dval > 1e9  # the DB clock for the skew
        writer.close()


async def test_packets_cut_anywhere_by_tcp_are_all_delivered():
    """A client's stream split at random points (one byte, inside headers, many packets per
    read): the DB reassembles every packet and forwards every notification in order."""
    import random

    rng = random.Random(20)
    async with MOOSDB(port=0) as db, MOOSClient("sink", port=db.port) as sink:
        sink.subscribe("CUT")
        await sink.flush()
        _reader, writer = await raw_connect(db.port, "cutter")
        writer.get_extra_info("socket").setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        stream = b"".join(
            p.encode_packet(
                [
                    p.notify("CUT", float(i * 3 + j), time=1.0, src="cutter", msg_id=i)
                    for j in range(rng.randint(1, 3))
                ]
            )
            for i in range(150)
        )
        pos = 0
        while pos < len(stream):
            step = rng.choice((1, 2, 5, 9, 13, 100, 700, 3000))
            writer.write(stream[pos : pos + step])
            pos += step
            await writer.drain()
            if rng.random() < 0.3:
                await asyncio.sleep(0.002)
        expected = []
        offset = 0
        while offset < len(stream):
            total, _ = p.parse_packet_header(stream[offset : offset + 9])
            expected += [m.dval for m in p.decode_packet(stream[offset : offset + total])]
            offset += total
        got = [(await _expect(sink, "CUT")).dval for _ in expected]
        assert got == expected
        writer.close()


async def test_close_while_the_connection_is_being_lost_returns():
    """close() at any point of the DB going away (here: 0..15 loop turns after it closed the
    connections) ends the client instead of leaving it reconnecting (antler's SIGINT reaches
    the DB and the apps at once)."""
    for turns in range(16):
        db = MOOSDB(port=0)
        await db.start()
        client = MOOSClient(f"closing{turns}", port=db.port, reconnect_interval=0.05)
        await client.connect()
        await db.stop()
        for _ in range(turns):
            await asyncio.sleep(0)
        closing = asyncio.ensure_future(client.close())
        done, _ = await asyncio.wait([closing], timeout=2)  # (wait_for would cancel and rescue it)
        assert done, f"close() hangs: the client goes on reconnecting ({turns} turns)"
