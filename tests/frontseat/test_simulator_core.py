"""The sans-I/O basic frontseat simulator: START/CMD/CTRL/IDLE sequences and the dynamics,
step by step against hand-computed values."""

from __future__ import annotations

import logging
import math

import pytest
from pyproj import Geod

from pygoby.frontseat.simulator.core import BasicFrontSeatSimulator
from pygoby.frontseat.simulator.protocol import Nav, parse_line
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.kinematics import wrap_heading

LAT, LON = 42.1234, -72.0
START = f"START,LAT:{LAT},LON:{LON}"


def nav_of(lines: list[str]) -> Nav:
    (line,) = lines
    return Nav.from_message(parse_line(line))


def started(extra: str = "") -> BasicFrontSeatSimulator:
    sim = BasicFrontSeatSimulator()
    assert sim.handle_line(START + extra) == ["CTRL,STATE:PAYLOAD"]
    return sim


def ticks(sim: BasicFrontSeatSimulator, n: int) -> list[Nav]:
    return [nav_of(sim.tick()) for _ in range(n)]


def test_nothing_happens_before_start_and_cmd_is_not_answered(caplog):
    sim = BasicFrontSeatSimulator()
    with caplog.at_level(logging.WARNING):
        assert sim.handle_line("CMD,HEADING:260,SPEED:1.5,DEPTH:100") == []
    assert "send START first" in caplog.text
    assert sim.tick() == []
    assert not sim.running
    assert sim.desired.speed == 0.0


def test_start_replies_payload_and_nav_follows_every_tick():
    sim = started()
    assert sim.running
    assert sim.tick() == ["NAV,LAT:42.1234,LON:-72,DEPTH:-0,HEADING:0,SPEED:0"]  # -0 as upstream
    assert sim.handle_line("CMD,HEADING:260,SPEED:1.5,DEPTH:100") == ["CMD,RESULT:OK"]
    assert sim.tick()[0].startswith("NAV,")


def test_start_resets_defaults_each_time():
    sim = started(",DURATION:5,FREQ:5,ACCEL:1,HDG_RATE:90,Z_RATE:4,WARP:3")
    assert sim.period == pytest.approx(1 / 15)
    assert (sim.params.freq, sim.params.accel, sim.params.warp) == (5, 1.0, 3)
    assert sim.handle_line("START,LAT:1,LON:2") == ["CTRL,STATE:PAYLOAD"]
    p = sim.params
    assert (p.duration, p.freq, p.accel, p.hdg_rate, p.z_rate, p.warp) == (0, 10, 0.5, 45, 2, 1)
    assert sim.period == pytest.approx(0.1)


def test_goby2_start_with_duration_ends_with_idle():
    sim = started(",DURATION:1")  # FREQ 10: ticks 1..19 have 19 // 10 <= 1
    assert len(ticks(sim, 19)) == 19
    assert sim.tick() == ["CTRL,STATE:IDLE"]  # tick 20: 20 // 10 = 2 > 1
    assert not sim.running
    assert sim.tick() == []
    assert sim.handle_line("CMD,HEADING:1,SPEED:1,DEPTH:1") == []  # after the mission: silent


def test_duration_zero_is_unlimited():
    sim = started(",DURATION:0,FREQ:1")
    assert len(ticks(sim, 500)) == 500


def test_a_new_start_restarts_the_mission_clock():
    sim = started(",DURATION:1,FREQ:2")
    ticks(sim, 3)  # 3 // 2 = 1: still running
    sim.handle_line(START + ",DURATION:1,FREQ:2")
    ticks(sim, 3)
    assert sim.tick() == ["CTRL,STATE:IDLE"]


def test_cmd_with_a_missing_or_bad_field_answers_error_and_keeps_the_course(caplog):
    sim = started()
    assert sim.handle_line("CMD,HEADING:90,SPEED:1,DEPTH:5") == ["CMD,RESULT:OK"]
    with caplog.at_level(logging.WARNING):
        assert sim.handle_line("CMD,HEADING:260,SPEED:1.5") == ["CMD,RESULT:ERROR"]
        assert sim.handle_line("CMD,HEADING:nan,SPEED:1.5,DEPTH:3") == ["CMD,RESULT:ERROR"]
    assert "CMD without DEPTH" in caplog.text
    assert (sim.desired.heading, sim.desired.speed, sim.desired.z) == (90.0, 1.0, -5.0)


@pytest.mark.parametrize(
    ("line", "log_text"),
    [
        ("CMD,HEADING", "invalid line"),
        ("START,LAT:abc,LON:3", "invalid line"),
        ("START,LAT:1,LON:2,FREQ:0", "FREQ must be positive"),
        ("FOO,A:1", "unknown key"),
        ("", "unknown key"),
        ("NAV,LAT:1,LON:2,DEPTH:3,HEADING:4,SPEED:5", "unknown key"),
    ],
)
def test_malformed_and_unknown_lines_are_logged_and_skipped(caplog, line, log_text):
    sim = started(",FREQ:20")
    before = (sim.params, sim.datum, sim.vehicle, sim.desired)
    with caplog.at_level(logging.WARNING):
        assert sim.handle_line(line) == []
    assert log_text in caplog.text
    assert (sim.params, sim.datum, sim.vehicle, sim.desired) == before
    assert sim.tick()[0].startswith("NAV,")


def test_depth_and_speed_slew_then_snap():
    sim = started()  # Z_RATE 2, ACCEL 0.5, FREQ 10: steps of 0.2 m and 0.05 m/s
    sim.handle_line("CMD,HEADING:0,SPEED:0.12,DEPTH:0.5")
    navs = ticks(sim, 4)
    assert [n.depth for n in navs] == [0.2, 0.4, 0.5, 0.5]
    assert [n.speed for n in navs] == [0.05, 0.1, 0.12, 0.12]
    sim.handle_line("CMD,HEADING:0,SPEED:0,DEPTH:0.1")  # back up: slew toward the surface
    navs = ticks(sim, 3)
    assert [n.depth for n in navs] == [0.3, 0.1, 0.1]
    assert [n.speed for n in navs] == [0.07, 0.02, 0.0]


def test_heading_slews_the_short_way_through_north_and_stays_in_0_360():
    sim = started()  # HDG_RATE 45, FREQ 10: 4.5 deg per tick
    sim.handle_line("CMD,HEADING:350,SPEED:0,DEPTH:0")
    assert [n.heading for n in ticks(sim, 3)] == [355.5, 351.0, 350.0]  # 0 -> 350 turning left
    sim.handle_line("CMD,HEADING:10,SPEED:0,DEPTH:0")
    # upstream (Quirk Q17) prints 354.5, 359, 363.5, 368, 370; "Sane": wrapped to [0, 360)
    assert [n.heading for n in ticks(sim, 5)] == [354.5, 359.0, 3.5, 8.0, 10.0]
    sim.handle_line("CMD,HEADING:-90,SPEED:0,DEPTH:0")  # desired heading wrapped too: 270
    assert sim.desired.heading == 270.0
    headings = [n.heading for n in ticks(sim, 25)]
    assert headings[:3] == [5.5, 1.0, 356.5]
    assert headings[-1] == 270.0
    assert all(0.0 <= h < 360.0 for h in headings)


def test_heading_exactly_opposite_turns_clockwise():
    sim = started(",HDG_RATE:90")
    sim.handle_line("CMD,HEADING:180,SPEED:0,DEPTH:0")
    assert [n.heading for n in ticks(sim, 2)] == [9.0, 18.0]


def test_wrap_heading():
    assert [wrap_heading(h) for h in (0.0, 360.0, 370.0, -10.0, -720.0, 359.5)] == [
        0.0,
        0.0,
        10.0,
        350.0,
        0.0,
        359.5,
    ]
    assert wrap_heading(-1e-20) == 0.0  # 360 - 1e-20 rounds to 360


def test_position_after_n_ticks_east_is_on_the_utm_grid_of_the_start_datum():
    sim = started(",ACCEL:1000,HDG_RATE:1000")  # speed and heading reached in the first tick
    sim.handle_line("CMD,HEADING:90,SPEED:2,DEPTH:0")
    navs = ticks(sim, 50)  # 5 s at 2 m/s due east (theta = 0)
    assert sim.vehicle.x == pytest.approx(10.0, abs=1e-9)
    assert sim.vehicle.y == pytest.approx(0.0, abs=1e-12)
    lat, lon = UTMGeodesy(LAT, LON).to_geo(sim.vehicle.x, sim.vehicle.y)
    assert navs[-1].lat == pytest.approx(lat, abs=1e-8)
    assert navs[-1].lon == pytest.approx(lon, abs=1e-8)
    # independent check: ~10 m away on the ellipsoid (UTM scale factor within 0.1 %)
    azimuth, _, distance = Geod(ellps="WGS84").inv(LON, LAT, navs[-1].lon, navs[-1].lat)
    assert distance == pytest.approx(10.0, rel=1e-3)
    # grid east is true east turned by the meridian convergence (zone 18, central meridian -75)
    convergence = math.degrees(
        math.atan(math.tan(math.radians(LON + 75)) * math.sin(math.radians(LAT)))
    )
    assert azimuth == pytest.approx(90.0 - convergence, abs=0.01)


def test_position_at_a_diagonal_heading():
    sim = started(",ACCEL:1000,HDG_RATE:1000,FREQ:4")
    sim.handle_line("CMD,HEADING:225,SPEED:1,DEPTH:0")  # south-west
    ticks(sim, 40)  # 10 s
    step = 1.0 * 0.25 * 2**-0.5
    assert sim.vehicle.x == pytest.approx(-40 * step, rel=1e-12)
    assert sim.vehicle.y == pytest.approx(-40 * step, rel=1e-12)


def test_quirk_q16_vehicle_state_continues_in_the_new_datum():
    sim = started(",ACCEL:1000,HDG_RATE:1000")
    sim.handle_line("CMD,HEADING:0,SPEED:10,DEPTH:20")
    ticks(sim, 20)
    x, y, z, v = sim.vehicle.x, sim.vehicle.y, sim.vehicle.z, sim.vehicle.speed
    assert (x, y, v) == (pytest.approx(0.0, abs=1e-9), pytest.approx(20.0), 10.0)
    assert sim.handle_line("START,LAT:10,LON:20") == ["CTRL,STATE:PAYLOAD"]
    assert (sim.vehicle.x, sim.vehicle.y, sim.vehicle.z, sim.vehicle.speed) == (x, y, z, v)
    nav = nav_of(sim.tick())  # one more metre north, in the new datum
    lat, lon = UTMGeodesy(10.0, 20.0).to_geo(x, y + 1.0)
    assert (nav.lat, nav.lon) == (pytest.approx(lat, abs=1e-8), pytest.approx(lon, abs=1e-8))
    assert nav.speed == 10.0
    assert sim.desired.speed == 10.0  # the desired course survives START too


def test_zero_rates_freeze_the_vehicle():
    sim = started(",ACCEL:0,HDG_RATE:0,Z_RATE:0")
    sim.handle_line("CMD,HEADING:90,SPEED:2,DEPTH:10")
    nav = ticks(sim, 10)[-1]
    assert (nav.depth, nav.heading, nav.speed, nav.lat, nav.lon) == (-0.0, 0.0, 0.0, LAT, LON)
