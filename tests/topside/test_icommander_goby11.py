"""iCommander headless on seed 003's ccl_and_dccl example (examples/goby1.1, run under `pygoby
antler` as tests/goby11 runs it: two communities, pAcommsHandler, iModemSim): textual's pilot
presses real keys to compose SIMPLE_STATUS (simple_status.xml), and mm2 decodes what mm1's
pAcommsHandler made of the posts."""

from __future__ import annotations

import asyncio

import pytest

from pygoby.apps.icommander import iCommander
from tests.goby11.test_examples import EXAMPLES, localize, run_pair, wait_for

from .test_icommander import type_text

pytestmark = pytest.mark.e2e

ICOMMANDER = """
ProcessConfig = iCommander
{
  common { log: false  app_tick: 20 }
  commander { autosave_path: "%s" }
}
"""


def report_fields(value: str) -> dict[str, str]:
    return dict(item.split("=", 1) for item in value.split(","))


async def press(pilot, *keys: str) -> None:
    await pilot.press(*keys)
    await pilot.pause()


@pytest.mark.timeout(180)
async def test_compose_simple_status_and_mm2_decodes_it(tmp_path):
    directory, ports = localize(tmp_path, "ccl_and_dccl")
    mission = directory / "mm1.moos"
    mission.write_text(mission.read_text() + ICOMMANDER % (tmp_path / "autosave.txt"))

    async def check():
        # the pair runs: mm2 hears mm1's SIMPLE_STATUS made from the initializers' NAV_*
        await wait_for(ports["mm2"], "STATUS_REPORT_IN", lambda v: "nav_x=100" in str(v))
        app = iCommander.from_mission(mission, "iCommander")
        async with app, app.tui.run_test(size=(110, 50)) as pilot:
            await pilot.pause()
            assert "1 messages loaded." in str(app.tui.screen.query_one(".title").render())
            await press(pilot, "enter")  # Select Message
            assert app.tui.screen.id == "select-message"
            await press(pilot, "enter")  # SIMPLE_STATUS
            edit = app.tui.screen
            assert edit.id == "edit" and edit.query_one("#field-MessageType").disabled
            assert edit.query_one("#field-MessageType").value == "LAMSS_STATUS"

            # Out of range: the key that makes Speed 25 is refused, the bound shown.
            edit.query_one("#field-Speed").focus()
            await type_text(pilot, "25")
            assert edit.query_one("#field-Speed").value == "2"
            assert "above the maximum 20" in str(edit.query_one("#info").render())
            await press(pilot, "backspace")
            for name, text in {
                "Speed": "1.5",
                "Node": "1",
                "nav_x": "250",
                "nav_y": "-40",
                "Heading": "90.25",
                "Depth": "12.5",
            }.items():
                edit.query_one(f"#field-{name}").focus()
                await pilot.pause()
                await type_text(pilot, text)
            # nav_x's source is NAV_X, not a trigger variable: editable, as in Goby 1.1
            assert edit.query_one("#field-nav_x").value == "250"

            # Preview: Goby 1.1's posts, a name=value string per source variable (a number where
            # the variable holds doubles: the MOOSDB refuses text there); nothing goes.
            await press(pilot, "enter")
            assert app.tui.screen.id == "actions"
            await press(pilot, "down", "down", "enter")  # Return, Send, [Preview]
            assert app.tui.screen.id == "preview"
            report = str(app.tui.screen.query_one("#report-text").render()).splitlines()
            assert report[1:] == [
                "NAV_DEPTH: 12.5",
                "NAV_HEADING: 90.25",
                "NAV_SPEED: 1.5",
                "NAV_X: 250.0",
                "NAV_Y: -40.0",
                "VEHICLE_NAME: Node=1",
            ]
            await asyncio.sleep(0.5)
            for var, value in (("NAV_X", 100.0), ("NAV_SPEED", 0.0), ("VEHICLE_NAME", "mm1")):
                assert (
                    await wait_for(ports["mm1"], var, lambda v: True) == value
                )  # the initializers'

            # Send (from the preview); mm1's pAcommsHandler makes SIMPLE_STATUS of the posts
            # (Goby 1.1's name=value rule) and mm2 decodes it.
            await press(pilot, "down", "enter")
            assert app.tui.screen.id == "sent"
            await wait_for(ports["mm1"], "VEHICLE_NAME", lambda v: v == "Node=1", timeout=20)
            status = await wait_for(
                ports["mm2"], "STATUS_REPORT_IN", lambda v: "nav_x=250" in str(v)
            )
            fields = report_fields(status)
            assert {
                k: fields[k]
                for k in ("Node", "MessageType", "nav_x", "nav_y", "Speed", "Heading", "Depth")
            } == {
                "Node": "1",
                "MessageType": "LAMSS_STATUS",
                "nav_x": "250",
                "nav_y": "-40",
                "Speed": "1.5",
                "Heading": "90.25",
                "Depth": "12.5",
            }
            assert (tmp_path / "autosave.txt").read_text().splitlines()[
                1
            ] == "message::SIMPLE_STATUS"

            # Import Message File: example1.xml's two messages join the list.
            await press(pilot, "down", "enter")  # Main menu
            assert app.tui.screen.id == "main-menu"
            await press(
                pilot, "down", "down", "down", "down", "enter"
            )  # Return, Select, Load, Save, [Import]
            assert app.tui.screen.id == "import-file"
            await type_text(pilot, str(EXAMPLES / "xml" / "example1.xml"))
            await press(pilot, "enter")
            assert "GoToCommand, VehicleStatus" in str(
                app.tui.screen.query_one("#report-text").render()
            )
            await press(pilot, "enter")
            assert "3 messages loaded." in str(app.tui.screen.query_one(".title").render())

    await run_pair(directory, ports, check)
