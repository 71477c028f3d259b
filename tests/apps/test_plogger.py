"""pLogger in a short mission on the embedded MOOSDB (MOOSTimeWarp 20): what it writes, then the
log converted and replayed into another MOOSDB, compared with what was posted."""

from __future__ import annotations

import asyncio
import logging
import re
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from pygoby.apps.plogger import pLogger
from pygoby.cli import main as pygoby_main
from pygoby.moos.alog import AlogFile
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.timewarp import moos_clock

WARP = 20.0

MISSION = """\
ServerHost = localhost
ServerPort = {port}
Community  = alpha
MOOSTimeWarp = 20

ProcessConfig = pLogger
{{
  AppTick   = 10
  CommsTick = 10
  File = Mission
  PATH = {tmp}/logs/
  FileTimeStamp = false
  SyncLog = true @ 0.2
  AsyncLog = true
  WildCardLogging = true
  WildCardOmitPattern = *_STATUS, DB_*
  Log = NAV_X @ 0
  LogAuxSrc = true
  LoggingDirectorySummaryFile = {tmp}/.LastOpenedMOOSLogDirectory
  Colour = blue
}}
"""

# what the "vehicle" posts: (variable, value, aux)
POSTS = [
    ("NAV_X", 1.5, ""),
    ("MSG", "hello  world, with spaces", "bhv_a"),
    ("RAW", b"\x00\x01\xfe\xff\n", ""),
    ("NAV_X", -2.25, ""),
    ("MSG", "x=1,y=2", ""),
    ("NAV_X", 3.0, ""),
]


async def wait_for(client: MOOSClient, key: str) -> None:
    while (await client.receive(5)).key != key:
        pass


async def post_mission(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> Path:
    clock = moos_clock(WARP)
    async with MOOSDB(port=0, community="alpha", clock=clock) as db:
        mission = tmp_path / "m.moos"
        mission.write_text(MISSION.format(port=db.port, tmp=tmp_path))
        app = pLogger.from_mission(mission)
        async with MOOSClient("vehicle", port=db.port, clock=clock) as vehicle, app:
            vehicle.subscribe("LOGGER_DIRECTORY")
            await wait_for(vehicle, "LOGGER_DIRECTORY")  # pLogger is connected and registered
            await asyncio.sleep(0.1)
            for key, value, aux in POSTS:
                vehicle.publish(key, value, src_aux=aux)
                await vehicle.flush()
                await asyncio.sleep(0.5 / WARP)  # half a second of MOOS time apart
            vehicle.publish("VEHICLE_STATUS", "omitted")
            await vehicle.flush()
            await asyncio.sleep(0.3)
    assert "unknown option 'Colour' ignored" in caplog.text
    return tmp_path / "logs" / "Mission"


async def test_plogger_writes_and_replay_reproduces(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, capsys: pytest.CaptureFixture[str]
) -> None:
    caplog.set_level(logging.WARNING)
    directory = await post_mission(tmp_path, caplog)
    assert sorted(p.name for p in directory.iterdir()) == [
        "Mission._moos",
        "Mission.alog",
        "Mission.blog",
        "Mission.slog",
    ]
    assert (tmp_path / ".LastOpenedMOOSLogDirectory").read_text() == (
        f"LastOpenedLoggingDirectory={directory}\n"
    )
    assert "ProcessConfig = pLogger" in (directory / "Mission._moos").read_text()
    slog = (directory / "Mission.slog").read_text()
    assert "%%   (2) NAV_X" in slog and "1.5" in slog

    log = AlogFile(directory / "Mission.alog")
    entries = [e for e in log if e.source == "vehicle"]
    assert log.reader.bad_lines == 0
    assert [(e.name, e.value, e.source_aux) for e in entries] == POSTS
    times = [e.time for e in entries]
    assert times == sorted(times) and times[0] > 0
    names = {e.name for e in AlogFile(directory / "Mission.alog")}
    assert "VEHICLE_STATUS" not in names and "PLOGGER_STATUS" not in names
    assert "LOGGER_DIRECTORY" in names

    out = tmp_path / "m.parquet"
    assert pygoby_main(["log", "convert", str(directory / "Mission.alog"), "-o", str(out)]) == 0
    capsys.readouterr()
    table = [r for r in pq.read_table(out).to_pylist() if r["source"].startswith("vehicle")]
    assert [r["name"] for r in table] == [k for k, _, _ in POSTS]
    assert table[2]["type"] == "binary" and table[2]["value"] == "0001feff0a"
    assert table[0]["value_double"] == 1.5 and table[1]["source"] == "vehicle:bhv_a"

    # replay into another DB: same values, order and source names
    async with (
        MOOSDB(port=0) as other,
        MOOSClient("watcher", port=other.port) as watcher,
    ):
        for key in ("NAV_X", "MSG", "RAW"):
            watcher.subscribe(key)
        await watcher.flush()
        command = ["log", "replay", str(directory / "Mission.alog"), "--port", str(other.port)]
        command += ["--warp", "20", "--only", "NAV_X", "MSG", "RAW"]
        assert await asyncio.to_thread(pygoby_main, command) == 0
        assert capsys.readouterr().out == f"{len(POSTS)} messages posted\n"
        got = [await watcher.receive(5) for _ in POSTS]
    assert [(m.key, m.value, m.src, m.src_aux) for m in got] == [
        (k, v, "vehicle", aux) for k, v, aux in POSTS
    ]


@pytest.mark.parametrize("vehicle", ["topside", "unicorn"])
def test_two_vehicles_missions_log_with_plogger(vehicle: str) -> None:
    mission = Path(__file__).resolve().parents[2] / "examples" / "two_vehicles" / f"{vehicle}.moos"
    app = pLogger.from_mission(mission)
    assert app.settings.warnings == []
    assert (app.settings.file, app.settings.path, app.settings.wildcard_logging) == (
        vehicle,
        "./logs",
        True,
    )
    stamp = rf"{vehicle}_\d{{1,2}}_\d{{1,2}}_\d{{4}}_____\d\d_\d\d_\d\d"  # D_M_YYYY_____HH_MM_SS
    assert re.fullmatch(stamp, app.settings.directory_name())


async def test_an_unusable_path_falls_back_to_the_working_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "a_file").write_text("not a directory")
    mission = tmp_path / "m.moos"
    mission.write_text(
        "ServerPort = 1\nProcessConfig = pLogger\n{\n  File = Day\n  FileTimeStamp = false\n"
        f"  PATH = {tmp_path}/a_file/logs\n  Log = X @ 0\n"
        f"  LoggingDirectorySummaryFile = {tmp_path}/summary\n}}\n"
    )
    monkeypatch.chdir(tmp_path)
    app = pLogger.from_mission(mission)
    await app.start()  # no MOOSDB needed: the files are made at start-up
    try:
        assert app.directory == Path("Day")
    finally:
        await app.stop()
    # on the app's terminal, as a user running pLogger sees it
    assert "(Warning): cannot make the log directory" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "Day").iterdir()) == ["Day._moos", "Day.alog"]


async def test_replay_skips_a_source_whose_name_is_taken(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    from pygoby.moos.alog import AlogFormatter, banner
    from pygoby.moos.alog.tools import replay

    path = tmp_path / "r.alog"
    fmt = AlogFormatter(0.0)
    path.write_text(
        banner(str(path), 0.0)
        + fmt.line(1.0, "A", "taken", 1.0)
        + fmt.line(1.1, "B", "free", "b")
        + fmt.line(1.2, "DB_TIME", "MOOSDB_#1", 5.0)
    )
    async with MOOSDB(port=0) as db, MOOSClient("taken", port=db.port) as taken:
        await taken.connect()
        taken.subscribe("B")
        await taken.flush()
        assert await replay(AlogFile(path), "127.0.0.1", db.port, warp=100) == 1
        got = await taken.receive(5)
    assert (got.key, got.value, got.src) == ("B", "b", "free")
    assert "not replaying taken's messages" in caplog.text


async def test_kill_9_loses_at_most_the_last_second(tmp_path: Path) -> None:
    """pLogger as a user starts it (its own process): its lines reach the disk without it
    closing the file (its writer flushes at least every half second), so kill -9 loses at
    most what arrived in the last second."""
    import os
    import signal
    import sys

    async with MOOSDB(port=0) as db, MOOSClient("vehicle", port=db.port) as vehicle:
        mission = tmp_path / "k.moos"
        mission.write_text(
            f"ServerPort = {db.port}\nProcessConfig = pLogger\n{{\n  AppTick = 10\n"
            f"  CommsTick = 10\n  File = K\n  FileTimeStamp = false\n  PATH = {tmp_path}\n"
            f"  Log = COUNT @ 0\n  LoggingDirectorySummaryFile = {tmp_path}/summary\n}}\n"
        )
        process = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "pygoby.apps.plogger",
            str(mission),
            stdout=asyncio.subprocess.DEVNULL,
            stderr=asyncio.subprocess.DEVNULL,
        )
        try:
            while "pLogger" not in db.client_names:
                await asyncio.sleep(0.1)
            await asyncio.sleep(0.5)  # its registration reaches the DB
            for i in range(20):
                vehicle.publish("COUNT", float(i))
            await vehicle.flush()
            alog = tmp_path / "K" / "K.alog"
            for _ in range(100):  # until the writer has flushed them
                await asyncio.sleep(0.1)
                if alog.exists() and len(list(AlogFile(alog))) == 20:
                    break
        finally:
            os.kill(process.pid, signal.SIGKILL)
            await process.wait()
    assert [e.value for e in AlogFile(alog)] == [float(i) for i in range(20)]


def test_plogger_example_config(capsys: pytest.CaptureFixture[str]) -> None:
    assert pLogger.main(["--example_config"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("ProcessConfig = pLogger\n{\n  AppTick = 4\n")
    assert "  Log = NAV_X @ 0 " in out and out.endswith("}\n")


async def test_logger_restart_starts_new_files(tmp_path: Path) -> None:
    async with MOOSDB(port=0) as db:
        mission = tmp_path / "r.moos"
        mission.write_text(
            f"ServerPort = {db.port}\nProcessConfig = pLogger\n{{\n  AppTick = 20\n"
            f"  CommsTick = 20\n  File = R\n  FileTimeStamp = false\n  PATH = {tmp_path}\n"
            f"  WildCardLogging = true\n  WildCardOmitPattern = *_STATUS, DB_*\n"
            f"  LoggingDirectorySummaryFile = {tmp_path}/summary\n}}\n"
        )
        async with MOOSClient("vehicle", port=db.port) as vehicle, pLogger.from_mission(mission):
            vehicle.subscribe("LOGGER_DIRECTORY")
            await wait_for(vehicle, "LOGGER_DIRECTORY")
            alog = tmp_path / "R" / "R.alog"
            for key in ("BEFORE", "LOGGER_RESTART", "AFTER"):
                vehicle.publish(key, "x")
                await vehicle.flush()
                if key == "LOGGER_RESTART":  # posted again once the new files are open
                    await wait_for(vehicle, "LOGGER_DIRECTORY")
            for _ in range(100):
                await asyncio.sleep(0.05)
                if "AFTER" in {e.name for e in AlogFile(alog)}:
                    break
    names = [e.name for e in AlogFile(alog) if e.source == "vehicle"]
    assert "BEFORE" not in names and names[-1] == "AFTER"


ROUND_TRIP_SECONDS = 120.0  # of MOOS time: 6 s at warp 20


def round_trip_posts() -> list[tuple[float, str, float | str | bytes]]:
    """(MOOS time from the start, variable, value) of a two-minute mission: navigation at 2 Hz,
    a status string every 2 s, a binary frame every 10 s."""
    posts: list[tuple[float, str, float | str | bytes]] = []
    for step in range(int(ROUND_TRIP_SECONDS * 2)):
        t = step * 0.5
        posts.append((t, "NAV_X", round(100 + 1.5 * t, 3)))
        if step % 4 == 1:
            posts.append((t + 0.1, "STATUS", f"mode = survey, leg {step // 4}, speed 1.5"))
        if step % 20 == 3:
            posts.append((t + 0.2, "FRAME", bytes([step % 256, 0, 255, 10])))
    return posts


@pytest.mark.e2e
async def test_a_two_minute_mission_logged_converted_and_replayed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The whole round trip a user makes after a mission: pLogger logs two minutes of a vehicle's
    posts; `pygoby log convert` gives every one of them as a row; `pygoby log replay` posts them
    into another MOOSDB in the same order with the same values and their original spacing (each
    message's time from the first within 10 % of the logged one)."""
    import pyarrow.parquet as pq

    posts = round_trip_posts()
    clock = moos_clock(WARP)
    async with MOOSDB(port=0, community="alpha", clock=clock) as db:
        mission = tmp_path / "m.moos"
        mission.write_text(MISSION.format(port=db.port, tmp=tmp_path))
        async with (
            MOOSClient("vehicle", port=db.port, clock=clock) as vehicle,
            pLogger.from_mission(mission),
        ):
            vehicle.subscribe("LOGGER_DIRECTORY")
            await wait_for(vehicle, "LOGGER_DIRECTORY")
            start = clock.now()
            for t, key, value in posts:  # on the mission's clock, from one origin (no drift)
                await asyncio.sleep(max(0.0, start + t - clock.now()) / WARP)
                vehicle.publish(key, value)
            await vehicle.flush()
            await asyncio.sleep(0.3)
    alog = tmp_path / "logs" / "Mission" / "Mission.alog"
    logged = [e for e in AlogFile(alog) if e.source == "vehicle"]
    assert [(e.name, e.value) for e in logged] == [(k, v) for _, k, v in posts]

    out = tmp_path / "m.parquet"
    assert pygoby_main(["log", "convert", str(alog), "-o", str(out)]) == 0
    table = pq.read_table(out).to_pylist()
    rows = [(r["name"], r["value_double"] if r["type"] == "double" else r["value"]) for r in table]
    assert [row for row in rows if row[0] in ("NAV_X", "STATUS", "FRAME")] == [
        (k, v.hex() if isinstance(v, bytes) else v) for _, k, v in posts
    ]

    async with MOOSDB(port=0) as other, MOOSClient("watcher", port=other.port) as watcher:
        for key in ("NAV_X", "STATUS", "FRAME"):
            watcher.subscribe(key)
        await watcher.flush()
        command = ["log", "replay", str(alog), "--port", str(other.port), "--warp", str(WARP)]
        command += ["--only", "NAV_X", "STATUS", "FRAME"]
        assert await asyncio.to_thread(pygoby_main, command) == 0
        capsys.readouterr()
        got = [await watcher.receive(5) for _ in posts]
    assert [(m.key, m.value, m.src) for m in got] == [(k, v, "vehicle") for _, k, v in posts]
    # spacing: a message's time since the first, stamped as the replay posted it, times the
    # warp, against the logged one (past the first few seconds, where 10 % is below the jitter
    # of a loaded machine's sleeps)
    for message, entry in zip(got, logged, strict=True):
        logged_since = entry.time - logged[0].time
        replayed_since = (message.time - got[0].time) * WARP
        if logged_since >= 5.0:
            assert replayed_since == pytest.approx(logged_since, rel=0.10), entry
