"""What liaison's pages show, from MOOS mail (the models without a browser)."""

from __future__ import annotations

from .liaison_server import Served


def test_the_acomms_page_shows_the_drivers_state(tmp_path):
    s = Served(tmp_path)
    s.web._socket.close()
    s.mail(
        "ACOMMS_DRIVER_STATUS",
        "primary driver WHOI_MICROMODEM::1: failed (1x): STARTUP_FAILED: could not open port "
        "/dev/ttyUSB7; next attempt in 60 s",
    )
    page = s.state.page("acomms", s.clock)
    assert page["drivers"] == [
        "primary driver WHOI_MICROMODEM::1: failed (1x): STARTUP_FAILED: could not open port "
        "/dev/ttyUSB7; next attempt in 60 s"
    ]
    s.mail("ACOMMS_DRIVER_STATUS", "primary driver WHOI_MICROMODEM::1: running")
    assert s.state.page("acomms", s.clock)["drivers"] == [
        "primary driver WHOI_MICROMODEM::1: running"
    ]


async def test_liaison_starts_with_the_defaults_without_its_block(tmp_path, capsys):
    """`pygoby liaison mission.moos` on a mission with no `ProcessConfig = liaison` block
    serves with the defaults and says so once (it refused to start)."""
    from pygoby.moos.db import MOOSDB
    from pygoby.topside.liaison import Liaison

    from .test_commander import MISSION

    async with MOOSDB(port=0, community="topside") as db:
        path = tmp_path / "m.moos"
        path.write_text(f"ServerPort = {db.port}\nCommunity = topside\n{MISSION}")
        app = Liaison.from_mission(path, "liaison", overrides=[("liaison", "http_port: 0")])
        async with app:
            assert app.web.port != 54321 and app.state.commander.commands.types
        out = capsys.readouterr()
        said = [x for x in (out.out + out.err).splitlines() if "serving with the defaults" in x]
        assert len(said) == 1 and f"no ProcessConfig = liaison block in {path}" in said[0]
