"""REMUS CCL frames (pygoby.dccl.ccl.remus) and pREMUSCodec's translation (run with `make bench`;
ops/s is frames per second). A REMUS vehicle sends a frame every few seconds at most: these
show the headroom, e.g. for replaying logs."""

from __future__ import annotations

from pygoby.dccl.ccl.remus import Ranger, State, TimeDate
from pygoby.moosacomms.remus_reports import RemusReports
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.modem_id import ModemIdLookup

STATE = State(
    latitude=42.35,
    longitude=-70.95,
    time=TimeDate(11, 14, 22, 13, 20),
    heading=45,
    depth=111,
    est_velocity=1.2,
    lat_goal=42.4,
    lon_goal=-70.9,
    battery_percent=80,
)


def test_encode_state(benchmark) -> None:
    data = benchmark(STATE.encode)
    assert len(data) == 32


def test_decode_state(benchmark) -> None:
    data = STATE.encode()
    assert benchmark(State.decode, data).depth == 111.0


def test_decode_ranger(benchmark) -> None:
    data = Ranger(latitude=42.35, longitude=-70.95, speed=1.2, heading=45.5, depth=111).encode()
    assert benchmark(Ranger.decode, data).depth == 111.0


def test_state_frame_to_moos_posts(benchmark) -> None:
    """What pREMUSCodec does per incoming State: decode, datum conversion, the strings."""
    reports = RemusReports(UTMGeodesy(42.35, -70.95), ModemIdLookup.from_text("2,mm2,auv\n"))
    data = STATE.encode()
    posts = benchmark(reports.incoming, "state", data, 2, 1, 1_700_000_000.0)
    assert posts[-1][0] == "NODE_REPORT"
