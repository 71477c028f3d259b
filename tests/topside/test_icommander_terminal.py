"""iCommander in an 80x24 terminal, as over ssh: textual's pilot presses keys, the screen's text
is read back. The documented configuration (`show_variable: ""`, `load: ""`) starts; Up/Down/Tab
move between fields of a message taller than the screen and the view follows; the status line
(acks, shown variables) is on every screen; keys typed faster than the app redraws all arrive."""

from __future__ import annotations

import pytest
from textual import events

from pygoby.apps.icommander import iCommander
from pygoby.moos.moosfile import MissionFile
from pygoby.moosacomms.acomms_config import read_acomms_config
from pygoby.topside.commander import Commander, CommandSet, Notice
from pygoby.topside.icommander import ICommanderTUI

from .test_commander import MISSION

SIZE = (80, 24)
FIELDS = ["src", "dest", "command_id", "heading", "speed", "depth"]  # `time` comes from DB_TIME


@pytest.fixture
def commander(tmp_path) -> Commander:
    path = tmp_path / "m.moos"
    path.write_text(MISSION)
    commands = CommandSet.from_pacommshandler(read_acomms_config(MissionFile.read(path)))
    return Commander(commands, community="topside", now=lambda: 1e9, autosave_path=None)


def test_empty_show_variable_and_load_mean_none(tmp_path):
    path = tmp_path / "m.moos"
    path.write_text(
        MISSION
        + """
ProcessConfig = iCommander
{
  common { log: false }
  show_variable: ""
  load: ""
  commander { load: "" }
}
"""
    )
    app = iCommander.from_mission(path, "iCommander")  # was ValueError / IsADirectoryError
    assert app.tui.show_variables == {} and app.load_warnings == []


def test_a_missing_save_file_is_a_configuration_error(tmp_path):
    from pygoby.errors import ConfigError

    path = tmp_path / "m.moos"
    path.write_text(MISSION + '\nProcessConfig = iCommander\n{\n  load: "nowhere.txt"\n}\n')
    with pytest.raises(ConfigError, match=r"m.moos:\d+: load: cannot open the save file"):
        iCommander.from_mission(path, "iCommander")


def screen_text(app) -> str:
    """What the terminal shows (every line of the current screen, composited)."""
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


async def open_command(pilot) -> None:
    names = list(pilot.app.commander.commands.types)
    await pilot.press("enter", *["down"] * names.index("pygoby.examples.Command"), "enter")
    await pilot.pause()
    assert pilot.app.screen.id == "edit"


def focused_field(app) -> str:
    return (app.focused.id or "").removeprefix("field-")


def in_view(app, widget) -> bool:
    region = widget.region
    return region.height > 0 and region.y >= 0 and region.bottom <= app.size.height


@pytest.mark.timeout(60)
async def test_up_down_and_tab_move_between_fields_and_the_view_follows(commander):
    app = ICommanderTUI(commander)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        await open_command(pilot)
        assert focused_field(app) == "src"
        seen = []
        for name, text in zip(FIELDS, ["1", "2", "7", "90", "1.5", "20"], strict=True):
            assert focused_field(app) == name
            assert in_view(app, app.focused), f"{name} is out of view"
            for char in text:
                await pilot.press(char)
            seen.append(name)
            await pilot.press("down")
            await pilot.pause()
        draft = app.screen.draft
        # leaving a field commits it: every value is in its own field
        assert {n: draft.value(n) for n in FIELDS} == dict(
            zip(FIELDS, ["1", "2", "7", "90", "1.5", "20"], strict=True)
        )
        assert app.screen.query_one("#field-depth").region.y > 0
        assert focused_field(app) == "src" and in_view(app, app.focused)  # Down wraps round
        await pilot.press("up", "up")
        assert focused_field(app) == "speed" and in_view(app, app.focused)
        await pilot.press("tab")
        assert focused_field(app) == "depth"
        await pilot.press(*["shift+tab"] * 3)
        assert focused_field(app) == "command_id" and in_view(app, app.focused)
        text = screen_text(app)
        assert "Up/Down/Tab: fields  Enter: options  specials: m modem id" in text
        # `t` is no special in an integer field that holds no time: refused, with the reason
        await pilot.press("t")
        assert app.screen.query_one("#field-command_id").value == "7"
        assert "refused" in screen_text(app)


@pytest.mark.timeout(60)
async def test_the_status_line_is_on_every_screen(commander):
    app = ICommanderTUI(commander, ["DESIRED_HEADING", ""])
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        app.show_variable("DESIRED_HEADING", 90.0)
        notice = Notice("acknowledged", "pygoby.examples.Command", "2", 1e9, "dest=2", None)
        app.show_notice(notice)
        await pilot.pause()
        assert app.screen.id == "main-menu"
        for step in ("enter", "escape", "down"):  # main menu, message list, main menu
            text = screen_text(app)
            assert "Message acknowledged from queue: Command for destination: 2" in text
            assert "DESIRED_HEADING: 90" in text
            await pilot.press(step)
            await pilot.pause()
        await pilot.press("up")
        await open_command(pilot)
        await pilot.press("enter")  # the action menu
        await pilot.pause()
        assert app.screen.id == "actions"
        app.show_variable("DESIRED_HEADING", 45.0)
        await pilot.pause()
        assert "DESIRED_HEADING: 45" in screen_text(app)


@pytest.mark.timeout(60)
async def test_keys_typed_faster_than_the_app_redraws_all_arrive(commander):
    app = ICommanderTUI(commander)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        names = list(commander.commands.types)
        keys = ["enter", *["down"] * names.index("pygoby.examples.Command"), "enter"]
        keys += ["1", "down", "2", "down", "3", "down", "4", "5", "down", "1"]
        keys += ["enter", "down", "down", "enter"]  # the action menu: Return, Send, [Preview]
        for key in keys:  # all at once, as a terminal's input arrives: no waiting in between
            char = key if len(key) == 1 else None
            app.post_message(events.Key(key, char))
        for _ in range(50):
            await pilot.pause(0.05)
            if app.screen.id == "preview":
                break
        assert app.screen.id == "preview"
        report = str(app.screen.query_one("#report-text").render())
        assert "src=1,dest=2,command_id=3,heading=45,speed=1" in report
