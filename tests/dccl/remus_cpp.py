"""REMUS State / Redirect frames (pygoby.dccl.ccl.remus) as the C++ DCCL messages that carry the
same bytes (dccl.legacyccl.protobuf.CCLMDATState / CCLMDATRedirect), for the recorder
(tests/dccl/oracle/record_remus.py) and the tests that read its file (data/remus_frames.jsonl)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from google.protobuf.message import Message

from pygoby.dccl.ccl import fields, remus
from pygoby.protobuf import builtin_class

DATA = Path(__file__).parent / "data" / "remus_frames.jsonl"
CCL_PROTO = "dccl/ccl/protobuf/ccl.proto"
MESSAGE = {
    "State": "dccl.legacyccl.protobuf.CCLMDATState",
    "Redirect": "dccl.legacyccl.protobuf.CCLMDATRedirect",
}
FRAME = {"State": remus.State, "Redirect": remus.Redirect}


def message_class(kind: str) -> type[Message]:
    return builtin_class(CCL_PROTO, MESSAGE[kind])


def to_message(frame: remus.State | remus.Redirect, now: float) -> Message:
    """The CCLMDAT message with the frame's values (`now`: the receiver's clock, whose year a
    decoded time_date takes)."""
    if isinstance(frame, remus.State):
        msg = message_class("State")(
            latitude=frame.latitude,
            longitude=frame.longitude,
            fix_age=frame.fix_age,
            time_date=fields.timegm(fields.utc_year(now), *frame.time) * 1_000_000,
            heading=frame.heading,
            depth=frame.depth,
            mission_mode=frame.mission_mode,
            faults=frame.faults.to_bytes(4, "little"),
            faults_2=bytes([frame.faults_2]),
            mission_leg=frame.mission_leg,
            est_velocity=frame.est_velocity,
            objective_index=bytes([frame.objective_index]),
            watts=frame.watts,
            lat_goal=frame.lat_goal,
            lon_goal=frame.lon_goal,
            battery_percent=frame.battery_percent,
        )
        gpo = frame.gfi_pitch_oil
        msg.gfi_pitch_oil.gfi, msg.gfi_pitch_oil.pitch, msg.gfi_pitch_oil.oil = (
            gpo.gfi,
            gpo.pitch,
            gpo.oil,
        )
        return msg
    flags = frame.speed_depth_flags
    return message_class("Redirect")(
        message_number=frame.message_number,
        latitude=frame.latitude,
        longitude=frame.longitude,
        transit_vertical_mode=flags & 7,
        transit_thrust_mode=flags >> 3 & 1,
        survey_vertical_mode=flags >> 4 & 7,
        survey_thrust_mode=flags >> 7 & 1,
        depth_goal_transit=frame.transit_depth,
        speed_transit=frame.transit_speed,
        device_cmd_transit=frame.transit_command,
        depth_goal_survey=frame.survey_depth,
        speed_survey=frame.survey_speed,
        device_cmd_survey=frame.survey_command,
        num_rows=frame.num_rows,
        row_length=frame.row_length,
        spacing_0=frame.spacing_0,
        spacing_1=frame.spacing_1,
        heading=frame.row_heading,
        lat_start=frame.start_latitude,
        lon_start=frame.start_longitude,
        spare=b"\0\0\0",
    )


def to_json(frame: remus.State | remus.Redirect) -> dict:
    return dataclasses.asdict(frame)


def from_json(kind: str, values: dict) -> remus.State | remus.Redirect:
    if kind == "State":
        values = dict(
            values,
            time=remus.TimeDate(*values["time"]),
            gfi_pitch_oil=remus.GFIPitchOil(*values["gfi_pitch_oil"]),
        )
    return FRAME[kind](**values)


def read_records() -> list[dict]:
    return [json.loads(line) for line in DATA.read_text().splitlines() if line.strip()]
