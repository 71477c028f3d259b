"""iFrontSeat's legacy Bluefin variables (pub_sub_bf_commands, subscribe_acomms_raw), sans I/O."""

from __future__ import annotations

import pytest

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.legacy import (
    LEGACY_REQUEST_ID_BASE,
    BluefinCommands,
    DesiredCourseCommands,
    RequestIds,
    bluefin_report_posts,
    modem_raw_data,
)

BFCMD = frontseat_pb.BluefinExtraCommands


@pytest.mark.parametrize(
    "var, text, number, expected",
    [
        ("BUOYANCY_CONTROL", " TRUE ", None, {"command": BFCMD.BUOYANCY_ADJUST}),
        ("BUOYANCY_CONTROL", "false", None, None),
        ("BUOYANCY_CONTROL", "", 1.0, None),  # a double reads as "" (as MOOS's GetString)
        ("TRIM_CONTROL", "1", None, {"command": BFCMD.TRIM_ADJUST}),
        ("FRONTSEAT_BHVOFF", "true", None, {"command": BFCMD.CANCEL_CURRENT_BEHAVIOR}),
        (
            "FRONTSEAT_SILENT",
            "true",
            None,
            {"command": BFCMD.SILENT_MODE, "silent_mode": BFCMD.SILENT},
        ),
        (
            "FRONTSEAT_SILENT",
            "no",
            None,
            {"command": BFCMD.SILENT_MODE, "silent_mode": BFCMD.NORMAL},
        ),
        (
            "BACKSEAT_ABORT",
            "",
            0.7,
            {"command": BFCMD.ABORT_MISSION, "abort_reason": BFCMD.SUCCESSFUL_MISSION},
        ),
        (
            "BACKSEAT_ABORT",
            "",
            2.0,
            {"command": BFCMD.ABORT_MISSION, "abort_reason": BFCMD.ABORT_WITH_ERRORS},
        ),
        (
            "BACKSEAT_ABORT",
            "x",
            None,
            {"command": BFCMD.ABORT_MISSION, "abort_reason": BFCMD.ABORT_WITH_ERRORS},
        ),
    ],
)
def test_bluefin_command_variables(var, text, number, expected):
    request = BluefinCommands().update(var, text, number)
    if expected is None:
        assert request is None
        return
    assert request.response_requested and request.request_id == LEGACY_REQUEST_ID_BASE
    extra = request.Extensions[frontseat_pb.BLUEFIN_COMMAND]
    assert extra == BFCMD(**expected)


def test_one_request_id_count_for_every_command_made_by_the_app():
    ids = RequestIds()
    course, bluefin = DesiredCourseCommands(ids), BluefinCommands(ids)
    first = course.update("DESIRED_SPEED", 1.0, 5.0)
    second = bluefin.update("TRIM_CONTROL", "true", None)
    assert (first.request_id, second.request_id) == (
        LEGACY_REQUEST_ID_BASE,
        LEGACY_REQUEST_ID_BASE + 1,
    )


def test_trim_and_buoyancy_reports():
    data = frontseat_pb.InterfaceData()
    extra = data.Extensions[frontseat_pb.BLUEFIN_DATA]
    extra.trim_status.status = frontseat_pb.TrimStatus.TRIM_COMPLETED_SUCCESSFULLY
    extra.trim_status.pitch_trim_degrees = 0.5
    extra.trim_status.roll_trim_degrees = -1.25
    extra.buoyancy_status.buoyancy_newtons = 12.3456789
    assert bluefin_report_posts(data) == [
        ("TRIM_REPORT", "status=2,error=0,trim_pitch=0.5,trim_roll=-1.25"),
        ("BUOYANCY_REPORT", "status=0,error=0,buoyancy=12.3457"),
    ]
    assert bluefin_report_posts(frontseat_pb.InterfaceData()) == []


def test_modem_raw_goes_in_the_bluefin_extension():
    raw = frontseat_pb.ModemRaw(raw=b"$CARXD,1*00", description="incoming")
    extra = modem_raw_data(raw, incoming=True).Extensions[frontseat_pb.BLUEFIN_DATA]
    assert extra.micro_modem_raw_in == raw and not extra.HasField("micro_modem_raw_out")
    extra = modem_raw_data(raw, incoming=False).Extensions[frontseat_pb.BLUEFIN_DATA]
    assert extra.micro_modem_raw_out == raw
