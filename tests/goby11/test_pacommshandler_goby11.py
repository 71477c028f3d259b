"""pAcommsHandler with a Goby 1.1 configuration on the embedded MOOSDB and emulated modems: XML
messages with the 1.1 header defaults, the 1.1 MOOS variables (ACOMMS_INCOMING_DATA,
ACOMMS_RANGE_COMMAND/RESPONSE, ACOMMS_POLLER_UPDATE, 1.1 MACUpdates), notes and errors."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path

import pytest
from google.protobuf import text_format

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.mmsim import LoopbackChannel
from pygoby.acomms.mmsim.channel import DEFAULT_SOUND_SPEED
from pygoby.dccl.dccl1 import Dccl1Codec, unstitch
from pygoby.dccl.xml import load_message_set
from pygoby.moos.client import MOOSClient
from pygoby.util.clock import WallClock
from tests.apps.acomms_mission import two_vehicle_missions
from tests.goby11.missions import micromodem_driver_goby11
from tests.goby11.seed_listings import EXAMPLES

pytestmark = pytest.mark.e2e

SIMPLE_STATUS = EXAMPLES / "xml" / "simple_status.xml"


def mission(modem_id: int, db_port: int, modem_port: int) -> str:
    manipulator = "" if modem_id == 1 else " manipulator: NO_ENCODE"
    return f"""ServerHost = localhost
ServerPort = {db_port}
Community = mm{modem_id}
LatOrigin = 42.35
LongOrigin = -70.95
modem_id_lookup_path = {EXAMPLES}/MOOS/ccl_and_dccl/modemidlookup.txt

ProcessConfig = pAcommsHandler
{{
  common
  {{
    verbosity: VERBOSITY_WARN
    log: false
    app_tick: 20
    initializer {{ type: INI_STRING moos_var: "VEHICLE_NAME" sval: "mm{modem_id}" }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_X" dval: 100 }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_Y" dval: 300 }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_HEADING" dval: -30 }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_SPEED" dval: 1.5 }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_DEPTH" dval: 20 }}
  }}
  modem_id: {modem_id}
{micromodem_driver_goby11(modem_port)}
  mac_cfg
  {{
    type: MAC_FIXED_DECENTRALIZED
    slot {{ src: 1 dest: 2 rate: 0 type: SLOT_DATA slot_seconds: 5 }}
  }}
  dccl_cfg {{ message_file {{ path: "{SIMPLE_STATUS}"{manipulator} }} }}
}}
"""


WATCHED = ["STATUS_REPORT_IN", "ACOMMS_INCOMING_DATA", "ACOMMS_RANGE_RESPONSE", "ACOMMS_NMEA_OUT"]


def two_nodes(tmp_path: Path):
    # in real time: Goby 1.1's header time is the time of day, placed in the day by the
    # receiver's clock
    clock = WallClock()
    channel = LoopbackChannel(clock, range_m=0.25 * DEFAULT_SOUND_SPEED)  # 0.25 s away
    return two_vehicle_missions(tmp_path, mission, WATCHED, channel, clock)


async def test_goby11_configuration_runs_with_the_11_variables(tmp_path):
    async with two_nodes(tmp_path) as (apps, recorders):
        mm1, _mm2 = apps
        assert any("VERBOSITY_WARN -> WARN" in note for note in mm1.config_notes)
        assert any("transitional_cfg" in note for note in mm1.config_notes)
        status = await recorders[1].wait_for(
            "STATUS_REPORT_IN", lambda v: "Node=1" in v, timeout=30
        )
        fields = dict(item.split("=", 1) for item in status.split(","))
        assert (fields["Heading"], fields["Speed"], fields["Depth"]) == (
            "330",
            "1.5",
            "20",
        )  # angle_0_360
        assert abs(float(fields["Timestamp"]) - WallClock().now()) < 60  # 1.1 header default
        incoming = await recorders[1].wait_for("ACOMMS_INCOMING_DATA")
        data = acomms_pb.V1ModemDataTransmission()
        text_format.Parse(incoming, data)
        # Goby 1.1's bytes (DCCL1): 0x20, then DCCL id 20 in the next 9 bits; a Goby 1.1
        # decoder (no passphrase configured: key SHA-256 of "") reads the values
        assert data.data[0] == 0x20 and (data.base.src, data.base.dest) == (1, 2)
        goby11 = Dccl1Codec()
        goby11.load(load_message_set(SIMPLE_STATUS))
        (part,) = unstitch(data.data)
        decoded = goby11.decode(part.data)
        assert (decoded.message, decoded.header.src, decoded.values["nav_x"]) == (
            "SIMPLE_STATUS",
            1,
            100,
        )

        async with MOOSClient("poker", port=mm1.client.port) as poker:
            poker.publish("ACOMMS_RANGE_COMMAND", "base { dest: 2 } type: MODEM_TWO_WAY_PING")
            reply = await recorders[0].wait_for("ACOMMS_RANGE_RESPONSE", timeout=20)
            ranging = acomms_pb.V1ModemRangingReply()
            text_format.Parse(reply, ranging)
            assert list(ranging.one_way_travel_time) == [0.25] and ranging.type == 1
            poker.publish(
                "ACOMMS_POLLER_UPDATE",
                "dest: 1 update_type: ADD slot { src: 1 dest: 2 type: SLOT_PING slot_seconds: 2 }",
            )
            poker.publish(
                "ACOMMS_MAC_CYCLE_UPDATE",
                "dest: 1 update_type: ADD slot { src: 2 dest: 1 type: SLOT_DATA slot_seconds: 3 }",
            )
            await poker.flush()
            await recorders[0].wait_for(
                "ACOMMS_NMEA_OUT", lambda v: v.startswith("$CCMPC"), timeout=20
            )
            async with asyncio.timeout(10):
                while len(mm1.acomms.mac.slots) < 3:
                    await asyncio.sleep(0.05)
        slots = mm1.acomms.mac.slots
        assert [(s.src, s.dest, s.slot_seconds) for s in slots] == [
            (1, 2, 5.0),
            (1, 2, 2.0),
            (2, 1, 3.0),
        ]
        assert (
            slots[1].Extensions[acomms_pb.MM_TRANSMISSION].type == acomms_pb.MICROMODEM_TWO_WAY_PING
        )


def test_xml_error_stops_pacommshandler_with_file_and_line(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text(SIMPLE_STATUS.read_text().replace("<max>20</max>", "<max>fast</max>"))
    path = tmp_path / "mm1.moos"
    path.write_text(mission(1, 1, 1).replace(str(SIMPLE_STATUS), str(bad)))
    result = subprocess.run(
        [str(Path(sys.executable).with_name("pAcommsHandler")), str(path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 1
    assert (
        f"fatal configuration error: {bad}:40: <max> must be a number, not 'fast'" in result.stderr
    )


def test_transitional_messages_expand_into_the_configuration(tmp_path):
    from pygoby.moosacomms.transitional import TransitionalMessages
    from pygoby.protobuf import ProtoLoader, builtin_class

    cfg = builtin_class(
        "goby/apps/moos/protobuf/pAcommsHandler_config.proto",
        "goby.apps.moos.protobuf.pAcommsHandlerConfig",
    )(modem_id=3)
    cfg.transitional_cfg.message_file.add(path=str(SIMPLE_STATUS), manipulator=[5])
    cfg.transitional_cfg.generated_proto_dir = str(tmp_path / "proto")
    loader = ProtoLoader()
    messages = TransitionalMessages.expand(cfg, loader)
    assert [e.protobuf_name for e in cfg.queue_cfg.message_entry] == ["SIMPLE_STATUS"]
    assert list(cfg.queue_cfg.message_entry[0].manipulator) == [5]
    assert [e.protobuf_name for e in cfg.translator_entry] == ["SIMPLE_STATUS"]
    assert (tmp_path / "proto" / "simple_status.proto").read_text().startswith("// Converted from")
    status = loader.message_class("SIMPLE_STATUS")(nav_x=5)
    messages.complete(status, 1234.5, 3)
    assert (status.Timestamp, status.Node) == (1234.5, 3)
    given = loader.message_class("SIMPLE_STATUS")(Timestamp=1.0, Node=7)
    assert messages.complete(given, 1234.5, 3) == given  # set fields are kept
