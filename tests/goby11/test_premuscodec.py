"""pREMUSCodec (seed 003 §2.5, spec goby-moos-apps.md §7): the exact MOOS strings and contact
variables for every frame type, the Redirect command parser, and the app against the embedded
MOOSDB (frames in, bad frames skipped with the reason, create_status every 10 s once all NAV_*
have arrived, OUTGOING_COMMAND -> Redirect), its configuration and console script."""

from __future__ import annotations

import asyncio
import itertools
import subprocess
import sys
from pathlib import Path

import pytest
from google.protobuf import text_format

from pygoby.acomms import messages as acomms_pb
from pygoby.apps.premuscodec import pREMUSCodec
from pygoby.dccl.ccl.remus import (
    Alert,
    Alert2,
    Alert2Contact,
    AlertContact,
    CCLEncodeError,
    CCLFrameError,
    Position,
    Ranger,
    Redirect,
    State,
    TimeDate,
)
from pygoby.errors import ConfigError
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.timewarp import moos_clock
from pygoby.moosacomms.remus_reports import RemusReports
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.modem_id import ModemIdLookup

pytestmark = pytest.mark.e2e

LOOKUP = ModemIdLookup.from_text("1,mm1,topside\n2,mm2,auv\n")
NOW = 1_700_000_001.5


@pytest.fixture
def reports() -> RemusReports:
    return RemusReports(UTMGeodesy(42.35, -70.95), LOOKUP)


# ------------------------------------------------------------------ the strings, exactly
def test_state_posts_exactly_as_goby_11(reports):
    data = reports.state_frame(123, 321, 111, 1.2, 45, now=1_700_000_000.25)
    assert data.hex() == "0e1d1e1e348ccd00d558b7201f040000000000001e0000000000000000000000"
    assert reports.incoming("state", data, src=2, dest=1, now=NOW) == [
        (
            "STATUS_REPORT_IN",
            "MessageType=CCL_STATUS,Node=2,Timestamp=1700000001.5,Latitude=42.352922243228228,"
            "Longitude=-70.948599690031969,Speed=1.2000000476837158,Heading=45.176470588235297,Depth=111,"
            "GoalLatitude=0,GoalLongitude=0,Batterypercent=0,GFI=0,Pitch=0,Oil=0",
        ),
        ("MM2_NAV_UTC", NOW),
        ("MM2_NAV_X", 122.77637262217468),
        ("MM2_NAV_Y", 321.84643903840333),
        ("MM2_NAV_LAT", 42.35292224322823),
        ("MM2_NAV_LONG", -70.94859969003197),
        ("MM2_NAV_SPEED", 1.2000000476837158),
        ("MM2_NAV_DEPTH", 111.0),
        ("MM2_NAV_HEADING", 45.1764705882353),
        (
            "NODE_REPORT",
            "NAME=mm2,TYPE=auv,MOOSDB_TIME=-1,UTC_TIME=1700000001.5,X=122.77637262217468,"
            "Y=321.84643903840333,LAT=42.352922243228228,LON=-70.948599690031969,SPD=1.2000000476837158,"
            "HDG=45.176470588235297,YAW=-314.8235294117647,DEPTH=111,LENGTH=4.0,MODE=NOMOOS,ALLSTOP=NotUsingIvP",
        ),
    ]


def test_ranger_posts(reports):
    data = Ranger(latitude=42.35, longitude=-70.95, speed=1.2, heading=45.5, depth=111).encode()
    posts = dict(reports.incoming("ranger", data, src=2, dest=1, now=NOW))
    assert posts["STATUS_REPORT_IN"] == (
        "MessageType=CCL_STATUS,Node=2,Timestamp=1700000001.5,"
        "Latitude=42.350000000000001,Longitude=-70.950000000000003,"
        "Speed=1.2000000000000002,Heading=45.5,Depth=111"
    )
    assert posts["NODE_REPORT"].startswith(
        "NAME=mm2,TYPE=auv,MOOSDB_TIME=-1,UTC_TIME=1700000001.5,X=0,Y=0,"
    )
    assert (posts["MM2_NAV_X"], posts["MM2_NAV_HEADING"], posts["MM2_NAV_DEPTH"]) == (
        0.0,
        45.5,
        111.0,
    )


def test_position_alert_and_alert2_posts(reports):
    position = Position(latitude=42.3, longitude=-70.9, type=2, label="buoy").encode()
    posts = reports.incoming("state", position, src=3, dest=0, now=5.0)  # id 8 read as a Position
    assert posts[0] == (
        "CCL_POSITION_IN",
        "MessageType=CCL_POSITION,Node=3,Type=Gateway Buoy,Timestamp=5,"
        "Latitude=42.300007617474513,Longitude=-70.89999805688835,Label=buoy",
    )
    assert [var for var, _ in posts[1:]] == [
        "3_NAV_UTC",
        "3_NAV_X",
        "3_NAV_Y",
        "3_NAV_LAT",
        "3_NAV_LONG",
    ]
    alert = Alert(
        oasis_time=123456,
        latitude=1,
        longitude=-2,
        heading=30,
        contacts=[AlertContact(1, 2, 3, 4, 5), AlertContact(600, 7, 8, 9, 10), AlertContact()],
    ).encode()
    assert reports.incoming("alert", alert, src=2, dest=0, now=5.0) == [
        (
            "CCL_ALERT_IN",
            (
                "MessageType=CCL_ALERT,Node=2,Timestamp=123456,Latitude=0.99999201297664797,Longitude=-2.000005483627973,"
                "Heading=29.647058823529413,Contact1Id=1,Contact1Age=2,Contact1Bearing=3,Contact1Signature1=4,"
                "Contact1Signature2=5,Contact2Id=600,Contact2Age=7,Contact2Bearing=8,Contact2Signature1=9,"
                "Contact2Signature2=10,Contact3Id=0,Contact3Age=0,Contact3Bearing=0,Contact3Signature1=0,"
                "Contact3Signature2=0"
            ),
        )
    ]
    alert2 = Alert2(
        oasis_time=7,
        latitude=1,
        longitude=-2,
        contacts=[Alert2Contact(1, 2, 3, 45, True, 4, 5), Alert2Contact(), Alert2Contact()],
    ).encode()
    ((var, text),) = reports.incoming("alert2", alert2, src=2, dest=0, now=5.0)
    assert var == "CCL_ALERT2_IN" and text.startswith(
        "MessageType=CCL_ALERT2,Node=2,Timestamp=7,Latitude=0.99999201297664797,Longitude=-2.000005483627973,"
        "Contact1Id=1,Contact1Age=2,Contact1Bearing=3,Contact1HeadingType=Absolute,"
        "Contact1Heading=45.176470588235297,Contact1Signature1=4,Contact1Signature2=5,Contact2Id=0,"
    )
    assert "Contact2HeadingType=Vehicle,Contact2Heading=0," in text


COMMAND = (
    "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Timestamp=5,Latitude=42.36,Longitude=-70.94,"
    "SpeedDepthFlags=88,TransitSpeed=1.5,TransitDepth=10,TransitCommand=1,SurveySpeed=1.0,"
    "SurveyDepth=20,SurveyCommand=2,NumberOfRows=4,RowLength=200,RowSpacing0=20,RowSpacing1=30,"
    "RowHeading=90,StartLatitude=42.35,StartLongitude=-70.95"
)


def test_redirect_command_to_frame_to_ccl_redirect_in(reports):
    dest, data = reports.redirect_command(COMMAND)
    assert (
        dest == 2
        and data.hex() == "0700671f1ec58dcd8864002d01c8001e0204c800141e40951d1ef38bcd000000"
    )
    ((var, text),) = reports.incoming("redirect", data, src=1, dest=2, now=1_700_000_002)
    assert var == "CCL_REDIRECT_IN" and text == (
        "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Timestamp=1700000002,Latitude=42.360003275871669,"
        "Longitude=-70.939995162486454,SpeedDepthFlags=88,TransitSpeed=1.5,TransitDepth=10,TransitCommand=1,"
        "SurveySpeed=1,SurveyDepth=20,SurveyCommand=2,NumberOfRows=4,RowLength=200,RowSpacing0=20,"
        "RowSpacing1=30,RowHeading=90.352941176470594,StartLatitude=42.350003999472143,"
        "StartLongitude=-70.94999443888598"
    )
    assert reports.redirect_command(text) == (2, data)  # CCL_REDIRECT_IN is a command again


def test_redirect_command_keys_defaults_and_errors(reports):
    dest, data = reports.redirect_command(
        "messagetype=ccl_redirect,destinationplatformid=3,"
        "latitude=-1.5,longitude=2,speeddepthflags=0x08"
    )
    redirect = Redirect.decode(data)
    assert dest == 3 and redirect.speed_depth_flags == 8 and redirect.num_rows == 0
    assert redirect.latitude == pytest.approx(-1.5, abs=2.2e-5)  # negative: sign extension (Q19)
    assert reports.redirect_command("MessageType=CCL_STATUS,Node=2") is None
    assert reports.redirect_command("no key value pairs at all") is None
    for text, reason in [
        ("MessageType=CCL_REDIRECT,Latitude=1,Longitude=2", "without DestinationPlatformId"),
        ("MessageType=CCL_REDIRECT,DestinationPlatformId=2,Longitude=2", "without Latitude"),
        (
            "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Latitude=north,Longitude=2",
            "Latitude='north' is not a number",
        ),
        (
            "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Latitude=95,Longitude=2",
            "latitude = 95.0 is beyond",
        ),
        (
            "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Latitude=1,Longitude=2,TransitDepth=nan",
            "not a finite",
        ),
        (
            "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Latitude=1,Longitude=2,SpeedDepthFlags=zz",
            "not hexadecimal",
        ),
        (
            "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Latitude=1,Longitude=2,SpeedDepthFlags=1FF",
            "speed_depth_flags = 511",
        ),
        (
            "MessageType=CCL_REDIRECT,DestinationPlatformId=2,Latitude=1,Longitude=2,NumberOfRows=300",
            "num_rows = 300",
        ),
        (
            "MessageType=CCL_REDIRECT,DestinationPlatformId=-1,Latitude=1,Longitude=2",
            "not a modem id",
        ),
    ]:
        with pytest.raises(CCLEncodeError, match=reason):
            reports.redirect_command(text)


def test_frames_are_read_by_id_alerts_by_variable(reports):
    state = State(latitude=1, longitude=1).encode()
    assert reports.incoming("redirect", state, 2, 1, NOW)[0][0] == "STATUS_REPORT_IN"
    with pytest.raises(CCLFrameError, match="unknown CCL id 31"):
        reports.incoming("state", Alert().encode(), 2, 1, NOW)
    assert reports.incoming("alert", state, 2, 1, NOW)[0][0] == "CCL_ALERT_IN"  # as Goby 1.1 does
    with pytest.raises(CCLFrameError, match="MDAT_STATE: 20-byte frame"):
        reports.incoming("state", state[:20], 2, 1, NOW)


def test_unknown_modem_ids_are_named_by_number(reports):
    posts = dict(reports.incoming("state", State().encode(), src=9, dest=0, now=NOW))
    assert "9_NAV_X" in posts and posts["NODE_REPORT"].startswith("NAME=9,TYPE=unknown_type,")


# ------------------------------------------------------------------ the app on a MOOSDB
WARP = 20
MISSION = """\
ServerHost = localhost
ServerPort = {port}
Community = topside
LatOrigin = 42.35
LongOrigin = -70.95
MOOSTimeWarp = {warp}
modem_id_lookup_path = {lookup}

ProcessConfig = pREMUSCodec
{{
  common {{ log: false  app_tick: 20  verbosity: WARN }}
  {options}
}}
"""


def write_mission(tmp_path: Path, port: int, options: str = "", warp: int = WARP) -> Path:
    (tmp_path / "ids.txt").write_text("1,mm1,topside\n2,mm2,auv\n")
    path = tmp_path / "m.moos"
    path.write_text(MISSION.format(port=port, warp=warp, lookup="ids.txt", options=options))
    return path


def transmission_text(data: bytes, src: int, dest: int) -> str:
    msg = acomms_pb.V1ModemDataTransmission(data=data)
    msg.base.src, msg.base.dest = src, dest
    return text_format.MessageToString(msg, as_one_line=True)


def parse_transmission(text: str):
    msg = acomms_pb.V1ModemDataTransmission()
    text_format.Parse(text, msg)
    return msg


async def next_value(client: MOOSClient, var: str, timeout: float = 10.0):
    async with asyncio.timeout(timeout):
        while True:
            msg = await client.receive()
            if msg.key == var:
                return msg


async def test_app_turns_frames_into_reports_and_skips_bad_ones(tmp_path, capsys):
    state = State(latitude=42.36, longitude=-70.94, heading=90, depth=5, est_velocity=1.5).encode()
    async with (
        MOOSDB(port=0) as db,
        MOOSClient("modem", port=db.port, clock=moos_clock(WARP)) as modem,
    ):
        for var in ("NODE_REPORT", "MM2_NAV_X", "STATUS_REPORT_IN", "CCL_REDIRECT_IN"):
            modem.subscribe(var)
        await modem.flush()
        async with pREMUSCodec.from_mission(write_mission(tmp_path, db.port)):
            await asyncio.sleep(0.3)
            for bad in (
                "not a transmission {",
                transmission_text(state[:12], 2, 1),
                transmission_text(b"\x2a" + bytes(31), 2, 1),
            ):
                modem.publish("IN_REMUS_STATUS_HEX_30B", bad)
            modem.publish("IN_REMUS_RANGER_HEX_30B", 3.0)  # (a double: the DB keeps it one)
            modem.publish("IN_REMUS_STATUS_HEX_30B", transmission_text(state, 2, 1))
            x = await next_value(modem, "MM2_NAV_X")  # (posted before NODE_REPORT)
            assert x.value == pytest.approx(
                UTMGeodesy(42.35, -70.95).to_local(42.36, -70.94)[0], abs=2
            )
            report = await next_value(modem, "NODE_REPORT")
            assert report.value.startswith("NAME=mm2,TYPE=auv,MOOSDB_TIME=-1,UTC_TIME=")
            assert report.src == "pREMUSCodec"
            redirect = Redirect(latitude=1, longitude=2).encode()
            modem.publish("IN_REMUS_REDIRECT_HEX_30B", transmission_text(redirect, 1, 2))
            assert "DestinationPlatformId=2," in (await next_value(modem, "CCL_REDIRECT_IN")).value
    warnings = capsys.readouterr().out
    assert "IN_REMUS_STATUS_HEX_30B: not a ModemDataTransmission" in warnings
    assert "bad CCL frame from modem 2 (MDAT_STATE: 12-byte frame, needs at least 32)" in warnings
    assert "(unknown CCL id 42 (known: 7, 8, 14, 16))" in warnings
    assert "IN_REMUS_RANGER_HEX_30B: a double (3), not a ModemDataTransmission" in warnings


async def test_create_status_every_10_s_once_all_nav_arrived(tmp_path):
    options = 'create_status: true  mdat_state_out: "OUT_STATE"'
    async with MOOSDB(port=0) as db, MOOSClient("nav", port=db.port, clock=moos_clock(WARP)) as nav:
        nav.subscribe("OUT_STATE")
        await nav.flush()
        nav.publish("MODEM_ID", 2.0)
        for var, value in (
            ("NAV_X", 123.0),
            ("NAV_Y", 321.0),
            ("NAV_DEPTH", 111.0),
            ("NAV_SPEED", 1.2),
        ):
            nav.publish(var, value)  # before the app starts: still its vehicle's state
        await nav.flush()
        async with pREMUSCodec.from_mission(write_mission(tmp_path, db.port, options)):
            with pytest.raises(TimeoutError):  # NAV_HEADING missing: nothing yet
                await next_value(nav, "OUT_STATE", timeout=1.5)  # 30 s of warped time
            nav.publish("NAV_HEADING", 45.0)
            posts = [await next_value(nav, "OUT_STATE") for _ in range(3)]
    frames = [parse_transmission(msg.value) for msg in posts]
    assert all((f.base.src, f.base.dest) == (2, 0) for f in frames)
    states = [State.decode(f.data) for f in frames]
    lat, lon = UTMGeodesy(42.35, -70.95).to_geo(123, 321)
    assert states[0].latitude == pytest.approx(lat, abs=1.1e-5) and states[
        0
    ].longitude == pytest.approx(lon, abs=1.1e-5)
    assert (states[0].heading, states[0].depth) == (32 * 360 / 255, 111.0)
    gaps = [b.time - a.time for a, b in itertools.pairwise(posts)]
    assert all(gap >= 10.0 for gap in gaps)  # MOOS (warped) seconds; each post has its frame's time
    for post, state in zip(posts, states, strict=True):
        assert state.time == TimeDate.at(post.time)._replace(
            second=TimeDate.at(post.time).second // 4 * 4
        )


async def test_outgoing_command_becomes_a_redirect_frame(tmp_path, capsys):
    async with (
        MOOSDB(port=0) as db,
        MOOSClient("operator", port=db.port, clock=moos_clock(WARP)) as operator,
    ):
        operator.subscribe("OUT_REMUS_REDIRECT_HEX_30B")
        await operator.flush()
        operator.publish("MODEM_ID", "1")  # a string works too
        async with pREMUSCodec.from_mission(write_mission(tmp_path, db.port)):
            await asyncio.sleep(0.3)
            operator.publish(
                "OUTGOING_COMMAND", "MessageType=CCL_REDIRECT,Latitude=1"
            )  # no destination
            operator.publish("OUTGOING_COMMAND", "MessageType=OTHER,Foo=1")  # not ours
            operator.publish("OUTGOING_COMMAND", COMMAND)
            msg = await next_value(operator, "OUT_REMUS_REDIRECT_HEX_30B")
    sent = parse_transmission(msg.value)
    assert (sent.base.src, sent.base.dest) == (1, 2)
    assert sent.data.hex() == "0700671f1ec58dcd8864002d01c8001e0204c800141e40951d1ef38bcd000000"
    assert (
        "OUTGOING_COMMAND: CCL_REDIRECT command without DestinationPlatformId; not sent"
        in capsys.readouterr().out
    )


# ------------------------------------------------------------------ configuration
def test_configuration_defaults_are_the_spec_table(tmp_path):
    cfg = pREMUSCodec.read_config(None, "pREMUSCodec")
    assert cfg.create_status is False
    for kind in ("state", "ranger", "redirect", "alert", "alert2"):
        name = "STATUS" if kind == "state" else kind.upper()
        assert getattr(cfg, f"mdat_{kind}_var") == f"IN_REMUS_{name}_HEX_30B"
        assert getattr(cfg, f"mdat_{kind}_out") == f"OUT_REMUS_{name}_HEX_30B"
    path = write_mission(tmp_path, 9000)
    app = pREMUSCodec.from_mission(path)
    assert app.cfg.modem_id_lookup_path == "ids.txt"  # the MOOS global
    assert app.reports.lookup.name(2) == "mm2"


def test_latorigin_is_required(tmp_path):
    path = tmp_path / "m.moos"
    path.write_text("ProcessConfig = pREMUSCodec\n{\n  create_status: true\n}\n")
    with pytest.raises(ConfigError, match="LatOrigin and LongOrigin are required"):
        pREMUSCodec.from_mission(path)


def test_console_script_example_config():
    out = subprocess.run(
        [str(Path(sys.executable).with_name("pREMUSCodec")), "--example_config"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert out.startswith("ProcessConfig = pREMUSCodec\n{")
    for line in (
        "create_status: false",
        'mdat_state_var: "IN_REMUS_STATUS_HEX_30B"',
        'mdat_alert2_out: "OUT_REMUS_ALERT2_HEX_30B"',
        'modem_id_lookup_path: ""',
    ):
        assert line in out
