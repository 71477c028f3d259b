"""`pygoby antler`: embedded DB + every Run process as real subprocesses, stopped on SIGINT."""

from __future__ import annotations

import asyncio
import signal
import socket
import stat
import sys
from pathlib import Path

import pytest

from pygoby.moos.antler import child_argv, db_listening
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.moosfile import AntlerRun

pytestmark = pytest.mark.e2e

HERE = Path(__file__).resolve().parent
PYGOBY = str(Path(sys.executable).with_name("pygoby"))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _write_mission(tmp_path: Path, port: int, two: str = "gain: 3", console: str = "false") -> Path:
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
  Run = pTestApp   @ NewConsole = {console}, Path = {tmp_path} ~ pEchoOne
  Run = pTestApp   @ NewConsole = false, Path = {tmp_path} ~ pEchoTwo
  Run = uNoSuchProgram @ NewConsole = false
}}

ProcessConfig = pEchoOne
{{
  common {{ log: false verbosity: VERBOSE }}
  out_var: "ECHO_ONE"
}}

ProcessConfig = pEchoTwo
{{
  common {{ log: false verbosity: VERBOSE }}
  out_var: "ECHO_TWO"
  {two}
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


async def _antler(*args: str) -> asyncio.subprocess.Process:
    return await asyncio.create_subprocess_exec(
        PYGOBY, "antler", *args, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT
    )


async def test_antler_launches_db_and_apps_and_stops_them(tmp_path):
    port = _free_port()
    mission = _write_mission(tmp_path, port)
    antler = await _antler(str(mission))
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
        out, _ = await asyncio.wait_for(antler.communicate(), 15)
    assert antler.returncode == 0
    assert not db_listening("127.0.0.1", port)
    lines = out.decode().splitlines()
    # every program's output behind its name, padded to the longest name; one status line each
    pad = len("uNoSuchProgram")
    assert f"{'MOOSDB':<{pad}} | MOOSDB alpha listening on 127.0.0.1:{port}" in lines
    assert any(line.startswith(f"{'pEchoTwo':<{pad}} | pEchoTwo [") for line in lines)
    assert (
        "antler: uNoSuchProgram: uNoSuchProgram is not available (no such program on PATH); the other processes run without it"
        in lines
    )
    for name in ("pEchoOne", "pEchoTwo", "MOOSDB"):
        assert f"antler: {name} exited with status 0" in lines, "\n".join(lines)
    assert sum("listening" in line for line in lines) == 1, lines


async def test_antler_exits_non_zero_when_an_app_dies(tmp_path):
    port = _free_port()
    mission = _write_mission(tmp_path, port, two="gain: 3 no_such_field: 1")
    antler = await _antler(str(mission))
    seen = []
    try:
        async with asyncio.timeout(30):
            while "antler: pEchoTwo exited with status 1" not in seen:
                seen.append((await antler.stdout.readline()).decode().rstrip("\n"))
        assert antler.returncode is None  # the others run on
    finally:
        antler.send_signal(signal.SIGINT)
        out, _ = await asyncio.wait_for(antler.communicate(), 15)
    lines = seen + out.decode().splitlines()
    assert antler.returncode == 1, lines
    assert any(
        "pEchoTwo: fatal configuration error: " in line and "no_such_field" in line
        for line in lines
    )
    assert "antler: pEchoOne exited with status 0" in lines  # stopped by antler
    assert lines[-1] == "antler: failed: pEchoTwo"


async def _clients_include(port: int, *names: str) -> bool:
    return set(names) <= await _clients(port)


async def test_antler_refuses_a_port_in_use_and_no_db_uses_it(tmp_path):
    async with MOOSDB(port=0) as db:
        mission = _write_mission(tmp_path, db.port)
        refused = await _antler(str(mission))
        out, _ = await asyncio.wait_for(refused.communicate(), 15)
        assert refused.returncode == 1
        assert out.decode().splitlines()[0] == (
            f"antler: port {db.port} on 127.0.0.1 (ServerPort of mission.moos) is already in use "
            "by another process: stop it, change ServerPort, or run antler with --no-db to use "
            "the MOOSDB listening there"
        )
        assert "pEchoOne" not in db.client_names  # nothing was launched
        antler = await _antler("--no-db", str(mission))
        try:
            await _until(lambda: asyncio.sleep(0, "pEchoOne" in db.client_names), 15)
        finally:
            antler.send_signal(signal.SIGTERM)
            await asyncio.wait_for(antler.communicate(), 15)
        assert antler.returncode == 0
        assert db.port  # our in-process DB kept serving


async def test_antler_logs_per_program_and_coloured_prefixes(tmp_path):
    port = _free_port()
    mission = _write_mission(tmp_path, port, console="true")
    logs = tmp_path / "logs"
    antler = await _antler("--logs", str(logs), str(mission))
    try:
        await _until(lambda: _clients_include(port, "pEchoOne", "pEchoTwo"), 15)
    finally:
        antler.send_signal(signal.SIGINT)
        out, _ = await asyncio.wait_for(antler.communicate(), 15)
    assert sorted(p.name for p in logs.iterdir()) == ["MOOSDB.log", "pEchoOne.log", "pEchoTwo.log"]
    assert "pEchoTwo [" in (logs / "pEchoTwo.log").read_text()
    assert f"listening on 127.0.0.1:{port}" in (logs / "MOOSDB.log").read_text()
    assert " | " not in out.decode()  # on the terminal: antler's own lines only

    antler = await _antler("--color", "always", str(mission))
    try:
        await _until(lambda: _clients_include(port, "pEchoOne", "pEchoTwo"), 15)
    finally:
        antler.send_signal(signal.SIGINT)
        out, _ = await asyncio.wait_for(antler.communicate(), 15)
    text = out.decode()
    pad = len("uNoSuchProgram")
    assert f"\x1b[36m{'pEchoOne':<{pad}}\x1b[0m | pEchoOne [" in text  # NewConsole: coloured
    lines = text.splitlines()
    assert any(line.startswith(f"{'pEchoTwo':<{pad}} | ") for line in lines)  # the others: plain
    assert any(line.startswith(f"{'MOOSDB':<{pad}} | ") for line in lines)


def test_child_argv(tmp_path):
    prog = tmp_path / "pX"
    prog.write_text("#!/bin/sh\n")
    prog.chmod(0o755)
    run = AntlerRun("pX", "alias", {"Path": str(tmp_path)}, ["--a", "--b=1"])
    assert child_argv(run, Path("/m.moos"), None) == [str(prog), "/m.moos", "alias", "--a", "--b=1"]
    run.options["InhibitMOOSParams"] = "true"
    assert child_argv(run, Path("/m.moos"), None) == [str(prog), "--a", "--b=1"]
    assert child_argv(AntlerRun("no_such_program_x", "n"), Path("/m.moos"), None) is None
