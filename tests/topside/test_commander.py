"""The commander core without MOOS: fields and their limits, specials, the posts of both send
styles, ack/expire matching, save files (with fuzzing of the parsers)."""

from __future__ import annotations

import contextlib

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import serialize_for_moos
from pygoby.moosacomms.acomms_config import read_acomms_config
from pygoby.topside.commander import (
    MULTIPLEX,
    Commander,
    CommanderError,
    CommandSet,
    FieldValueError,
    SaveFileError,
    SpecialError,
    savefile,
    specials,
)
from tests.apps.acomms_mission import PROTO

MISSION = f"""\
LatOrigin = 42.358
LongOrigin = -71.087
ProcessConfig = pAcommsHandler
{{
  modem_id: 1
  load_proto_file: "{PROTO}"
  multiplex_create_moos_var: "LIAISON_COMMANDER_OUT"
  queue_cfg {{ message_entry {{ protobuf_name: "pygoby.examples.Command" ack: true
                               role {{ type: DESTINATION_ID field: "dest" }} }} }}
  translator_entry {{
    protobuf_name: "pygoby.examples.Command"
    trigger {{ type: TRIGGER_PUBLISH moos_var: "COMMAND_OUT" }}
    create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "COMMAND_OUT" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "DB_TIME" format: "%1%" }}
  }}
  translator_entry {{
    protobuf_name: "pygoby.examples.SimpleStatus"
    trigger {{ type: TRIGGER_PUBLISH moos_var: "SEND_STATUS" mandatory_content: "go" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "REPORT_X" format: "%10%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "REPORT_Y" format: "%11%" }}
  }}
}}
"""


@pytest.fixture
def commands(tmp_path) -> CommandSet:
    path = tmp_path / "m.moos"
    path.write_text(MISSION)
    mission = MissionFile.read(path)
    return CommandSet.from_pacommshandler(read_acomms_config(mission))


def make(commands, posts, **kwargs) -> Commander:
    return Commander(
        commands,
        community="topside",
        now=lambda: 1700000000.25,
        publish=posts.append,
        autosave_path=None,
        **kwargs,
    )


def test_fields_sources_and_limits(commands):
    command = commands.find("Command")
    assert command.trigger_var == "COMMAND_OUT" and command.ack and command.dest_field == "dest"
    time, src, dest = command.field("time"), command.field("src"), command.field("dest")
    assert (time.editable, time.automatic_from) == (False, "DB_TIME")  # set by the later create
    assert (src.editable, src.source) == (True, "COMMAND_OUT")
    assert dest.describe() == "(int) min: 0, max: 31"
    heading = command.field("heading")
    heading.check("359")
    for bad, reason in [
        ("361", "above the maximum 360"),
        ("-1", "below the minimum 0"),
        ("1.5", "at most 0 decimals"),
        ("x", "not a number"),
        ("nan", "finite"),
    ]:
        with pytest.raises(FieldValueError, match=reason):
            heading.check(bad)
    heading.check("3", partial=True)
    heading.check("_y:", partial=True)  # a placeholder being typed
    with pytest.raises(FieldValueError, match="minimum"):
        heading.check("-", partial=True)  # min 0: no minus sign
    with pytest.raises(FieldValueError):
        time.check("1")  # automatic: the operator cannot set it


def test_key_value_send_posts_and_preview_publishes_nothing(commands):
    posts = []
    commander = make(commands, posts)
    draft = commander.open("pygoby.examples.Command")
    for name, value in {
        "src": "1",
        "dest": "2",
        "command_id": "7",
        "heading": "90",
        "speed": "1.5",
    }.items():
        commander.set_value(draft, name, value)
    preview = commander.preview(draft)
    assert posts == []
    assert [(p.var, p.value) for p in preview.posts] == [
        ("COMMAND_OUT", "src=1,dest=2,command_id=7,heading=90,speed=1.5")
    ]
    assert preview.warnings == ["depth: not set"]
    record = commander.send(draft)
    assert posts == preview.posts and record.status == "awaiting ack"


def test_trigger_without_create_and_mandatory_content(commands):
    posts = []
    commander = make(commands, posts)
    draft = commander.open("SimpleStatus")
    assert commands.find("SimpleStatus").operator_vars == ("REPORT_X", "REPORT_Y")
    commander.set_value(draft, "nav_x", "100")
    commander.set_value(draft, "nav_y", "-50")
    commander.send(draft)
    # every source variable in sorted order, the trigger (with its mandatory content) last
    assert [(p.var, p.value) for p in posts] == [
        ("REPORT_X", 100.0),
        ("REPORT_Y", -50.0),
        ("SEND_STATUS", "go"),
    ]


def test_multiplex_style_posts_one_prefixed_text(commands, tmp_path):
    posts = []
    commander = make(commands, posts, style=MULTIPLEX)
    draft = commander.open("Command")
    commander.set_value(draft, "dest", "2")
    commander.set_value(draft, "heading", "45")
    commander.send(draft)
    assert [(p.var, p.value) for p in posts] == [
        ("LIAISON_COMMANDER_OUT", "@PB[pygoby.examples.Command] dest: 2 heading: 45 ")
    ]
    no_multiplex = CommandSet(commands.translator, {})
    with pytest.raises(CommanderError, match="multiplex_create_moos_var"):
        Commander(no_multiplex, style=MULTIPLEX)


def test_specials_time_xy_community_modem_id(commands):
    assert specials.lat_lon_pairs(["depth", "lat", "lon", "lon2", "y_lat2"]) == [(1, 2), (4, 3)]
    to_geo = commands.geodesy.to_geo
    out = specials.substitute(
        ["_time", "_y:300", "7", "_x:100", "y(lat)2:0", "x(lon)2:0"], 12.5, to_geo
    )
    lat, lon = to_geo(100, 300)
    assert out[:4] == ["12.5", repr(lat), "7", repr(lon)]
    assert [float(v) for v in out[4:]] == pytest.approx([42.358, -71.087])
    with pytest.raises(SpecialError):
        specials.substitute(["_y:1"], 0, to_geo)
    with pytest.raises(SpecialError):
        specials.substitute(["y(lat)1:5", "x(lon)2:5"], 0, to_geo)
    posts = []
    commander = make(commands, posts)
    draft = commander.open("Command")
    commander.insert_time(draft, "heading")  # a placeholder is accepted as typed ...
    assert draft.values["heading"] == "_time"
    out = commander.preview(draft)  # ... and checked once replaced: the time is above 360
    assert any("above the maximum 360" in w for w in out.warnings)
    commander.insert_modem_id(draft, "dest", 2)
    assert draft.values["dest"] == "2"
    with pytest.raises(FieldValueError, match="latitude/longitude"):
        commander.insert_xy(draft, "dest")


def test_ack_and_expire_match_what_was_sent(commands):
    posts = []
    commander = make(commands, posts)
    draft = commander.open("Command")
    for name, value in {"dest": "2", "command_id": "7", "speed": "1.5"}.items():
        commander.set_value(draft, name, value)
    first = commander.send(draft)
    commander.set_value(draft, "command_id", "8")
    second = commander.send(draft)
    original = commands.resolve("pygoby.examples.Command")(
        time=5, src=1, dest=2, command_id=8, speed=1.5
    )
    [notice] = commander.handle_mail("ACOMMS_EXPIRE", serialize_for_moos(original), 20.0)
    assert (notice.kind, notice.record, notice.dest) == ("expired", second, "2")
    assert "Message expired from queue: Command" in notice.banner()
    original.command_id = 7
    [notice] = commander.handle_mail("ACOMMS_ACK_ORIGINAL", serialize_for_moos(original), 21.0)
    assert notice.record is first and first.status == "acknowledged" and second.status == "expired"
    assert commander.handle_mail("ACOMMS_ACK_ORIGINAL", "garbage") == []
    assert commander.handle_mail("OTHER", serialize_for_moos(original)) == []


def test_save_file_round_trip_with_commas(commands, tmp_path):
    commander = make(commands, [])
    draft = commander.open("Command")
    commander.set_value(draft, "dest", "3")
    commander.set_value(draft, "heading", "_y:12")
    commander.save(tmp_path / "s.txt")
    other = make(commands, [])
    assert other.load(tmp_path / "s.txt") == []
    assert other.open("Command").values == {"dest": "3", "heading": "_y:12"}
    text = savefile.dump([("Msg", [("V", "name", "a,b=c"), ("V", "n2", "2"), ("W", "z", "")])], 0)
    assert text.splitlines()[1:] == ["message::Msg", "V:=name=a,b=c,n2=2 W:=z="]
    assert savefile.parse(text, {"Msg": ["name", "n2", "z"]}) == [
        ("Msg", {"name": "a,b=c", "n2": "2", "z": ""})
    ]
    with pytest.raises(SaveFileError):
        savefile.parse("not a save file")
    (tmp_path / "bad.txt").write_text(
        f"{savefile.HEADER_PREFIX}x %%%\nmessage::Nope\nV:=a=1\n"
        "message::Command\nCOMMAND_OUT:=heading=999\n"
    )
    warnings = other.load(tmp_path / "bad.txt")
    assert warnings[0] == "Nope: not a message of this mission"
    assert "above the maximum 360" in warnings[1]
    # a Latin-1 save file (issue 16 item 10's class: bytes that are not UTF-8) loads
    (tmp_path / "latin1.txt").write_bytes(
        f"{savefile.HEADER_PREFIX}x caf\xe9\nmessage::Command\nCOMMAND_OUT:=dest=3\n".encode(
            "latin-1"
        )
    )
    assert other.load(tmp_path / "latin1.txt") == [] and other.open("Command").values["dest"] == "3"


@given(st.text(max_size=300))
def test_save_file_parser_never_fails_unexpectedly(text):
    try:
        savefile.parse(savefile.HEADER_PREFIX + text, {"Command": ["dest", "heading"]})
        savefile.parse(text)
    except SaveFileError:
        pass


@given(st.text(max_size=40), st.booleans())
def test_field_checks_only_raise_field_value_errors(text, partial):
    from pygoby.topside.commander.fields import FieldSpec

    for spec in (
        FieldSpec("f", 1, "float", "double", minimum=0, maximum=360, precision=1, source="V"),
        FieldSpec("i", 2, "int", "uint32", minimum=0, maximum=31, source="V"),
        FieldSpec("e", 3, "enum", "E", enum_values=("A", "B"), source="V"),
        FieldSpec("s", 4, "string", "string", max_length=5, source="V"),
        FieldSpec("b", 5, "bytes", "bytes", max_length=2, source="V"),
        FieldSpec("t", 6, "bool", "bool", source="V"),
        FieldSpec("r", 7, "int", "int32", repeated=True, max_repeat=3, source="V"),
    ):
        with contextlib.suppress(FieldValueError):
            spec.check(text, partial=partial)
