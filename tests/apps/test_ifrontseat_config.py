"""iFrontSeat's command line and configuration: the driver named by IFRONTSEAT_DRIVER_LIBRARY
or `driver_library` (resolved before the options, so --example_config shows its block), clear
failures listing the installed drivers, the Goby 2 `[abc_config]` form and `exit_on_error` (a real iFrontSeat process on the
embedded MOOSDB)."""

from __future__ import annotations

import asyncio
import logging
import os
import sys
from pathlib import Path

import pytest

from pygoby.apps.ifrontseat import iFrontSeat
from pygoby.frontseat import messages as frontseat_pb
from pygoby.moos.appconfig import ConfigError
from pygoby.moos.db import MOOSDB
from pygoby.moos.moosfile import MissionFile

from .acomms_mission import Recorder

pytestmark = pytest.mark.e2e

REPO = Path(__file__).resolve().parents[2]
LOOPBACK = "tests.apps.ifs_loopback_driver"
FOUND = "drivers found: abc, basic_simulator, bluefin"

SIMULATOR_BLOCK = """
  [goby.middleware.frontseat.protobuf.basic_simulator_config] {
    tcp_address: "localhost"  start { lat: 1  lon: 2 } }"""


def mission(tmp_path, body: str, port: int = 9000) -> Path:
    path = tmp_path / "auv.moos"
    path.write_text(
        f"ServerHost = localhost\nServerPort = {port}\nCommunity = auv\n"
        f"ProcessConfig = iFrontSeat\n{{\n  common {{ log: false }}\n{body}\n}}\n"
    )
    return path


@pytest.fixture(autouse=True)
def no_driver_in_environment(monkeypatch):
    monkeypatch.delenv("IFRONTSEAT_DRIVER_LIBRARY", raising=False)


def test_example_config_shows_the_drivers_block(monkeypatch, capsys):
    monkeypatch.setenv("IFRONTSEAT_DRIVER_LIBRARY", LOOPBACK)
    assert iFrontSeat.main(["--example_config"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("ProcessConfig = iFrontSeat\n{\n")
    block = out[out.index("    [pygoby.test.loopback_config] {") :]
    assert block.splitlines()[1].startswith("      nav_period: 0.1  # Seconds between")
    assert "  driver_library: " in out and "    status_period: 5  # " in out


def test_a_wrong_driver_name_exits_1_listing_the_drivers(monkeypatch, capsys, tmp_path):
    monkeypatch.setenv("IFRONTSEAT_DRIVER_LIBRARY", "no_such_driver")
    assert iFrontSeat.main(["--example_config"]) == 1
    err = capsys.readouterr().err
    assert "'no_such_driver'" in err and FOUND in err

    monkeypatch.delenv("IFRONTSEAT_DRIVER_LIBRARY")
    path = mission(
        tmp_path,
        f'  driver_library: "libgoby_frontseat_iver.so.30"\n  frontseat_cfg {{ {SIMULATOR_BLOCK} }}',
    )
    assert iFrontSeat.main([str(path)]) == 1
    err = capsys.readouterr().err
    assert "fatal configuration error" in err and "'iver'" in err and FOUND in err

    # goby3's Bluefin library name is pygoby's bluefin driver, which needs its own block
    path = mission(
        tmp_path,
        f'  driver_library: "libgoby_frontseat_bluefin.so.30"\n  frontseat_cfg {{ {SIMULATOR_BLOCK} }}',
    )
    assert iFrontSeat.main([str(path)]) == 1
    err = capsys.readouterr().err
    assert (
        "'bluefin' failed to start" in err
        and "has no [goby.middleware.frontseat.protobuf.bluefin_config]" in err
    )

    path = mission(tmp_path, f"  frontseat_cfg {{ {SIMULATOR_BLOCK} }}")
    assert iFrontSeat.main([str(path)]) == 1
    err = capsys.readouterr().err
    assert "IFRONTSEAT_DRIVER_LIBRARY" in err and FOUND in err


def test_the_environment_wins_over_driver_library(monkeypatch, tmp_path):
    monkeypatch.setenv("IFRONTSEAT_DRIVER_LIBRARY", LOOPBACK)
    path = mission(tmp_path, '  driver_library: "no_such_driver"\n  frontseat_cfg { }')
    app = iFrontSeat.from_mission(path)
    assert type(app.interface).__name__ == "LoopbackFrontSeat"


def test_driver_library_names_a_driver_whose_block_is_in_the_config(tmp_path):
    # The loopback driver's extension is only known once its module is imported: the
    # driver_library field is read first, then the block is parsed with it.
    body = (
        f'  driver_library: "{LOOPBACK}"\n'
        "  frontseat_cfg { [pygoby.test.loopback_config] { nav_period: 0.25 } }"
    )
    app = iFrontSeat.from_mission(mission(tmp_path, body))
    assert app.interface.settings.nav_period == 0.25


def test_goby2_abc_config_is_read_as_the_basic_simulator_block(tmp_path, caplog):
    body = """  driver_library: "abc"
  [abc_config] {  # Goby 2 form, as in the Goby 2 documentation
    tcp_address: "localhost"
    tcp_port: 54322
    start { lat: 44.0888889 lon: 9.84861111 duration: 600 }
  }"""
    with caplog.at_level(logging.WARNING):
        cfg = iFrontSeat.read_config(MissionFile.read(mission(tmp_path, body)), "iFrontSeat")
    sim = cfg.frontseat_cfg.Extensions[frontseat_pb.BASIC_SIMULATOR_CONFIG]
    assert (sim.tcp_address, sim.tcp_port) == ("localhost", 54322)
    assert (sim.start.lat, sim.start.lon, sim.start.duration) == (44.0888889, 9.84861111, 600)
    assert "Goby 2 [abc_config] block is read as frontseat_cfg" in caplog.text

    both = body + f"\n  frontseat_cfg {{ {SIMULATOR_BLOCK} }}"
    with pytest.raises(ConfigError, match="both \\[abc_config\\] and frontseat_cfg"):
        iFrontSeat.read_config(MissionFile.read(mission(tmp_path, both)), "iFrontSeat")

    missing = '  driver_library: "abc"'
    with pytest.raises(ConfigError, match="missing required configuration fields: frontseat_cfg"):
        iFrontSeat.read_config(MissionFile.read(mission(tmp_path, missing)), "iFrontSeat")


async def test_exit_on_error_stops_the_process_with_status_1(tmp_path):
    """No helm within helm_running_timeout -> HELM_ERROR -> exit 1; status_period 0 posts
    no IFS_STATUS at all (Quirk Q15: goby3 would post one every iteration)."""
    async with MOOSDB(port=0) as db:
        recorder = Recorder("tester", db.port)
        await recorder.start(["IFS_STATUS", "IFS_NODE_STATUS"])
        body = f"""  driver_library: "{LOOPBACK}"
  frontseat_cfg {{ helm_running_timeout: 1  exit_on_error: true  status_period: 0 }}"""
        path = mission(tmp_path, body, db.port)
        env = {**os.environ, "PYTHONPATH": str(REPO)}
        env.pop("IFRONTSEAT_DRIVER_LIBRARY", None)
        process = await asyncio.create_subprocess_exec(
            str(Path(sys.executable).with_name("iFrontSeat")),
            str(path),
            cwd=tmp_path,
            env=env,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT,
        )
        try:
            async with asyncio.timeout(30):
                output, _ = await process.communicate()
        finally:
            if process.returncode is None:
                process.kill()
        await recorder.close()
    assert process.returncode == 1, output.decode()
    assert b"INTERFACE_HELM_ERROR with exit_on_error: true" in output
    assert recorder.values("IFS_NODE_STATUS")  # it ran (LISTEN) before the helm timeout
    assert recorder.values("IFS_STATUS") == []


def test_the_example_mission_reads():
    cfg = iFrontSeat.read_config(
        MissionFile.read(REPO / "examples/frontseat/abc_auv.moos"), "iFrontSeat"
    )
    assert cfg.driver_library == "abc" and cfg.legacy_cfg.publish_fs_bs_ready
    sim = cfg.frontseat_cfg.Extensions[frontseat_pb.BASIC_SIMULATOR_CONFIG]
    assert (sim.tcp_port, sim.start.lat) == (54321, 44.0888889)


async def test_the_example_demo_converges():
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        str(REPO / "examples/frontseat/run_demo.py"),
        "--warp",
        "10",
        "--duration",
        "15",
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.STDOUT,
    )
    try:
        async with asyncio.timeout(60):
            output, _ = await process.communicate()
    finally:
        if process.returncode is None:
            process.kill()
    assert process.returncode == 0, output.decode()
    *table, verdict = output.decode().splitlines()
    assert verdict == "iFrontSeat demo: OK, the vehicle follows the helm in COMMAND"
    last = table[-1].split()
    # "<t>s COMMAND 90 1.5 10.0  90.0 1.50 10.0  x y": on the helm's course, heading east
    assert last[1:8] == ["COMMAND", "90", "1.5", "10.0", "90.0", "1.50", "10.0"]
    assert float(last[8]) > 5.0
