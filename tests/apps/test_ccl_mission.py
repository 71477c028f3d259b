"""goby3-examples' ccl_and_dccl mission: vehicle 1 sends the legacy CCL MDAT_STATE message,
vehicle 2 a DCCL status, both with `load_shared_library: ".../libdccl_ccl_compat.so"` (mapped
to pygoby's built-in legacy CCL). Two communities (embedded MOOSDB + pAcommsHandler each) over
emulated Micro-Modems on real loopback TCP (the example uses UDP multicast), the status type
from a .proto file (the example loads it from a C++ library)."""

from __future__ import annotations

import asyncio

import pytest

from pygoby.acomms import messages as m
from pygoby.acomms.mmsim import LoopbackChannel
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.moos.appconfig import ConfigError
from pygoby.moos.translator import parse_for_moos

from .acomms_mission import PROTO, WARP, Recorder, mission_clock, two_vehicle_missions

pytestmark = pytest.mark.e2e

STATE = "dccl.legacyccl.protobuf.CCLMDATState"
STATUS = "pygoby.examples.SimpleStatus"
# as the example writes it in the mission file (quotes and backslashes escaped in the sval)
STATE_TEXT = (
    r"latitude: 42.5  longitude: -10.56  fix_age: 3  time_date: 1360620606000000  heading: 195"
    r"  depth: 345  mission_mode: NORMAL  faults: \"\\000\\000\\000\\000\" faults_2: \"0\""
    r"  mission_leg: 1  est_velocity: 1.5  objective_index: \"\\000\" watts: 20  lat_goal: 42.49"
    r"  lon_goal: -10.54  battery_percent: 85  gfi_pitch_oil { gfi: 0  pitch: 3  oil: 80 }"
)


def mission(modem_id: int, db_port: int, modem_port: int) -> str:
    other = 3 - modem_id
    if modem_id == 1:
        initializer = f'initializer {{ type: INI_STRING moos_var: "REMUS_STATUS_REPORT_OUT" sval: "@PB[{STATE}] {STATE_TEXT}" }}'
        ccl_manipulator, status_manipulator = "", "manipulator: NO_QUEUE"
    else:
        initializer = 'initializer { type: INI_STRING moos_var: "STATUS_REPORT_OUT" sval: "nav_x=550,nav_y=125,speed=1.6,heading=213,depth=5" }'
        ccl_manipulator, status_manipulator = "manipulator: NO_QUEUE", ""
    return f"""\
ServerHost = localhost
ServerPort = {db_port}
Community  = mm{modem_id}
MOOSTimeWarp = {WARP}

ProcessConfig = pAcommsHandler
{{
  common {{ log: false  app_tick: 20  verbosity: WARN
    initializer {{ type: INI_DOUBLE moos_var: "STATUS_DESTINATION" dval: {other} }}
    {initializer}
  }}
  modem_id: {modem_id}
  driver_cfg {{
    driver_type: DRIVER_WHOI_MICROMODEM
    connection_type: CONNECTION_TCP_AS_CLIENT
    tcp_server: "127.0.0.1"
    tcp_port: {modem_port}
    [goby.acomms.micromodem.protobuf.config] {{ query_cfg_on_startup: false }}
  }}
  mac_cfg {{
    type: MAC_FIXED_DECENTRALIZED
    slot {{ src: 1 type: DATA rate: 1 slot_seconds: 3 }}
    slot {{ src: 2 type: DATA rate: 1 slot_seconds: 3 }}
  }}
  queue_cfg {{
    message_entry {{ protobuf_name: "{STATE}" ack: false blackout_time: 1 ttl: 300 value_base: 1.5
                    {ccl_manipulator} }}
    message_entry {{ protobuf_name: "{STATUS}" ack: false blackout_time: 1 ttl: 300 value_base: 1.5
      role {{ type: SOURCE_ID field: "src" }}
      role {{ type: DESTINATION_ID field: "dest" }}
      role {{ type: TIMESTAMP field: "time" }}
      {status_manipulator} }}
  }}
  translator_entry {{
    protobuf_name: "{STATE}"
    trigger {{ type: TRIGGER_TIME period: 1 }}
    create {{ technique: TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT moos_var: "REMUS_STATUS_REPORT_OUT" }}
    publish {{ technique: TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT moos_var: "REMUS_STATUS_REPORT_IN" }}
  }}
  translator_entry {{
    protobuf_name: "{STATUS}"
    trigger {{ type: TRIGGER_TIME period: 1 }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "DB_TIME" format: "%1%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "MODEM_ID" format: "%2%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "STATUS_DESTINATION" format: "%3%" }}
    create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "STATUS_REPORT_OUT" }}
    publish {{ technique: TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT moos_var: "STATUS_REPORT_IN_PB" }}
  }}
  load_shared_library: "/home/toby/dccl/build/lib/libdccl_ccl_compat.so"
  load_proto_file: "{PROTO}"
}}
"""


def two_vehicles(tmp_path):
    watched = ["REMUS_STATUS_REPORT_IN", "STATUS_REPORT_IN_PB", "ACOMMS_MODEM_TRANSMIT"]
    clock = mission_clock()
    return two_vehicle_missions(tmp_path, mission, watched, LoopbackChannel(clock), clock)


async def test_ccl_state_and_dccl_status_between_two_vehicles(tmp_path):
    async with two_vehicles(tmp_path) as ((app1, _app2), (r1, r2)):
        assert app1.acomms.codec.id_codec == "dccl.ccl.id"
        state = await r2.wait_for("REMUS_STATUS_REPORT_IN", timeout=30)
        assert state.startswith(f"@PB[{STATE}] ")
        assert "mission_mode: NORMAL" in state and "battery_percent: 85" in state
        status = await r1.wait_for("STATUS_REPORT_IN_PB", timeout=30)
        assert status.startswith(f"@PB[{STATUS}] ") and "nav_x: 550" in status
        # on the wire: a CCL frame starts with its mode byte (0x0E, MDAT_STATE), a DCCL message
        # among CCL frames with 0x20
        assert (await first_frame(r1))[:1] == b"\x0e"
        assert (await first_frame(r2))[:1] == b"\x20"


async def first_frame(recorder: Recorder) -> bytes:
    def frames(value: str) -> list[bytes]:
        t = m.ModemTransmission()
        parse_for_moos(value, t)
        return [bytes(f) for f in t.frame if f] if t.type == m.DATA else []

    value = await recorder.wait_for("ACOMMS_MODEM_TRANSMIT", lambda v: bool(frames(v)), timeout=30)
    return frames(value)[0]


def test_other_shared_libraries_say_what_to_use(tmp_path):
    path = tmp_path / "mm1.moos"
    text = mission(1, 9000, 62000).replace("libdccl_ccl_compat.so", "libgobyexample_protobuf.so")
    path.write_text(text)
    with pytest.raises(ConfigError, match="load_proto_file"):
        pAcommsHandler.from_mission(path, "pAcommsHandler")


if __name__ == "__main__":  # pragma: no cover
    asyncio.run(test_ccl_state_and_dccl_status_between_two_vehicles(None))
