"""pTranslator end to end: embedded MOOSDB + pTranslator configured from a .moos file; inputs
are poked and the translated variables read back with the MOOS client."""

from __future__ import annotations

import asyncio
import logging
import subprocess
import sys
from pathlib import Path

import pytest

from pygoby.apps.ptranslator import pTranslator
from pygoby.moos.appconfig import ConfigError
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.moosfile import MissionFile

from .test_algorithms import LOOKUP

PROTO = Path(__file__).resolve().parent / "protos" / "translator_test.proto"
BNR = "pygoby.test.translator.BasicNodeReport"
NODE_FORMAT = "NAME=%1%,X=%202%,Y=%3%,HEADING=%201%"


def mission_text(port: int, lookup: Path, entries: str) -> str:
    return f"""\
ServerHost = localhost
ServerPort = {port}
Community  = alpha
LatOrigin  = 42.35
LongOrigin = -70.95
modem_id_lookup_path = {lookup}

ProcessConfig = pTranslator
{{
  common {{ log: false  app_tick: 20  verbosity: QUIET }}
  load_proto_file: "{PROTO}"
{entries}
}}
"""


ENTRIES = f"""\
  translator_entry {{
    protobuf_name: "{BNR}"
    trigger {{ type: TRIGGER_PUBLISH  moos_var: "NAV_HEADING" }}
    create {{ technique: TECHNIQUE_FORMAT  moos_var: "NAV_X"  format: "%202%" }}
    create {{ technique: TECHNIQUE_FORMAT  moos_var: "VEHICLE_NAME"  format: "%1%"
             algorithm {{ name: "to_lower"  primary_field: 1 }} }}
    create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS  moos_var: "NAV_HEADING"
             algorithm {{ name: "angle_0_360"  primary_field: 201 }} }}
    create {{ technique: TECHNIQUE_FORMAT  moos_var: "NAV_Y"  format: "%3%" }}
    publish {{ technique: TECHNIQUE_FORMAT  moos_var: "NODE_REPORT_%1%"
              format: "{NODE_FORMAT};X+Y=%104%;ID=%102%"
              algorithm {{ name: "add"  output_virtual_field: 104  primary_field: 202  reference_field: 3 }}
              algorithm {{ name: "name2modem_id"  output_virtual_field: 102  primary_field: 1 }} }}
    publish {{ technique: TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT  moos_var: "NODE_REPORT_PB" }}
    publish {{ technique: TECHNIQUE_FORMAT  moos_var: "NODE_X"  format: "%202%" }}
  }}
  translator_entry {{
    protobuf_name: "pygoby.test.translator.Deploy"
    trigger {{ moos_var: "DEPLOY_CMD"  mandatory_content: "deploy" }}
    create {{ technique: TECHNIQUE_PROTOBUF_TEXT_FORMAT  moos_var: "DEPLOY_TEXT" }}
    create {{ technique: TECHNIQUE_FORMAT  moos_var: "DEPLOY_CMD"  format: "deploy %4%" }}
    publish {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS  moos_var: "DEPLOY_KV" }}
  }}
"""
OUTPUTS = ("NODE_REPORT_unicorn", "NODE_REPORT_PB", "NODE_X", "DEPLOY_KV")


@pytest.fixture
def lookup_file(tmp_path):
    path = tmp_path / "modemidlookup.txt"
    path.write_text(LOOKUP)
    return path


async def test_ptranslator_end_to_end(tmp_path, lookup_file, caplog):
    async with (
        MOOSDB(port=0, community="alpha") as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        tester.publish("NAV_HEADING", "heading=5")  # before the app starts: must not trigger
        await tester.flush()
        path = tmp_path / "mission.moos"
        path.write_text(mission_text(db.port, lookup_file, ENTRIES))
        app = pTranslator.from_mission(path, "pTranslator")
        async with app:
            for var in OUTPUTS:
                tester.subscribe(var)
            await tester.flush()
            await asyncio.sleep(0.2)
            tester.publish("NAV_X", 550.0)
            tester.publish("NAV_Y", 1023.5)
            tester.publish("VEHICLE_NAME", "UNICORN")
            tester.publish("NAV_HEADING", "heading=-120")
            got = {}
            while len(got) < 3:
                msg = await tester.receive(3)
                assert msg.key not in got, f"{msg.key} posted twice (stale trigger?)"
                got[msg.key] = msg
            assert got["NODE_REPORT_unicorn"].value == (
                "NAME=unicorn,X=550,Y=1023.5,HEADING=240;X+Y=1573.5;ID=3"
            )
            assert got["NODE_REPORT_unicorn"].src_aux == f"{BNR}:TECHNIQUE_FORMAT"
            assert got["NODE_REPORT_PB"].value == (
                f'@PB[{BNR}] Name: "unicorn" y: 1023.5 heading: 240 x: 550 '
            )
            assert got["NODE_X"].is_double and got["NODE_X"].value == 550.0

            # Malformed input: a warning, nothing half-built is posted, the app keeps going.
            with caplog.at_level(logging.WARNING):
                tester.publish("DEPLOY_TEXT", "destination: {")
                tester.publish("DEPLOY_CMD", "deploy 7")
                tester.publish("DEPLOY_CMD", "status")  # lacks the mandatory content
                tester.publish("NAV_HEADING", "heading=10,colour=red")
                keys = []
                while len(keys) < 3:
                    msg = await tester.receive(3)
                    keys.append(msg.key)
                    if msg.key == "NODE_REPORT_unicorn":
                        assert msg.value == "NAME=unicorn,X=550,Y=1023.5,HEADING=10;X+Y=1573.5;ID=3"
                assert keys == ["NODE_REPORT_PB", "NODE_REPORT_unicorn", "NODE_X"]  # by name
                tester.publish("DEPLOY_TEXT", "mode: DEPLOY_MODE_STAY")
                tester.publish("DEPLOY_CMD", "deploy 7")
                while (msg := await tester.receive(3)).key != "DEPLOY_KV":
                    assert msg.key in OUTPUTS
            assert msg.value == "mode=DEPLOY_MODE_STAY,destination=7"
            assert "cannot parse pygoby.test.translator.Deploy" in caplog.text
            assert "unknown key(s) 'colour'" in caplog.text
            assert app.connected


async def test_time_trigger_and_datum_from_origin_mail(tmp_path, lookup_file):
    entries = f"""\
  translator_entry {{
    protobuf_name: "{BNR}"
    trigger {{ type: TRIGGER_TIME  period: 1 }}
    create {{ technique: TECHNIQUE_FORMAT  moos_var: "NAV_Y"  format: "%3%" }}
    publish {{ technique: TECHNIQUE_FORMAT  moos_var: "LAT"  format: "%100%"
              algorithm {{ name: "utm_y2lat"  output_virtual_field: 100  primary_field: 3  reference_field: 202 }} }}
  }}
"""
    async with (
        MOOSDB(port=0, community="alpha") as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        path = tmp_path / "mission.moos"
        path.write_text(mission_text(db.port, lookup_file, entries))
        async with pTranslator.from_mission(path, "pTranslator"):
            tester.subscribe("LAT")
            tester.publish("NAV_Y", 0.0)
            msg = await tester.receive(3)
            assert (msg.key, msg.value) == ("LAT", 42.35)
            tester.publish("LAT_ORIGIN", 10.0)
            tester.publish("LONG_ORIGIN", 20.0)
            for _ in range(4):
                msg = await tester.receive(3)
                if msg.value == 10.0:
                    break
            assert msg.value == 10.0


def test_configuration_errors(tmp_path, lookup_file):
    missing = '  translator_entry { protobuf_name: "no.Such" }'
    mission = MissionFile.from_text(mission_text(9000, lookup_file, missing))
    with pytest.raises(ConfigError, match='"no.Such" is not a loaded message type'):
        pTranslator(
            pTranslator.read_config(mission, "pTranslator"), name="pTranslator", mission=mission
        )


async def test_entries_goby3_runs_start_with_one_warning_per_oddity(tmp_path, lookup_file, caplog):
    # goby3 starts with these: an unknown algorithm passes the value through, a publish
    # directive naming no field prints "unknown" (or nothing past the highest field number,
    # 202 here; the two indexed directives become 203 and 204), an index on a field that is not
    # repeated prints the whole field.
    entries = f"""\
  translator_entry {{
    protobuf_name: "{BNR}"
    trigger {{ type: TRIGGER_PUBLISH  moos_var: "NAV_X" }}
    create {{ technique: TECHNIQUE_FORMAT  moos_var: "NAV_X"  format: "%202%"
             algorithm {{ name: "alg_nope"  primary_field: 202 }} }}
    publish {{ technique: TECHNIQUE_FORMAT  moos_var: "ODD"
              format: "a=%5%;b=%6.0%;c=%104%;d=%202%;e=%11.1%;f=%300%" }}
  }}
"""
    async with (
        MOOSDB(port=0, community="alpha") as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        path = tmp_path / "mission.moos"
        path.write_text(mission_text(db.port, lookup_file, entries))
        caplog.clear()  # (the DB's start is logged at INFO when an earlier test left that level on)
        with caplog.at_level(logging.WARNING):
            app = pTranslator.from_mission(path, "pTranslator")
        assert [r.getMessage() for r in caplog.records] == [
            f"{path}:16: translator_entry[0].create[0].algorithm[0].name: {BNR}: unknown "
            "algorithm 'alg_nope': the value passes through unchanged, as in goby3",
            f"{path}:18: translator_entry[0].publish[0].format: {BNR}: %6.0%: field 6 (depth) "
            "is not repeated: the whole field prints, as in goby3",
            f"{path}:18: translator_entry[0].publish[0].format: {BNR}: %11.1% names no field of "
            f"{BNR}: it prints 'unknown', as in goby3",
        ] + [
            f"{path}:18: translator_entry[0].publish[0].format: {BNR}: %{n}% names no field of "
            f"{BNR} (nor an algorithm's output_virtual_field): it prints 'unknown' or nothing, "
            "as in goby3"
            for n in (5, 104, 300)
        ]
        async with app:
            tester.subscribe("ODD")
            await tester.flush()
            await asyncio.sleep(0.2)
            tester.publish("NAV_X", 550.0)
            msg = await tester.receive(3)
        assert (msg.key, msg.value) == ("ODD", "a=unknown;b=0;c=unknown;d=550;e=unknown;f=")


def test_example_config_command():
    result = subprocess.run(
        [sys.executable, "-m", "pygoby.apps.ptranslator", "--example_config"],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    lines = result.stdout.splitlines()
    assert lines[:2] == ["ProcessConfig = pTranslator", "{"] and lines[-1] == "}"
    assert any(line.startswith("  translator_entry {") for line in lines)
    assert any(line.startswith("  modem_id_lookup_path: ") for line in lines)


async def test_shared_library_and_multiplexed_commands(tmp_path, lookup_file):
    from grpc_tools import protoc

    assert protoc.main(["protoc", f"-I{PROTO.parent}", f"--python_out={tmp_path}", str(PROTO)]) == 0
    generated = tmp_path / "translator_test_pb2.py"
    entries = """\
  multiplex_create_moos_var: "MUX"
  translator_entry {
    protobuf_name: "pygoby.test.translator.Deploy"
    trigger { moos_var: "DEPLOY_KV_IN" }
    create { technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS  moos_var: "DEPLOY_KV_IN" }
    publish { technique: TECHNIQUE_FORMAT  moos_var: "DEPLOY_OUT"  format: "%2%/%4%" }
  }
"""
    text = mission_text(0, lookup_file, entries).replace(
        f'  load_proto_file: "{PROTO}"', f'  load_shared_library: "{generated}"'
    )
    async with (
        MOOSDB(port=0, community="alpha") as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        path = tmp_path / "mission.moos"
        path.write_text(text.replace("ServerPort = 0", f"ServerPort = {db.port}"))
        async with pTranslator.from_mission(path, "pTranslator"):
            tester.subscribe("DEPLOY_OUT")
            tester.subscribe("DEPLOY_KV_IN")
            await tester.flush()
            tester.publish(
                "MUX", "@PB[pygoby.test.translator.Deploy] mode: DEPLOY_MODE_STAY destination: 4"
            )
            tester.publish("MUX", "@PB[unknown.Type] x: 1")  # warned about and ignored
            got = {}
            while len(got) < 2:
                msg = await tester.receive(3)
                got[msg.key] = msg
            assert got["DEPLOY_KV_IN"].value == "mode=DEPLOY_MODE_STAY,destination=4"
            assert got["DEPLOY_OUT"].value == "DEPLOY_MODE_STAY/4"


def test_unloadable_message_definitions_are_config_errors(tmp_path, lookup_file):
    broken = tmp_path / "broken.proto"
    broken.write_text('syntax = "proto2"; message X { optional nonsense y = 1; }')
    for line in (f'  load_proto_file: "{broken}"', '  load_shared_library: "no_such_module_pb2"'):
        text = mission_text(9000, lookup_file, "").replace(f'  load_proto_file: "{PROTO}"', line)
        mission = MissionFile.from_text(text)
        with pytest.raises(ConfigError, match=r"load_(proto_file|shared_library): cannot load "):
            pTranslator(
                pTranslator.read_config(mission, "pTranslator"), name="pTranslator", mission=mission
            )
