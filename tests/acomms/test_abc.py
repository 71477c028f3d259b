"""ABC example modem: protocol, simulator and driver end to end over TCP."""

import asyncio

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.abc_protocol import ABCParseError, format_abc, parse_abc
from pygoby.acomms.abc_simulator import ABCSimulator, serve_abc
from pygoby.acomms.drivers.abc import ABCDriver
from pygoby.util.clock import WallClock

from .mm_e2e import run_until
from .queue_helpers import status_link


def test_parse_and_simulator_rules():
    assert parse_abc("SEND,TO:2,FROM:1,HEX:0102abcd,BITRATE:100,ACK:TRUE\r\n") == (
        "SEND",
        {"TO": "2", "FROM": "1", "HEX": "0102abcd", "BITRATE": "100", "ACK": "TRUE"},
    )
    with pytest.raises(ABCParseError):
        parse_abc("SEND,TO2")
    sim = ABCSimulator()
    sim.handle("a", "CONF,MAC:1")
    sim.handle("b", "CONF,MAC:2")
    sim.handle("c", "CONF,MAC:3")
    assert sim.handle("a", "SEND,TO:2,FROM:1,HEX:0102abcd,BITRATE:100,ACK:TRUE") == [
        ("b", "RECV,FROM:1,TO:2,HEX:0102abcd,BITRATE:100\r\n"),
        ("a", "ACKN,FROM:2,TO:1\r\n"),
    ]
    assert sorted(e for e, _ in sim.handle("a", "SEND,TO:0,FROM:1,HEX:00,BITRATE:100")) == [
        "b",
        "c",
    ]
    assert sim.handle("a", "SEND,TO:9,FROM:1,HEX:00,BITRATE:100") == []
    assert sim.handle("a", "SEND,TO:2,FROM:1,BITRATE:100") == []


def abc_cfg(modem_id, port):
    return acomms_pb.DriverConfig(
        driver_type=3,
        modem_id=modem_id,
        tcp_server="127.0.0.1",
        tcp_port=port,
        connection_type=acomms_pb.DriverConfig.CONNECTION_TCP_AS_CLIENT,
    )


async def test_abc_driver_queue_to_queue_with_ack():
    server = await serve_abc(ABCSimulator())
    port = server.sockets[0].getsockname()[1]
    clock = WallClock()
    d1, d2 = ABCDriver(clock), ABCDriver(clock)
    d1.startup(abc_cfg(1, port))
    d2.startup(abc_cfg(2, port))
    q1, _q2, Status, got, acked = status_link(clock, d1, d2)
    try:
        await d1.link.wait_open()
        await d2.link.wait_open()
        d1.do_work()
        d2.do_work()
        await asyncio.sleep(0.05)  # let the CONF lines register both modems
        q1.push_message(Status(src=1, dest=2, value=5))
        await asyncio.sleep(0.01)
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=0))
        await run_until(lambda: bool(acked), [d1, d2], timeout=10)
        assert [x.value for x in got] == [5] and acked == [5]
    finally:
        d1.shutdown()
        d2.shutdown()
        server.close()


async def test_simulator_survives_bad_lines_and_a_modem_that_never_reads():
    """Issue 16 (the store_server class of defect, found in the ABC simulator): a number that is
    not a number or an over-long line used to end the client's connection, and a modem that
    never reads grew the simulator's memory without bound."""
    from pygoby.acomms import abc_simulator

    sim = ABCSimulator()
    server = await serve_abc(sim)
    port = server.sockets[0].getsockname()[1]
    try:
        _a_reader, a_writer = await asyncio.open_connection("127.0.0.1", port)
        _, b_writer = await asyncio.open_connection("127.0.0.1", port)
        c_reader, c_writer = await asyncio.open_connection("127.0.0.1", port)
        a_writer.write(b"CONF,MAC:nope\r\n" + b"x" * 200_000 + b"\r\nCONF,MAC:1\r\n")
        b_writer.write(b"CONF,MAC:2\r\n")  # modem 2 never reads
        c_writer.write(b"CONF,MAC:3\r\n")
        await asyncio.gather(a_writer.drain(), b_writer.drain(), c_writer.drain())
        async with asyncio.timeout(10):
            while len(sim.modems) < 3:
                await asyncio.sleep(0.01)
        hex_payload = "ab" * 4000
        for _ in range(1000):  # 8 MB for modem 2, which reads none of it
            a_writer.write(format_abc("SEND", HEX=hex_payload, FROM=1, BITRATE=0, TO=2).encode())
        a_writer.write(format_abc("SEND", HEX="0102", FROM=1, BITRATE=0, TO=3).encode())
        await a_writer.drain()
        line = await asyncio.wait_for(c_reader.readline(), 30)  # modem 3 still served
        assert line.startswith(b"RECV,FROM:1,TO:3,HEX:0102")
        buffered = [w.transport.get_write_buffer_size() for w in sim.modems.values()]
        assert max(buffered) <= abc_simulator.MAX_UNREAD_BYTES + 10_000
        for writer in (a_writer, b_writer, c_writer):
            writer.close()
    finally:
        server.close()
