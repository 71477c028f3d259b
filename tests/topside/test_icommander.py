"""iCommander headless: textual's test pilot presses real keys; the app talks to real embedded
MOOSDBs, and to pAcommsHandlers with emulated Micro-Modems for the ack."""

from __future__ import annotations

import asyncio

import pytest

from pygoby.apps.icommander import iCommander
from pygoby.moos.db import MOOSDB
from tests.apps.acomms_mission import Recorder, TwoCommunities

from .mission import topside_mission

pytestmark = pytest.mark.e2e

ICOMMANDER = """
ProcessConfig = iCommander
{
  common { log: false  app_tick: 20 }
  commander { autosave_path: "%s" }
  show_variable: "DESIRED_HEADING"
}
"""


async def type_text(pilot, text: str) -> None:
    for char in text:
        await pilot.press(char)


async def open_command(pilot) -> None:
    """Main menu -> Select Message -> Command."""
    await pilot.press("enter")  # Select Message (the first entry: no active message yet)
    await pilot.pause()
    assert pilot.app.screen.id == "select-message"
    names = list(pilot.app.commander.commands.types)
    await pilot.press(*["down"] * names.index("pygoby.examples.Command"), "enter")
    await pilot.pause()
    assert pilot.app.screen.id == "edit"


async def fill(pilot, values: dict[str, str]) -> None:
    for name, text in values.items():
        pilot.app.screen.query_one(f"#field-{name}").focus()
        await pilot.pause()
        await type_text(pilot, text)
    pilot.app.screen.query_one("#field-dest").focus()  # leaving a field commits it
    await pilot.pause()


@pytest.mark.timeout(120)
async def test_send_refusal_preview_and_ack(tmp_path):
    # in real time: textual's pilot waits for the screen after each key, and the three apps
    # ticking MOOSTimeWarp times as often in its event loop slow it more than they save
    async with TwoCommunities(tmp_path, warp=1) as net:
        (r1, r2) = net.recorders
        await net.ready()
        r1.client.subscribe("COMMAND_OUT")
        await r1.client.flush()
        path = topside_mission(net, tmp_path, ICOMMANDER % (tmp_path / "autosave.txt"))
        app = iCommander.from_mission(path, "iCommander")
        async with app, app.tui.run_test(size=(110, 45)) as pilot:
            await pilot.pause()
            assert app.tui.screen.id == "main-menu"
            await open_command(pilot)
            edit = app.tui.screen
            # Out of range: the key that makes heading 400 is refused, with the bound shown.
            edit.query_one("#field-heading").focus()
            await type_text(pilot, "400")
            assert edit.query_one("#field-heading").value == "40"
            assert "above the maximum 360" in str(edit.query_one("#info").render())
            await pilot.press("backspace", "backspace")
            await fill(
                pilot,
                {"heading": "90", "dest": "2", "command_id": "7", "speed": "1.5", "depth": "20"},
            )
            assert edit.query_one("#field-speed").value == "1.5"
            assert edit.query_one(
                "#field-time"
            ).disabled  # automatic: pAcommsHandler fills it from DB_TIME

            # Preview: the exact post is shown, nothing is published.
            edit.query_one("#field-depth").focus()
            await pilot.press("enter")
            await pilot.pause()
            assert app.tui.screen.id == "actions"
            await pilot.press("down", "down", "enter")  # Return, Send, [Preview]
            await pilot.pause()
            assert app.tui.screen.id == "preview"
            report = str(app.tui.screen.query_one("#report-text").render())
            assert "COMMAND_OUT: dest=2,command_id=7,heading=90,speed=1.5,depth=20" in report
            await asyncio.sleep(0.5)
            assert "COMMAND_OUT" not in r1.seen

            # Send (from the preview), the command arrives, the ack banner shows.
            await pilot.press("down", "enter")
            await pilot.pause()
            assert app.tui.screen.id == "sent"
            assert await r2.wait_for("DESIRED_HEADING", timeout=30) == 90.0
            assert r1.values("COMMAND_OUT") == ["dest=2,command_id=7,heading=90,speed=1.5,depth=20"]
            async with asyncio.timeout(30):
                while "acknowledged" not in str(app.tui.screen.query_one("#status").render()):
                    await pilot.pause(0.1)
            banner = str(app.tui.screen.query_one("#status").render())
            assert "Message acknowledged from queue: Command" in banner
            assert "for destination: 2" in banner
            assert app.commander.records[0].status == "acknowledged"
            autosaved = (tmp_path / "autosave.txt").read_text().splitlines()
            assert autosaved[1:] == [
                "message::Command",
                "COMMAND_OUT:=dest=2,command_id=7,heading=90,speed=1.5,depth=20",
            ]


SAVE_MISSION = """\
ServerPort = {port}
Community = topside
LatOrigin = 42.358
LongOrigin = -71.087

ProcessConfig = pAcommsHandler
{{
  modem_id: 1
  load_proto_file: "{proto}"
  queue_cfg {{ message_entry {{ protobuf_name: "pygoby.examples.Command" ack: true }} }}
  translator_entry {{
    protobuf_name: "pygoby.examples.Command"
    trigger {{ type: TRIGGER_PUBLISH moos_var: "COMMAND_OUT" }}
    create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "COMMAND_OUT" }}
  }}
}}

ProcessConfig = iCommander
{{
  common {{ log: false }}
  commander {{ autosave_path: "" }}
}}
"""


@pytest.mark.timeout(60)
async def test_save_and_load_round_trip_and_time_special(tmp_path):
    from tests.apps.acomms_mission import PROTO

    async with MOOSDB(port=0, community="topside") as db:
        path = tmp_path / "topside.moos"
        path.write_text(SAVE_MISSION.format(port=db.port, proto=PROTO))
        recorder = Recorder("recorder", db.port)
        await recorder.start(["COMMAND_OUT"])
        app = iCommander.from_mission(path)
        saved = tmp_path / "saved.txt"
        async with app, app.tui.run_test(size=(110, 45)) as pilot:
            await pilot.pause()
            await open_command(pilot)
            await fill(pilot, {"dest": "2", "heading": "180", "speed": "2.5"})
            app.tui.screen.query_one("#field-time").focus()
            await pilot.press("t")  # shortcut: the current-time special
            await pilot.pause()
            assert app.tui.screen.query_one("#field-time").value == "_time"
            await pilot.press("enter")
            await pilot.pause()
            await pilot.press(*["down"] * 9, "enter")  # Main Menu
            await pilot.pause()
            assert app.tui.screen.id == "main-menu"
            await pilot.press("down", "down", "down", "enter")  # Return, Select, Load, [Save]
            await pilot.pause()
            assert app.tui.screen.id == "save-file"
            await type_text(pilot, str(saved))
            await pilot.press("enter", "enter")
            await pilot.pause()
            lines = saved.read_text().splitlines()
            assert lines[0].startswith("%%% iCommander message save file: ") and lines[0].endswith(
                " %%%"
            )
            assert lines[1:] == [
                "message::Command",
                "COMMAND_OUT:=time=_time,src=,dest=2,command_id=,heading=180,speed=2.5,depth=",
            ]
            assert "COMMAND_OUT" not in recorder.seen  # saving publishes nothing

        # A new iCommander loads the file at start-up (`load:`) with the same values.
        loaded = iCommander.from_mission(path, overrides=[("load", str(saved))])
        draft = loaded.commander.open("Command")
        assert draft.values == {"time": "_time", "dest": "2", "heading": "180", "speed": "2.5"}
        await recorder.close()
