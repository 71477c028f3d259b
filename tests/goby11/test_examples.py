"""Seed 003's example missions, shipped in examples/goby1.1/ as printed, run under `pygoby
antler` (time-warped) and deliver the messages of the manual."""

from __future__ import annotations

import asyncio
import difflib
import json
import shutil
import signal
import socket
import sys
from pathlib import Path

import pytest
from google.protobuf import text_format

from pygoby.acomms import messages as acomms_pb
from pygoby.cli import main as pygoby_main
from pygoby.moos.alog.files import AlogFile
from pygoby.moos.alog.tools import summarize
from pygoby.moos.client import MOOSClient
from pygoby.moos.timewarp import moos_clock
from pygoby.util.geodesy import UTMGeodesy
from tests.goby11.seed_listings import EXAMPLES, LISTINGS, plogger_addition, printed

pytestmark = pytest.mark.e2e

PYGOBY = str(Path(sys.executable).with_name("pygoby"))
WARP = 20
# upstream Goby's line where the print is cut off (and shows %3$.01f / %6$1f for %3$.0lf / %6$lf)
SIMPLE_STATUS_FORMAT = (
    "        <format>NAME=%1%,TYPE=%2%,UTC_TIME=%3$.0lf,X=%4%,Y=%5%,LAT=%6$lf,"
    "LON=%7$lf,SPD=%8%,HDG=%9%,DEPTH=%10%</format>"
)


@pytest.mark.parametrize("name", sorted(LISTINGS))
def test_shipped_files_are_the_printed_ones(name):
    shipped = (EXAMPLES / name).read_text().splitlines()
    seed = printed(name).splitlines()
    changed = [
        line
        for line in difflib.unified_diff(seed, shipped, lineterm="", n=0)
        if line[:1] in "+-" and not line.startswith(("+++", "---"))
    ]
    if name == "xml/simple_status.xml":  # the one documented fix (README, Coming from Goby 1.1)
        assert changed == ["-" + seed[67], "+" + SIMPLE_STATUS_FORMAT]
        assert seed[67].endswith("HDG=%9%,DEP")
    elif name.endswith(".moos"):  # the one addition: pLogger (README, Coming from Goby 1.1)
        community = Path(name).stem
        assert [line for line in changed if line.strip("+-")] == [
            "+" + line for line in plogger_addition(community)
        ]
    else:
        assert changed == []


def free_port(kind=socket.SOCK_STREAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def localize(tmp_path: Path, example: str) -> tuple[Path, dict[str, int]]:
    """A copy of examples/goby1.1 where `example`'s missions use free ports, pty links under
    `tmp_path` and MOOSTimeWarp (the only changes: counted, so nothing else moves)."""
    root = tmp_path / "goby1.1"
    shutil.copytree(EXAMPLES, root)
    udp = free_port(socket.SOCK_DGRAM)
    ports = {}
    for node, default in (("mm1", 9101), ("mm2", 9102)):
        path = root / "MOOS" / example / f"{node}.moos"
        text = path.read_text()
        ports[node] = free_port()
        for old, new, count in (
            (f"ServerPort = {default}", f"ServerPort = {ports[node]}", 1),
            ("/tmp/ttyLOOP", f"{tmp_path}/ttyLOOP", 2),
            ("IPPort = 49234", f"IPPort = {udp}", 1),
            (f"Community = {node}", f"Community = {node}\nMOOSTimeWarp = {WARP}", 1),
        ):
            assert text.count(old) == count, (node, old)
            text = text.replace(old, new)
        path.write_text(text)
    return root / "MOOS" / example, ports


async def wait_for(port: int, var: str, accept, timeout: float = 90.0):
    """The first value of `var` on the DB at `port` that `accept` takes."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    async with MOOSClient(f"probe_{var.lower()}", port=port) as client:
        client.subscribe(var)
        while True:
            remaining = deadline - loop.time()
            assert remaining > 0, f"{var} with the expected value never arrived"
            try:
                msg = await client.receive(min(remaining, 5.0))
            except TimeoutError:
                continue
            if msg.key == var and accept(msg.value):
                return msg.value


async def run_pair(directory: Path, ports: dict[str, int], check):
    procs = []
    try:
        for node in ("mm1", "mm2"):
            procs.append(
                await asyncio.create_subprocess_exec(
                    PYGOBY,
                    "antler",
                    f"{node}.moos",
                    cwd=directory,
                    stdout=asyncio.subprocess.DEVNULL,
                    stderr=asyncio.subprocess.PIPE,
                )
            )
        await asyncio.sleep(1.0)
        return await check()
    finally:
        errors = []
        for proc in procs:
            if proc.returncode is None:
                proc.send_signal(signal.SIGINT)
            _, err = await asyncio.wait_for(proc.communicate(), 30)
            errors.append(err.decode())
        run_pair.stderr = errors


def goby11_transmission(value: str):
    out = acomms_pb.V1ModemDataTransmission()
    text_format.Parse(value, out)
    return out


async def test_basic_ccl_bytes_reach_mm2(tmp_path):
    """Example 1: uTimerScript posts OUT_TEST_32B on mm1; the CCL queue (id 2), the MAC slot, the
    Micro-Modem driver, iModemSim over UDP deliver the bytes 02 02 03 04 to mm2's IN_TEST_32B."""
    directory, ports = localize(tmp_path, "basic_ccl")

    async def check():
        value = await wait_for(ports["mm2"], "IN_TEST_32B", lambda v: isinstance(v, str))
        return goby11_transmission(value)

    received = await run_pair(directory, ports, check)
    assert received.data == b"\x02\x02\x03\x04"
    assert (received.base.src, received.base.dest, received.queue_key.id) == (1, 2, 2)
    assert not list(tmp_path.glob("ttyLOOP*"))  # the pairs iModemSim made are gone
    # each community's pLogger (pygoby's addition) left its log: what was sent and received
    assert "OUT_TEST_32B" in community_log(directory, "mm1")
    assert "IN_TEST_32B" in community_log(directory, "mm2")


async def test_ccl_and_dccl_simple_status_reaches_mm2(tmp_path):
    """Example 2, DCCL half: mm1's SIMPLE_STATUS (simple_status.xml, the initializers' NAV_*)
    decoded on mm2 and published as the XML says (the REMUS half: the test below)."""
    directory, ports = localize(tmp_path, "ccl_and_dccl")

    async def check():
        status = await wait_for(ports["mm2"], "STATUS_REPORT_IN", lambda v: "Node=1" in str(v))
        report = await wait_for(ports["mm2"], "NODE_REPORT", lambda v: "NAME=mm1" in str(v))
        return status, report

    status, report = await run_pair(directory, ports, check)
    fields = dict(item.split("=", 1) for item in status.split(","))
    assert {
        k: fields[k] for k in ("Node", "MessageType", "nav_x", "nav_y", "Speed", "Heading", "Depth")
    } == {
        "Node": "1",
        "MessageType": "LAMSS_STATUS",
        "nav_x": "100",
        "nav_y": "300",
        "Speed": "0",
        "Heading": "150",
        "Depth": "0",
    }
    assert float(fields["Timestamp"]) > 0  # Goby 1.1's header default: the time of creation
    node = dict(item.split("=", 1) for item in report.split(","))
    lat, lon = UTMGeodesy(42.35, -70.95).to_geo(100, 300)
    assert (node["NAME"], node["TYPE"], node["X"], node["Y"], node["HDG"]) == (
        "mm1",
        "topside",
        "100",
        "300",
        "150",
    )
    assert float(node["LAT"]) == pytest.approx(lat, abs=1e-9) and float(
        node["LON"]
    ) == pytest.approx(lon, abs=1e-9)
    assert not any("is not available" in err for err in run_pair.stderr)
    assert "STATUS_REPORT_IN" in community_log(directory, "mm2")
    assert "ACOMMS_MODEM_TRANSMIT" in community_log(directory, "mm1")
    # `pygoby log convert --mission`: the Goby 1.1 frame's DCCL1 bytes, read through the XML
    # message set, give what mm1 sent; QSIZE is read in Goby 1.1's form
    (log,) = (directory / "logs").glob("mm2_*/mm2_*.alog")
    out = directory / "mm2.jsonl"
    assert (
        pygoby_main(
            ["log", "convert", str(log), "--mission", str(directory / "mm2.moos"), "-o", str(out)]
        )
        == 0
    )
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    frames = [r for r in rows if r["name"] == "ACOMMS_MODEM_RECEIVE" and r["type"] == "string"]
    assert frames  # every frame mm2 heard is one of mm1's statuses
    for frame in frames:
        assert frame["ModemTransmission.src"] == "1"
        assert (frame["SIMPLE_STATUS.nav_x"], frame["SIMPLE_STATUS.nav_y"]) == ("100.0", "300.0")
        assert frame["SIMPLE_STATUS.MessageType"] == "LAMSS_STATUS"
    sizes = [r for r in rows if r["name"] == "ACOMMS_QSIZE"]
    assert sizes and all("QueueSize.key.id" in r for r in sizes)


def community_log(directory: Path, community: str) -> dict[str, int]:
    """{variable: entries} of the one .alog `community`'s pLogger wrote under logs/."""
    (path,) = (directory / "logs").glob(f"{community}_*/{community}_*.alog")
    return {name: row.count for name, row in summarize(AlogFile(path)).items()}


# Example 2 carries REMUS State frames only (CCL id 14, mm2 -> mm1); the Redirect command needs
# a CCL queue for id 7 on both nodes, on pREMUSCodec's default Redirect variables (README,
# "pREMUSCodec": with value_base 10 it beats SIMPLE_STATUS's queue after 18 s of waiting).
REDIRECT_QUEUE = """queue_cfg
{
    queue
    {
        key { type: QUEUE_CCL id: 7 }
        in_pubsub_var: "IN_REMUS_REDIRECT_HEX_30B"
        out_pubsub_var: "OUT_REMUS_REDIRECT_HEX_30B"
        name: "Remus_Redirect"
        value_base: 10
    }
"""
REDIRECT = (
    "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Latitude=42.36,Longitude=-70.94,"
    "SpeedDepthFlags=88,TransitSpeed=1.5,TransitDepth=10,TransitCommand=1,SurveySpeed=1.0,"
    "SurveyDepth=20,SurveyCommand=2,NumberOfRows=4,RowLength=200,RowSpacing0=20,"
    "RowSpacing1=30,RowHeading=90,StartLatitude=42.35,StartLongitude=-70.95"
)


def key_values(text: str) -> dict[str, str]:
    return dict(item.split("=", 1) for item in text.split(","))


async def test_ccl_and_dccl_remus_state_reaches_mm1_and_a_redirect_reaches_mm2(tmp_path):
    """Example 2, REMUS half: mm2's pREMUSCodec (create_status) encodes its NAV_* (the
    initializers: x 123, y 321, heading 45, speed 1.2, depth 111) as a CCL State frame every 10 s;
    the CCL queue (id 14), MAC, Micro-Modem driver and iModemSim carry it to mm1, whose
    pREMUSCodec posts NODE_REPORT and MM2_NAV_*. An OUTGOING_COMMAND CCL_REDIRECT on mm1 reaches
    mm2 as CCL_REDIRECT_IN with the values sent."""
    directory, ports = localize(tmp_path, "ccl_and_dccl")
    for node in ("mm1", "mm2"):
        path = directory / f"{node}.moos"
        text = path.read_text()
        start = text.index("queue_cfg")
        end = text.index("{", start) + 1
        path.write_text(text[:start] + REDIRECT_QUEUE + text[end:])

    async def check():
        report = key_values(
            await wait_for(ports["mm1"], "NODE_REPORT", lambda v: "NAME=mm2" in str(v))
        )
        contacts = {
            var: await wait_for(ports["mm1"], f"MM2_NAV_{var}", lambda v: isinstance(v, float))
            for var in ("X", "Y", "SPEED", "HEADING", "DEPTH", "LAT", "LONG")
        }
        status = key_values(
            await wait_for(ports["mm1"], "STATUS_REPORT_IN", lambda v: "CCL_STATUS" in str(v))
        )
        async with MOOSClient("operator", port=ports["mm1"], clock=moos_clock(WARP)) as operator:
            operator.publish("OUTGOING_COMMAND", REDIRECT)
            await operator.flush()
        redirect = key_values(
            await wait_for(ports["mm2"], "CCL_REDIRECT_IN", lambda v: isinstance(v, str))
        )
        return report, contacts, status, redirect

    report, contacts, status, redirect = await run_pair(directory, ports, check)
    assert (report["NAME"], report["TYPE"], report["MODE"], report["MOOSDB_TIME"]) == (
        "mm2",
        "auv",
        "NOMOOS",
        "-1",
    )
    # what mm2 sent, within the frame's resolution (lat/lon ~2 m, heading 360/255, 2.5 cm/s)
    sent = {"X": 123.0, "Y": 321.0, "SPEED": 1.2, "HEADING": 45.0, "DEPTH": 111.0}
    within = {"X": 2.5, "Y": 2.5, "SPEED": 0.02, "HEADING": 360 / 255 / 2, "DEPTH": 0.1}
    for var, value in sent.items():
        assert contacts[var] == pytest.approx(value, abs=within[var]), var
    for key, var in (
        ("X", "X"),
        ("Y", "Y"),
        ("SPD", "SPEED"),
        ("HDG", "HEADING"),
        ("DEPTH", "DEPTH"),
        ("LAT", "LAT"),
        ("LON", "LONG"),
    ):
        assert float(report[key]) == contacts[var], key  # the same numbers, 17 digits
    lat, lon = UTMGeodesy(42.35, -70.95).to_geo(123, 321)
    assert contacts["LAT"] == pytest.approx(lat, abs=2.2e-5) and contacts["LONG"] == pytest.approx(
        lon, abs=2.2e-5
    )
    assert float(report["YAW"]) == pytest.approx(float(report["HDG"]) - 360)
    assert (status["Node"], float(status["Speed"]), float(status["Depth"])) == (
        "2",
        contacts["SPEED"],
        111.0,
    )
    assert redirect["DestinationPlatformId"] == "2" and redirect["SpeedDepthFlags"] == "88"
    expected = key_values(REDIRECT)
    for key in ("Latitude", "Longitude", "StartLatitude", "StartLongitude"):
        assert float(redirect[key]) == pytest.approx(float(expected[key]), abs=1.1e-5), key
    for key in ("TransitSpeed", "TransitDepth", "SurveySpeed", "SurveyDepth"):
        assert float(redirect[key]) == float(expected[key]), key  # on a step: exact
    for key in (
        "TransitCommand",
        "SurveyCommand",
        "NumberOfRows",
        "RowLength",
        "RowSpacing0",
        "RowSpacing1",
    ):
        assert redirect[key] == expected[key], key
    assert float(redirect["RowHeading"]) == pytest.approx(90, abs=360 / 255 / 2)


def test_antler_block_of_the_seed_with_xconfig_and_geometry_lines():
    from pygoby.moos.moosfile import MissionFile

    config = MissionFile.read(EXAMPLES / "MOOS" / "ccl_and_dccl" / "mm1.moos").antler()
    assert [(r.program, r.options.get("XConfig")) for r in config.runs] == [
        ("MOOSDB", None),
        ("pREMUSCodec", "1"),
        ("pAcommsHandler", "2"),
        ("iModemSim", "3"),
        ("pLogger", None),  # pygoby's addition
    ]
    assert config.ms_between_launches == 10
