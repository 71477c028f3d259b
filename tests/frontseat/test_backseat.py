"""The rules between the backseat's variables and a frontseat driver (pygoby.frontseat.backseat),
on a scripted driver and a virtual clock, without MOOS."""

from __future__ import annotations

import logging
import math

import pytest

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.backseat import Backseat
from pygoby.protobuf import builtin_class
from pygoby.util.clock import VirtualClock

from .scripted_driver import ScriptedFrontSeat

LegacyOperations = builtin_class(
    "goby/moos/protobuf/iFrontSeat_config.proto", "goby.apps.moos.protobuf.iFrontSeatConfig"
)().legacy_cfg.__class__


def backseat(**legacy) -> Backseat:
    driver = ScriptedFrontSeat(frontseat_pb.Config(), VirtualClock(1000.0))
    return Backseat(driver, LegacyOperations(**legacy))


def bring_to(seat: Backseat, state: int) -> None:
    driver = seat.interface
    driver.set_helm_state(frontseat_pb.HELM_DRIVE)
    driver.fs_state, driver.providing = frontseat_pb.FRONTSEAT_IDLE, True
    driver.do_work()  # LISTEN
    if state == frontseat_pb.INTERFACE_COMMAND:
        driver.fs_state = frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS
        driver.do_work()
    assert driver.state == state


@pytest.mark.parametrize(
    ("state", "command", "send"),
    [
        (frontseat_pb.INTERFACE_STANDBY, False, False),
        (frontseat_pb.INTERFACE_LISTEN, False, True),
        (frontseat_pb.INTERFACE_COMMAND, True, True),
    ],
)
def test_what_may_go_to_the_frontseat_in_each_state(state, command, send, caplog):
    seat = backseat()
    if state != frontseat_pb.INTERFACE_STANDBY:
        bring_to(seat, state)
    with caplog.at_level(logging.DEBUG, logger="pygoby.frontseat.backseat"):
        assert seat.may_command("IFS_COMMAND_REQUEST") is command
        assert seat.may_send("IFS_DATA_OUT") is send
    if not command:
        name = frontseat_pb.InterfaceState.Name(state)
        assert f"IFS_COMMAND_REQUEST not sent: the interface is in {name}" in caplog.text
    if not send:
        assert "IFS_DATA_OUT not sent: the interface is in INTERFACE_STANDBY" in caplog.text


def test_helm_state_by_posting_process(caplog):
    seat = backseat()
    with caplog.at_level(logging.INFO, logger="pygoby.frontseat.backseat"):
        seat.helm_state("DRIVE", "pHelmIvP")
    assert seat.interface.helm_state == frontseat_pb.HELM_DRIVE
    change = "helm state HELM_NOT_RUNNING -> HELM_DRIVE (IVPHELM_STATE='DRIVE' from pHelmIvP)"
    assert change in caplog.text
    seat.helm_state("PARK+", "pHelmIvP_standby")
    assert seat.interface.helm_state == frontseat_pb.HELM_PARK
    seat.helm_state("DRIVE", "uPokeDB")  # not a helm: the helm is not running
    assert seat.interface.helm_state == frontseat_pb.HELM_NOT_RUNNING


def test_origin_applies_once_both_are_known():
    seat = backseat()
    seat.set_origin(lat=42.0)
    assert seat.interface.geodesy is None and math.isnan(seat.origin[1])
    seat.set_origin(lon=-70.0)
    assert seat.origin == (42.0, -70.0) and seat.interface.geodesy is not None
    seat.set_origin(lat=43.0)
    assert seat.origin == (43.0, -70.0)


def test_desired_course_becomes_a_command_request_on_desired_speed():
    seat = backseat(subscribe_desired=True)
    assert seat.desired("DESIRED_HEADING", 90.0, 1.0) is None
    request = seat.desired("DESIRED_SPEED", 1.5, 2.0)
    course = request.desired_course
    assert (course.heading, course.speed, course.time) == (90.0, 1.5, 2.0)
    assert backseat(subscribe_desired=False).desired_course is None


def test_ctd_sample_at_the_last_position_with_missing_fields_computed():
    seat = backseat(subscribe_ctd=True, publish_nav=False)
    data = frontseat_pb.InterfaceData()
    data.node_status.global_fix.lat, data.node_status.global_fix.lon = 42.5, -70.25
    assert seat.legacy_posts(data) == []  # publish_nav is off; the position is kept
    assert seat.ctd("CTD_CONDUCTIVITY", 4.2914, 1.0) is None
    assert seat.ctd("CTD_PRESSURE", 10.0, 1.0) is None
    out = seat.ctd("CTD_TEMPERATURE", 15.0, 3.0)
    sample = out.ctd_sample
    assert (sample.global_fix.lat, sample.global_fix.lon, sample.time) == (42.5, -70.25, 3.0)
    assert sample.pressure == 1e5  # dbar -> Pa
    assert sample.HasField("salinity") and sample.HasField("sound_speed")
    assert backseat(subscribe_ctd=False).ctd_samples is None


def test_legacy_posts_with_publish_nav():
    seat = backseat(publish_nav=True)
    assert seat.legacy_posts(frontseat_pb.InterfaceData(dccl_message=b"x")) == []
    data = frontseat_pb.InterfaceData()
    data.node_status.local_fix.x = 1.5
    data.node_status.speed.over_ground = 2.0
    posts = dict(seat.legacy_posts(data))
    assert posts["NAV_X"] == 1.5 and posts["NAV_SPEED"] == 2.0
