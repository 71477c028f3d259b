"""RUDICS framing, the SQLite store (persistence across restarts), driver ⇄ server over TCP."""

import asyncio
import contextlib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.store_server import StoreServerDriver
from pygoby.acomms.rudics import (
    MAX_PACKET_BYTES,
    RudicsPacketError,
    max_data_bytes,
    parse_rudics_packet,
    serialize_rudics_packet,
)
from pygoby.acomms.store_server import StoreServer, TransmissionStore, serve_store
from pygoby.util.clock import WallClock
from tests.hypothesis_profiles import examples

from .mm_e2e import run_until
from .queue_helpers import status_link

pytestmark = pytest.mark.e2e


def schoolbook_convert(data: bytes, source_base: int, sink_base: int) -> bytes:
    """The conversion digit by digit, as C++ Goby's base_convert does it: the oracle."""
    value = 0
    for digit in reversed(data):
        value = value * source_base + digit
    out = bytearray()
    while value:
        value, remainder = divmod(value, sink_base)
        out.append(remainder)
    return bytes(out) + b"\0" * (len(data) - len(data.rstrip(b"\0")))


@settings(max_examples=examples(200), deadline=None)
@given(st.binary(max_size=300) | st.binary(min_size=1000, max_size=3000), st.integers(0, 3))
def test_rudics_round_trip_and_no_cr(data, top_zeros):
    data += b"\0" * top_zeros
    packet = serialize_rudics_packet(data)
    assert packet.endswith(b"\r") and b"\r" not in packet[:-1]
    assert parse_rudics_packet(packet) == data
    plain = serialize_rudics_packet(data, include_crc=False)
    assert plain[:-1].replace(b"\xff", b"\r") == schoolbook_convert(data, 256, 255)


@settings(max_examples=examples(300), deadline=None)
@given(st.binary(max_size=400))
def test_rudics_parse_of_arbitrary_bytes_raises_only_its_own_error(garbage):
    with contextlib.suppress(RudicsPacketError):
        parse_rudics_packet(garbage + b"\r")


def test_rudics_packet_limit_is_checked_before_any_conversion():
    """Issue 16 item 2: a 128 KB garbage line used to be converted (38 s on the event loop)."""
    with pytest.raises(RudicsPacketError, match="exceeds the 65536-byte limit"):
        parse_rudics_packet(b"\x01" * (128 * 1024) + b"\r")
    # the largest payload the limit allows, in its worst case (no zero digits to spare), fits
    worst = serialize_rudics_packet(b"\xfe" * max_data_bytes())
    assert len(worst) <= MAX_PACKET_BYTES
    assert parse_rudics_packet(worst) == b"\xfe" * max_data_bytes()


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
    assert (
        list(store.exchange(acomms_pb.StoreServerRequest(modem_id=2), 103.0).inbox) == []
    )  # cursor kept


def store_cfg(modem_id, port):
    cfg = acomms_pb.DriverConfig(
        driver_type=5,
        modem_id=modem_id,
        tcp_server="127.0.0.1",
        tcp_port=port,
        connection_type=acomms_pb.DriverConfig.CONNECTION_TCP_AS_CLIENT,
    )
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


def bulk(src: int, size: int, dest: int = 0) -> acomms_pb.ModemTransmission:
    return acomms_pb.ModemTransmission(src=src, dest=dest, type=acomms_pb.DATA, frame=[b"x" * size])


def test_responses_stay_within_a_packet_and_the_rest_comes_next_time(caplog):
    """Issue 16 item 2: a response never exceeds the packet limit (a client's line limit)."""
    store = TransmissionStore()
    request = acomms_pb.StoreServerRequest(modem_id=1)
    request.outbox.extend([bulk(1, 30000), bulk(1, 30000), bulk(1, 70000), bulk(1, 30000)])
    store.exchange(request, 100.0)
    sizes = []
    for t in (101.0, 102.0, 103.0):
        reply = store.exchange(acomms_pb.StoreServerRequest(modem_id=2), t, max_data_bytes())
        assert reply.ByteSize() <= max_data_bytes()
        sizes.append([len(x.frame[0]) for x in reply.inbox])
    # two fit in the first; the 70 000-byte one can never fit: skipped with a warning
    assert sizes == [[30000, 30000], [30000], []]
    assert "cannot fit in a response" in caplog.text


def test_driver_requests_stay_within_a_packet():
    """The driver sends its outbox over as many requests as it needs, and its own frames are
    never larger than a packet allows, whatever max_frame_size says."""
    from pygoby.util.clock import VirtualClock
    from pygoby.util.linebased import MemoryLink

    link = MemoryLink("\r")
    driver = StoreServerDriver(VirtualClock(0), link)
    cfg = acomms_pb.DriverConfig(driver_type=5, modem_id=1)
    cfg.Extensions[acomms_pb.STORE_SERVER_CONFIG].max_frame_size = 1_000_000
    driver.startup(cfg)
    requests = []
    driver.signal_data_request.connect(lambda msg: requests.append(msg.max_frame_bytes))
    driver.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=2, rate=0))
    assert 0 < requests[0] < max_data_bytes()
    driver._outbox.extend([bulk(1, 30000), bulk(1, 30000), bulk(1, 30000)])
    driver._send_request(0.0)
    driver._send_request(1.0)
    packets = [text.encode("latin-1") for text in link.take_written()]
    assert all(len(p) <= MAX_PACKET_BYTES for p in packets)
    outboxes = [
        acomms_pb.StoreServerRequest.FromString(parse_rudics_packet(p)).outbox for p in packets
    ]
    assert [len(o) for o in outboxes] == [2, 1] and driver._outbox == []


async def test_a_garbage_line_and_a_pipelining_client_do_not_hold_up_others():
    """Issue 16 item 2: a 128 KB garbage line is dropped as it streams in (never converted),
    and a client pipelining thousands of requests delays another's by a few requests only."""
    store = TransmissionStore()
    server = StoreServer(store)
    tcp = await serve_store(server, "127.0.0.1", 0)
    port = tcp.sockets[0].getsockname()[1]
    request = serialize_rudics_packet(acomms_pb.StoreServerRequest(modem_id=1).SerializeToString())
    try:
        a_reader, a_writer = await asyncio.open_connection("127.0.0.1", port)
        a_writer.write(b"\x01" * (128 * 1024) + b"\r" + request)
        await a_writer.drain()
        reply = await asyncio.wait_for(a_reader.readuntil(b"\r"), 30)
        assert acomms_pb.StoreServerResponse.FromString(parse_rudics_packet(reply)).modem_id == 1
        assert server.requests_answered == 1 and server.requests_refused == 0  # never parsed

        pipelined = 3000
        a_writer.write(request * pipelined)
        await a_writer.drain()
        while server.requests_answered < 2:  # A's requests are being served
            await asyncio.sleep(0)
        b_reader, b_writer = await asyncio.open_connection("127.0.0.1", port)
        b_writer.write(
            serialize_rudics_packet(acomms_pb.StoreServerRequest(modem_id=2).SerializeToString())
        )
        await b_writer.drain()
        await asyncio.wait_for(b_reader.readuntil(b"\r"), 60)
        served_before_b = server.requests_answered - 2
        assert served_before_b < pipelined // 10, served_before_b
        b_writer.close()
        a_writer.close()
    finally:
        tcp.close()
        store.close()


# -- issue 16 item 13: who may read a modem's mail, a locked database, pruning -------------------


def signed(modem_id: int, secret: bytes | None, now: float, **fields) -> bytes:
    from pygoby.acomms.store_server.auth import sign_request

    payload = acomms_pb.StoreServerRequest(modem_id=modem_id, **fields).SerializeToString()
    if secret is not None:
        payload = sign_request(payload, secret, now)
    return serialize_rudics_packet(payload)


def answer(server: StoreServer, packet: bytes):
    """(response, error) for a request packet."""
    payload = parse_rudics_packet(server.handle_packet(packet))
    return (
        acomms_pb.StoreServerResponse.FromString(payload),
        acomms_pb.StoreServerResponseStatus.FromString(payload).error,
    )


def test_only_the_holder_of_a_modem_ids_secret_reads_its_mail():
    from pygoby.util.clock import VirtualClock

    clock = VirtualClock(1000.0)
    store = TransmissionStore()
    server = StoreServer(store, clock, secrets={1: b"one", 2: b"two"})
    mail = acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DATA, frame=[b"for two"])
    response, error = answer(server, signed(1, b"one", 1000.0, outbox=[mail]))
    assert error == "" and server.requests_answered == 1
    # an unsigned request, a wrong secret, an unknown id, a stale time: refused, nothing taken
    for packet in (
        signed(2, None, 1000.0),
        signed(2, b"one", 1000.0),
        signed(3, b"x", 1000.0),
        signed(2, b"two", 1000.0 - 301),
    ):
        response, error = answer(server, packet)
        assert error == "not authenticated for this modem id" and not response.inbox
    assert server.requests_refused == 4
    clock.set(1001.0)
    recorded = signed(2, b"two", 1001.0)
    response, error = answer(server, recorded)
    assert error == "" and [bytes(t.frame[0]) for t in response.inbox] == [b"for two"]
    # the recorded request played back (to read mail that arrives later) is refused
    answer(server, signed(1, b"one", 1001.5, outbox=[mail]))
    response, error = answer(server, recorded)
    assert error and not response.inbox
    # a C++ style client without a secret is answered as before by a server without secrets
    open_server = StoreServer(store, clock)
    response, error = answer(open_server, signed(2, None, 0.0))
    assert error == "" and len(response.inbox) == 1


@settings(max_examples=examples(50), deadline=None)
@given(st.lists(st.integers(0, 4), max_size=6))
def test_a_signed_modem_cannot_post_mail_as_another(claimed_sources):
    # issue 25, item 8: modem 1, signing with its own secret, claims other sources
    from pygoby.util.clock import VirtualClock

    clock = VirtualClock(1000.0)
    server = StoreServer(TransmissionStore(), clock, secrets={1: b"one", 3: b"three"})
    outbox = [
        acomms_pb.ModemTransmission(src=src, dest=3, type=acomms_pb.DATA, frame=[bytes([k])])
        for k, src in enumerate(claimed_sources)
    ]
    _, error = answer(server, signed(1, b"one", 1000.0, outbox=outbox))
    assert error == ""
    clock.set(1001.0)
    response, error = answer(server, signed(3, b"three", 1001.0))
    assert error == ""
    assert [(t.src, bytes(t.frame[0])) for t in response.inbox] == [
        (1, bytes([k])) for k, src in enumerate(claimed_sources) if src == 1
    ]


def test_a_secrets_file_others_may_read_is_refused(tmp_path):
    # issue 25, item 9: as ssh refuses a private key others can read
    import subprocess
    import sys

    from pygoby.acomms.store_server.auth import read_secrets
    from pygoby.errors import ConfigError

    path = tmp_path / "secrets"
    path.write_text("1 alpha\n")
    for mode in (0o644, 0o640, 0o604, 0o620):
        path.chmod(mode)
        with pytest.raises(ConfigError, match=f"permissions {mode:04o} let others"):
            read_secrets(path)
        assert read_secrets(path, allow_readable=True) == {1: b"alpha"}
    path.chmod(0o600)
    assert read_secrets(path) == {1: b"alpha"}
    path.chmod(0o644)
    command = [
        sys.executable,
        "-m",
        "pygoby.cli",
        "store_server",
        "--port",
        "0",
        "--db",
        str(tmp_path / "s.db"),
        "--secrets",
        str(path),
    ]
    run = subprocess.run(command, capture_output=True, text=True, timeout=30)
    assert run.returncode == 1
    assert f"{path}: permissions 0644 let others than its owner use it (chmod 600" in run.stderr
    server = subprocess.Popen(
        [*command, "--allow-readable-secrets"], stdout=subprocess.PIPE, text=True
    )
    try:
        assert "store_server listening on" in server.stdout.readline()
    finally:
        server.kill()
        server.wait()


def test_a_locked_database_gets_an_error_reply_and_the_driver_sends_again(tmp_path):
    """Issue 16 item 13: SQLite's lock timeout used to drop the connection (and the outbox)."""
    import sqlite3

    from pygoby.util.clock import VirtualClock
    from pygoby.util.linebased import MemoryLink

    db = tmp_path / "store.db"
    store = TransmissionStore(db, lock_timeout_seconds=0.05)
    server = StoreServer(store)
    link = MemoryLink("\r")
    driver = StoreServerDriver(VirtualClock(0), link)
    driver.startup(acomms_pb.DriverConfig(driver_type=5, modem_id=1))
    driver._outbox.append(bulk(1, 10, dest=2))
    other = sqlite3.connect(db)
    other.execute("BEGIN EXCLUSIVE")  # another process holds the database
    driver._send_request(0.0)
    reply = server.handle_packet(link.take_written()[0].encode("latin-1"))
    status = acomms_pb.StoreServerResponseStatus.FromString(parse_rudics_packet(reply))
    assert server.store_errors == 1 and status.error.startswith("store unavailable: database")
    link.feed(reply.decode("latin-1"))
    driver.do_work()
    assert len(driver._outbox) == 1  # nothing was stored: the transmission is kept
    other.rollback()
    other.close()
    driver._send_request(1.0)
    link.feed(server.handle_packet(link.take_written()[0].encode("latin-1")).decode("latin-1"))
    driver.do_work()
    assert driver._outbox == [] and server.requests_answered == 1
    got = store.exchange(acomms_pb.StoreServerRequest(modem_id=2), 2.0)
    assert [bytes(t.frame[0]) for t in got.inbox] == [b"x" * 10]  # stored once
    store.close()


def test_delivered_transmissions_are_pruned_after_the_retention_time():
    store = TransmissionStore(max_lookback_seconds=1000.0, retention_seconds=100.0)
    request = acomms_pb.StoreServerRequest(modem_id=1)
    request.outbox.extend([bulk(1, 1, dest=2), bulk(1, 2, dest=3), bulk(1, 3, dest=0)])
    store.exchange(request, 0.0)
    store.exchange(
        acomms_pb.StoreServerRequest(modem_id=2), 10.0
    )  # 2 reads its mail and the broadcast
    store.exchange(acomms_pb.StoreServerRequest(modem_id=3), 10.0)  # 3 too
    store.exchange(acomms_pb.StoreServerRequest(modem_id=4), 10.0)  # 4 only knows the broadcast
    assert store.prune(50.0) == 0  # delivered, but within the retention time
    store.exchange(request, 60.0)  # new mail for 2, 3 and all, read by nobody yet
    assert store.prune(150.0) == 3  # the first three: delivered and older than 100 s
    store.exchange(acomms_pb.StoreServerRequest(modem_id=2), 160.0)
    assert store.prune(200.0) == 1  # 2's new mail went; 3's and the broadcast wait for 3 and 4
    assert store.prune(1059.0) == 0
    assert store.prune(1061.0) == 2  # past the look-back nobody can be served them
    assert store.db.execute("SELECT COUNT(*) FROM transmission").fetchone()[0] == 0


async def test_signed_drivers_exchange_mail_through_a_server_with_secrets(tmp_path):
    clock = WallClock()
    store = TransmissionStore(tmp_path / "s.db")
    (tmp_path / "secrets").write_text("# modem secrets\n1 alpha\n2 bravo\n")
    (tmp_path / "secrets").chmod(0o600)
    from pygoby.acomms.store_server.auth import read_secrets

    tcp = await serve_store(
        StoreServer(store, secrets=read_secrets(tmp_path / "secrets")), "127.0.0.1", 0
    )
    port = tcp.sockets[0].getsockname()[1]
    drivers = []
    for modem_id, secret in ((1, "alpha"), (2, "bravo")):
        (tmp_path / f"{modem_id}.secret").write_text(secret + "\n")
        cfg = store_cfg(modem_id, port)
        cfg.Extensions[acomms_pb.STORE_SERVER_AUTH].secret_file = str(
            tmp_path / f"{modem_id}.secret"
        )
        driver = StoreServerDriver(clock)
        driver.startup(cfg)
        drivers.append(driver)
    d1, d2 = drivers
    q1, q2, Status, got, acked = status_link(clock, d1, d2)
    try:
        await d1.link.wait_open()
        q1.push_message(Status(src=1, dest=2, value=7))
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=0))
        await run_until(lambda: bool(acked), [d1, d2, q1, q2], timeout=10)
        assert [x.value for x in got] == [7]
    finally:
        d1.shutdown()
        d2.shutdown()
        tcp.close()
        store.close()


def test_store_server_refuses_a_bad_secrets_file(tmp_path):
    import subprocess
    import sys

    (tmp_path / "secrets").write_text("1 alpha\ntwo bravo\n")
    (tmp_path / "secrets").chmod(0o600)
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "pygoby.cli",
            "store_server",
            "--port",
            "0",
            "--db",
            str(tmp_path / "s.db"),
            "--secrets",
            str(tmp_path / "secrets"),
        ],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert run.returncode == 1 and "secrets:2: expected MODEM_ID SECRET" in run.stderr


def test_store_server_stops_cleanly_on_sigint_with_a_client_connected(tmp_path):
    import signal
    import socket
    import subprocess
    import sys

    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "pygoby.cli",
            "store_server",
            "--port",
            "0",
            "--db",
            str(tmp_path / "s.db"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline()
        assert "listening on 127.0.0.1:" in line
        port = int(line.split("127.0.0.1:")[1].split()[0])
        with socket.create_connection(("127.0.0.1", port)) as client:
            client.sendall(
                serialize_rudics_packet(
                    acomms_pb.StoreServerRequest(modem_id=1).SerializeToString()
                )
            )
            assert client.recv(100)  # answered: its task is running
            proc.send_signal(signal.SIGINT)
            assert proc.wait(timeout=10) == 0
        assert "Traceback" not in proc.stderr.read()
    finally:
        proc.kill()
        proc.wait()
