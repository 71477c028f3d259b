"""Cross-check the emulator with a third-party client: WHOI's `acomms` package (pyacomms).

pyacomms runs in its own process (`import acomms` here would find this test package) and talks
to the emulators over serial ptys linked at stable paths, with the emulators' real timing.
"""

import asyncio
import datetime as dt
import importlib.metadata
import json
import sys
from pathlib import Path

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.mmsim import LoopbackChannel, MicroModemModel
from pygoby.acomms.mmsim.server import MMSimServer
from pygoby.util.clock import WallClock

from .mm_e2e import run_until, started_driver

CLIENT = Path(__file__).with_name("pyacomms_client.py")
SESSION = Path(__file__).with_name("pyacomms_session.py")
RANGE_M = 1500.0  # one second of travel at 1500 m/s


def _pyacomms_installed() -> bool:
    # by distribution: `import acomms` here would find this test package instead
    try:
        importlib.metadata.version("acomms")
    except importlib.metadata.PackageNotFoundError:
        return False
    return True


pytestmark = [
    pytest.mark.skipif(not _pyacomms_installed(), reason="pyacomms (acomms) not installed"),
    pytest.mark.e2e,
]


async def test_pyacomms_drives_two_emulators_through_their_api(tmp_path):
    clock = WallClock()
    channel = LoopbackChannel(clock, RANGE_M)
    links = [tmp_path / "ttyLOOPA1", tmp_path / "ttyLOOPB1"]
    servers = [
        MMSimServer(MicroModemModel(modem_id, clock, channel), channel, pty_path=str(link))
        for modem_id, link in zip((1, 2), links, strict=True)
    ]
    for server in servers:
        await server.start()
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        str(SESSION),
        *map(str, links),
        str(tmp_path),
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        cwd=tmp_path,
    )
    steps: dict[str, list[dict]] = {}
    try:
        async with asyncio.timeout(150):
            while line := await proc.stdout.readline():
                step = json.loads(line)
                steps.setdefault(step["step"], []).append(step)
            await proc.wait()
    finally:
        if proc.returncode is None:
            proc.kill()
            await proc.wait()
        for server in servers:
            await server.close()
    assert proc.returncode == 0, (await proc.stderr.read()).decode()[-3000:]

    assert steps["connected"] == [{"step": "connected", "ids": [1, 2]}]
    (config,) = steps["config"]
    assert config["set"] == ["200", "AGN"] and config["get"] == {"AGN": "200"}
    assert config["unknown"] is None  # $CAERR: a real modem's NVRAM has no FOO
    assert config["info"] == {"info.firmware_version": "2.0.40000"}
    assert config["api_level"] == 11

    (set_time,) = steps["set_time"]
    assert set_time["timed_out"] == "0"
    assert dt.datetime.fromisoformat(set_time["time"]).replace(tzinfo=None) == dt.datetime(
        2030, 1, 2, 3, 4, 5
    )
    (get_time,) = steps["get_time"]
    elapsed = dt.datetime.fromisoformat(get_time["time"]).replace(tzinfo=None) - dt.datetime(
        2030, 1, 2, 3, 4, 5
    )
    assert dt.timedelta(seconds=1) <= elapsed <= dt.timedelta(seconds=4)
    assert get_time["sources"] == ["USER", "RTC"]

    (ping,) = steps["ping"]
    assert ping["owtt"] == pytest.approx(RANGE_M / 1500.0, abs=2e-3)

    packets = {p["rate"]: p for p in steps["packet"]}
    assert sorted(packets) == [0, 1, 5]
    for rate, packet in packets.items():
        assert packet["received"] == packet["sent"], f"rate {rate}"  # every frame, in order
    assert len(bytes.fromhex(packets[5]["received"])) == 2048

    (mini,) = steps["mini"]
    assert mini["received"].lower() == "0abc"

    (fdp,) = steps["fdp"]
    assert fdp["received"] == fdp["sent"] and fdp["good"] and fdp["stats"]


async def test_pyacomms_talks_to_emulator_and_our_driver():
    channel = LoopbackChannel()
    clock = WallClock()
    sim1 = MMSimServer(MicroModemModel(1, clock, channel), channel, pty_path="")
    sim2 = MMSimServer(MicroModemModel(2, clock, channel), channel)
    await sim1.start()
    await sim2.start()
    driver = await started_driver(2, sim2.port)
    got = []
    driver.signal_receive.connect(got.append)
    driver.signal_data_request.connect(lambda msg: msg.frame.append(b"to pyacomms"))
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        str(CLIENT),
        sim1.pty_path,
        "2",
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.DEVNULL,
        cwd="/tmp",
    )
    try:
        connected = json.loads(await asyncio.wait_for(proc.stdout.readline(), 20))
        assert connected == {"event": "connected", "id": 1}  # parsed our $CACFG,SRC,1
        # pyacomms -> emulator 1 -> channel -> emulator 2 -> our driver
        await run_until(lambda: any(t.frame for t in got), [driver], timeout=20)
        rx = next(t for t in got if t.frame)
        assert (rx.src, rx.dest, bytes(rx.frame[0])) == (1, 2, b"from pyacomms")
        # our driver -> emulators -> pyacomms parses our $CACYC/$CARXD
        driver.handle_initiate_transmission(acomms_pb.ModemTransmission(src=2, dest=1, rate=1))
        line = asyncio.ensure_future(proc.stdout.readline())
        await run_until(line.done, [driver], timeout=20)
        frames = json.loads(line.result())["frames"]
        assert frames == [[2, 1, b"to pyacomms".hex()]]
    finally:
        if proc.returncode is None:
            proc.kill()
        await proc.wait()
        driver.shutdown()
        await sim1.close()
        await sim2.close()
