"""Write the two pygoby pLogger logs of this directory (see README.md).

    cd tests/data/alog/moosivp && PYTHONPATH=../../../../src python make_plogger_logs.py

Each log comes from a short mission on pygoby's own MOOSDB in real time: a "vehicle"
client posts doubles, strings with spaces, binary values and values with an aux source; a
"pShare" client forwards messages from another community (community "bravo") as a bridge does.
The logs are made once and committed: their times and LOGSTART are those of the run.
"""

from __future__ import annotations

import asyncio
import os
import shutil
import tempfile
from pathlib import Path

from pygoby.apps.plogger import pLogger
from pygoby.moos import protocol as p
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.timewarp import moos_clock

WARP = 1.0  # real time: LOGSTART is then the UNIX time of the run, as on a vehicle
HERE = Path(__file__).resolve().parent

MISSION = """\
ServerHost = localhost
ServerPort = {port}
Community  = alpha
MOOSTimeWarp = 1

ProcessConfig = pLogger
{{
  AppTick   = 10
  CommsTick = 10
  File = {file}
  PATH = ./
  FileTimeStamp = false
  AsyncLog = true
  WildCardLogging = true
  WildCardOmitPattern = *_STATUS, DB_*, LOGGER_DIRECTORY
  LogAuxSrc = true
  MarkExternalCommunityMessages = true
{options}}}
"""

# (variable, value, aux): what the vehicle posts, half a second of MOOS time apart
VEHICLE_POSTS: list[tuple[str, float | str | bytes, str]] = [
    ("NAV_X", 1.5, ""),
    ("NAV_Y", -2.25, ""),
    ("MSG", "hello  world, with spaces", "bhv_a"),
    ("RAW", b"\x00\x01\xfe\xff\n", ""),
    ("NAV_X", 123456.123456789, ""),
    ("NAV_Y", 1e-7, ""),
    ("MSG", "x=1,y=2", ""),
    ("DESIRED_NAV_X", 10.0, "waypt"),
    ("NUMERIC_TEXT", "3.5", ""),
    ("MSG_LEN", 7.0, ""),
    ("SCI_TEXT", "1e5", ""),
    ("EMPTY", "", ""),
    ("RAW", b"binary\x00 data", "bhv_b"),
    ("NAV_X", 0.0, ""),
    ("MSG", "trailing space ", "bhv_a"),
    ("NAV_Y", -0.000001, ""),
    ("NAV_X", 3.0, ""),
]
# (variable, value): what reaches the DB from community bravo
BRIDGED_POSTS: list[tuple[str, float | str]] = [
    ("NODE_REPORT", "NAME=bravo,X=12.5,Y=-3,SPD=1.2"),
    ("BRAVO_DEPTH", 42.125),
    ("NODE_REPORT", "NAME=bravo,X=13.5,Y=-3.5,SPD=1.2"),
]


async def run_mission(directory: Path, file: str, options: str) -> None:
    clock = moos_clock(WARP)
    async with MOOSDB(port=0, community="alpha", clock=clock) as db:
        mission = directory / f"{file}.moos"
        mission.write_text(MISSION.format(port=db.port, file=file, options=options))
        app = pLogger.from_mission(mission)
        async with (
            MOOSClient("vehicle", port=db.port, clock=clock) as vehicle,
            MOOSClient("pShare", port=db.port, clock=clock) as bridge,
        ):
            # posted before pLogger starts: pLogger gets it from the DB when it registers and
            # logs it at its own time, before LOGSTART (a negative time)
            vehicle.publish("PRESTART", "posted before pLogger started")
            await vehicle.flush()
            await asyncio.sleep(0.5 / WARP)
            async with app:
                await _post(vehicle, bridge)
            await asyncio.sleep(0.1)


async def _post(vehicle: MOOSClient, bridge: MOOSClient) -> None:
    vehicle.subscribe("LOGGER_DIRECTORY")
    while (await vehicle.receive(5)).key != "LOGGER_DIRECTORY":
        pass  # pLogger is connected and registered
    await asyncio.sleep(0.1)
    bridged = iter(BRIDGED_POSTS)
    for index, (key, value, aux) in enumerate(VEHICLE_POSTS):
        vehicle.publish(key, value, src_aux=aux)
        await vehicle.flush()
        if index % 5 == 2:
            name, forwarded = next(bridged)
            # a bridge forwards the message with its originating community set: the DB passes
            # it on untouched (the client API has no publish for this)
            bridge._queue(
                p.notify(name, forwarded, time=bridge.time(), src="pShare", community="bravo")
            )
            await bridge.flush()
        await asyncio.sleep(0.5 / WARP)
    await asyncio.sleep(0.3)


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        cwd = os.getcwd()
        os.chdir(work)  # the banner's LOG FILE path is then short and relative
        try:
            asyncio.run(run_mission(work, "plogger_blog", ""))
            asyncio.run(
                run_mission(
                    work,
                    "plogger_inline",
                    "  DoublePrecision = 3\n  MarkDataAsBinary = true\n  MarkDataType = true\n",
                )
            )
        finally:
            os.chdir(cwd)
        for name, suffixes in (
            ("plogger_blog", (".alog", ".blog")),
            ("plogger_inline", (".alog",)),
        ):
            for suffix in suffixes:
                shutil.copy(work / name / f"{name}{suffix}", HERE / f"{name}{suffix}")


if __name__ == "__main__":
    main()
