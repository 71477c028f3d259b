"""pAcommsHandler's MOOS interface with DRIVER_NONE (one community, no modem): injected
receptions, queue flush/expire/size, MAC updates, config request, frontseat forwarding,
multiplexing, renamed variables and bad input; a fatal driver failure as a process."""

from __future__ import annotations

import asyncio
import base64
import logging
import sys
from pathlib import Path

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.dccl import Codec
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.translator import parse_for_moos, serialize_for_moos

from .acomms_mission import COMMAND, PROTO, STATUS, TRANSLATOR_ENTRIES, Recorder

pytestmark = pytest.mark.e2e

MISSION = f"""\
ServerHost = localhost
ServerPort = @PORT@
Community = alpha
ProcessConfig = pAcommsHandler
{{
  common {{ log: false  app_tick: 20  verbosity: QUIET }}
  modem_id: 1
  mac_cfg {{ type: MAC_FIXED_DECENTRALIZED  slot {{ src: 1 slot_seconds: 1 }}
              slot {{ src: 2 slot_seconds: 1 }} }}
  queue_cfg {{
    message_entry {{ protobuf_name: "{STATUS}" ack: false
                     role {{ type: SOURCE_ID field: "src" }} role {{ type: DESTINATION_ID field: "dest" }} }}
    message_entry {{ protobuf_name: "{COMMAND}" ttl: 2
                     role {{ type: SOURCE_ID field: "src" }} role {{ type: DESTINATION_ID field: "dest" }} }}
  }}
  load_proto_file: "{PROTO}"
  dccl_frontseat_forward_name: "{STATUS}"
  multiplex_create_moos_var: "LIAISON_COMMANDER_OUT"
@EXTRA@
{TRANSLATOR_ENTRIES}
}}
"""

WATCH = [
    "MODEM_ID",
    "STATUS_REPORT_IN",
    "IFS_DATA_OUT",
    "ACOMMS_QUEUE_RECEIVE",
    "ACOMMS_QSIZE",
    "ACOMMS_EXPIRE",
    "ACOMMS_CONFIG",
    "ACOMMS_MAC_SLOT_START",
    "ACOMMS_MAC_INITIATE_TRANSMISSION",
    "AC_QSIZE",
    "AC_MAC_SLOT_START",
]


def qsize(dccl_id: int, size: int):
    return lambda v: f"dccl_id: {dccl_id} size: {size} " in v


async def start(tmp_path, db, extra=""):
    path = tmp_path / "alpha.moos"
    path.write_text(MISSION.replace("@PORT@", str(db.port)).replace("@EXTRA@", extra))
    recorder = Recorder("tester", db.port)
    await recorder.start(WATCH)
    app = pAcommsHandler.from_mission(path)
    await app.start(connect_timeout=5)
    async with asyncio.timeout(10):
        while "DB_TIME" not in app.dynamic_vars:
            await asyncio.sleep(0.02)
    return app, recorder


async def test_moos_interface_without_a_modem(tmp_path, caplog):
    async with MOOSDB(port=0) as db:
        app, r = await start(tmp_path, db)
        try:
            assert await r.wait_for("MODEM_ID") == 1.0
            await r.wait_for("ACOMMS_QSIZE", qsize(20, 0))  # queues announced; the unknown
            await r.wait_for("ACOMMS_QSIZE", qsize(21, 0))  # type got no queue
            assert sorted(app.queue.queues) == [20, 21]
            start_ = acomms_pb.ModemTransmission()
            parse_for_moos(await r.wait_for("ACOMMS_MAC_SLOT_START"), start_)
            assert start_.src in (1, 2) and start_.time > 0  # the MAC runs without a driver

            # Another process injects a reception: decoded, published, forwarded to iFrontSeat.
            codec = Codec()
            status_cls = codec.load_proto(PROTO, STATUS)
            status = status_cls(time=1.8e9, src=2, nav_x=5, nav_y=6, speed=1, heading=2, depth=3)
            data = codec.encode(status)
            rx = acomms_pb.ModemTransmission(src=2, dest=0, type=acomms_pb.DATA, frame=[data])
            r.client.publish("ACOMMS_MODEM_RECEIVE", serialize_for_moos(rx))
            report = await r.wait_for("STATUS_REPORT_IN")
            assert report == "src=2,x=5,y=6,speed=1,heading=2,depth=3"
            assert (await r.wait_for("ACOMMS_QUEUE_RECEIVE")).startswith(f"@PB[{STATUS}] ")
            ifs = await r.wait_for("IFS_DATA_OUT")
            assert ifs.startswith("@PB[goby.middleware.frontseat.protobuf.InterfaceData] ")
            forwarded = pAcommsHandler_interface_data()
            parse_for_moos(ifs, forwarded)
            assert codec.decode(forwarded.dccl_message) == codec.decode(data)

            # Queue: a command is queued, flushed; another expires (ttl 2 s).
            r.client.publish("COMMAND_OUT", "dest=2,command_id=4,heading=1,speed=1,depth=1")
            await r.wait_for("ACOMMS_QSIZE", qsize(21, 1))
            r.client.publish(
                "ACOMMS_FLUSH_QUEUE", serialize_for_moos(acomms_pb.QueueFlush(dccl_id=21))
            )
            async with asyncio.timeout(5):
                while app.queue.size(21):
                    await asyncio.sleep(0.02)
            r.client.publish("COMMAND_OUT", "dest=2,command_id=5,heading=1,speed=1,depth=1")
            expired = await r.wait_for("ACOMMS_EXPIRE", timeout=10)
            assert expired.startswith(f"@PB[{COMMAND}] ") and "command_id: 5" in expired

            # Multiplexed creation (goby_liaison): posted back to the create variables, queued.
            seen = len(r.values("ACOMMS_QSIZE"))
            r.client.publish(
                "LIAISON_COMMANDER_OUT",
                f"@PB[{COMMAND}] time: 1.8e9 src: 1 dest: 2 command_id: 6 "
                "heading: 10 speed: 1 depth: 2",
            )
            await r.wait_for("ACOMMS_QSIZE", qsize(21, 1), timeout=5, start=seen)
            assert app.queue.queues[21].next_item().msg.command_id == 6

            # The configuration on request: base64 of the binary pAcommsHandlerConfig.
            r.client.publish("ACOMMS_CONFIG_REQUEST", "now")
            cfg = type(app.cfg)()
            cfg.ParseFromString(base64.b64decode(await r.wait_for("ACOMMS_CONFIG")))
            assert cfg == app.cfg

            # MAC updates: only those for our id; cycle_state STOPPED shuts the MAC down.
            app.log.addHandler(caplog.handler)  # the app's log does not propagate
            with caplog.at_level(logging.WARNING):
                r.client.publish(
                    "ACOMMS_MAC_CYCLE_UPDATE", "@PB[goby.acomms.protobuf.MACUpdate] garbage {"
                )
                update = acomms_pb.MACUpdate(src=2, dest=5, update_type=acomms_pb.MACUpdate.CLEAR)
                r.client.publish("ACOMMS_MAC_CYCLE_UPDATE", serialize_for_moos(update))
                update = acomms_pb.MACUpdate(
                    src=2,
                    dest=1,
                    update_type=acomms_pb.MACUpdate.PUSH_BACK,
                    slot=[acomms_pb.ModemTransmission(src=1, slot_seconds=1)],
                )
                r.client.publish("ACOMMS_MAC_CYCLE_UPDATE", serialize_for_moos(update))
                async with asyncio.timeout(5):
                    while len(app.acomms.mac.slots) != 3:
                        await asyncio.sleep(0.02)
                update = acomms_pb.MACUpdate(src=2, dest=1, cycle_state=acomms_pb.MACUpdate.STOPPED)
                r.client.publish("ACOMMS_MAC_CYCLE_UPDATE", serialize_for_moos(update))
                r.client.publish("ACOMMS_DRIVER_RESET", "now")  # no driver: a warning
                r.client.publish("ACOMMS_MODEM_RECEIVE", "not a transmission")
                async with asyncio.timeout(5):
                    while app.acomms.mac.running:
                        await asyncio.sleep(0.02)
            assert "cannot parse ACOMMS_MAC_CYCLE_UPDATE" in caplog.text
            assert "there is no primary driver" in caplog.text
            assert "cannot parse ACOMMS_MODEM_RECEIVE" in caplog.text
        finally:
            await app.stop()
            await r.close()


def pAcommsHandler_interface_data():
    from pygoby.frontseat.messages import InterfaceData

    return InterfaceData()


async def test_renamed_variables(tmp_path):
    async with MOOSDB(port=0) as db:
        app, r = await start(
            tmp_path, db, extra='  moos_var { prefix: "AC_" queue_size: "QUEUE_SIZE" }'
        )
        try:
            await r.wait_for("AC_MAC_SLOT_START")
            assert "ACOMMS_QSIZE" not in r.seen and "ACOMMS_MAC_SLOT_START" not in r.seen
            r2 = Recorder("tester2", db.port)
            await r2.start(["AC_QUEUE_SIZE"])
            value = await r2.wait_for("AC_QUEUE_SIZE")
            assert value.startswith("@PB[goby.acomms.protobuf.QueueSize] dccl_id: 2")
            await r2.close()
        finally:
            await app.stop()
            await r.close()


ON_DEMAND = f"""\
ServerHost = localhost
ServerPort = @PORT@
ProcessConfig = pAcommsHandler
{{
  common {{ log: false  app_tick: 20  verbosity: QUIET }}
  modem_id: 1
  driver_cfg {{ driver_name: "SCRIPTED" }}
  mac_cfg {{ type: MAC_FIXED_DECENTRALIZED  slot {{ src: 1 slot_seconds: 1 max_frame_bytes: 32 }} }}
  queue_cfg {{
    message_entry {{ protobuf_name: "{STATUS}" ack: false  manipulator: ON_DEMAND
                     role {{ type: SOURCE_ID field: "src" }} role {{ type: DESTINATION_ID field: "dest" }} }}
  }}
  load_proto_file: "{PROTO}"
{TRANSLATOR_ENTRIES}
}}
"""


async def test_on_demand_messages_are_created_at_each_data_request(tmp_path, monkeypatch):
    monkeypatch.setenv("PACOMMSHANDLER_PLUGINS", "tests.apps.plugin_driver")
    async with MOOSDB(port=0) as db:
        path = tmp_path / "on_demand.moos"
        path.write_text(ON_DEMAND.replace("@PORT@", str(db.port)))
        r = Recorder("tester", db.port)
        await r.start(["ACOMMS_MODEM_TRANSMIT"])
        app = pAcommsHandler.from_mission(path)
        await app.start(connect_timeout=5)
        try:
            for value, var in enumerate(
                ("NAV_X", "NAV_Y", "NAV_SPEED", "NAV_HEADING", "NAV_DEPTH")
            ):
                r.client.publish(var, float(value + 1))
            codec = Codec()
            status_cls = codec.load_proto(PROTO, STATUS)

            def carries_nav(text):
                tx = acomms_pb.ModemTransmission()
                parse_for_moos(text, tx)
                return tx.frame and tx.frame[0] and codec.decode(tx.frame[0]).nav_x == 1.0

            await r.wait_for("ACOMMS_MODEM_TRANSMIT", carries_nav, timeout=15)
            assert status_cls  # created from the newest NAV_* values, never triggered
        finally:
            await app.stop()
            await r.close()


async def test_received_route_command_replaces_the_route(tmp_path):
    route_cfg = """  route_cfg { route { hop: 1 hop: 3 } }
  queue_cfg { message_entry { protobuf_name: "goby.acomms.protobuf.RouteCommand" } }"""
    async with MOOSDB(port=0) as db:
        app, r = await start(tmp_path, db, extra=route_cfg)
        try:
            assert 514 in app.queue.queues
            command_cls = app.message_types("goby.acomms.protobuf.RouteCommand")
            command = command_cls(src=3, dest=1, time=int(1.8e15))
            command.new_route.hop.extend([1, 2, 3])
            frame = app.acomms.codec.encode(command)
            rx = acomms_pb.ModemTransmission(src=3, dest=1, type=acomms_pb.DATA, frame=[frame])
            r.client.publish("ACOMMS_MODEM_RECEIVE", serialize_for_moos(rx))
            async with asyncio.timeout(5):
                while list(app.acomms.route_cfg.route.hop) != [1, 2, 3]:
                    await asyncio.sleep(0.02)
        finally:
            await app.stop()
            await r.close()


async def test_a_fatal_driver_failure_ends_the_process_with_status_1(tmp_path):
    # The primary driver fails (a manual reset) under MOVE_LISTEN_DRIVER_TO_PRIMARY with no
    # listen driver to replace it: pAcommsHandler stops, and says so with its exit status.
    extra = """  driver_cfg { driver_type: DRIVER_UDP  [goby.acomms.udp.protobuf.config] { local { port: 0 } } }
  driver_failure_approach { technique: MOVE_LISTEN_DRIVER_TO_PRIMARY }"""
    async with MOOSDB(port=0, community="alpha") as db:
        path = tmp_path / "alpha.moos"
        path.write_text(MISSION.replace("@PORT@", str(db.port)).replace("@EXTRA@", extra))
        proc = await asyncio.create_subprocess_exec(
            str(Path(sys.executable).with_name("pAcommsHandler")),
            str(path),
            stdout=asyncio.subprocess.DEVNULL,
            stderr=asyncio.subprocess.PIPE,
        )
        try:
            async with MOOSClient("tester", port=db.port) as tester:
                async with asyncio.timeout(15):
                    while "pAcommsHandler" not in db.client_names:
                        await asyncio.sleep(0.05)
                tester.publish("ACOMMS_DRIVER_RESET", "now")
                _, err = await asyncio.wait_for(proc.communicate(), 15)
        finally:
            if proc.returncode is None:
                proc.kill()
    assert proc.returncode == 1
    assert "no listen driver to replace it" in err.decode()
