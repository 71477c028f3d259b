"""The ABC / basic simulator driver, sans-I/O: a MemoryLink for the wire and a VirtualClock."""

from __future__ import annotations

import logging

import pytest
from google.protobuf import text_format

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.drivers.abc import (
    AbcConfigError,
    AbcFrontSeat,
    frontseat_driver_load,
    start_params,
)
from pygoby.frontseat.simulator.protocol import Start
from pygoby.util.clock import VirtualClock
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.linebased import MemoryLink

T0 = 1_700_000_000.0
ORIGIN = (44.08, 9.84)

CONFIG = """
name: "auv1"
origin { lat: 44.08 lon: 9.84 }
sim_warp_factor: 3
[goby.middleware.frontseat.protobuf.basic_simulator_config] {
  tcp_address: "localhost"
  tcp_port: 54321
  start { lat: 44.0888889 lon: 9.84861111 duration: 600 }
}
"""


def config(text: str = CONFIG):
    return text_format.Parse(text, frontseat_pb.Config())


class Recorder:
    """Every signal of a driver, in lists."""

    def __init__(self, driver: AbcFrontSeat) -> None:
        self.data, self.responses, self.raw_in, self.raw_out = [], [], [], []
        driver.signal_data_from_frontseat.connect(self.data.append)
        driver.signal_command_response.connect(self.responses.append)
        driver.signal_raw_from_frontseat.connect(lambda r: self.raw_in.append(r.raw.decode()))
        driver.signal_raw_to_frontseat.connect(lambda r: self.raw_out.append(r.raw.decode()))


@pytest.fixture
def rig():
    link = MemoryLink()
    driver = AbcFrontSeat(config(), VirtualClock(T0), link=link)
    return driver, link, Recorder(driver)


def connect(driver: AbcFrontSeat, link: MemoryLink) -> list[str]:
    link.open()
    driver.loop()
    return link.take_written()


def request(request_id: int, heading=260.0, speed=1.5, depth=100.0, response=True):
    return frontseat_pb.CommandRequest(
        desired_course=frontseat_pb.DesiredCourse(
            time=T0, heading=heading, speed=speed, depth=depth
        ),
        response_requested=response,
        request_id=request_id,
    )


def test_start_is_sent_once_connected_with_all_eight_fields(rig):
    driver, link, rec = rig
    driver.loop()
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_NOT_CONNECTED
    written = connect(driver, link)
    line = (
        "START,LAT:44.0888889,LON:9.84861111,DURATION:600,FREQ:10,ACCEL:0.5,HDG_RATE:45,"
        "Z_RATE:2,WARP:3"
    )
    assert written == [line + "\r\n"]
    assert rec.raw_out == [line]
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_IDLE
    driver.loop()
    assert link.take_written() == []  # once per connection


@pytest.mark.parametrize(
    ("line", "state"),
    [
        ("CTRL,STATE:PAYLOAD", frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS),
        ("CTRL,STATE:AUV", frontseat_pb.FRONTSEAT_IN_CONTROL),
        ("CTRL,STATE:IDLE", frontseat_pb.FRONTSEAT_IDLE),
        ("CTRL,STATE:WHATEVER", frontseat_pb.FRONTSEAT_IDLE),
        ("CTRL", frontseat_pb.FRONTSEAT_IDLE),
    ],
)
def test_ctrl_sets_the_frontseat_state(rig, line, state):
    driver, link, rec = rig
    connect(driver, link)
    link.feed("CTRL,STATE:PAYLOAD\r\n")
    driver.loop()
    link.feed(line + "\r\n")
    driver.loop()
    assert driver.frontseat_state() == state
    assert rec.raw_in[-1] == line


def test_nav_becomes_a_full_node_status(rig):
    driver, link, rec = rig
    connect(driver, link)
    link.feed(" NAV,LAT:44.0889,LON:9.8486,DEPTH:12.5,HEADING:223,SPEED:1.4 \r\n")
    driver.loop()
    assert rec.raw_in == ["NAV,LAT:44.0889,LON:9.8486,DEPTH:12.5,HEADING:223,SPEED:1.4"]
    (data,) = rec.data
    status = data.node_status
    assert status.name == "auv1" and status.type == frontseat_pb.VehicleType.Value("AUV")
    assert status.time == T0
    assert (status.global_fix.lat, status.global_fix.lon) == (44.0889, 9.8486)
    assert status.global_fix.depth == 12.5
    assert (status.pose.heading, status.speed.over_ground) == (223.0, 1.4)
    x, y = UTMGeodesy(*ORIGIN).to_local(44.0889, 9.8486)
    assert status.local_fix.x == pytest.approx(x, abs=1e-9)
    assert status.local_fix.y == pytest.approx(y, abs=1e-9)
    assert status.local_fix.z == -12.5
    assert status.IsInitialized()
    assert driver.frontseat_providing_data()


def test_providing_data_ends_10_s_after_the_last_nav(rig):
    driver, link, _ = rig
    connect(driver, link)
    assert not driver.frontseat_providing_data()
    link.feed("NAV,LAT:44.0889,LON:9.8486,DEPTH:0,HEADING:0,SPEED:0\r\n")
    driver.loop()
    driver.clock.advance(10.0)
    driver.loop()
    assert driver.frontseat_providing_data()  # exactly 10 s: not yet
    driver.clock.advance(0.001)
    driver.loop()
    assert not driver.frontseat_providing_data()


def test_command_is_formatted_with_six_digits_and_answered_with_its_id(rig):
    driver, link, rec = rig
    connect(driver, link)
    driver.send_command_to_frontseat(request(7, heading=123.4567891, speed=1.5, depth=100))
    assert link.take_written() == ["CMD,HEADING:123.457,SPEED:1.5,DEPTH:100\r\n"]
    assert rec.raw_out[-1] == "CMD,HEADING:123.457,SPEED:1.5,DEPTH:100"
    link.feed("CMD,RESULT:OK\r\n")
    driver.loop()
    assert rec.responses == [frontseat_pb.CommandResponse(request_successful=True, request_id=7)]
    driver.send_command_to_frontseat(request(8))
    link.feed("CMD,RESULT:ERROR\r\n")
    driver.loop()
    assert rec.responses[-1] == frontseat_pb.CommandResponse(request_successful=False, request_id=8)


def test_no_response_unless_requested(rig):
    driver, link, rec = rig
    connect(driver, link)
    link.feed("CMD,RESULT:OK\r\n")  # no request yet
    driver.loop()
    driver.send_command_to_frontseat(request(9, response=False))
    link.feed("CMD,RESULT:OK\r\n")
    driver.loop()
    assert rec.responses == []


def test_other_commands_data_are_ignored_and_raw_is_written(rig, caplog):
    driver, link, rec = rig
    connect(driver, link)
    with caplog.at_level(logging.INFO):
        driver.send_command_to_frontseat(frontseat_pb.CommandRequest(cancel_request_id=3))
    assert "unhandled command" in caplog.text
    driver.send_data_to_frontseat(frontseat_pb.InterfaceData(dccl_message=b"\x01"))
    assert link.take_written() == []
    driver.send_raw_to_frontseat(frontseat_pb.Raw(raw=b"CMD,HEADING:1,SPEED:2,DEPTH:3"))
    assert link.take_written() == ["CMD,HEADING:1,SPEED:2,DEPTH:3\r\n"]
    assert rec.raw_out[-1] == "CMD,HEADING:1,SPEED:2,DEPTH:3"


@pytest.mark.parametrize(
    ("line", "log_text"),
    [
        ("NAV,LAT:44", "NAV without LON"),
        ("NAV,LAT:x,LON:1,DEPTH:0,HEADING:0,SPEED:0", "not a decimal number"),
        ("CTRL,STATE", "not NAME:VALUE"),
    ],
)
def test_malformed_lines_are_logged_and_skipped_but_still_emitted_raw(rig, caplog, line, log_text):
    driver, link, rec = rig
    connect(driver, link)
    with caplog.at_level(logging.WARNING):
        link.feed(line + "\r\nNAV,LAT:44.0889,LON:9.8486,DEPTH:0,HEADING:0,SPEED:0\r\n")
        driver.loop()
    assert log_text in caplog.text
    assert rec.raw_in[0] == line
    assert len(rec.data) == 1  # the following good line still counts
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_IDLE


def test_lost_connection_goes_back_to_not_connected_and_a_new_one_restarts(rig, caplog):
    driver, link, _rec = rig
    connect(driver, link)
    link.feed("CTRL,STATE:PAYLOAD\r\n")
    driver.loop()
    link.feed("CTRL,STATE:PAYLOAD\r\n")  # read after the loss: must not count
    link.close()
    with caplog.at_level(logging.WARNING):
        driver.loop()
        driver.send_command_to_frontseat(request(1))  # not sent, no exception
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_NOT_CONNECTED
    assert "reconnecting" in caplog.text and "not sent" in caplog.text
    written = connect(driver, link)
    assert len(written) == 1 and written[0].startswith("START,")
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_IDLE


def test_interface_state_machine_runs_on_the_driver(rig):
    driver, link, _ = rig
    driver.do_work()
    assert driver.state == frontseat_pb.INTERFACE_STANDBY
    link.open()
    link.feed("CTRL,STATE:PAYLOAD\r\nNAV,LAT:44.0889,LON:9.8486,DEPTH:0,HEADING:0,SPEED:0\r\n")
    driver.do_work()  # transition check first (nothing yet), then loop() reads the lines
    driver.do_work()
    assert driver.state == frontseat_pb.INTERFACE_LISTEN
    driver.set_helm_state(frontseat_pb.HELM_DRIVE)
    driver.do_work()
    assert driver.state == frontseat_pb.INTERFACE_COMMAND
    link.feed("CTRL,STATE:IDLE\r\n")
    driver.do_work()
    driver.do_work()
    assert driver.state == frontseat_pb.INTERFACE_LISTEN
    driver.clock.advance(10.5)  # no NAV any more
    driver.do_work()
    driver.do_work()
    assert driver.state == frontseat_pb.INTERFACE_FS_ERROR
    assert driver.status().frontseat_error == frontseat_pb.ERROR_FRONTSEAT_NOT_PROVIDING_DATA


def test_config_errors_are_specific():
    with pytest.raises(AbcConfigError, match="no \\[goby.middleware"):
        start_params(frontseat_pb.Config())
    with pytest.raises(AbcConfigError, match="lacks required start.lon"):
        start_params(
            config(
                "[goby.middleware.frontseat.protobuf.basic_simulator_config] "
                "{ tcp_address: 'h' start { lat: 1 } }"
            )
        )
    with pytest.raises(AbcConfigError, match="WARP must be positive"):
        start_params(config(CONFIG.replace("sim_warp_factor: 3", "sim_warp_factor: 0")))


def test_start_params_defaults_and_vehicle_settings():
    cfg = config(CONFIG.replace("duration: 600", "vehicle { accel: 1.25 z_rate: 0.5 }"))
    cfg.ClearField("sim_warp_factor")
    assert start_params(cfg) == Start(44.0888889, 9.84861111, 0, 10, 1.25, 45.0, 0.5, 1)


def test_factory_builds_a_tcp_driver():
    driver = frontseat_driver_load(config(), VirtualClock(T0))
    assert isinstance(driver, AbcFrontSeat)
    assert (driver.link.host, driver.link.port) == ("localhost", 54321)
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_NOT_CONNECTED
