"""Sub-message fields in the commander core and iCommander: a singular sub-message's fields are
composed one by one (`target.x`), a repeated one's with one value per element (`track.x`), sent
with either style, read back by pAcommsHandler's own translator, matched in acks, saved and
loaded; recursive ones stay one field that says why it cannot be composed."""

from __future__ import annotations

import pytest

from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import serialize_for_moos
from pygoby.moosacomms.acomms_config import AcommsMessageSet, read_acomms_config
from pygoby.topside.commander import MULTIPLEX, Commander, CommandSet, FieldValueError
from pygoby.topside.icommander import ICommanderTUI

PROTO = """\
syntax = "proto2";
import "dccl/option_extensions.proto";
package pygoby.test;

message Waypoint
{
    required double x = 1 [(dccl.field) = { min: -1000 max: 1000 precision: 1 }];
    optional double y = 2 [(dccl.field) = { min: -1000 max: 1000 precision: 1 }];
}
message Tree
{
    optional int32 v = 1 [(dccl.field) = { min: 0 max: 7 }];
    optional Tree child = 2;
}
message Goto
{
    option (dccl.msg) = { id: 30 max_bytes: 64 codec_version: 3 };
    required int32 dest = 1 [(dccl.field) = { min: 0 max: 31 in_head: true }];
    required Waypoint target = 2;
    optional Waypoint via = 3;
    repeated Waypoint track = 4 [(dccl.field).max_repeat = 3];
    optional Tree tree = 5;
}
"""

MISSION = """\
LatOrigin = 42.358
LongOrigin = -71.087
ProcessConfig = pAcommsHandler
{{
  modem_id: 1
  load_proto_file: "{proto}"
  multiplex_create_moos_var: "LIAISON_COMMANDER_OUT"
  queue_cfg {{ message_entry {{ protobuf_name: "pygoby.test.Goto" ack: true
                               role {{ type: DESTINATION_ID field: "dest" }} }} }}
  translator_entry {{
    protobuf_name: "pygoby.test.Goto"
    trigger {{ type: TRIGGER_PUBLISH moos_var: "GOTO_OUT" }}
    create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "GOTO_OUT" }}
  }}
}}
"""


@pytest.fixture
def commands(tmp_path) -> CommandSet:
    (tmp_path / "goto.proto").write_text(PROTO)
    path = tmp_path / "m.moos"
    path.write_text(MISSION.format(proto=tmp_path / "goto.proto"))
    mission = MissionFile.read(path)
    return CommandSet.from_messages(
        AcommsMessageSet.load(read_acomms_config(mission), mission.find_file)
    )


def make(commands, posts, **kwargs) -> Commander:
    return Commander(
        commands, now=lambda: 100.0, publish=posts.append, autosave_path=None, **kwargs
    )


def test_sub_message_fields_are_composable(commands):
    goto = commands.find("Goto")
    assert [(f.name, f.kind, f.editable, f.required) for f in goto.fields] == [
        ("dest", "int", True, True),
        ("target.x", "float", True, True),
        ("target.y", "float", True, False),
        ("via.x", "float", True, False),
        ("via.y", "float", True, False),  # via is optional
        ("track.x", "float", True, False),
        ("track.y", "float", True, False),
        ("tree.v", "int", True, False),
        ("tree.child", "message", False, False),
    ]
    assert goto.field("target.x").describe() == "(float) min: -1000, max: 1000, precision: 1"
    assert goto.field("track.x").describe() == (
        "(float) min: -1000, max: 1000, precision: 1, up to 3 values separated by commas"
    )
    assert goto.field("tree.child").describe() == (
        "(pygoby.test.Tree) recursive or deeper sub-messages cannot be composed here"
    )
    with pytest.raises(FieldValueError, match="track.x: at most 3 values"):
        goto.field("track.x").check("1,2,3,4")
    with pytest.raises(FieldValueError, match="target.x: 1001 is above the maximum 1000"):
        goto.field("target.x").check("1001")


def test_send_both_styles_and_pacommshandler_reads_it_back(commands):
    posts = []
    commander = make(commands, posts)
    draft = commander.open("Goto")
    for name, value in {"dest": "2", "target.x": "1.5", "target.y": "-2"}.items():
        commander.set_value(draft, name, value)
    preview = commander.preview(draft)
    assert posts == [] and preview.warnings == []
    # goby's key=value technique flattens one level (sub-message field `target_x`)
    assert [(p.var, p.value) for p in preview.posts] == [
        ("GOTO_OUT", "dest=2,target_x=1.5,target_y=-2")
    ]
    assert not preview.message.HasField("via")  # untouched sub-messages stay unset
    record = commander.send(draft)
    created = commands.translator.create("pygoby.test.Goto", {p.var: p.value for p in posts})
    assert created == record.message
    multiplex = make(commands, posts, style=MULTIPLEX)
    out = multiplex.preview(multiplex.open("Goto"))
    assert out.warnings == ["dest: not set", "target.x: not set"]  # required all the way down
    draft = multiplex.open("Goto")
    multiplex.set_value(draft, "via.y", "7")
    multiplex.set_value(draft, "tree.v", "3")
    assert (
        multiplex.preview(draft).posts[0].value
        == "@PB[pygoby.test.Goto] via { y: 7 } tree { v: 3 } "
    )


def test_repeated_sub_message_one_value_per_element(commands):
    posts = []
    commander = make(commands, posts)
    draft = commander.open("Goto")
    for name, value in {"dest": "1", "target.x": "0", "track.x": "1,2,3", "track.y": "4,5"}.items():
        commander.set_value(draft, name, value)
    preview = commander.preview(draft)
    assert [(w.x, w.y if w.HasField("y") else None) for w in preview.message.track] == [
        (1, 4),
        (2, 5),
        (3, None),
    ]
    assert [(p.var, p.value) for p in preview.posts] == [
        ("GOTO_OUT", "dest=1,target_x=0,target_y=0,track_x={1,2,3},track_y={4,5,0}")
    ]
    record = commander.send(draft)
    assert (
        commands.translator.create("pygoby.test.Goto", {p.var: p.value for p in posts}).track[:2]
        == record.message.track[:2]
    )
    commander.set_value(draft, "track.x", "1")  # element 2 keeps a y, without its required x
    assert commander.preview(draft).warnings == ["track[1].x: not set"]


def test_acks_match_nested_values(commands):
    commander = make(commands, [])
    draft = commander.open("Goto")
    for name, value in {"dest": "2", "target.x": "1.5", "via.x": "10"}.items():
        commander.set_value(draft, name, value)
    record = commander.send(draft)
    original = commands.resolve("pygoby.test.Goto")(dest=2)
    original.target.x, original.via.x = 1.5, 11
    assert (
        commander.handle_mail("ACOMMS_ACK_ORIGINAL", serialize_for_moos(original), 1.0)[0].record
        is None
    )
    original.via.x = 10
    assert (
        commander.handle_mail("ACOMMS_ACK_ORIGINAL", serialize_for_moos(original), 2.0)[0].record
        is record
    )


def test_save_and_load_nested_names(commands, tmp_path):
    commander = make(commands, [])
    draft = commander.open("Goto")
    commander.set_value(draft, "target.x", "_y:5")
    commander.set_value(draft, "via.y", "3")
    commander.save(tmp_path / "s.txt")
    assert (
        "GOTO_OUT:=dest=,target.x=_y:5,target.y=,via.x=,via.y=3,track.x=,track.y=,tree.v="
        in (tmp_path / "s.txt").read_text()
    )
    other = make(commands, [])
    assert other.load(tmp_path / "s.txt") == []
    assert other.open("Goto").values == {"target.x": "_y:5", "via.y": "3"}


async def test_icommander_edits_sub_message_fields(commands):
    posts = []
    tui = ICommanderTUI(make(commands, posts))
    async with tui.run_test(size=(110, 50)) as pilot:
        await pilot.pause()
        await pilot.press("enter")  # Select Message
        await pilot.pause()
        await pilot.press("enter")  # Goto
        await pilot.pause()
        edit = tui.screen
        assert edit.id == "edit" and edit.query_one("#field-tree--child").disabled
        edit.query_one("#field-target--x").focus()
        await pilot.pause()
        for key in "1001":
            await pilot.press(key)
        assert edit.query_one("#field-target--x").value == "100"  # the last 1 is refused
        assert "above the maximum 1000" in str(edit.query_one("#info").render())
        edit.query_one("#field-dest").focus()  # leaving the field commits it
        await pilot.pause()
        assert tui.commander.drafts["pygoby.test.Goto"].values == {"target.x": "100"}
