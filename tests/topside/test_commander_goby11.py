"""The commander core with Goby 1.1 XML message sets (seed 003 §2.4, spec goby-moos-apps.md §6):
the messages of examples/goby1.1 (ccl_and_dccl's simple_status.xml, example1.xml), Goby 1.1's
fields and `name=value` posts, and what pAcommsHandler makes of those posts: mm1's translator
builds SIMPLE_STATUS from them, DCCL carries it, mm2's translator publishes it."""

from __future__ import annotations

import contextlib
import shutil
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.dccl import Codec
from pygoby.errors import ConfigError
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import ModemIdLookup, Translator, TranslatorError
from pygoby.moosacomms.acomms_config import AcommsMessageSet, read_acomms_config
from pygoby.topside.commander import Commander, CommandSet, FieldValueError
from pygoby.util.clock import VirtualClock
from tests.hypothesis_profiles import examples

EXAMPLES = Path(__file__).parents[2] / "examples" / "goby1.1"
CCL_AND_DCCL = EXAMPLES / "MOOS" / "ccl_and_dccl"
EXAMPLE1 = EXAMPLES / "xml" / "example1.xml"
NOW = 1700000000.25


def message_set(node: str) -> AcommsMessageSet:
    """The message set of the example's pAcommsHandler on `node` (mm1 or mm2), as it loads it."""
    mission = MissionFile.read(CCL_AND_DCCL / f"{node}.moos")
    return AcommsMessageSet.load(read_acomms_config(mission), mission.find_file)


def translator(messages: AcommsMessageSet) -> Translator:
    """pAcommsHandler's translator for `messages` (with Goby 1.1's name=value rule)."""
    cfg = messages.cfg
    out = Translator(
        cfg.translator_entry,
        messages.types,
        lat_origin=42.35,
        lon_origin=-70.95,
        modem_ids=ModemIdLookup.from_file(messages.find(cfg.modem_id_lookup_path)),
    )
    messages.read_named_values(out)
    return out


@pytest.fixture
def commands() -> CommandSet:
    return CommandSet.from_messages(message_set("mm1"))


def make(commands: CommandSet, posts: list, **kwargs) -> Commander:
    return Commander(
        commands,
        community="mm1",
        now=lambda: NOW,
        publish=posts.append,
        autosave_path=None,
        **kwargs,
    )


STATUS = {
    "Node": "1",
    "nav_x": "250",
    "nav_y": "-40",
    "Speed": "1.5",
    "Heading": "90.25",
    "Depth": "12.5",
}


def test_simple_status_is_listed_with_goby11_fields(commands):
    status = commands.find("SIMPLE_STATUS")  # a time-triggered XML message is listed too
    assert status.goby11 and status.trigger_var == "" and not status.ack
    # Goby 1.1's fields: named header pieces (src_id "Node"; not the time), then the layout
    assert [(f.name, f.kind, f.source, f.editable) for f in status.fields] == [
        ("Node", "int", "VEHICLE_NAME", True),
        ("MessageType", "static", "", False),
        ("nav_x", "float", "NAV_X", True),
        ("nav_y", "float", "NAV_Y", True),
        ("Speed", "float", "NAV_SPEED", True),
        ("Heading", "float", "NAV_HEADING", True),
        ("Depth", "float", "NAV_DEPTH", True),
    ]
    assert status.field("Speed").describe() == "(float) min: -2, max: 20, precision: 1"
    assert status.field("Node").describe() == "(int) min: 0, max: 31"


def test_send_posts_name_value_per_source_variable_and_preview_publishes_nothing(commands):
    posts = []
    commander = make(commands, posts)
    draft = commander.open("SIMPLE_STATUS")
    for name, value in STATUS.items():
        commander.set_value(draft, name, value)
    preview = commander.preview(draft)
    assert posts == []  # Quirk Q18 fixed
    assert [(p.var, p.value) for p in preview.posts] == [
        ("NAV_DEPTH", "Depth=12.5"),
        ("NAV_HEADING", "Heading=90.25"),
        ("NAV_SPEED", "Speed=1.5"),
        ("NAV_X", "nav_x=250"),
        ("NAV_Y", "nav_y=-40"),
        ("VEHICLE_NAME", "Node=1"),
    ]
    assert preview.warnings == []
    commander.send(draft)
    assert posts == preview.posts


def test_a_number_where_the_variable_holds_doubles(commands):
    """The MOOSDB refuses a string for a variable that holds doubles (NAV_X): a source variable
    feeding one numeric field then gets the number, which Goby 1.1's pAcommsHandler reads as is."""
    posts = []
    values = {"NAV_X": 100.0, "NAV_Y": 300.0, "VEHICLE_NAME": "mm1", "NAV_SPEED": "fast"}
    commander = make(commands, posts, values=values)
    draft = commander.open("SIMPLE_STATUS")
    for name, value in STATUS.items():
        commander.set_value(draft, name, value)
    commander.send(draft)
    assert [(p.var, p.value) for p in posts] == [
        ("NAV_DEPTH", "Depth=12.5"),
        ("NAV_HEADING", "Heading=90.25"),
        ("NAV_SPEED", "Speed=1.5"),
        ("NAV_X", 250.0),
        ("NAV_Y", -40.0),
        ("VEHICLE_NAME", "Node=1"),
    ]
    created = TRANSLATOR.create("SIMPLE_STATUS", {p.var: p.value for p in posts})
    assert (created.nav_x, created.nav_y, created.Speed, created.Node) == (250, -40, 1.5, 1)
    commands.import_xml(str(EXAMPLE1))
    go_to = commander.open("GoToCommand")
    commander.set_value(go_to, "goto_x", "5")
    values["OUTGOING_COMMAND"] = 1.0  # several fields share it: only text can carry them
    outgoing = commander.preview(go_to)
    assert (
        "OUTGOING_COMMAND holds numbers: the MOOSDB would refuse text, not sent"
        in outgoing.warnings
    )


def test_out_of_range_xml_field_is_refused_with_its_bound(commands):
    commander = make(commands, [])
    draft = commander.open("SIMPLE_STATUS")
    with pytest.raises(FieldValueError, match="Speed: 25 is above the maximum 20"):
        commander.set_value(draft, "Speed", "25")
    with pytest.raises(FieldValueError, match="at most 1 decimals"):
        commander.set_value(draft, "Speed", "1.55")
    with pytest.raises(FieldValueError, match="Node: 32 is above the maximum 31"):
        commander.set_value(draft, "Node", "32")
    with pytest.raises(FieldValueError, match="static"):
        commander.set_value(draft, "MessageType", "OTHER")
    assert draft.values == {}


def test_the_posts_make_simple_status_on_mm1_and_mm2_decodes_it(commands):
    """pAcommsHandler's side with real parts: mm1's translator creates SIMPLE_STATUS from the
    posted strings (Goby 1.1's name=value rule), the DCCL codec encodes it, mm2's decodes it and
    publishes it as the XML says."""
    posts = []
    commander = make(commands, posts)
    draft = commander.open("SIMPLE_STATUS")
    for name, value in STATUS.items():
        commander.set_value(draft, name, value)
    commander.send(draft)
    mm1, mm2 = message_set("mm1"), message_set("mm2")
    created = translator(mm1).create("SIMPLE_STATUS", {p.var: p.value for p in posts})
    mm1.transitional.complete(created, NOW, 1)
    data = Codec(loader=mm1.loader, clock=VirtualClock(NOW)).encode(created)
    codec = Codec(loader=mm2.loader, clock=VirtualClock(NOW + 4))  # heard 4 s later
    codec.load(mm2.types("SIMPLE_STATUS"))
    received = codec.decode(data)
    published = {p.var: p.value for p in translator(mm2).publish(received)}
    fields = dict(item.split("=", 1) for item in published["STATUS_REPORT_IN"].split(","))
    assert fields == {
        "Timestamp": "1700000000",
        "Node": "1",
        "MessageType": "LAMSS_STATUS",
        "nav_x": "250",
        "nav_y": "-40",
        "Speed": "1.5",
        "Heading": "90.25",
        "Depth": "12.5",
    }
    node = dict(item.split("=", 1) for item in published["NODE_REPORT"].split(","))
    assert [node[k] for k in ("NAME", "TYPE", "X", "Y", "SPD", "HDG", "DEPTH")] == [
        "mm1",
        "topside",
        "250",
        "-40",
        "1.5",
        "90.25",
        "12.5",
    ]


@settings(max_examples=examples(60), deadline=None)
@given(
    x=st.integers(-100000, 100000),
    speed=st.integers(-20, 200),
    heading=st.integers(0, 35999),
    depth=st.integers(0, 64000),
    node=st.integers(0, 31),
)
def test_any_value_in_range_arrives_as_typed(x, speed, heading, depth, node):
    commands = CommandSet.from_messages(MESSAGES)
    posts = []
    commander = make(commands, posts)
    draft = commander.open("SIMPLE_STATUS")
    typed = {
        "Node": str(node),
        "nav_x": str(x),
        "Speed": f"{speed / 10:g}",
        "Heading": f"{heading / 100:g}",
        "Depth": f"{depth / 10:g}",
    }
    for name, value in typed.items():
        commander.set_value(draft, name, value)
    commander.send(draft)
    created = TRANSLATOR.create("SIMPLE_STATUS", {p.var: p.value for p in posts})
    assert (
        created.Node,
        created.nav_x,
        created.Speed,
        created.Heading,
        created.Depth,
    ) == pytest.approx((node, x, speed / 10, heading / 100, depth / 10))


MESSAGES = message_set("mm1")
TRANSLATOR = translator(MESSAGES)


@given(st.text(max_size=60), st.floats(allow_nan=True))
def test_name_value_rule_reads_any_string_without_surprises(text, number):
    """Goby 1.1's rule is a decoder of operator strings: anything either gives a value or the
    translator's own error, never something else."""
    for value in (text, f"nav_x={text}", f"Speed={number}", number):
        with contextlib.suppress(TranslatorError):
            TRANSLATOR.create(
                "SIMPLE_STATUS", {"NAV_X": value, "NAV_SPEED": value, "VEHICLE_NAME": value}
            )


def test_name_value_rule_and_whole_values():
    created = TRANSLATOR.create(
        "SIMPLE_STATUS",
        {
            "NAV_X": "nav_x=3",
            "NAV_Y": 4.0,
            "NAV_SPEED": "1.5",
            "VEHICLE_NAME": "Node=MM2",
            "NAV_DEPTH": "x=1,Depth=7",
        },
    )
    assert (created.nav_x, created.nav_y, created.Speed, created.Node, created.Depth) == (
        3,
        4,
        1.5,
        2,
        7,
    )


def test_field_from_another_variable_than_the_trigger_is_editable_and_posted(tmp_path):
    """example1.xml's GoToCommand: new_instructions reads SPECIAL_INSTRUCTIONS, not the trigger
    variable OUTGOING_COMMAND; Goby 1.1's iCommander posted it there."""
    commands = CommandSet.from_messages(message_set("mm1"))
    names = commands.import_xml(str(EXAMPLE1))
    assert names == ["GoToCommand", "VehicleStatus"] and len(commands) == 3
    go_to = commands.find("GoToCommand")
    assert [(f.name, f.source, f.editable) for f in go_to.fields] == [
        ("Destination", "OUTGOING_COMMAND", True),
        ("type", "OUTGOING_COMMAND", False),
        ("goto_x", "OUTGOING_COMMAND", True),
        ("goto_y", "OUTGOING_COMMAND", True),
        ("lights_on", "OUTGOING_COMMAND", True),
        ("new_instructions", "SPECIAL_INSTRUCTIONS", True),
        ("goto_speed", "OUTGOING_COMMAND", True),
    ]
    assert commands.find("VehicleStatus").field("health").enum_values == (
        "good",
        "low_battery",
        "abort",
    )
    posts = []
    commander = make(commands, posts)
    draft = commander.open("GoToCommand")
    for name, value in {
        "Destination": "2",
        "goto_x": "100",
        "lights_on": "true",
        "new_instructions": "dive",
        "goto_speed": "1.25",
    }.items():
        commander.set_value(draft, name, value)
    outgoing = commander.preview(draft)
    # the trigger variable last; the static field goes with its variable, as in Goby 1.1
    assert [(p.var, p.value) for p in outgoing.posts] == [
        ("SPECIAL_INSTRUCTIONS", "new_instructions=dive"),
        ("OUTGOING_COMMAND", "Destination=2,type=goto,goto_x=100,lights_on=true,goto_speed=1.25"),
    ]
    # the manual's example asks for content the message never holds: the operator is told
    assert outgoing.warnings == [
        "OUTGOING_COMMAND lacks its mandatory content 'CommandType=GoTo': "
        "pAcommsHandler will not make the message"
    ]
    status = commander.open("VehicleStatus")
    commander.set_value(status, "health", "low_battery")
    with pytest.raises(FieldValueError, match="one of good, low_battery, abort"):
        commander.set_value(status, "health", "HEALTH_abort")
    assert [(p.var, p.value) for p in commander.preview(status).posts] == [
        ("VEHICLE_HEALTH", "health=low_battery")
    ]
    assert commander.preview(status).message.health == 1


def test_import_errors_name_the_file(tmp_path):
    commands = CommandSet.from_messages(message_set("mm1"))
    with pytest.raises(ConfigError, match="SIMPLE_STATUS is defined in .*simple_status.xml too"):
        commands.import_xml(str(EXAMPLES / "xml" / "simple_status.xml"))
    bad = tmp_path / "bad.xml"
    bad.write_text(EXAMPLE1.read_text().replace("<max>3</max>", "<max>fast</max>"))
    with pytest.raises(ConfigError, match=rf"{bad}:\d+: <max> must be a number"):
        commands.import_xml(str(bad))
    assert len(commands) == 1 and len(commands.messages.cfg.transitional_cfg.message_file) == 1
    assert commands.import_xml(str(EXAMPLE1)) == ["GoToCommand", "VehicleStatus"]  # still possible


def test_save_and_load_round_trip(commands, tmp_path):
    commander = make(commands, [])
    draft = commander.open("SIMPLE_STATUS")
    for name, value in STATUS.items():
        commander.set_value(draft, name, value)
    commander.save(tmp_path / "saved.txt")
    lines = (tmp_path / "saved.txt").read_text().splitlines()
    assert lines[1:] == [
        "message::SIMPLE_STATUS",
        "NAV_DEPTH:=Depth=12.5 NAV_HEADING:=Heading=90.25 "
        "NAV_SPEED:=Speed=1.5 NAV_X:=nav_x=250 NAV_Y:=nav_y=-40 VEHICLE_NAME:=Node=1",
    ]
    other = make(commands, [])
    assert other.load(tmp_path / "saved.txt") == []
    assert other.open("SIMPLE_STATUS").values == STATUS


ICOMMANDER_11 = """
ProcessConfig = iCommander
{
  common { log: false }
  dccl_cfg
  {
    modem_id: 1
    message_file { path: "../../xml/simple_status.xml" }
    message_file { path: "../../xml/example1.xml" }
  }
}
"""


def test_icommander_block_in_goby11_form(tmp_path):
    """Goby 1.1's iCommander block names its XML files itself (dccl_cfg): the ones pAcommsHandler
    loads are not loaded twice; without a pAcommsHandler block they are all there is."""
    from pygoby.apps.icommander import iCommander

    root = tmp_path / "goby1.1"
    shutil.copytree(EXAMPLES, root)
    mission = root / "MOOS" / "ccl_and_dccl" / "mm1.moos"
    mission.write_text(mission.read_text() + ICOMMANDER_11)
    app = iCommander.from_mission(mission, "iCommander")
    assert sorted(app.commander.commands.types) == ["GoToCommand", "SIMPLE_STATUS", "VehicleStatus"]
    assert any("transitional_cfg.message_file" in note for note in app.config_notes)
    alone = root / "MOOS" / "ccl_and_dccl" / "alone.moos"
    alone.write_text("LatOrigin = 42.35\nLongOrigin = -70.95\n" + ICOMMANDER_11)
    app = iCommander.from_mission(alone, "iCommander")
    assert sorted(app.commander.commands.types) == ["GoToCommand", "SIMPLE_STATUS", "VehicleStatus"]


def test_an_xml_file_found_nowhere_is_located_like_load_proto_file(tmp_path, monkeypatch):
    """A misspelled message_file names the mission line and the folders searched, in
    pAcommsHandler's block (read by pAcommsHandler and iCommander) and in iCommander's own."""
    from pygoby.apps.icommander import iCommander
    from pygoby.apps.pacommshandler import pAcommsHandler

    root = tmp_path / "goby1.1"
    shutil.copytree(EXAMPLES, root)
    mission = root / "MOOS" / "ccl_and_dccl" / "mm1.moos"
    text = mission.read_text().replace("simple_status.xml", "simple_stats.xml")
    mission.write_text(text + "\nProcessConfig = iCommander\n{\n  common { log: false }\n}\n")
    line = text.splitlines().index('    message_file { path: "../../xml/simple_stats.xml" }') + 1
    monkeypatch.chdir(tmp_path)
    searched = f"searched: {tmp_path}, {mission.parent}"
    expected = (
        f'{mission}:{line}: message_file.path: "../../xml/simple_stats.xml" not found; {searched}'
    )
    for app in (pAcommsHandler, iCommander):
        with pytest.raises(ConfigError) as caught:
            app.from_mission(mission, app.default_name)
        assert str(caught.value) == expected
    mission.write_text(
        text.replace("simple_stats.xml", "simple_status.xml")
        + ICOMMANDER_11.replace("example1.xml", "exampel1.xml")
    )
    line = (
        mission.read_text()
        .splitlines()
        .index('    message_file { path: "../../xml/exampel1.xml" }')
        + 1
    )
    with pytest.raises(ConfigError) as caught:
        iCommander.from_mission(mission, "iCommander")
    assert (
        str(caught.value)
        == f'{mission}:{line}: message_file.path: "../../xml/exampel1.xml" not found; {searched}'
    )
