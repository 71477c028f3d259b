"""iFrontSeat's legacy variable translations (pygoby.frontseat.legacy), without MOOS."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.legacy import (
    LEGACY_REQUEST_ID_BASE,
    CtdSamples,
    DesiredCourseCommands,
    nav_posts,
    ready_posts,
)
from tests.hypothesis_profiles import examples


def node_status(**pose):
    status = frontseat_pb.NodeStatus(time=1700000000.123456789, name="auv")
    status.global_fix.lat, status.global_fix.lon = 42.5, -70.25
    status.local_fix.x, status.local_fix.y = 10.5, -3.25
    status.speed.over_ground = 1.5
    for name, value in pose.items():
        setattr(status.pose, name, value)
    return status


def test_nav_posts_minimal_solution():
    posts = nav_posts(node_status())
    assert posts == [
        ("NAV_X", 10.5),
        ("NAV_Y", -3.25),
        ("NAV_LAT", 42.5),
        ("NAV_LONG", -70.25),
        ("NAV_SPEED", 1.5),
    ]


def test_nav_posts_full_solution_with_gps():
    status = node_status(heading=90.0, pitch=-10.0, roll=5.0)
    status.local_fix.z = -12.0
    status.global_fix.depth = 12.0
    status.global_fix.altitude = 30.0
    status.source.position = frontseat_pb.Source.GPS
    posts = dict(nav_posts(status))
    assert [var for var, _ in nav_posts(status)] == [
        "NAV_X",
        "NAV_Y",
        "NAV_LAT",
        "NAV_LONG",
        "NAV_Z",
        "NAV_DEPTH",
        "NAV_HEADING",
        "NAV_YAW",
        "NAV_SPEED",
        "NAV_PITCH",
        "NAV_ROLL",
        "NAV_ALTITUDE",
        "GPS_UPDATE_RECEIVED",
    ]
    assert posts["NAV_Z"] == -12.0 and posts["NAV_DEPTH"] == 12.0
    assert posts["NAV_HEADING"] == 90.0
    assert math.isclose(posts["NAV_YAW"], -math.pi / 2)
    assert math.isclose(posts["NAV_PITCH"], -math.pi / 18)
    assert math.isclose(posts["NAV_ROLL"], math.pi / 36)
    assert posts["NAV_ALTITUDE"] == 30.0
    # 15 significant digits of the fix time
    assert posts["GPS_UPDATE_RECEIVED"] == "Timestamp=1700000000.12346"


def test_no_gps_update_for_other_or_unknown_position_sources():
    status = node_status()
    status.source.depth = frontseat_pb.Source.PRESSURE  # position source not given (reads GPS=1)
    assert "GPS_UPDATE_RECEIVED" not in dict(nav_posts(status))
    status.source.position = frontseat_pb.Source.INERTIAL_NAVIGATION_SYSTEM
    assert "GPS_UPDATE_RECEIVED" not in dict(nav_posts(status))


def test_desired_course_posts_a_request_on_each_speed():
    commands = DesiredCourseCommands()
    assert commands.update("DESIRED_HEADING", 270.0, 10.0) is None
    assert commands.update("DESIRED_DEPTH", 5.0, 10.1) is None
    first = commands.update("DESIRED_SPEED", 1.2, 10.2)
    assert first.response_requested and first.request_id == LEGACY_REQUEST_ID_BASE
    course = first.desired_course
    assert (course.time, course.heading, course.speed, course.depth) == (10.2, 270.0, 1.2, 5.0)
    assert not course.HasField("pitch") and course.altitude == 10.0  # defaults untouched
    commands.update("DESIRED_HEADING", 90.0, 11.0)
    commands.update("DESIRED_ALTITUDE", 3.0, 11.0)
    second = commands.update("DESIRED_SPEED", 1.0, 11.5)
    assert second.request_id == LEGACY_REQUEST_ID_BASE + 1
    assert (second.desired_course.heading, second.desired_course.depth) == (90.0, 5.0)
    assert second.desired_course.altitude == 3.0
    assert first.desired_course.heading == 270.0  # earlier requests are copies


def test_ctd_sample_on_temperature_at_the_last_fix():
    ctd = CtdSamples()
    ctd.update("CTD_PRESSURE", 10.0, 1.0)  # dbar
    ctd.update("CTD_CONDUCTIVITY", 4.2, 1.0)
    early = ctd.update("CTD_TEMPERATURE", 15.0, 2.0)
    assert math.isnan(early.global_fix.lat) and math.isnan(early.global_fix.lon)
    assert early.pressure == 1e5 and early.conductivity == 4.2 and early.time == 2.0
    ctd.update_position(node_status())
    assert ctd.update("CTD_SALINITY", 35.0, 3.0) is None
    sample = ctd.update("CTD_TEMPERATURE", 14.0, 4.0)
    assert (sample.global_fix.lat, sample.global_fix.lon) == (42.5, -70.25)
    assert (sample.temperature, sample.salinity, sample.time) == (14.0, 35.0, 4.0)


def test_ready_posts():
    status = frontseat_pb.InterfaceStatus(
        state=frontseat_pb.INTERFACE_COMMAND,
        frontseat_state=frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS,
        helm_state=frontseat_pb.HELM_DRIVE,
    )
    assert ready_posts(status) == [("FRONTSEAT_READY", 1.0), ("BACKSEAT_READY", 1.0)]
    status.frontseat_state, status.helm_state = frontseat_pb.FRONTSEAT_IDLE, frontseat_pb.HELM_PARK
    assert ready_posts(status) == [("FRONTSEAT_READY", 0.0), ("BACKSEAT_READY", 0.0)]


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=examples(200), deadline=None)
@given(heading=finite, pitch=finite, speed=finite, time=st.floats(0, 4e9))
def test_nav_posts_are_numbers_for_any_solution(heading, pitch, speed, time):
    status = node_status(heading=heading, pitch=pitch)
    status.speed.over_ground = speed
    status.time = time
    status.source.position = frontseat_pb.Source.GPS
    posts = dict(nav_posts(status))
    assert posts["NAV_YAW"] == -math.radians(heading)
    assert float(posts["GPS_UPDATE_RECEIVED"].removeprefix("Timestamp=")) == float(f"{time:.15g}")
    assert all(isinstance(v, float) for k, v in posts.items() if k != "GPS_UPDATE_RECEIVED")
