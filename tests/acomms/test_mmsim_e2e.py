"""Two emulated Micro-Modems, two drivers over real TCP (and a pty): data + ack, ranging, faults."""

import asyncio

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem import MMDriver
from pygoby.acomms.mmsim import LoopbackChannel, MicroModemModel
from pygoby.acomms.mmsim.server import ANONYMOUS_PTY, MMSimServer
from pygoby.util.clock import WallClock

from .mm_e2e import run_until, start_emulators, started_driver
from .queue_helpers import status_link

pytestmark = pytest.mark.e2e


async def test_data_with_ack_and_ranging_over_tcp():
    _channel, (sim1, sim2) = await start_emulators([1, 2], range_m=1000.0)  # 0.6667 s away
    d1 = await started_driver(1, sim1.port)
    d2 = await started_driver(2, sim2.port, query=True)  # also exercises CFQ,ALL at start-up
    try:
        got1, got2, results = [], [], []
        d1.signal_receive.connect(got1.append)
        d2.signal_receive.connect(got2.append)
        d1.signal_transmit_result.connect(results.append)

        def fill(msg):
            msg.dest = 2
            msg.frame.append(b"hello")
            msg.frame.append(b"world")

        d1.signal_data_request.connect(fill)
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, rate=1))
        data = lambda: [t for t in got2 if t.type == acomms_pb.DATA and t.frame]  # noqa: E731
        acks = lambda: [t for t in got1 if t.type == acomms_pb.ACK]  # noqa: E731
        await run_until(lambda: data() and acks(), [d1, d2])
        (rx,) = data()
        assert (rx.src, rx.dest, list(rx.frame)) == (1, 2, [b"hello", b"world"])
        assert rx.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat[0].snr_in == 15
        assert sorted(acks()[0].acked_frame) == [0, 1]
        assert results and results[0].Extensions[acomms_pb.MM_TRANSMISSION].transmit_stat

        ping = acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DRIVER_SPECIFIC)
        ping.Extensions[acomms_pb.MM_TRANSMISSION].type = acomms_pb.MICROMODEM_TWO_WAY_PING
        got1.clear()
        d1.handle_initiate_transmission(ping)
        await run_until(lambda: any(t.type == acomms_pb.DRIVER_SPECIFIC for t in got1), [d1, d2])
        reply = next(t for t in got1 if t.type == acomms_pb.DRIVER_SPECIFIC)
        owtt = reply.Extensions[acomms_pb.MM_TRANSMISSION].ranging_reply.one_way_travel_time
        assert list(owtt) == [0.6667] and (reply.src, reply.dest) == (2, 1)  # (exact: 4 digits)
        assert any(t.type == acomms_pb.DRIVER_SPECIFIC and t.src == 1 for t in got2)  # $CAMPA heard
    finally:
        for d in (d1, d2):
            d.shutdown()
        for s in (sim1, sim2):
            await s.close()


async def test_polled_transmission_rate0_over_tcp():
    _channel, (sim1, sim2) = await start_emulators([1, 2])
    d1, d2 = await started_driver(1, sim1.port), await started_driver(2, sim2.port)
    try:
        got1 = []
        d1.signal_receive.connect(got1.append)
        d2.signal_data_request.connect(lambda msg: msg.frame.append(b"\x2a" * 32))
        d1.handle_initiate_transmission(
            acomms_pb.ModemTransmission(src=2, dest=1, rate=0)
        )  # poll node 2
        await run_until(lambda: any(t.frame for t in got1), [d1, d2])
        (rx,) = [t for t in got1 if t.frame]
        assert (rx.src, rx.dest, list(rx.frame)) == (2, 1, [b"\x2a" * 32])
    finally:
        for d in (d1, d2):
            d.shutdown()
        for s in (sim1, sim2):
            await s.close()


async def test_driver_reconnects_after_link_drop_and_resumes():
    _channel, (sim1, sim2) = await start_emulators([1, 2])
    d1, d2 = await started_driver(1, sim1.port), await started_driver(2, sim2.port)
    try:
        got2 = []
        d2.signal_receive.connect(got2.append)
        sim1.drop_clients()
        await run_until(lambda: not d1.link.is_open, [d1, d2])
        requests = []
        d1.signal_data_request.connect(requests.append)
        d1.signal_data_request.connect(lambda msg: msg.frame.append(b"after"))
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=2, rate=0))
        assert requests == []  # link down: nothing is taken from the queue
        await run_until(lambda: d1.link.is_open, [d1, d2], timeout=10)  # reconnects (1 s)
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=2, rate=0))
        await run_until(lambda: any(t.frame for t in got2), [d1, d2], timeout=10)
        assert [bytes(f) for t in got2 for f in t.frame] == [b"after"]
    finally:
        for d in (d1, d2):
            d.shutdown()
        for s in (sim1, sim2):
            await s.close()


async def test_driver_over_serial_pty():
    channel = LoopbackChannel()
    sim = MMSimServer(MicroModemModel(3, WallClock(), channel), channel, pty_path=ANONYMOUS_PTY)
    await sim.start()
    cfg = acomms_pb.DriverConfig(
        driver_type=2, modem_id=3, serial_port=sim.pty_path, serial_baud=19200
    )
    cfg.Extensions[acomms_pb.MM_CONFIG].query_cfg_on_startup = False
    driver = MMDriver(WallClock())
    driver.startup(cfg)
    try:
        await run_until(lambda: driver.startup_complete, [driver], timeout=15)
        assert driver.revision == (2, 0, 40000)  # (the emulator is a Micro-Modem 2)
    finally:
        driver.shutdown()
        await sim.close()
        await asyncio.sleep(0)


async def test_acked_message_queued_during_link_outage_is_delivered_after_reconnect():
    from pygoby.acomms.bind import bind
    from pygoby.acomms.mac import MAC_FIXED_DECENTRALIZED, MACManager

    from .queue_helpers import entry, manager

    _channel, (sim1, sim2) = await start_emulators([1, 2])
    d1, d2 = await started_driver(1, sim1.port), await started_driver(2, sim2.port)
    clock = WallClock()
    q1, (Status, *_) = manager(clock, modem_id=1, entries=[entry("Status")])
    q2, _ = manager(clock, modem_id=2, entries=[entry("Status")])
    mac = MACManager(clock)  # node 1 owns every slot, one a rate-1 packet and its ack fit in
    mac.startup(
        acomms_pb.MACConfig(
            modem_id=1,
            type=MAC_FIXED_DECENTRALIZED,
            slot=[acomms_pb.ModemTransmission(src=1, dest=-1, rate=1, slot_seconds=3)],
        )
    )
    bind(d1, q1, mac)
    bind(d2, q2)
    received, acked = [], []
    q2.signal_receive.connect(received.append)
    q1.signal_ack.connect(lambda ack, original: acked.append(original))
    workers = [d1, d2, mac, q1, q2]
    try:
        sim1.drop_clients()  # the modem link goes down...
        await run_until(lambda: not d1.link.is_open, workers)
        q1.push_message(Status(src=1, dest=2, value=42))  # ...while a message waits, ack=true
        await run_until(lambda: bool(acked), workers, timeout=15)  # reconnect within 1 s
        assert [x.value for x in received] == [42]
        assert acked[0].value == 42 and q1.size(20) == 0
    finally:
        mac.shutdown()
        for d in (d1, d2):
            d.shutdown()
        for s in (sim1, sim2):
            await s.close()


async def test_application_acks_over_tcp():
    _channel, (sim1, sim2) = await start_emulators([1, 2])
    d1 = await started_driver(1, sim1.port, use_application_acks=True)
    d2 = await started_driver(2, sim2.port, use_application_acks=True)
    clock = WallClock()
    q1, _q2, Status, got, acked = status_link(clock, d1, d2)
    try:
        q1.push_message(Status(src=1, dest=2, value=77))
        await asyncio.sleep(0.01)
        d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=1))
        await run_until(lambda: bool(got), [d1, d2])
        assert [x.value for x in got] == [77] and acked == []  # the ack is owed, not sent yet
        d2.handle_initiate_transmission(
            acomms_pb.ModemTransmission(src=2, dest=-1, rate=1)
        )  # no data
        await run_until(lambda: bool(acked), [d1, d2])  # the ack-only packet acknowledges
        assert acked == [77] and q1.size(20) == 0
    finally:
        for d in (d1, d2):
            d.shutdown()
        for s in (sim1, sim2):
            await s.close()
