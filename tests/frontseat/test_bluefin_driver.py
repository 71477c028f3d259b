"""The Bluefin driver alone, on a memory link and a virtual clock: what it writes for each
request, how it reads each Huxley sentence, ACKs, NAKs, resends and the frontseat states."""

from __future__ import annotations

import base64

import pytest

from pygoby.errors import ConfigError
from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.bluefin import sentences
from pygoby.frontseat.drivers.bluefin import LOG_REQUESTS, rpm_for_speed
from pygoby.frontseat.plugins import load_driver

from .bluefin_scenario import LAT, LON, T0, command, config, driver_on_memory

BFCMD = frontseat_pb.BluefinExtraCommands


def lines(link) -> list[str]:
    return [text.removesuffix("\r\n") for text in link.take_written()]


def feed(link, token: str, *values: object) -> None:
    link.feed(sentences.build(token, values).message() + "\r\n")


def ack(link, name: str, status: int = 2, text: str = "") -> None:
    feed(link, "$BFACK", "221320.000", name, "", "", status, "", text)


def started(extra: str = ""):
    """A driver whose start-up requests have all been acknowledged."""
    driver, link, clock = driver_on_memory(config(extra=extra))
    for _ in range(60):  # goby3's order each tick: write, then read (an ACK frees the next tick)
        driver.do_work()
        for line in lines(link):
            ack(link, line.split(",")[0][3:])
    assert not driver.out
    return driver, link, clock


def test_loaded_by_plugin_name_and_by_goby3_library_name():
    for name in (
        "bluefin",
        "libgoby_frontseat_bluefin.so.30",
        "/usr/lib/libgoby_frontseat_bluefin.so",
    ):
        assert type(load_driver(name, config())).__name__ == "BluefinFrontSeat"


@pytest.mark.parametrize(
    "extra, error",
    [
        ("", None),
        ("use_rpm_table_for_speed: true rpm_table { speed: 1 rpm: 500 }", "two rpm_table"),
    ],
)
def test_configuration_is_checked(extra, error):
    if error is None:
        driver_on_memory(config(extra=extra))
        return
    with pytest.raises(ConfigError, match=error):
        driver_on_memory(config(extra=extra))
    with pytest.raises(ConfigError, match="bluefin_config"):
        driver_on_memory(frontseat_pb.Config())


def test_start_up_asks_for_acks_first_then_each_sentence_one_at_a_time():
    driver, link, _ = driver_on_memory(
        config(extra='accepting_commands_hook: BFCTL_TRIGGER extra_bplog: "cma"')
    )
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_NOT_CONNECTED
    driver.do_work()
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_IDLE
    sent = lines(link)
    for _ in range(60):
        for line in sent[-1:]:
            ack(link, line.split(",")[0][3:])
        driver.do_work()
        written = lines(link)
        assert len(written) <= 1  # one sentence waits for its ACK at a time
        sent += written
    names = [s.split(",")[1] for s in sent if s.startswith("$BPLOG")]
    assert names == ["ACK", *LOG_REQUESTS, "CTL", "CMA"]
    assert sent[0] == "$BPLOG,ACK,ON*1E"
    assert sent[-1].startswith("$BPSTS,221320.000,1,Deploy*")


def test_without_acks_every_sentence_goes_at_once_and_is_never_resent():
    driver, link, clock = driver_on_memory(config(extra="disable_ack: true"))
    driver.do_work()
    written = lines(link)
    assert [w.split(",")[1] for w in written[:-1]] == list(LOG_REQUESTS)
    assert written[-1].startswith("$BPSTS")
    clock.advance(0.5)
    driver.do_work()
    assert lines(link) == []


def test_an_unacknowledged_sentence_is_written_again_then_dropped_and_demerits_add_up():
    driver, link, clock = driver_on_memory()
    driver.do_work()
    assert lines(link) == ["$BPLOG,ACK,ON*1E"]
    writes = 1
    while driver.state != frontseat_pb.INTERFACE_FS_ERROR:
        clock.advance(1.0)
        driver.set_helm_state(frontseat_pb.HELM_DRIVE)
        driver.do_work()
        writes += len(lines(link))
        assert clock.now() < T0 + 200
    # 4 sentences (more than allowed_nmea_demerits 3) each written 3 times (nmea_resend_attempts),
    # 5 s apart (nmea_resend_interval), then dropped
    assert writes == 4 * 3
    # (the next sentence goes out on the tick after a drop: 1 s here)
    assert clock.now() - T0 == pytest.approx(4 * 3 * 5 + 3)
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_NOT_CONNECTED
    assert driver.status().frontseat_error == frontseat_pb.ERROR_FRONTSEAT_IGNORING_COMMANDS
    driver.do_work()  # goby3 starts up again on the next tick: the link is still open
    assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_IDLE
    assert lines(link)[0] == "$BPLOG,ACK,ON*1E"


def test_any_received_sentence_clears_the_demerits():
    driver, link, clock = driver_on_memory()
    driver.do_work()
    for _ in range(100):
        clock.advance(1.0)
        feed(link, "$BFSVS", sentences.time_of_day(clock.now()), 1500)
        driver.do_work()
    assert driver.state != frontseat_pb.INTERFACE_FS_ERROR


def desired(heading=90.0, speed=1.5, depth=10.0, request_id=1):
    return command(heading, speed, depth, request_id)


@pytest.mark.parametrize(
    "course, extra, expected",
    [
        ((90.0, 1.5, 10.0), "", "90,10,0,1.5,1,0"),
        ((271.25, 2.0, 0.5), "", "271.25,0.5,0,2,1,0"),
        ((90.0, 0.0, 10.0), "", "0,0,2,0,0,1"),  # no speed: stop
        ((90.0, 0.5, 0.5), "", "0,0,2,0,0,1"),  # goby3: both under 1 -> stop (reproduced)
        (
            (90.0, 1.25, 10.0),
            "use_rpm_table_for_speed: true rpm_table { speed: 1 rpm: 500 } rpm_table { speed: 2 rpm: 1000 }",
            "90,10,0,625,0,0",
        ),
    ],
)
def test_desired_course_becomes_bprmb(course, extra, expected):
    driver, link, _ = started(extra)
    driver.send_command_to_frontseat(desired(*course))
    assert lines(link) == [sentences.build("$BPRMB", ("221320.000", expected)).message()]


def test_rpm_interpolation_clips_and_truncates():
    table = [(1.0, 500), (2.0, 1000)]
    assert [rpm_for_speed(s, table) for s in (0.5, 1.0, 1.333, 2.0, 3.0)] == [
        500,
        500,
        666,
        1000,
        1000,
    ]


@pytest.mark.parametrize(
    "fields, expected",
    [
        ({"command": BFCMD.TRIM_ADJUST}, "$BPTRM,221320.000"),
        ({"command": BFCMD.BUOYANCY_ADJUST}, "$BPBOY,221320.000"),
        ({"command": BFCMD.SILENT_MODE, "silent_mode": BFCMD.SILENT}, "$BPSIL,221320.000,1"),
        ({"command": BFCMD.CANCEL_CURRENT_BEHAVIOR}, "$BPRCE,221320.000,0"),
        ({"command": BFCMD.MISSION_END_CONFIRM}, "$BPRCE,221320.000,0"),
        ({"command": BFCMD.ABORT_MISSION}, "$BPABT,221320.000,backseat abort,1"),
        ({"command": BFCMD.MISSION_START_CONFIRM}, "$BPSMC,221320.000,1"),
    ],
)
def test_extra_commands_and_their_responses(fields, expected):
    driver, link, _ = started()
    responses = []
    driver.signal_command_response.connect(responses.append)
    request = frontseat_pb.CommandRequest(response_requested=True, request_id=7)
    request.Extensions[frontseat_pb.BLUEFIN_COMMAND].MergeFrom(BFCMD(**fields))
    request.desired_course.heading = 10  # ignored: one command per request
    driver.send_command_to_frontseat(request)
    (written,) = lines(link)
    assert written.rsplit("*", 1)[0] == expected
    ack(link, expected[3:6])
    driver.do_work()
    assert responses == [frontseat_pb.CommandResponse(request_successful=True, request_id=7)]


def test_a_nak_answers_the_request_unsuccessfully_and_is_not_resent():
    driver, link, clock = started()
    responses = []
    driver.signal_command_response.connect(responses.append)
    driver.send_command_to_frontseat(desired(request_id=3))
    lines(link)
    ack(link, "RMB", status=1, text="payload is not in control")
    driver.do_work()
    assert responses == [
        frontseat_pb.CommandResponse(
            request_successful=False,
            request_id=3,
            error_code=1,
            error_string="payload is not in control",
        )
    ]
    clock.advance(0.5)
    driver.do_work()
    assert not [w for w in lines(link) if "RMB" in w]


def test_a_pending_request_waits_for_its_final_ack():
    driver, link, _ = started()
    responses = []
    driver.signal_command_response.connect(responses.append)
    request = frontseat_pb.CommandRequest(response_requested=True, request_id=9)
    request.Extensions[frontseat_pb.BLUEFIN_COMMAND].command = BFCMD.TRIM_ADJUST
    driver.send_command_to_frontseat(request)
    lines(link)
    ack(link, "TRM", status=3)
    driver.do_work()
    assert responses == [] and len(driver.pending) == 1
    driver.send_command_to_frontseat(desired(request_id=10))  # the queue moves on meanwhile
    assert lines(link)[0].startswith("$BPRMB")
    ack(link, "TRM", status=2)  # final ACK: front of the pending queue
    driver.do_work()
    assert [r.request_id for r in responses] == [9] and not driver.pending
    ack(link, "XYZ")  # heads neither queue: both emptied
    driver.do_work()
    assert not driver.out and not driver.pending


def test_cancel_request_id_forgets_the_outstanding_request():
    driver, link, _ = started()
    responses = []
    driver.signal_command_response.connect(responses.append)
    driver.send_command_to_frontseat(desired(request_id=5))
    driver.send_command_to_frontseat(frontseat_pb.CommandRequest(cancel_request_id=5))
    ack(link, "RMB")
    driver.do_work()
    assert responses == []


def test_navigation_becomes_a_node_status():
    driver, link, _clock = started()
    data = []
    driver.signal_data_from_frontseat.connect(data.append)
    feed(
        link,
        "$BFNVG",
        "221320.000",
        "4405.3333",
        "N",
        "00950.9167",
        "E",
        1,
        "12.5",
        "10.25",
        "90",
        "1",
        "-2",
        "221319.500",
    )
    feed(link, "$BFNVR", "221320.000", "1.2", "0.9", "0", "0.1", "0.2", "0.3")
    driver.do_work()
    (status,) = [d.node_status for d in data]
    assert status.name == "bluefin_auv"
    assert (status.global_fix.lat, status.global_fix.lon) == pytest.approx((LAT, LON), abs=1e-6)
    assert (status.global_fix.altitude, status.global_fix.depth) == (12.5, 10.25)
    assert (status.pose.heading, status.pose.roll, status.pose.pitch) == (90, 1, -2)
    assert (status.pose.pitch_rate, status.pose.roll_rate, status.pose.heading_rate) == (
        0.1,
        0.2,
        0.3,
    )
    assert status.speed.over_ground == pytest.approx(1.5)
    assert status.source.position == frontseat_pb.Source.GPS
    assert status.time == T0 - 0.5  # the time the solution was computed
    assert (
        abs(status.local_fix.x) < 1 and abs(status.local_fix.y) < 1 and status.local_fix.z == -10.25
    )
    assert driver.frontseat_providing_data()


def test_only_nvg_counts_as_data_arriving():
    """goby3 also counts $BFACK, which comes for every heartbeat: missing navigation would then
    go unnoticed (fixed: the configuration says "without $BFNVG")."""
    driver, link, clock = started()
    feed(
        link,
        "$BFNVG",
        "221320.000",
        "4405.3333",
        "N",
        "00950.9167",
        "E",
        0,
        "",
        "1",
        "0",
        "0",
        "0",
        "221320.000",
    )
    driver.do_work()
    assert driver.frontseat_providing_data()
    for _ in range(7):
        clock.advance(1.0)
        for line in lines(link):
            ack(link, line.split(",")[0][3:])
        driver.do_work()
    assert not driver.frontseat_providing_data()


def test_sensor_sentences_become_extension_data():
    driver, link, _ = started()
    data = []
    driver.signal_data_from_frontseat.connect(data.append)
    feed(link, "$BFCTD", "221320.000", "42000", "10.5", "101.325", "221320.000")
    feed(link, "$BFRVL", "221320.000", "750", "1.5")
    feed(link, "$BFDVL", "221320.000", "1.4", "0.1", "", "20", "21", "", "23", "9.5", "221319.50")
    feed(link, "$BFBOY", "221320.000", 2, 0, "done", "1.5")
    feed(link, "$BFTRM", "221320.000", 2, 7, "done", "0.5", "-0.25")
    driver.do_work()
    ctd, rvl, dvl, boy, trm = data
    assert ctd.ctd_sample.conductivity == pytest.approx(4.2)
    assert ctd.ctd_sample.pressure == pytest.approx(101325) and ctd.ctd_sample.HasField("salinity")
    bf = frontseat_pb.BLUEFIN_DATA
    assert rvl.Extensions[bf].thruster.rotation == 750
    assert not dvl.Extensions[bf].dvl.HasField("w") and dvl.Extensions[bf].dvl.dvl_time == 221319.5
    assert boy.Extensions[bf].buoyancy_status.buoyancy_newtons == 1.5
    trim = trm.Extensions[bf].trim_status
    assert trim.status == frontseat_pb.TrimStatus.TRIM_COMPLETED_SUCCESSFULLY
    assert not trim.HasField("error")  # 7 is no TrimStatus.Error: left unset
    assert (trim.pitch_trim_degrees, trim.roll_trim_degrees) == (0.5, -0.25)


@pytest.mark.parametrize(
    "hook, events, expected",
    [
        ("BFMSC_TRIGGER", [("$BFMIS", "x", "Running")], frontseat_pb.FRONTSEAT_IN_CONTROL),
        ("BFMSC_TRIGGER", [("$BFMSC", "go")], frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS),
        (
            "BFMIS_RUNNING_TRIGGER",
            [("$BFMIS", "x", "Running")],
            frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS,
        ),
        ("BFCTL_TRIGGER", [("$BFMSC", "go")], frontseat_pb.FRONTSEAT_IDLE),
        ("BFCTL_TRIGGER", [("$BFCTL", "1")], frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS),
        ("BFCTL_TRIGGER", [("$BFCTL", "1"), ("$BFCTL", "0")], frontseat_pb.FRONTSEAT_IN_CONTROL),
        (
            "BFMSC_TRIGGER",
            [("$BFMSC", "go"), ("$BFMIS", "x", "Stopped")],
            frontseat_pb.FRONTSEAT_IDLE,
        ),
    ],
)
def test_accepting_commands_hooks(hook, events, expected):
    driver, link, _ = started(f"accepting_commands_hook: {hook}")
    for token, *values in events:
        feed(link, token, "221320.000", *values)
    driver.do_work()
    assert driver.frontseat_state() == expected


def test_data_to_the_frontseat():
    driver, link, _clock = started()
    data = frontseat_pb.InterfaceData(dccl_message=b"\x01\x02\xff")
    ctd = data.ctd_sample
    ctd.conductivity, ctd.temperature, ctd.pressure, ctd.time = 4.2, 10.5, 101325.0, T0 - 1
    extra = data.Extensions[frontseat_pb.BLUEFIN_DATA]
    extra.micro_modem_raw_in.raw = b"$CARXD,1,2,0,1,abcd*7F\r"
    driver.send_data_to_frontseat(data)
    sent = []
    for _ in range(3):
        (line,) = lines(link)
        sent.append(line.rsplit("*", 1)[0])
        ack(link, line[3:6])
        driver.do_work()  # reads the ACK
        driver.do_work()  # writes the next
    assert sent == [
        "$BPCTD,221320.000,4.2,10.5,101.325,221319.000",
        "$BPDCL,221320.000," + base64.b64encode(b"\x01\x02\xff").decode(),
        "$BPTMR,221320.000,3,$CARXD:1:2:0:1:abcd/7F ",
    ]


def test_heartbeat_every_interval_with_payload_status():
    driver, link, clock = started()
    data = frontseat_pb.InterfaceData()
    status = data.Extensions[frontseat_pb.BLUEFIN_DATA].payload_status.add()
    status.id, status.expire_time, status.msg, status.all_ok = (
        1,
        int((T0 + 2.5) * 1e6),
        "sonar warm",
        False,
    )
    driver.send_data_to_frontseat(data)
    beats = []
    for _ in range(4):
        clock.advance(1.0)
        driver.do_work()
        for line in lines(link):
            beats.append(line.rsplit("*", 1)[0])
            ack(link, "STS")
        driver.do_work()
    assert beats == [
        "$BPSTS,221321.000,0,2023-Nov-14 22:13:21; sonar warm",
        "$BPSTS,221322.000,0,2023-Nov-14 22:13:22; sonar warm",
        "$BPSTS,221323.000,1,Deploy",
        "$BPSTS,221324.000,1,Deploy",
    ]


def test_raw_out_is_written_with_its_checksum_recomputed():
    driver, link, _ = started()
    driver.send_raw_to_frontseat(frontseat_pb.Raw(raw=b"$BPMSG,hello*00"))
    driver.send_raw_to_frontseat(frontseat_pb.Raw(raw=b"not a sentence"))
    assert lines(link) == ["$BPMSG,hello*05"]
