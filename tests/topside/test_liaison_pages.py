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
        overrides = [("liaison", "http_port: 0"), ("common", "log: false")]
        app = Liaison.from_mission(path, "liaison", overrides=overrides)
        async with app:
            assert app.web.port != 54321 and app.state.commander.commands.types
        out = capsys.readouterr()
        said = [x for x in (out.out + out.err).splitlines() if "serving with the defaults" in x]
        assert len(said) == 1 and f"no ProcessConfig = liaison block in {path}" in said[0]


def _status_expired(s: Served, t: float) -> None:
    from pygoby.moos.translator import serialize_for_moos

    status = s.state.commander.commands.resolve("pygoby.examples.SimpleStatus")(time=t, src=1)
    s.clock = t
    s.mail("ACOMMS_EXPIRE", serialize_for_moos(status))


def test_repeated_expiries_of_one_message_are_one_line(tmp_path):
    s = Served(tmp_path)
    s.web._socket.close()
    for t in range(1000, 1060, 5):  # a telemetry queue expiring every 5 s
        _status_expired(s, float(t))
    timeline = s.state.page("acomms", s.clock)["timeline"]
    assert len(timeline) == 1 and "SimpleStatus expired (12 in a row)" in timeline[0]["text"]
    notices = s.state.page("commander", s.clock)["notices"]
    assert len(notices) == 1 and "(12 in a row; the newest shown)" in notices[0]


def test_ccl_frames_are_named(tmp_path):
    from pygoby.acomms import messages as acomms_pb
    from pygoby.dccl.ccl.remus import MDAT_STATE
    from pygoby.moos.translator import serialize_for_moos

    s = Served(tmp_path)
    s.web._socket.close()
    received = acomms_pb.ModemTransmission(src=2, dest=1, type=acomms_pb.DATA)
    received.frame.append(bytes([MDAT_STATE]) + bytes(31))
    received.frame.append(bytes([0x55]) + bytes(31))  # a CCL type REMUS frames do not use
    s.mail("ACOMMS_MODEM_RECEIVE", serialize_for_moos(received))
    (row,) = s.state.page("acomms", s.clock)["rx"]
    assert row["messages"] == ["REMUS State", "CCL 0x55"]
    # a Goby 1.1 CCL queue names its frames
    s.state.acomms.ccl_queues[MDAT_STATE] = "Remus_State"
    s.mail("ACOMMS_MODEM_RECEIVE", serialize_for_moos(received))
    assert s.state.page("acomms", s.clock)["rx"][0]["messages"] == ["Remus_State", "CCL 0x55"]


def test_the_commander_offers_commands_and_the_rest_behind_show_all(tmp_path):
    from pygoby.moos.moosfile import MissionFile
    from pygoby.moosacomms.acomms_config import read_acomms_config
    from pygoby.topside.commander import CommandSet
    from tests.goby11.test_examples import EXAMPLES

    # Goby 1.1: GoToCommand has <trigger>publish</trigger>, VehicleStatus <trigger>time</trigger>
    mission = tmp_path / "goby11.moos"
    mission.write_text(
        "ProcessConfig = pAcommsHandler\n{\n  modem_id: 1\n"
        f'  dccl_cfg {{ message_file {{ path: "{EXAMPLES}/xml/example1.xml" }} }}\n}}\n'
    )
    commands = CommandSet.from_pacommshandler(read_acomms_config(MissionFile.read(mission)))
    assert {n: t.command for n, t in commands.types.items()} == {
        "GoToCommand": True,
        "VehicleStatus": False,
    }
    # a `command` list in the configuration says which ones (goby3: all are publish-triggered)
    s = Served(tmp_path, commander={"command": ["Command"]})
    s.web._socket.close()
    offered = {t["short"]: t["command"] for t in s.state.commander_types()}
    assert offered == {"Command": True, "SimpleStatus": False}
    # `command: ""` (as --example_config prints it) lists none
    s = Served(tmp_path, commander={"command": [""]})
    s.web._socket.close()
    assert all(t["command"] for t in s.state.commander_types())
