"""Cross-check the emulator with a third-party client: WHOI's `acomms` package (pyacomms).

pyacomms (in its own process) talks to emulator 1 over a serial pty; our MMDriver talks to
emulator 2 over TCP; the emulators share a loopback channel.
"""

import asyncio
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


def _pyacomms_installed() -> bool:
    # by distribution: `import acomms` here would find this test package instead
    try:
        importlib.metadata.version("acomms")
    except importlib.metadata.PackageNotFoundError:
        return False
    return True


pytestmark = pytest.mark.skipif(not _pyacomms_installed(), reason="pyacomms (acomms) not installed")


async def test_pyacomms_talks_to_emulator_and_our_driver():
    channel = LoopbackChannel()
    clock = WallClock()
    sim1 = MMSimServer(MicroModemModel(1, clock, channel), channel, use_pty=True)
    sim2 = MMSimServer(MicroModemModel(2, clock, channel), channel)
    await sim1.start()
    await sim2.start()
    driver = await started_driver(2, sim2.port)
    got = []
    driver.signal_receive.connect(got.append)
    driver.signal_data_request.connect(lambda msg: msg.frame.append(b"to pyacomms"))
    proc = await asyncio.create_subprocess_exec(
        sys.executable, str(CLIENT), sim1.pty_path, "2", stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.DEVNULL, cwd="/tmp",
    )  # fmt: skip
    try:
        connected = json.loads(await asyncio.wait_for(proc.stdout.readline(), 20))
        assert connected == {"event": "connected", "id": 1}  # parsed our $CACFG,SRC,1
        # pyacomms -> emulator 1 -> channel -> emulator 2 -> our driver
        await run_until(lambda: any(t.frame for t in got), [driver])
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
