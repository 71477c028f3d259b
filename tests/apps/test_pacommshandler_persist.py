"""The persistent queue through kill -9 of a real pAcommsHandler process (issue 16 item 12).

Vehicle 1's pAcommsHandler runs as its own process (the console script) on an embedded MOOSDB
and an emulated Micro-Modem served by the test; vehicle 2 (in-process) joins the water later.
A command queued with ack=true survives kill -9 and a restart, is delivered once and, acked,
is gone for good; one whose ttl passed while the process was dead expires at the restart.
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
import sys
from pathlib import Path

import pytest

from pygoby.acomms.mmsim import LoopbackChannel
from pygoby.acomms.queue.persist import QueueStore
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.moos.db import MOOSDB

from .acomms_mission import (
    SLOT_SECONDS,
    WARP,
    Recorder,
    mission_clock,
    mission_text,
    modem_and_db,
)

pytestmark = pytest.mark.e2e

PACOMMSHANDLER = str(Path(sys.executable).with_name("pAcommsHandler"))
# the commands' ttl, in real seconds (the mission runs at MOOSTimeWarp WARP): the first command
# does not outlive the first kill, the second one does (and has time left, after the restart,
# for the process and its driver to start, its slot to come and the ack to return)
TTL = 14
CYCLE = 2 * SLOT_SECONDS / WARP  # a TDMA cycle, real seconds
PERSIST = '  queue_cfg {\n    persistent_queue_file: "vehicle1_queue.sqlite"\n'


class Vehicle1:
    """pAcommsHandler of vehicle 1 as a process that the test kills with SIGKILL."""

    def __init__(self, tmp_path: Path, mission: Path, db: MOOSDB) -> None:
        self.tmp_path, self.mission, self.db = tmp_path, mission, db
        self.proc: asyncio.subprocess.Process | None = None
        self.runs = 0

    async def start(self) -> None:
        self.runs += 1
        log = open(self.tmp_path / f"vehicle1_run{self.runs}.log", "wb")  # noqa: SIM115
        self.proc = await asyncio.create_subprocess_exec(
            PACOMMSHANDLER, str(self.mission), cwd=self.tmp_path, stdout=log, stderr=log
        )
        log.close()
        async with asyncio.timeout(20):
            while "pAcommsHandler" not in self.db.client_names:
                assert self.proc.returncode is None, self.output()
                await asyncio.sleep(0.05)

    async def kill(self) -> None:
        assert self.proc is not None and self.proc.returncode is None, self.output()
        self.proc.send_signal(signal.SIGKILL)
        assert await self.proc.wait() == -signal.SIGKILL
        async with asyncio.timeout(5):  # the DB notices the closed socket
            while "pAcommsHandler" in self.db.client_names:
                await asyncio.sleep(0.05)

    def output(self) -> str:
        return (self.tmp_path / f"vehicle1_run{self.runs}.log").read_text(errors="replace")


def command_ids(recorder: Recorder) -> list[str]:
    return [v for v in recorder.values("COMMAND_IN") if isinstance(v, str)]


async def test_queued_commands_survive_kill_9(tmp_path):
    clock = mission_clock()
    channel = LoopbackChannel(clock)
    async with contextlib.AsyncExitStack() as stack:
        sim1, db1 = await modem_and_db(stack, 1, channel, clock)
        text = mission_text(1, db1.port, sim1.port).replace("  queue_cfg {\n", PERSIST, 1)
        mission = tmp_path / "vehicle1.moos"
        mission.write_text(
            text.replace(
                "ack: true  value_base: 5  ttl: 600", f"ack: true  value_base: 5  ttl: {TTL * WARP}"
            )
        )
        r1 = Recorder("recorder1", db1.port, clock)
        await r1.start(["ACOMMS_QSIZE", "ACOMMS_EXPIRE", "ACOMMS_ACK_ORIGINAL", "DB_TIME"])
        stack.push_async_callback(r1.close)
        vehicle1 = Vehicle1(tmp_path, mission, db1)
        await vehicle1.start()
        stack.push_async_callback(lambda: _kill_quietly(vehicle1))
        loop = asyncio.get_running_loop()

        # Two commands nobody hears yet (vehicle 2 is not in the water): sent, never acked.
        await r1.wait_for("ACOMMS_QSIZE", lambda v: "dccl_id: 21 size: 0" in v)
        # a DB_TIME posted since the app subscribed: it has the commands' time source
        await r1.wait_for("DB_TIME", start=len(r1.values("DB_TIME")), timeout=5)
        await asyncio.sleep(0.2)
        r1.client.publish("COMMAND_OUT", "dest=2,command_id=11,heading=10,speed=1,depth=5")
        await r1.wait_for("ACOMMS_QSIZE", lambda v: "dccl_id: 21 size: 1" in v)
        first_queued = loop.time()
        await asyncio.sleep(TTL - 4)
        r1.client.publish("COMMAND_OUT", "dest=2,command_id=22,heading=20,speed=1,depth=5")
        await r1.wait_for("ACOMMS_QSIZE", lambda v: "dccl_id: 21 size: 2" in v)
        await vehicle1.kill()
        await asyncio.sleep(first_queued + TTL + 1 - loop.time())  # 11 expires, 22 does not

        # Vehicle 2 joins; vehicle 1 restarts: 11 expires at once, 22 is sent and acked.
        sim2, db2 = await modem_and_db(stack, 2, channel, clock)
        path2 = tmp_path / "vehicle2.moos"
        path2.write_text(mission_text(2, db2.port, sim2.port))
        r2 = Recorder("recorder2", db2.port, clock)
        await r2.start(["COMMAND_IN"])
        stack.push_async_callback(r2.close)
        await stack.enter_async_context(pAcommsHandler.from_mission(path2, "pAcommsHandler"))
        seen = len(r1.values("ACOMMS_EXPIRE"))
        await vehicle1.start()
        expired = await r1.wait_for("ACOMMS_EXPIRE", start=seen, timeout=10)
        assert "command_id: 11" in expired, vehicle1.output()
        assert "command_id=22" in await r2.wait_for("COMMAND_IN", timeout=20)
        original = await r1.wait_for(
            "ACOMMS_ACK_ORIGINAL", lambda v: "command_id: 22" in v, timeout=10
        )
        assert original
        await asyncio.sleep(0.5)  # the ack's removal is committed at once; let the posts out

        # Killed and restarted again: nothing left to send; 22 arrived once, 11 never.
        await vehicle1.kill()
        store = QueueStore(tmp_path / "vehicle1_queue.sqlite")
        assert store.items() == []
        store.close()
        await vehicle1.start()
        await asyncio.sleep(1 + 3 * CYCLE)  # the driver's start and three TDMA cycles
        assert [v for v in command_ids(r2) if "command_id=22" in v] == [command_ids(r2)[0]]
        assert not any("command_id=11" in v for v in command_ids(r2))
        assert len(command_ids(r2)) == 1


async def _kill_quietly(vehicle: Vehicle1) -> None:
    if vehicle.proc is not None and vehicle.proc.returncode is None:
        vehicle.proc.kill()
        await vehicle.proc.wait()
