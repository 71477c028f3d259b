"""pAcommsHandler end to end: two communities (embedded MOOSDB + pAcommsHandler each) talking
through emulated Micro-Modems over real loopback TCP, with TDMA slots, through a modem link
outage and a MOOSDB outage."""

from __future__ import annotations

import asyncio

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.moos.db import MOOSDB
from pygoby.moos.translator import parse_for_moos, serialize_for_moos

from .acomms_mission import COMMAND, SLOT_SECONDS, STATUS, TwoCommunities

pytestmark = pytest.mark.e2e

NAV = {"NAV_X": 100.0, "NAV_Y": -50.0, "NAV_SPEED": 1.5, "NAV_HEADING": -90.0, "NAV_DEPTH": 10.0}


def parsed(cls, text):
    msg = cls()
    parse_for_moos(text, msg)
    return msg


async def test_status_and_acked_command_between_two_vehicles(tmp_path):
    async with TwoCommunities(tmp_path) as net:
        (r1, r2), (app1, _) = net.recorders, net.apps
        await net.ready()
        assert r1.values("MODEM_ID") == [1.0] and r1.values("VEHICLE_ID") == [1.0]
        for var, value in NAV.items():
            r1.client.publish(var, value)
        await r1.wait_for("ACOMMS_QSIZE")  # queues announced at creation
        r1.client.publish("SEND_STATUS", "now")
        report = await r2.wait_for("STATUS_REPORT_IN")
        assert report == "src=1,x=100,y=-50,speed=1.5,heading=270,depth=10"
        received = await r2.wait_for("ACOMMS_QUEUE_RECEIVE")
        assert received.startswith(f"@PB[{STATUS}] ")

        r1.client.publish("COMMAND_OUT", "dest=2,command_id=7,heading=90,speed=1.5,depth=20")
        assert await r2.wait_for("DESIRED_HEADING") == 90.0
        assert "command_id=7" in await r2.wait_for("COMMAND_IN")
        ack = parsed(acomms_pb.ModemTransmission, await r1.wait_for("ACOMMS_ACK"))
        assert (ack.type, ack.src, ack.dest) == (acomms_pb.ACK, 2, 1)
        original = await r1.wait_for("ACOMMS_ACK_ORIGINAL")
        assert original.startswith(f"@PB[{COMMAND}] ") and "command_id: 7" in original

        # The informational variables of the primary driver, the MAC and the queue.
        assert any(v.startswith("$CCCYC") for v in r1.values("ACOMMS_NMEA_OUT"))
        assert any(v.startswith("$CARXD") for v in r2.values("ACOMMS_NMEA_IN"))
        raw = parsed(acomms_pb.ModemRaw, r2.values("ACOMMS_RAW_INCOMING")[0])
        assert raw.raw.startswith(b"$CA") or raw.raw.startswith(b"$SN")
        assert r1.values("ACOMMS_RAW_OUTGOING")
        sent = [parsed(acomms_pb.ModemTransmission, v) for v in r1.values("ACOMMS_MODEM_TRANSMIT")]
        assert any(t.src == 1 and t.frame for t in sent)
        heard = [parsed(acomms_pb.ModemTransmission, v) for v in r2.values("ACOMMS_MODEM_RECEIVE")]
        assert any(t.src == 1 and t.type == acomms_pb.DATA and t.frame for t in heard)
        starts = [
            parsed(acomms_pb.ModemTransmission, v) for v in r1.values("ACOMMS_MAC_SLOT_START")
        ]
        assert {s.src for s in starts} == {1, 2}  # every slot, own or not
        initiated = [
            parsed(acomms_pb.ModemTransmission, v)
            for v in r1.values("ACOMMS_MAC_INITIATE_TRANSMISSION")
        ]
        assert initiated and {s.src for s in initiated} == {1}  # own slots only
        sizes = [parsed(acomms_pb.QueueSize, v) for v in r1.values("ACOMMS_QSIZE")]
        assert {(s.dccl_id, s.size) for s in sizes} >= {(20, 0), (20, 1), (21, 0), (21, 1)}
        assert app1.queue.size(21) == 0

        # Another process asks for a ping through ACOMMS_MAC_INITIATE_TRANSMISSION.
        ping = acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DRIVER_SPECIFIC)
        ping.Extensions[acomms_pb.MM_TRANSMISSION].type = acomms_pb.MICROMODEM_TWO_WAY_PING
        r1.client.publish("ACOMMS_MAC_INITIATE_TRANSMISSION", serialize_for_moos(ping))
        reply = await r1.wait_for("ACOMMS_MODEM_RECEIVE", lambda v: "ranging_reply" in v)
        assert "one_way_travel_time" in reply

        # MACUpdate with cycle_state STOPPED: the MAC stops and the Micro-Modem goes silent.
        stop = acomms_pb.MACUpdate(src=2, dest=2, cycle_state=acomms_pb.MACUpdate.STOPPED)
        r2.client.publish("ACOMMS_MAC_CYCLE_UPDATE", serialize_for_moos(stop))
        await r2.wait_for("ACOMMS_NMEA_OUT", lambda v: v.startswith("$CCCFG,SRC,0*"))
        assert not net.apps[1].acomms.mac.running


async def test_acked_command_survives_a_modem_link_outage(tmp_path):
    async with TwoCommunities(tmp_path) as net:
        (r1, r2), (app1, _) = net.recorders, net.apps
        await net.ready()
        driver = app1.acomms.primary.driver
        net.sims[0].drop_clients()  # the modem's TCP link drops ...
        async with asyncio.timeout(10):
            while driver.link.is_open:
                await asyncio.sleep(0.01)
        r1.client.publish("COMMAND_OUT", "dest=2,command_id=9,heading=45,speed=1,depth=5")
        await r1.wait_for("ACOMMS_QSIZE", lambda v: "dccl_id: 21 size: 1" in v)
        # ... the driver reconnects (1 s) and the queued command goes out and is acknowledged.
        assert await r2.wait_for("DESIRED_HEADING", timeout=30) == 45.0
        original = await r1.wait_for("ACOMMS_ACK_ORIGINAL", timeout=30)
        assert "command_id: 9" in original
        assert r2.values("DESIRED_HEADING") == [45.0]  # delivered once
        assert app1.queue.size(21) == 0


async def test_the_acoustic_link_keeps_working_through_a_moosdb_outage(tmp_path):
    # at a lower warp: the slots during the outage are checked by their times, and a host busy
    # with other tests must not put a slot of the TDMA cycle out of the outage's window
    async with TwoCommunities(tmp_path, warp=3) as net:
        (r1, r2), (app1, _) = net.recorders, net.apps
        await net.ready()
        for recorder in (r1, r2):
            for var, value in NAV.items():
                recorder.client.publish(var, value)
        r1.client.publish("SEND_STATUS", "now")  # queued on vehicle 1 before its DB goes away
        await r1.wait_for("ACOMMS_QSIZE", lambda v: "dccl_id: 20 size: 1" in v)
        heard_before = len(r2.values("STATUS_REPORT_IN"))
        db1 = net.dbs[0]
        port = db1.port
        loop = asyncio.get_running_loop()
        await db1.stop()
        outage_start = app1.clock.now()
        # vehicle 1's MAC and modem go on: its status goes out in its next slot ...
        report = await r2.wait_for(
            "STATUS_REPORT_IN", lambda v: v.startswith("src=1,"), timeout=15, start=heard_before
        )
        assert report == "src=1,x=100,y=-50,speed=1.5,heading=270,depth=10"
        # ... and it hears vehicle 2's status while its DB is still down
        r2.client.publish("SEND_STATUS", "now")
        await asyncio.sleep(2 * 2 * SLOT_SECONDS / net.warp)  # two TDMA cycles
        assert not app1.connected
        outage_end = app1.clock.now()
        db1 = MOOSDB(port=port, community="vehicle1")
        await db1.start()
        try:
            started = loop.time()
            # what vehicle 1 posted meanwhile reaches its DB once it is back
            await r1.wait_for("STATUS_REPORT_IN", lambda v: v.startswith("src=2,"), timeout=15)
            heard = [m for m in r1.seen["STATUS_REPORT_IN"] if m.string.startswith("src=2,")]
            assert outage_start < heard[0].time < outage_end  # posted when it was heard
            slots = [m.time for m in r1.seen["ACOMMS_MAC_INITIATE_TRANSMISSION"]]
            assert any(outage_start < t < outage_end for t in slots)
            assert loop.time() - started < 15
        finally:
            await db1.stop()
