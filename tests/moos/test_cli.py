"""The real `pygoby` console script as a subprocess: moosdb, moos poke/get/watch."""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pygoby.moos.client import MOOSClient

pytestmark = pytest.mark.e2e

PYGOBY = str(Path(sys.executable).with_name("pygoby"))


def _pygoby(*args: str, timeout: float = 20) -> subprocess.CompletedProcess[str]:
    return subprocess.run([PYGOBY, *args], capture_output=True, text=True, timeout=timeout)


@pytest.fixture
def moosdb(tmp_path):
    """`pygoby moosdb` on an ephemeral port, community from a mission file."""
    mission = tmp_path / "m.moos"
    mission.write_text("ServerPort = 0\nCommunity = alpha\n")
    proc = subprocess.Popen([PYGOBY, "moosdb", str(mission)], stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    match = re.search(r"MOOSDB (\S+) listening on 127\.0\.0\.1:(\d+)", line)
    assert match, line
    assert match.group(1) == "alpha"
    yield int(match.group(2))
    proc.send_signal(signal.SIGINT)
    assert proc.wait(10) == 0


def _wait_for_client(port: int, prefix: str, timeout: float = 10.0) -> None:
    async def connected() -> bool:
        async with MOOSClient("probe_watch", port=port) as probe:
            replies = await probe.server_request("PROC_SUMMARY")
        return any(m.string.startswith(prefix) for m in replies)

    deadline = time.monotonic() + timeout
    while not asyncio.run(connected()):
        assert time.monotonic() < deadline, f"no client {prefix}* connected"
        time.sleep(0.1)
    time.sleep(0.2)  # its registrations follow its handshake


def test_poke_then_get(moosdb):
    port = str(moosdb)
    done = _pygoby("moos", "poke", "--port", port, "DEPTH=12.5", "NAME=alpha one", "CODE:=42")
    assert done.returncode == 0, done.stderr
    got = _pygoby("moos", "get", "--port", port, "--json", "DEPTH", "NAME", "CODE")
    assert got.returncode == 0, got.stderr
    values = json.loads(got.stdout)
    assert values["DEPTH"]["type"] == "double" and values["DEPTH"]["value"] == 12.5
    assert values["NAME"] == {**values["NAME"], "type": "string", "value": "alpha one"}
    assert values["CODE"]["type"] == "string" and values["CODE"]["value"] == "42"
    assert values["CODE"]["community"] == "alpha"
    text = _pygoby("moos", "get", "--port", port, "DEPTH")
    assert text.stdout.startswith("DEPTH = 12.5")
    missing = _pygoby("moos", "get", "--port", port, "DEPTH", "NEVER_WRITTEN")
    assert missing.returncode == 1 and "NEVER_WRITTEN has never been written" in missing.stderr


def test_watch_streams_wildcard_notifications(moosdb):
    port = str(moosdb)
    watch = subprocess.Popen(
        [PYGOBY, "moos", "watch", "--port", port, "--secs", "6", "--json", "NAV_*"],
        stdout=subprocess.PIPE,
        text=True,
    )
    _wait_for_client(moosdb, "pygoby_watch_")  # connected (and so registered)
    assert _pygoby("moos", "poke", "--port", port, "NAV_X=1", "OTHER=2", "NAV_Y=3").returncode == 0
    lines = []
    while len(lines) < 2:
        line = watch.stdout.readline()
        assert line, "watch ended early"
        lines.append(json.loads(line))
    watch.terminate()
    watch.wait(5)
    assert [(m["name"], m["value"]) for m in lines] == [("NAV_X", 1.0), ("NAV_Y", 3.0)]


def test_poke_without_db_fails_cleanly():
    done = _pygoby("moos", "poke", "--port", "1", "--connect-timeout", "0.5", "X=1")
    assert done.returncode == 1 and "cannot connect" in done.stderr


def test_a_taken_name_fails_cleanly(moosdb):
    async def poke_as_a_taken_name() -> subprocess.CompletedProcess[str]:
        async with MOOSClient("taken", port=moosdb):
            return await asyncio.to_thread(
                _pygoby, "moos", "poke", "--port", str(moosdb), "--name", "taken", "X=1"
            )

    done = asyncio.run(poke_as_a_taken_name())
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert 'A client of this name ("taken") already exists' in done.stderr


def test_bad_assignment_is_usage_error():
    done = _pygoby("moos", "poke", "--port", "1", "novalue")
    assert done.returncode == 2 and "VAR=value" in done.stderr


def test_moosdb_port_option_overrides_mission(tmp_path):
    env = dict(os.environ)
    proc = subprocess.Popen(
        [PYGOBY, "moosdb", "--port", "0", "--community", "c2"],
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert "MOOSDB c2 listening on 127.0.0.1:" in proc.stdout.readline()
    finally:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(10) == 0
