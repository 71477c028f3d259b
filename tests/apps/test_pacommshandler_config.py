"""pAcommsHandler configuration: the spec's example block, --example_config, start-up errors,
and paths relative to the mission file."""

from __future__ import annotations

import shutil
import subprocess
import sys
import time

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.dccl import Codec
from pygoby.moos.appconfig import ConfigError

from .acomms_mission import PROTO, STATUS

# spec goby-moos-apps.md 4.11, with a real DCCL type
EXAMPLE = f"""\
ProcessConfig = pAcommsHandler
{{
  common {{ verbosity: VERBOSE  app_tick: 10  log: false }}
  modem_id: 1
  driver_cfg {{
    driver_type: DRIVER_WHOI_MICROMODEM
    connection_type: CONNECTION_SERIAL
    serial_port: "/dev/ttyUSB0"
    serial_baud: 19200
    [goby.acomms.micromodem.protobuf.config] {{ reset_nvram: false  nvram_cfg: "DQF,1" }}
  }}
  mac_cfg {{
    type: MAC_FIXED_DECENTRALIZED
    slot {{ src: 1 dest: -1 rate: 0 type: DATA slot_seconds: 10 }}
    slot {{ src: 2 dest: -1 rate: 0 type: DATA slot_seconds: 10 }}
  }}
  queue_cfg {{
    message_entry {{
      protobuf_name: "{STATUS}"
      ack: false  ttl: 300  value_base: 1.5  blackout_time: 10
      role {{ type: SOURCE_ID field: "src" }}
      role {{ type: DESTINATION_ID setting: STATIC static_value: 0 }}
    }}
  }}
  dccl_cfg {{ crypto_passphrase: "secret"  skip_crypto_for_id: 5 }}
  route_cfg {{ route {{ hop: 1 hop: 2 }} }}
  driver_failure_approach {{ technique: MOVE_LISTEN_DRIVER_TO_PRIMARY driver_backoff_sec: 30 }}
  moos_var {{ prefix: "AC_" }}
  load_proto_file: "@PROTO@"
  translator_entry {{
    protobuf_name: "{STATUS}"
    trigger {{ type: TRIGGER_TIME period: 15 }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_X" format: "%10%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_Y" format: "%11%" }}
    publish {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "NODE_REPORT_IN" }}
  }}
}}
"""


def write(tmp_path, text: str, proto=str(PROTO)):
    path = tmp_path / "mission.moos"
    path.write_text(text.replace("@PROTO@", proto))
    return path


def test_spec_example_configures_every_layer(tmp_path):
    app = pAcommsHandler.from_mission(write(tmp_path, EXAMPLE))
    acomms = app.acomms
    assert type(acomms.primary.driver).__name__ == "MMDriver"
    assert acomms.primary.cfg.modem_id == 1 and acomms.primary.cfg.serial_port == "/dev/ttyUSB0"
    assert acomms.primary.cfg.Extensions[acomms_pb.MM_CONFIG].nvram_cfg == ["DQF,1"]
    assert len(acomms.mac_cfg.slot) == 2 and acomms.mac_cfg.modem_id == 1
    app.on_start()
    assert acomms.mac.running and len(acomms.mac.slots) == 2 and acomms.mac.cfg.modem_id == 1
    assert acomms.queue.modem_id == 1 and list(acomms.queue.queues) == [20]
    assert acomms.queue.queues[20].entry.blackout_time == 10
    assert list(acomms.route_cfg.route.hop) == [1, 2]
    assert acomms.failure.driver_backoff_sec == 30
    assert app.var["queue_size"] == "AC_QSIZE" and app.ifs_data_out == "IFS_DATA_OUT"
    status = app.message_types(STATUS)(
        time=float(int(time.time())), src=1, nav_x=1, nav_y=2, speed=0, heading=0, depth=0
    )
    encrypted = acomms.codec.encode(status)
    plain = Codec()
    plain.load(type(status))
    assert encrypted != plain.encode(status) and acomms.codec.decode(encrypted) == status


def test_goby_messages_resolve_for_translator_entries(tmp_path):
    app = pAcommsHandler.from_mission(write(tmp_path, EXAMPLE))
    assert app.message_types("goby.acomms.protobuf.MACUpdate") is acomms_pb.MACUpdate
    assert app.message_types("goby.acomms.protobuf.RouteCommand").DESCRIPTOR.name == "RouteCommand"


@pytest.mark.parametrize(
    ("change", "error"),
    [
        (("modem_id: 1", "modem_id: 0"), "broadcast"),
        (("modem_id: 1", ""), "missing required configuration fields: modem_id"),
        (("DRIVER_WHOI_MICROMODEM", "DRIVER_BENTHOS_ATM900"), "not implemented"),
        (
            ('load_proto_file: "@PROTO@"', 'load_proto_file: "no/such.proto"'),
            'no/such.proto" not found; searched: ',
        ),
        (("moos_var {", 'dccl_frontseat_forward_name: "no.Such"\n  moos_var {'), "no.Such"),
        (("period: 15", "period: 0"), "TRIGGER_TIME needs a period"),
        (("common {", "common { moos_parser_technique: TECHNIQUE_FORMAT "), "Non-PROTOBUF"),
    ],
)
def test_configuration_errors_are_clear(tmp_path, change, error):
    old, new = change
    with pytest.raises(ConfigError, match=error):
        pAcommsHandler.from_mission(write(tmp_path, EXAMPLE.replace(old, new)))


def test_relative_paths_are_found_next_to_the_mission(tmp_path, monkeypatch):
    shutil.copy(PROTO, tmp_path / "messages.proto")
    (tmp_path / "ids.txt").write_text("1, alpha, auv\n2, bravo, auv\n")
    text = EXAMPLE.replace("  moos_var {", '  modem_id_lookup_path: "ids.txt"\n  moos_var {')
    path = write(tmp_path, text, proto="messages.proto")
    monkeypatch.chdir("/")
    app = pAcommsHandler.from_mission(path)
    assert list(app.acomms.queue.queues) == [20]
    assert app.translator.registry.modem_ids.name(2) == "bravo"


def test_example_config_command_line():
    done = subprocess.run(
        [sys.executable, "-m", "pygoby.apps.pacommshandler", "--example_config"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0
    out = done.stdout
    assert out.startswith("ProcessConfig = pAcommsHandler\n{")
    for needle in (
        "modem_id: 1",
        "driver_cfg {",
        "listen_driver_cfg {",
        "mac_cfg {",
        "queue_cfg {",
        "dccl_cfg {",
        "route_cfg {",
        "moos_var {",
        'prefix: "ACOMMS_"',
        "translator_entry {",
        "multiplex_create_moos_var:",
        "modem_id_lookup_path:",
        "driver_failure_approach {",
        "load_proto_file:",
    ):
        assert needle in out, needle


def test_route_cfg_gives_outgoing_messages_their_next_hop(tmp_path):
    """route_cfg hops 1 -> 2 -> 3: a command for 3 leaves vehicle 1 addressed to 2 on the link."""
    from .acomms_mission import COMMAND, QUEUE_ENTRIES

    mission = f"""\
ProcessConfig = pAcommsHandler
{{
  common {{ log: false }}
  modem_id: 1
  driver_cfg {{ driver_type: DRIVER_NONE }}
{QUEUE_ENTRIES}
  route_cfg {{ route {{ hop: 1 hop: 2 hop: 3 }} subnet_mask: 0xFFFFFF00 }}
  load_proto_file: "@PROTO@"
}}
"""
    app = pAcommsHandler.from_mission(write(tmp_path, mission))
    command = app.message_types(COMMAND)(
        time=float(int(time.time())), src=1, dest=3, command_id=7, heading=90, speed=1, depth=5
    )
    app.acomms.queue.push_message(command)
    request = acomms_pb.ModemTransmission(
        src=1, dest=acomms_pb.QUERY_DESTINATION_ID, type=acomms_pb.DATA, max_frame_bytes=32
    )
    app.acomms.queue.handle_modem_data_request(request)
    assert request.dest == 2
    assert list(request.frame)  # the command is in the frame
