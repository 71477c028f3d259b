"""The parts of the Goby MOOS application base outside its core (pygoby.moos.appcli, appconfig's
initializer posts and moos_var names, appstatus), and the base's protobuf-on-MOOS helpers
(publish_pb, parse_pb, subscribe_pb) against the embedded MOOSDB."""

from __future__ import annotations

import asyncio
import logging
import math
import sys
from pathlib import Path

import pytest

from pygoby.moos import appcli
from pygoby.moos.appconfig import ConfigError, initializer_posts, prefixed_var_names
from pygoby.moos.appstatus import StatusReport
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.moosfile import MissionFile
from pygoby.protobuf import builtin_class

sys.path.insert(0, str(Path(__file__).resolve().parent))
from example_app import config_class, pTestApp

MISSION = """\
ServerHost = localhost
ServerPort = {port}
Community = alpha
LatOrigin = 42.5
Name = ship one
ProcessConfig = pTestApp
{{
  common {{ log: false app_tick: 20 verbosity: QUIET {common} }}
  out_var: "ECHO"
}}
"""


def read(port: int = 9000, common: str = "") -> tuple:
    mission = MissionFile.from_text(MISSION.format(port=port, common=common))
    return pTestApp.read_config(mission, "pTestApp"), mission


def test_parse_overrides():
    assert appcli.parse_overrides(["--gain", "2", "--common=app_tick: 5"]) == [
        ("gain", "2"),
        ("common", "app_tick: 5"),
    ]
    with pytest.raises(ValueError, match="unexpected argument 'x'"):
        appcli.parse_overrides(["x"])
    with pytest.raises(ValueError, match="option --gain needs a value"):
        appcli.parse_overrides(["--gain"])


def test_program_name():
    assert appcli.program_name(pTestApp, "/usr/bin/pAlias") == "pAlias"
    for run_from_python in ("", "example_app.py", "python3", "-c"):
        assert appcli.program_name(pTestApp, run_from_python) == "pTestApp"


def test_initializer_posts(caplog):
    common = """initializer { type: INI_DOUBLE moos_var: "LAT" global_cfg_var: "LatOrigin" }
      initializer { type: INI_DOUBLE moos_var: "BAD" global_cfg_var: "Name" }
      initializer { type: INI_STRING moos_var: "NAME" global_cfg_var: "Name" trim: false }
      initializer { type: INI_STRING moos_var: "HI" sval: " hi " }
      initializer { type: INI_DOUBLE moos_var: "C" dval: 2.5 }
      initializer { type: INI_STRING moos_var: "NEVER" global_cfg_var: "Missing" }"""
    cfg, mission = read(common=common)
    with caplog.at_level(logging.WARNING):
        posts = dict(initializer_posts(cfg.common, mission))
    assert posts.pop("LAT") == 42.5 and math.isnan(posts.pop("BAD"))
    assert posts == {"NAME": "shipone", "HI": "hi", "C": 2.5}  # (MOOS globals lose spaces)
    assert "initializer: global Missing not found; NEVER not posted" in caplog.text
    assert initializer_posts(cfg.common, None)[-1] == ("C", 2.5)  # no mission: constants only


def test_prefixed_var_names():
    cfg = builtin_class(
        "goby/moos/protobuf/iFrontSeat_config.proto", "goby.apps.moos.protobuf.iFrontSeatConfig"
    )()
    cfg.moos_var.prefix = "X_"
    names = prefixed_var_names(cfg.moos_var, skip=("status",))
    assert names["command_request"] == "X_COMMAND_REQUEST" and "prefix" not in names
    assert "status" not in names and len(names) == len(cfg.moos_var.DESCRIPTOR.fields) - 2


def test_status_report_is_due_every_period():
    report = StatusReport(period=2.0)
    assert report.due(10.0) and not report.due(11.9) and report.due(12.0)
    line = report.line("pX", 3.5, {"B", "A"}, ["S"])
    assert line.startswith("AppErrorFlag=false,Uptime=3.5,cpuload=")
    assert line.endswith(',MOOSName=pX,Publishing="A,B,",Subscribing="S,"')


def test_find_file_next_to_the_mission(tmp_path, monkeypatch):
    (tmp_path / "mission").mkdir()
    (tmp_path / "mission" / "types.proto").write_text("")
    path = tmp_path / "mission" / "m.moos"
    path.write_text(MISSION.format(port=9000, common=""))
    monkeypatch.chdir(tmp_path)
    mission = MissionFile.read(path)
    app = pTestApp(pTestApp.read_config(mission, "pTestApp"), mission=mission)
    assert app.find_file("types.proto") == str(tmp_path / "mission" / "types.proto")
    assert app.find_file("missing.proto") == "missing.proto"
    assert pTestApp(read()[0]).find_file("types.proto") == "types.proto"  # no mission file


def test_unusable_moos_parser_technique_is_a_config_error():
    with pytest.raises(ConfigError, match="Non-PROTOBUF"):
        pTestApp(read(common="moos_parser_technique: TECHNIQUE_FORMAT")[0])


async def test_protobuf_messages_on_moos_variables(caplog):
    message_class = config_class()
    async with MOOSDB(port=0) as db, MOOSClient("tester", port=db.port) as tester:
        cfg, mission = read(db.port)
        app = pTestApp(cfg, name="pTestApp", mission=mission)
        app.log.addHandler(caplog.handler)  # the app's log does not propagate to the root
        got, others = [], []
        app.subscribe_pb("PB_IN", message_class, got.append)
        app.subscribe_pb("PB_IN", message_class, others.append, ignore_own=True)
        tester.subscribe("PB_OUT")
        async with app:
            app.publish_pb("PB_OUT", message_class(out_var="Y", gain=2))
            msg = await tester.receive(3)
            posted = '@PB[pygoby.test.TestAppConfig] gain: 2 out_var: "Y" '  # goby3's text form
            assert (msg.key, msg.value) == ("PB_OUT", posted)
            tester.publish("PB_IN", "@PB[pygoby.test.TestAppConfig] no_such_field: 1")
            tester.publish("PB_IN", msg.value)
            app.publish("PB_IN", msg.value)  # its own post: only for `got`
            async with asyncio.timeout(3):
                while len(got) < 2:
                    await asyncio.sleep(0.02)
            assert got == [message_class(out_var="Y", gain=2)] * 2
            assert others == [message_class(out_var="Y", gain=2)]
            parsed = app.parse_pb(msg, message_class)
            assert parsed == got[0]
    assert "cannot parse PB_IN as pygoby.test.TestAppConfig" in caplog.text
