"""`pygoby antler`: embedded DB + every Run process as real subprocesses, stopped on SIGINT."""

from __future__ import annotations

import asyncio
import signal
import socket
import stat
import sys
from pathlib import Path

from pygoby.moos.antler import child_argv, db_listening
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.moosfile import AntlerRun

HERE = Path(__file__).resolve().parent
PYGOBY = str(Path(sys.executable).with_name("pygoby"))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _write_mission(tmp_path: Path, port: int) -> Path:
    launcher = tmp_path / "pTestApp"
    launcher.write_text(f'#!/bin/sh\nexec "{sys.executable}" "{HERE / "example_app.py"}" "$@"\n')
    launcher.chmod(launcher.stat().st_mode | stat.S_IXUSR)
    mission = tmp_path / "mission.moos"
    mission.write_text(f"""\
ServerHost = localhost
ServerPort = {port}
Community  = alpha

ProcessConfig = ANTLER
{{
  MSBetweenLaunches = 50
  Run = MOOSDB     @ NewConsole = false
  Run = pTestApp   @ NewConsole = false, Path = {tmp_path} ~ pEchoOne
  Run = pTestApp   @ NewConsole = false, Path = {tmp_path} ~ pEchoTwo
}}

ProcessConfig = pEchoOne
{{
  common {{ log: false verbosity: QUIET }}
  out_var: "ECHO_ONE"
}}

ProcessConfig = pEchoTwo
{{
  common {{ log: false verbosity: QUIET }}
  out_var: "ECHO_TWO"
  gain: 3
}}
""")
    return mission


async def _until(cond, timeout: float) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while not await cond():
        assert loop.time() < deadline, "condition not met in time"
        await asyncio.sleep(0.1)


async def _clients(port: int) -> set[str]:
    async with MOOSClient("probe_clients", port=port) as probe:
        replies = await probe.server_request("PROC_SUMMARY")
    return {m.string.split(":", 1)[0] for m in replies} - {"probe_clients"}


async def test_antler_launches_db_and_apps_and_stops_them(tmp_path):
    port = _free_port()
    mission = _write_mission(tmp_path, port)
    antler = await asyncio.create_subprocess_exec(PYGOBY, "antler", str(mission))
    try:
        await _until(lambda: asyncio.to_thread(db_listening, "127.0.0.1", port), 10)

        async def both_connected():
            return await _clients(port) == {"pEchoOne", "pEchoTwo"}

        await _until(both_connected, 15)
        async with MOOSClient("tester", port=port) as tester:
            tester.subscribe("ECHO_ONE")
            tester.subscribe("ECHO_TWO")
            await asyncio.sleep(0.2)
            tester.publish("NAV_X", 2.0)
            got = {}
            while len(got) < 2:
                msg = await tester.receive(5)
                got[msg.key] = msg.value
            assert got == {"ECHO_ONE": 3.0, "ECHO_TWO": 6.0}
    finally:
        antler.send_signal(signal.SIGINT)
        assert await asyncio.wait_for(antler.wait(), 15) == 0
    assert not db_listening("127.0.0.1", port)


async def test_antler_uses_a_db_that_is_already_listening(tmp_path):
    async with MOOSDB(port=0) as db:
        mission = _write_mission(tmp_path, db.port)
        antler = await asyncio.create_subprocess_exec(PYGOBY, "antler", str(mission))
        try:
            await _until(lambda: asyncio.sleep(0, "pEchoOne" in db.client_names), 15)
        finally:
            antler.send_signal(signal.SIGTERM)
            assert await asyncio.wait_for(antler.wait(), 15) == 0
        assert db.port  # our in-process DB kept serving


def test_child_argv(tmp_path):
    prog = tmp_path / "pX"
    prog.write_text("#!/bin/sh\n")
    prog.chmod(0o755)
    run = AntlerRun("pX", "alias", {"Path": str(tmp_path)}, ["--a", "--b=1"])
    assert child_argv(run, Path("/m.moos"), None) == [str(prog), "/m.moos", "alias", "--a", "--b=1"]
    run.options["InhibitMOOSParams"] = "true"
    assert child_argv(run, Path("/m.moos"), None) == [str(prog), "--a", "--b=1"]
    assert child_argv(AntlerRun("no_such_program_x", "n"), Path("/m.moos"), None) is None
