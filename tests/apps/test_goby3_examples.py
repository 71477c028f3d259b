"""goby3-examples' pAcommsHandler missions run as a user runs them, `pygoby antler mm1.moos` and
`pygoby antler mm2.moos`, with only paths changed: dual_status (tests/apps/data/dual_status, UDP
multicast), where the two vehicles exchange their SimpleStatus messages, and ccl_and_dccl
(tests/apps/data/ccl_and_dccl), where vehicle 1 sends a REMUS CCL State and vehicle 2 a
SimpleStatus whose depth it never had."""

from __future__ import annotations

import asyncio
import os
import random
import re
import shutil
import signal
import socket
import sys
from pathlib import Path

import pytest

from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.errors import ConfigError

from .acomms_mission import Recorder

pytestmark = pytest.mark.e2e

DATA = Path(__file__).resolve().parent / "data" / "dual_status"
CCL_DATA = Path(__file__).resolve().parent / "data" / "ccl_and_dccl"
BIN = str(Path(sys.executable).parent)
LIBRARY_LINE = 'load_shared_library: "../../../../../build/lib/libgobyexample_protobuf.so"'


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def copy_mission(
    tmp_path: Path, multicast_port: int, data: Path = DATA
) -> dict[int, tuple[Path, int]]:
    """The missions in tmp_path with their ports changed (so parallel runs do not meet);
    {modem id: (mission, ServerPort)}."""
    shutil.copy(DATA / "simple_status.proto", tmp_path)
    missions = {}
    for modem_id in (1, 2):
        text = (data / f"mm{modem_id}.moos").read_text()
        port = _free_port()
        text = re.sub(r"ServerPort = \d+", f"ServerPort = {port}", text)
        text = text.replace("multicast_port: 50021", f"multicast_port: {multicast_port}")
        path = tmp_path / f"mm{modem_id}.moos"
        path.write_text(text)
        missions[modem_id] = (path, port)
    return missions


def test_the_compiled_message_library_gets_one_clear_sentence(tmp_path):
    missions = copy_mission(tmp_path, 50021)
    with pytest.raises(ConfigError) as info:
        pAcommsHandler.from_mission(missions[1][0])
    lines = missions[1][0].read_text().splitlines()
    line = next(i for i, text in enumerate(lines, 1) if "load_shared_library" in text)
    assert str(info.value) == (
        f'{missions[1][0]}:{line}: load_shared_library: "../../../../../build/lib/'
        'libgobyexample_protobuf.so": pygoby cannot load compiled C++ libraries; use '
        "load_proto_file with the .proto file(s) the library was built from instead"
    )


def with_proto_file(missions: dict[int, tuple[Path, int]]) -> None:
    """The only change a user makes: the compiled example messages become their .proto."""
    for path, _ in missions.values():
        path.write_text(
            path.read_text().replace(LIBRARY_LINE, 'load_proto_file: "simple_status.proto"')
        )


async def start_antlers(missions: dict[int, tuple[Path, int]]) -> list:
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    return [
        await asyncio.create_subprocess_exec(
            f"{BIN}/pygoby",
            "antler",
            str(path),
            env=env,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT,
        )
        for path, _ in missions.values()
    ]


async def start_recorders(
    missions: dict[int, tuple[Path, int]], variables: list[str]
) -> list[Recorder]:
    recorders = [Recorder(f"watch{i}", port) for i, (_, port) in missions.items()]
    for recorder in recorders:
        async with asyncio.timeout(30):
            while True:
                try:
                    await recorder.start(variables)
                    break
                except (OSError, TimeoutError):  # antler is still starting the DB
                    await asyncio.sleep(0.2)
    return recorders


async def run_until_heard(
    missions: dict[int, tuple[Path, int]], variables: list[str], wanted: list[tuple[int, str]]
) -> tuple[list[str], list[Recorder], list[asyncio.subprocess.Process], list[str]]:
    """Both vehicles' antlers, run until each (recorder index, variable) of `wanted` is heard
    (60 s each), then stopped with SIGINT: the values heard, the recorders, the antlers and
    their outputs."""
    antlers = await start_antlers(missions)
    recorders: list[Recorder] = []
    try:
        recorders = await start_recorders(missions, variables)
        heard = [await recorders[i].wait_for(var, timeout=60) for i, var in wanted]
    finally:
        for recorder in recorders:
            await recorder.close()
        for antler in antlers:
            antler.send_signal(signal.SIGINT)
        outputs = [(await asyncio.wait_for(a.communicate(), 30))[0].decode() for a in antlers]
    return heard, recorders, antlers, outputs


async def test_dual_status_mission_runs_with_paths_changed(tmp_path):
    missions = copy_mission(tmp_path, random.randint(40000, 60000))
    with_proto_file(missions)
    # 10 s TDMA slots each, a status every 5 s: one cycle (20 s) plus start-up
    (from_1, from_2), recorders, antlers, outputs = await run_until_heard(
        missions,
        ["STATUS_REPORT_IN", "STATUS_REPORT_IN_PB"],
        [(1, "STATUS_REPORT_IN"), (0, "STATUS_REPORT_IN")],
    )
    # the initializers' values, across the multicast link
    assert re.fullmatch(
        r"timestamp=[\d.]+,src=1,dest=2,x=150,y=200,speed=1\.4,heading=125,depth=23", from_1
    )
    assert re.fullmatch(
        r"timestamp=[\d.]+,src=2,dest=1,x=550,y=125,speed=1\.6,heading=213,depth=20", from_2
    )
    assert (
        recorders[1].values("STATUS_REPORT_IN_PB")[0].startswith("@PB[goby.example.SimpleStatus] ")
    )
    for antler, out in zip(antlers, outputs, strict=True):
        lines = out.splitlines()
        assert antler.returncode == 0, out
        assert (
            "antler: uXMS: uXMS is not available (no such program on PATH); the other "
            "processes run without it"
        ) in lines  # MOOS-IvP's, not ours
        assert "antler: pAcommsHandler exited with status 0" in lines
        assert any(
            line.endswith("show_gui: standard output is not a terminal; the log stays plain text")
            for line in lines
        )
        assert any(
            re.search(
                r"^pAcommsHandler \| pAcommsHandler \[.*\{goby::acomms::modemdriver::out::"
                r"UDP_MULTICAST::\d\}: >> <\d+ B> ",
                line,
            )
            for line in lines
        )  # DEBUG1


async def test_ccl_and_dccl_mission_runs_with_paths_changed(tmp_path):
    # Vehicle 2 never has DEPTH (the example initialises it on vehicle 1 only), so its create
    # rule `depth:=%14%` matches nothing: goby3 still creates the SimpleStatus (depth NaN, the
    # rest filled) and sends it, and so do we, with one warning. goby3's pTranslator's output
    # for this entry is recorded in tests/data/goby3 (test_goby3_recorded.py).
    missions = copy_mission(tmp_path, random.randint(40000, 60000), CCL_DATA)
    with_proto_file(missions)
    # 10 s TDMA slots each, a message every 5 s: one cycle (20 s) plus start-up
    (from_2, from_1), _, antlers, outputs = await run_until_heard(
        missions,
        ["STATUS_REPORT_IN", "REMUS_STATUS_REPORT_IN"],
        [(0, "STATUS_REPORT_IN"), (1, "REMUS_STATUS_REPORT_IN")],
    )
    # The NaN depth crosses DCCL as goby3's x86-64 build sends it: as the field's minimum.
    assert re.fullmatch(
        r"timestamp=[\d.]+,src=2,dest=1,x=550,y=125,speed=1\.6,heading=213,depth=0", from_2
    ), from_2
    assert from_1.startswith("@PB[dccl.legacyccl.protobuf.CCLMDATState] ")
    for expected in ("mission_mode: NORMAL", "battery_percent: 85", "watts: 20"):
        assert expected in from_1
    warnings = [
        line
        for line in outputs[1].splitlines()
        if "goby.example.SimpleStatus from DEPTH: input '' does not match format" in line
    ]
    assert len(warnings) == 1, outputs[1]  # once a minute
    assert "no 'd' (format character 0) in the input after character 0" in warnings[0]
    assert "does not match format" not in outputs[0]  # vehicle 1 has its DEPTH
    for antler, out in zip(antlers, outputs, strict=True):
        assert antler.returncode == 0, out
