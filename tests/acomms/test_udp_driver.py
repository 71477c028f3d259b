"""UDP driver over real loopback sockets: queue to queue with acks, wire format, garbage."""

import logging
import socket

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.bind import bind
from pygoby.acomms.drivers.udp import UDPDriver
from pygoby.util.clock import VirtualClock

from .queue_helpers import entry, manager, status_link

DRIVER_UDP = 6


def udp_cfg(modem_id, local_port, remotes):
    cfg = acomms_pb.DriverConfig(driver_type=DRIVER_UDP, modem_id=modem_id)
    ext = cfg.Extensions[acomms_pb.UDP_CONFIG]
    ext.local.port = local_port
    for rid, port in remotes:
        ext.remote.add(modem_id=rid, ip="127.0.0.1", port=port)
    return cfg


def pump(drivers, rounds=50):
    import time

    for _ in range(rounds):
        for d in drivers:
            d.do_work()
        time.sleep(0.002)


def test_queue_to_queue_over_udp_with_ack():
    clock = VirtualClock(1_700_000_000.0)
    d1, d2 = UDPDriver(clock), UDPDriver(clock)
    d2.startup(udp_cfg(2, 0, []))
    port2 = d2.local_port
    d1.startup(udp_cfg(1, 0, [(2, port2)]))
    d2.shutdown()  # restart with the remote now that d1's ephemeral port is known
    d2.startup(udp_cfg(2, port2, [(1, d1.local_port)]))
    try:
        q1, (Status, *_) = manager(clock, modem_id=1, entries=[entry("Status")])
        q2, _ = manager(clock, modem_id=2, entries=[entry("Status")])
        bind(d1, q1)
        bind(d2, q2)
        got, acked = [], []
        q2.signal_receive.connect(got.append)
        q1.signal_ack.connect(lambda ack, orig: acked.append((list(ack.acked_frame), orig.value)))
        q1.push_message(Status(src=1, dest=2, value=11))
        clock.advance(1)
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=0))
        pump([d1, d2])
        assert [x.value for x in got] == [11]
        assert acked == [([0], 11)] and q1.size(20) == 0
        q1.push_message(Status(src=1, dest=2, value=12))
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=0))
        pump([d1, d2])
        assert acked[-1] == ([1], 12)  # running frame counter
    finally:
        d1.shutdown()
        d2.shutdown()


def test_datagram_is_plain_protobuf_and_garbage_is_skipped(caplog):
    clock = VirtualClock(1_700_000_000.0)
    listener = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    listener.bind(("127.0.0.1", 0))
    listener.settimeout(2)
    d = UDPDriver(clock)
    d.startup(udp_cfg(1, 0, [(2, listener.getsockname()[1])]))
    try:
        d.signal_data_request.connect(lambda msg: msg.frame.append(b"\x01\x02\x03\x04\x05"))
        d.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=2, rate=0))
        data, _ = listener.recvfrom(65535)
        expected = acomms_pb.ModemTransmission(
            src=1, dest=2, rate=0, max_frame_bytes=1400, frame_start=0
        )
        expected.frame.append(b"\x01\x02\x03\x04\x05")
        assert acomms_pb.ModemTransmission.FromString(data) == expected
        got = []
        d.signal_receive.connect(got.append)
        with caplog.at_level(logging.WARNING):
            listener.sendto(b"\xff\xff\xff", ("127.0.0.1", d.local_port))
            pump([d], rounds=20)
        assert got == [] and "not a ModemTransmission" in caplog.text
    finally:
        d.shutdown()
        listener.close()


def test_multicast_queue_to_queue_with_ack():
    import random

    from pygoby.acomms.drivers import make_driver

    ext = acomms_pb.UDP_MULTICAST_CONFIG
    port = random.randint(40000, 60000)
    clock = VirtualClock(1_700_000_000.0)
    drivers = []
    for i in (1, 2):
        cfg = acomms_pb.DriverConfig(driver_type=11, modem_id=i)
        cfg.Extensions[ext].listen_address = "127.0.0.1"
        cfg.Extensions[ext].multicast_address = "239.255.42.97"
        cfg.Extensions[ext].multicast_port = port
        d = make_driver(cfg, clock)
        d.startup(cfg)
        drivers.append(d)
    d1, d2 = drivers
    try:
        q1, _q2, Status, got, acked = status_link(clock, d1, d2)
        reported = []
        d2.signal_transmit_result.connect(reported.append)
        q1.push_message(Status(src=1, dest=2, value=8))
        clock.advance(1)
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=0))
        pump(drivers)
        assert [x.value for x in got] == [8] and acked == [8]
        # the acknowledgement is a transmission too (ACOMMS_MODEM_TRANSMIT), as in goby3
        assert [(t.type, t.src, t.dest) for t in reported] == [(acomms_pb.ACK, 2, 1)]
    finally:
        for d in drivers:
            d.shutdown()


def test_a_broadcast_without_a_broadcast_remote_is_reported_once(caplog):
    d = UDPDriver(VirtualClock(0.0))
    d.startup(udp_cfg(1, 0, [(2, 9)]))  # a remote for modem 2 only
    try:
        frame = acomms_pb.ModemTransmission(src=1, dest=0, frame=[b"x"])
        with caplog.at_level(logging.WARNING):
            d.handle_initiate_transmission(frame)
            d.handle_initiate_transmission(frame)
        warnings = [r.getMessage() for r in caplog.records if "no remote" in r.getMessage()]
        assert warnings == [
            "UDP driver: no remote for destination 0 (remotes configured for modem ids [2]); "
            "a broadcast (0) reaches only the remotes whose modem_id is 0"
        ]
    finally:
        d.shutdown()
