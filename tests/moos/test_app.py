"""GobyMOOSApp: configuration (TextFormat block, globals, errors, --example_config), initializers,
mail handling, ticks, timers and the command line, against the embedded MOOSDB."""

from __future__ import annotations

import asyncio
import contextlib
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import ConfigError
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.moosfile import MissionFile
from pygoby.util.aiorun import STOP_GRACE
from tests.faults import CuttableRelay
from tests.hypothesis_profiles import examples

sys.path.insert(0, str(Path(__file__).resolve().parent))
from example_app import pTestApp

HERE = Path(__file__).resolve().parent


def _mission(port: int, block: str, extra: str = "") -> str:
    return f"""\
ServerHost = localhost
ServerPort = {port}
Community  = alpha
LatOrigin  = 42.35
VehicleName = ship one
{extra}
ProcessConfig = pOther
{{
  LongOrigin = 5
}}
ProcessConfig = pTestApp
{{
{block}
}}
"""


BLOCK = """\
  common {
    log: false
    app_tick: 20
    verbosity: QUIET
    lat_origin: 1.0   // kept: globals fill only unset fields (quirk Q2, fixed)
    server_host: "127.0.0.1"  // not "http://x" // a comment
    initializer { type: INI_DOUBLE  moos_var: "LAT_ORIGIN"  global_cfg_var: "LatOrigin" }
    initializer { type: INI_STRING  moos_var: "VEHICLE"  global_cfg_var: "VehicleName" }
    initializer { type: INI_STRING  moos_var: "GREETING"  sval: "  hi  " }
    initializer { type: INI_DOUBLE  moos_var: "CONST"  dval: 2.5 }
    initializer { type: INI_DOUBLE  moos_var: "NEVER"  global_cfg_var: "NoSuchGlobal" }
  }
  gain: 2
  out_var: "ECHO"
"""


def test_configuration_globals_and_defaults():
    mission = MissionFile.from_text(_mission(9123, BLOCK))
    cfg = pTestApp.read_config(mission, "pTestApp")
    assert cfg.common.lat_origin == 1.0
    assert cfg.common.community == "alpha"
    assert cfg.common.server_port == 9123 and cfg.common.server_host == "127.0.0.1"
    assert not cfg.common.HasField("lon_origin")  # LongOrigin inside pOther's block: not global
    assert cfg.gain == 2.0 and cfg.mode == cfg.SLOW
    assert cfg.common.app_tick == 20 and cfg.common.comm_tick == 10


def test_command_line_overrides():
    mission = MissionFile.from_text(_mission(9123, BLOCK))
    cfg = pTestApp.read_config(
        mission, "pTestApp", [("gain", "4"), ("common", "app_tick: 5"), ("out_var", 'say "hi"')]
    )
    assert cfg.gain == 4 and cfg.common.app_tick == 5 and cfg.out_var == 'say "hi"'
    assert cfg.common.verbosity == 1 and not cfg.common.log  # merged into the block's common
    with pytest.raises(ConfigError, match="unknown option --nope"):
        pTestApp.read_config(mission, "pTestApp", [("nope", "1")])


def test_parse_error_names_line_and_field(tmp_path):
    text = _mission(9000, '  common { log: false }\n  gain: fast\n  out_var: "X"')
    path = tmp_path / "m.moos"
    path.write_text(text)
    with pytest.raises(ConfigError) as err:
        pTestApp.read_config(MissionFile.read(path), "pTestApp")
    line = text.splitlines().index("  gain: fast") + 1
    assert line == 14
    assert f"m.moos:{line}:" in str(err.value) and "gain" in str(err.value)
    with pytest.raises(ConfigError, match='no field named "AppTick"'):
        pTestApp.read_config(MissionFile.from_text(_mission(9000, "  AppTick = 4")), "pTestApp")
    with pytest.raises(ConfigError, match="no ProcessConfig block for pMissing"):
        pTestApp.read_config(MissionFile.from_text(_mission(9000, BLOCK)), "pMissing")
    with pytest.raises(ConfigError, match="out_var"):
        pTestApp.read_config(MissionFile.from_text(_mission(9000, "  gain: 1")), "pTestApp")


def test_enum_global_must_be_a_value_name():
    mission = MissionFile.from_text(_mission(9000, BLOCK, "moos_parser_technique = NOPE"))
    with pytest.raises(ConfigError, match="invalid enumeration"):
        pTestApp.read_config(mission, "pTestApp")


def test_main_stops_on_config_error_before_connecting(tmp_path, capsys):
    path = tmp_path / "m.moos"
    path.write_text(_mission(1, '  common { app_tick: many }\n  out_var: "X"'))
    assert pTestApp.main([str(path)], prog="pTestApp") == 1
    err = capsys.readouterr().err
    assert (
        "fatal configuration error" in err and "m.moos:13: app_tick: Couldn't parse integer" in err
    )


def test_example_config():
    text = pTestApp.example_config("pTestApp")
    lines = text.splitlines()
    assert lines[:2] == ["ProcessConfig = pTestApp", "{"] and lines[-1] == "}"
    assert lines[2].startswith("  common {  # Configuration common")
    assert "    log: true  # Should we write a text log of the terminal " in lines
    assert any("(default=true) (can also set " in ln for ln in lines)
    assert '    community: "AUV23"  # The vehicle\'s name (optional) (can also ' in lines
    assert "  mode: SLOW  #  (FAST, SLOW) (optional) (default=SLOW)" in lines
    assert any(ln.startswith('  out_var: "OUT"  # Variable to publish (required)') for ln in lines)
    assert "hidden" not in text  # cfg.action NEVER
    assert any(ln.startswith("  [pygoby.test.extra_gain]:   # An extension field") for ln in lines)
    assert "(INI_DOUBLE, " in text and "(repeated)" in text
    # the example parses back as a configuration (once the enum without a value gets one)
    body = "\n".join(lines[2:-1]).replace("type:   #", "type: INI_DOUBLE  #")
    body = body.replace("extra_gain]:   #", "extra_gain]: 2  #")
    pTestApp.read_config(
        MissionFile.from_text(f"ProcessConfig = pTestApp\n{{\n{body}\n}}"), "pTestApp"
    )


async def _wait_for(cond, timeout=3.0):
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while not cond():
        assert loop.time() < deadline, "condition not met in time"
        await asyncio.sleep(0.02)


async def test_app_runs_against_embedded_db():
    async with (
        MOOSDB(port=0, community="alpha") as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        tester.publish("NAV_X", 100.0)  # written before the app starts: stale for it
        await tester.flush()
        mission = MissionFile.from_text(_mission(db.port, BLOCK))
        cfg = pTestApp.read_config(mission, "pTestApp")
        await asyncio.sleep(0.02)
        app = pTestApp(cfg, name="pTestApp", mission=mission)
        async with app:
            for var in (
                "ECHO",
                "LAT_ORIGIN",
                "VEHICLE",
                "GREETING",
                "CONST",
                "NEVER",
                "PTESTAPP_STATUS",
            ):
                tester.subscribe(var)
            got: dict[str, list] = {}

            async def collect(*keys):
                while not set(keys) <= set(got):
                    msg = await tester.receive(3)
                    got.setdefault(msg.key, []).append(msg.value)

            await collect("LAT_ORIGIN", "VEHICLE", "GREETING", "CONST")
            assert got["LAT_ORIGIN"] == [42.35] and got["VEHICLE"] == ["shipone"]
            assert got["GREETING"] == ["hi"] and got["CONST"] == [2.5]
            await _wait_for(lambda: "NAV_X" in app.dynamic_vars)
            assert app.seen == []  # the snapshot of NAV_X predates the app: not handled
            tester.publish("NAV_X", 3.0)
            tester.publish("PAT_A", "p")
            await collect("ECHO")
            assert got["ECHO"] == [6.0] and app.seen == [3.0]
            await _wait_for(lambda: app.pattern_seen and app.timer_fired >= 1 and app.ticks >= 5)
            assert app.pattern_seen[0].key == "PAT_A"
            await collect("PTESTAPP_STATUS")
            assert "MOOSName=pTestApp" in got["PTESTAPP_STATUS"][0]
            assert "NEVER" not in got


async def test_app_reconnects_reposts_initializers_and_keeps_queued_posts(caplog):
    db = MOOSDB(port=0)
    await db.start()
    port = db.port
    mission = MissionFile.from_text(_mission(port, BLOCK))
    app = pTestApp(pTestApp.read_config(mission, "pTestApp"), name="pTestApp", mission=mission)
    app.log.addHandler(caplog.handler)  # the app's log does not propagate to the root
    await app.start(connect_timeout=3)
    await db.stop()
    await _wait_for(lambda: not app.connected)
    assert "lost the connection to the MOOSDB" in caplog.text
    app.publish("WHILE_AWAY", 1.0)
    db = MOOSDB(port=port)
    await db.start()
    try:
        async with MOOSClient("tester", port=port) as tester:
            await app.client.wait_connected(2.0)
            tester.subscribe("WHILE_AWAY")
            tester.subscribe("CONST")
            keys = {(await tester.receive(3)).key for _ in range(2)}
            assert keys == {"WHILE_AWAY", "CONST"}
            tester.publish("NAV_X", 1.0)  # the app re-subscribed
            await _wait_for(lambda: app.seen == [1.0])
    finally:
        await app.stop()
        await db.stop()


async def test_a_clean_stop_is_not_reported_as_a_lost_connection(caplog):
    async with MOOSDB(port=0) as db:
        mission = MissionFile.from_text(_mission(db.port, BLOCK))
        app = pTestApp(pTestApp.read_config(mission, "pTestApp"), name="pTestApp", mission=mission)
        await app.start(connect_timeout=3)
        with caplog.at_level("INFO", logger="pygoby.app.pTestApp"):
            await app.stop()
        assert "disconnected from the MOOSDB" in caplog.text
        assert "lost the connection" not in caplog.text


async def test_command_line_and_example_config_as_a_program(tmp_path):
    script = HERE / "example_app.py"
    shown = subprocess.run(
        [sys.executable, str(script), "--example_config"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert shown.returncode == 0 and shown.stdout.startswith("ProcessConfig = pTestApp\n{\n")
    async with MOOSDB(port=0) as db, MOOSClient("tester", port=db.port) as tester:
        block = BLOCK.replace("pTestApp", "pAlias")
        path = tmp_path / "m.moos"
        path.write_text(
            _mission(db.port, block).replace("ProcessConfig = pTestApp", "ProcessConfig = pAlias")
        )
        tester.subscribe("ECHO")
        proc = await asyncio.create_subprocess_exec(
            sys.executable, str(script), str(path), "pAlias"
        )
        try:
            await _wait_for(lambda: "pAlias" in db.client_names, timeout=10)
            await asyncio.sleep(0.3)
            tester.publish("NAV_X", 5.0)
            msg = await tester.receive(5)
            assert (msg.key, msg.value, msg.src) == ("ECHO", 10.0, "pAlias")
        finally:
            proc.terminate()
            assert await asyncio.wait_for(proc.wait(), 10) == 0


async def _app_process(
    tmp_path: Path, db_port: int, script: str = "example_app.py"
) -> asyncio.subprocess.Process:
    """`script` run as a program on a mission whose DB is at `db_port` (pipes for its output)."""
    path = tmp_path / "m.moos"
    path.write_text(_mission(db_port, BLOCK))
    return await asyncio.create_subprocess_exec(
        sys.executable,
        str(HERE / script),
        str(path),
        "pTestApp",
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )


async def test_a_second_instance_with_a_taken_name_exits_with_a_clear_error(tmp_path):
    async with MOOSDB(port=0) as db:
        first = await _app_process(tmp_path, db.port)
        try:
            await _wait_for(lambda: "pTestApp" in db.client_names, timeout=10)
            second = await _app_process(tmp_path, db.port)
            _, err = await asyncio.wait_for(second.communicate(), 10)
            assert second.returncode == 1
            assert 'A client of this name ("pTestApp") already exists' in err.decode()
            assert "is another pTestApp running?" in err.decode()
            assert first.returncode is None and "pTestApp" in db.client_names
        finally:
            first.terminate()
            assert await asyncio.wait_for(first.wait(), 10) == 0


@pytest.mark.e2e  # (an app process)
async def test_an_app_refused_on_reconnect_keeps_trying(tmp_path):
    # The app's link to the DB breaks without the DB noticing (it keeps the stale session for
    # its client timeout and refuses the name meanwhile): the app must come back by itself.
    async with (
        MOOSDB(port=0, client_timeout=1.5) as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        relay = CuttableRelay(db.port)
        await relay.start()
        proc = await _app_process(tmp_path, relay.port)
        try:
            tester.subscribe("ECHO")
            await _wait_for(lambda: "pTestApp" in db.client_names, timeout=10)
            relay.cut()
            # (the DB lists the stale session until its client timeout, so the name alone does
            # not show the app is back: its echo does)
            async with asyncio.timeout(20):
                while True:
                    tester.publish("NAV_X", 4.0)
                    with contextlib.suppress(TimeoutError):
                        msg = await _expect_key(tester, "ECHO", 1)
                        break
            assert (msg.value, msg.src) == (8.0, "pTestApp")
        finally:
            proc.terminate()
            await asyncio.wait_for(proc.communicate(), 10)
            await relay.close()
        assert proc.returncode == 0


@pytest.mark.e2e  # (an app process, its stop hanging)
@pytest.mark.parametrize("signals", [["SIGTERM"], ["SIGINT"], ["SIGTERM", "SIGINT"]])
async def test_a_signal_ends_an_app_whose_stop_hangs(tmp_path, signals):
    async with MOOSDB(port=0) as db:
        proc = await _app_process(tmp_path, db.port, "stuck_app.py")
        try:
            await _wait_for(lambda: "pTestApp" in db.client_names, timeout=10)
            loop = asyncio.get_running_loop()
            started = loop.time()
            proc.send_signal(getattr(signal, signals[0]))
            assert await asyncio.wait_for(proc.stdout.readline(), 5) == b"stopping\n"
            for name in signals[1:]:  # a second signal: at once
                proc.send_signal(getattr(signal, name))
            _, err = await asyncio.wait_for(proc.communicate(), STOP_GRACE + 5)
        finally:
            if proc.returncode is None:
                proc.kill()
        took = loop.time() - started
        last = getattr(signal, signals[-1])
        assert proc.returncode == 128 + last
        if len(signals) == 1:
            assert f"pTestApp: did not stop within {STOP_GRACE:g} s; exiting now" in err.decode()
            assert took >= STOP_GRACE
        else:
            assert "pTestApp: second SIGINT; exiting now" in err.decode()
            assert took < STOP_GRACE


async def _expect_key(client: MOOSClient, key: str, timeout: float):
    async with asyncio.timeout(timeout):
        while (msg := await client.receive()).key != key:
            pass
    return msg


def test_subclass_without_config_is_an_error():
    class Bare(GobyMOOSApp):
        pass

    with pytest.raises(TypeError, match="config_class or config_proto"):
        Bare.load_config_class()


async def test_log_file_named_after_app_and_community(tmp_path):
    block = BLOCK.replace("log: false", f'log: true log_path: "{tmp_path}"')
    mission = MissionFile.from_text(_mission(1, block))
    app = pTestApp(pTestApp.read_config(mission, "pTestApp"), name="pTestApp", mission=mission)
    await app.start()  # no DB on port 1: the app keeps trying, logging works regardless
    app.log.warning("hello log")
    await app.stop()
    files = sorted(p.name for p in tmp_path.iterdir())
    assert len(files) == 2 and files[1] == "pTestApp_alpha_latest.txt"
    assert files[0].startswith("pTestApp_alpha_2") and files[0].endswith(".txt")
    assert "hello log" in (tmp_path / files[1]).read_text()


@settings(max_examples=examples(200), deadline=None)
@given(st.text(alphabet=st.sampled_from('abc_:{}"#/ \n0123.-=common gain out_var'), max_size=120))
def test_fuzz_config_block_gives_config_errors_only(text):
    mission = MissionFile.from_text(f"ProcessConfig = pTestApp\n{{\n{text}\n}}\n")
    try:
        pTestApp.read_config(mission, "pTestApp")
    except ConfigError as err:
        assert str(err)
