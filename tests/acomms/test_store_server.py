"""RUDICS framing, the SQLite store (persistence across restarts), driver ⇄ server over TCP."""

import asyncio

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.store_server import StoreServerDriver
from pygoby.acomms.rudics import RudicsPacketError, parse_rudics_packet, serialize_rudics_packet
from pygoby.acomms.store_server import StoreServer, TransmissionStore, serve_store
from pygoby.util.clock import WallClock

from .mm_e2e import run_until
from .queue_helpers import status_link


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=300))
def test_rudics_round_trip_and_no_cr(data):
    packet = serialize_rudics_packet(data)
    assert packet.endswith(b"\r") and b"\r" not in packet[:-1]
    assert parse_rudics_packet(packet) == data


def test_rudics_known_layout_and_errors():
    # base 255, little-endian digits, CRC-32 appended big-endian; zero bytes at the most
    # significant end survive as zero digits
    # 00 01 00 00 = 256 = 1 + 1*255 -> digits 01 01, then the two most significant zeros
    packet = serialize_rudics_packet(b"\x00\x01\x00\x00", include_crc=False)
    assert packet == b"\x01\x01\x00\x00\r"
    assert parse_rudics_packet(packet, include_crc=False) == b"\x00\x01\x00\x00"
    assert serialize_rudics_packet(b"\x0d", include_crc=False) == b"\xff\r"  # CR digit moved
    assert serialize_rudics_packet(b"\xff", include_crc=False) == b"\x00\x01\r"  # 255 = 0 + 1*255
    with pytest.raises(RudicsPacketError, match="CRC"):
        parse_rudics_packet(serialize_rudics_packet(b"abc")[:-2] + b"\x01\r")
    with pytest.raises(RudicsPacketError):
        parse_rudics_packet(b"")


def test_store_keeps_messages_across_restart(tmp_path):
    db = tmp_path / "store.db"
    store = TransmissionStore(db)
    request = acomms_pb.StoreServerRequest(modem_id=1, request_id=1)
    request.outbox.add(src=1, dest=2, frame=[b"kept"])
    assert list(store.exchange(request, 100.0).inbox) == []
    store.close()
    store = TransmissionStore(db)  # restart
    reply = store.exchange(acomms_pb.StoreServerRequest(modem_id=2, request_id=5), 101.0)
    assert [bytes(t.frame[0]) for t in reply.inbox] == [b"kept"] and reply.request_id == 5
    assert list(store.exchange(acomms_pb.StoreServerRequest(modem_id=2), 102.0).inbox) == []  # seen
    store.close()
    store = TransmissionStore(db)
    assert list(store.exchange(acomms_pb.StoreServerRequest(modem_id=2), 103.0).inbox) == []  # cursor kept


def store_cfg(modem_id, port):
    cfg = acomms_pb.DriverConfig(driver_type=5, modem_id=modem_id, tcp_server="127.0.0.1", tcp_port=port,
                         connection_type=acomms_pb.DriverConfig.CONNECTION_TCP_AS_CLIENT)  # fmt: skip
    cfg.Extensions[acomms_pb.STORE_SERVER_CONFIG].query_interval_seconds = 0.05
    return cfg


async def test_driver_to_driver_through_store_server_with_ack(tmp_path):
    clock = WallClock()
    store = TransmissionStore(tmp_path / "s.db")
    server = await serve_store(StoreServer(store), "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    d1, d2 = StoreServerDriver(clock), StoreServerDriver(clock)
    d1.startup(store_cfg(1, port))
    d2.startup(store_cfg(2, port))
    q1, q2, Status, got, acked = status_link(clock, d1, d2)
    try:
        await d1.link.wait_open()
        q1.push_message(Status(src=1, dest=2, value=33))
        await asyncio.sleep(0.01)
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=0))
        await run_until(lambda: bool(acked), [d1, d2, q1, q2], timeout=10)
        assert [x.value for x in got] == [33] and acked == [33] and q1.size(20) == 0
        # polling: node 1 asks node 2 for data through the store
        q2.push_message(Status(src=2, dest=1, value=44))
        back = []
        q1.signal_receive.connect(back.append)
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=2, dest=1, rate=0))
        await run_until(lambda: bool(back), [d1, d2, q1, q2], timeout=10)
        assert [x.value for x in back] == [44]
    finally:
        d1.shutdown()
        d2.shutdown()
        server.close()
        store.close()
