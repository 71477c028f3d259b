"""The .moos mission-file reader: globals, comments, quotes, macros, blocks, ANTLER."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.moos.moosfile import MissionFile, strip_comment
from tests.hypothesis_profiles import examples

MISSION = """\
// mission for one vehicle
ServerHost   = localhost
ServerPort   = 9000
Community    = my ship     // spaces are removed from globals
MOOSTimeWarp = 1
LatOrigin    = 43.825300
LongOrigin   = nope
url = "http://host//x" // comment
define: DEPTH = 12
TargetDepth = ${DEPTH}
log = TRUE

ProcessConfig = ANTLER
{
  MSBetweenLaunches = 200
  Run = MOOSDB          @ NewConsole = false
  Run = pHelmIvP        @ NewConsole = false
  Run = uSim            @ NewConsole = false, ExtraProcessParams = SimArgs ~ sim_one
  SimArgs = --moos_suicide_disable,--verbose=true
}

ProcessConfig = pHelmIvP          // a classic MOOS block
{
  AppTick   = 4
  behaviors = alpha bravo.bhv
  domain    = course:0:359:360
  domain    = speed:0:4:41
  empty =
}

ProcessConfig = pAcommsHandler
{
  common { app_tick: 10  // a comment
           verbosity: VERBOSE
           server_host: "http://a//b"  // quoted // kept }
  }
  modem_id: 1
}
"""


def test_globals():
    m = MissionFile.from_text(MISSION)
    assert m.get_value("serverhost") == "localhost"
    assert m.get_int("ServerPort") == 9000
    assert m.get_value("Community") == "myship"
    assert m.get_float("LatOrigin") == 43.8253
    assert m.get_float("LongOrigin") is None  # not numeric
    assert m.get_value("url") == "http://host//x"
    assert m.get_value("TargetDepth") == "12"
    assert m.get_bool("log") is True and m.get_bool("MOOSTimeWarp") is True
    assert m.get_value("AppTick") == "4"  # MOOS globals match inside blocks too
    assert m.get_value("AppTick", outside_blocks=True) is None
    assert m.get_value("Community", outside_blocks=True) == "myship"
    assert m.get_value("Missing") is None


def test_process_config_keeps_order_and_spaces():
    m = MissionFile.from_text(MISSION)
    cfg = m.process_config("PHELMIVP")
    assert [(s.name, s.value) for s in cfg] == [
        ("AppTick", "4"),
        ("behaviors", "alpha bravo.bhv"),
        ("domain", "course:0:359:360"),
        ("domain", "speed:0:4:41"),
    ]
    lines = MISSION.splitlines()
    assert [lines[s.line - 1].strip().split()[0] for s in cfg] == [
        "AppTick",
        "behaviors",
        "domain",
        "domain",
    ]
    assert m.block_value("pHelmIvP", "apptick") == "4"
    assert m.process_config("nothere") is None


def test_goby_block_text_and_lines():
    m = MissionFile.from_text(MISSION)
    block = m.goby_block("pAcommsHandler")
    assert block is not None
    assert "common { app_tick: 10  # a comment" in block.text
    assert 'server_host: "http://a//b"  # quoted # kept }' in block.text
    assert block.text.strip().endswith("modem_id: 1")
    lines = MISSION.splitlines()
    assert lines[block.file_line(2) - 1].strip().startswith("common {")
    # a trailing comment on the header prevents the Goby match
    assert m.goby_block("pHelmIvP") is None


def test_antler_block():
    cfg = MissionFile.from_text(MISSION).antler()
    assert cfg.ms_between_launches == 200
    assert [(r.program, r.moos_name) for r in cfg.runs] == [
        ("MOOSDB", "MOOSDB"),
        ("pHelmIvP", "pHelmIvP"),
        ("uSim", "sim_one"),
    ]
    assert cfg.runs[2].extra_args == ["--moos_suicide_disable", "--verbose=true"]
    assert cfg.runs[0].options == {"NewConsole": "false"}


def test_strip_comment():
    assert strip_comment("  // all comment") == ""
    assert strip_comment('a = "x//y" // c') == "a = x//y "
    assert strip_comment("a = b // c") == "a = b "
    assert strip_comment('a // "quoted"') == "a "


@settings(max_examples=examples(200), deadline=None)
@given(st.text(max_size=400))
def test_fuzz_reader_never_crashes(text):
    m = MissionFile.from_text(text)
    m.get_value("x")
    m.process_config("x")
    m.goby_block("x")
