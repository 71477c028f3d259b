"""pLogger under load (`make bench`): a load generator posts 20,000 notifications a second (64-byte
strings, batched as libMOOS batches) into a MOOSDB process for a few seconds while pygoby's
pLogger (in this process, WildCardLogging as MOOS-IvP missions run it) logs them. Printed and
stored in extra_info: how many reached the .alog, how many the writer dropped, this process's
CPU time per logged notification, how far behind pLogger was when the publisher stopped and how
long it took to get every line on disk. Nothing is asserted about the figures but that nothing was lost."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path

import pytest

from benchmarks.test_moos_bench import _result, _spawn, _wait_ready, moosdb  # noqa: F401
from pygoby.apps.plogger import pLogger

RATE = 20_000
SECONDS = 5.0
MISSION = """\
ServerHost = localhost
ServerPort = {port}
Community  = bench

ProcessConfig = pLogger
{{
  AppTick   = 10
  CommsTick = 10
  File = Flood
  PATH = {folder}/
  FileTimeStamp = false
  AsyncLog = true
  WildCardLogging = true
  WildCardOmitPattern = DB_*
  LoggingDirectorySummaryFile = {folder}/.LastOpenedMOOSLogDirectory
}}
"""


async def _flood(port: int, folder: Path) -> dict:
    mission = folder / "flood.moos"
    mission.write_text(MISSION.format(port=port, folder=folder))
    app = pLogger.from_mission(mission)
    count = int(RATE * SECONDS)
    async with app:
        await asyncio.sleep(0.5)  # registered for every variable
        pub = _spawn(
            "pub",
            *("--port", str(port), "--name", f"flooder_{time.monotonic_ns()}"),
            *("--var", "FLOOD", "--count", str(count), "--rate", str(RATE), "--batch", "100"),
        )
        await asyncio.to_thread(_wait_ready, [pub])
        assert app.sink is not None
        sink = app.sink
        await asyncio.sleep(1.0)  # the lines of the start are on disk
        before = sink.written
        cpu0 = time.process_time()
        pub.stdin.write("go\n")
        pub.stdin.flush()
        while pub.poll() is None:
            await asyncio.sleep(0.1)
        sent = _result(pub)
        behind = count - (sink.written - before)  # not yet on disk
        deadline = time.monotonic() + 30
        while sink.written - before < count and time.monotonic() < deadline:
            await asyncio.sleep(0.05)
        caught_up = time.monotonic() - sent["end"]
        cpu = time.process_time() - cpu0
        dropped = sink.dropped
    alog = folder / "Flood" / "Flood.alog"
    with open(alog, "rb") as lines:
        logged = sum(1 for line in lines if b" FLOOD " in line)
    return {
        "sent": sent["sent"],
        "offered_per_second": sent["sent"] / (sent["end"] - sent["start"]),
        "logged": logged,
        "dropped": dropped,
        "cpu_us_per_notification": 1e6 * cpu / max(logged, 1),
        "behind_at_end": behind,
        "caught_up_s": caught_up,
    }


@pytest.mark.benchmark(group="plogger")
def test_plogger_keeps_up_with_20k_notifications_per_second(benchmark, moosdb, tmp_path):  # noqa: F811
    port, _ = moosdb
    result = benchmark.pedantic(lambda: asyncio.run(_flood(port, tmp_path)), rounds=1, iterations=1)
    benchmark.extra_info.update(result)
    print(
        f"\npLogger, {RATE:,} notifications/s for {SECONDS:g} s "
        f"({result['offered_per_second']:,.0f}/s offered): {result['logged']}/{result['sent']} "
        f"logged, {result['dropped']} dropped, {result['cpu_us_per_notification']:.1f} us CPU "
        f"each, {result['behind_at_end']} behind when the publisher stopped, all logged "
        f"{result['caught_up_s']:.2f} s after"
    )
    assert result["logged"] == result["sent"] and result["dropped"] == 0
