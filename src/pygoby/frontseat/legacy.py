"""iFrontSeat's legacy MOOS variables, sans I/O.

* `nav_posts(node_status)`: the NAV_* doubles (and GPS_UPDATE_RECEIVED) for one navigation
  solution of the frontseat (`publish_nav`).
* `DesiredCourseCommands`: the helm's DESIRED_* doubles accumulated into one DesiredCourse; each
  DESIRED_SPEED yields a CommandRequest (`subscribe_desired`).
* `CtdSamples`: CTD_* doubles accumulated into one CTDSample; each CTD_TEMPERATURE yields a
  sample placed at the last navigation fix (`subscribe_ctd`).
* `ready_posts(status)`: FRONTSEAT_READY / BACKSEAT_READY for an interface status
  (`publish_fs_bs_ready`).
* `BluefinCommands`: BUOYANCY_CONTROL, TRIM_CONTROL, FRONTSEAT_BHVOFF, FRONTSEAT_SILENT,
  BACKSEAT_ABORT -> CommandRequests with the Bluefin extra command; `bluefin_report_posts(data)`:
  TRIM_REPORT / BUOYANCY_REPORT for the driver's Bluefin trim/buoyancy status
  (`pub_sub_bf_commands`).
* `modem_raw_data(raw, incoming)`: a Micro-Modem sentence (ACOMMS_RAW_INCOMING/OUTGOING) as
  InterfaceData for the frontseat (`subscribe_acomms_raw`).

A "post" is a (MOOS variable, value) pair: float for a MOOS double, str for a string.
"""

from __future__ import annotations

import math
from typing import Any

from pygoby.frontseat import messages as frontseat_pb

Post = tuple[str, float | str]

# Request ids of the commands made from DESIRED_* start here (goby3's legacy identifier), so
# that they do not collide with the ids other processes choose for IFS_COMMAND_REQUEST.
LEGACY_REQUEST_ID_BASE = 65536

# DESIRED_* variable -> DesiredCourse field (degrees, m/s, m as the helm posts them).
DESIRED_FIELDS = {
    "DESIRED_HEADING": "heading",
    "DESIRED_SPEED": "speed",
    "DESIRED_DEPTH": "depth",
    "DESIRED_PITCH": "pitch",
    "DESIRED_ROLL": "roll",
    "DESIRED_Z_RATE": "z_rate",
    "DESIRED_ALTITUDE": "altitude",
}
DESIRED_TRIGGER = "DESIRED_SPEED"

# CTD_* variable -> (CTDSample field, factor to the field's unit). CTD_PRESSURE is in dbar.
CTD_FIELDS = {
    "CTD_CONDUCTIVITY": ("conductivity", 1.0),
    "CTD_TEMPERATURE": ("temperature", 1.0),
    "CTD_PRESSURE": ("pressure", 1e4),
    "CTD_SALINITY": ("salinity", 1.0),
}
CTD_TRIGGER = "CTD_TEMPERATURE"


def nav_posts(status: Any) -> list[Post]:
    """NAV_* for a NodeStatus: NAV_X/NAV_Y/NAV_LAT/NAV_LONG/NAV_SPEED always, the others when
    their field is set; NAV_YAW is the heading negated, in radians (MOOS's yaw), NAV_PITCH and
    NAV_ROLL are radians. A position whose source is GPS also gives GPS_UPDATE_RECEIVED with the
    fix time."""
    fix, pose = status.global_fix, status.pose
    posts: list[Post] = [
        ("NAV_X", status.local_fix.x),
        ("NAV_Y", status.local_fix.y),
        ("NAV_LAT", fix.lat),
        ("NAV_LONG", fix.lon),
    ]
    if status.local_fix.HasField("z"):
        posts.append(("NAV_Z", status.local_fix.z))
    if fix.HasField("depth"):
        posts.append(("NAV_DEPTH", fix.depth))
    if pose.HasField("heading"):
        posts.append(("NAV_HEADING", pose.heading))
        posts.append(("NAV_YAW", -math.radians(pose.heading)))
    posts.append(("NAV_SPEED", status.speed.over_ground))
    if pose.HasField("pitch"):
        posts.append(("NAV_PITCH", math.radians(pose.pitch)))
    if pose.HasField("roll"):
        posts.append(("NAV_ROLL", math.radians(pose.roll)))
    if fix.HasField("altitude"):
        posts.append(("NAV_ALTITUDE", fix.altitude))
    # Only a position source that is set: goby3 compares the proto2 default too (unset reads GPS).
    if status.source.HasField("position") and status.source.position == frontseat_pb.Source.GPS:
        posts.append(("GPS_UPDATE_RECEIVED", f"Timestamp={status.time:.15g}"))
    return posts


class RequestIds:
    """The request ids of the commands iFrontSeat makes itself: one count for every kind, from
    LEGACY_REQUEST_ID_BASE (as goby3's translator)."""

    def __init__(self) -> None:
        self.count = 0

    def request(self) -> Any:
        """A new CommandRequest asking for a response, with the next id."""
        request = frontseat_pb.CommandRequest(
            response_requested=True, request_id=LEGACY_REQUEST_ID_BASE + self.count
        )
        self.count += 1
        return request


class DesiredCourseCommands:
    """The helm's desired course, one variable at a time."""

    def __init__(self, ids: RequestIds | None = None) -> None:
        self.course = frontseat_pb.DesiredCourse()
        self.ids = ids if ids is not None else RequestIds()

    def update(self, var: str, value: float, time: float) -> Any | None:
        """Record DESIRED_* `var`; returns the CommandRequest to post when `var` is
        DESIRED_SPEED (its mail time becomes the course time), else None."""
        setattr(self.course, DESIRED_FIELDS[var], value)
        if var != DESIRED_TRIGGER:
            return None
        self.course.time = time
        request = self.ids.request()
        request.desired_course.CopyFrom(self.course)
        return request


class CtdSamples:
    """CTD readings, one variable at a time, at the position of the last NodeStatus (NaN until
    one arrives)."""

    def __init__(self) -> None:
        self.sample = frontseat_pb.CTDSample()
        self.lat = math.nan
        self.lon = math.nan

    def update_position(self, status: Any) -> None:
        self.lat, self.lon = status.global_fix.lat, status.global_fix.lon

    def update(self, var: str, value: float, time: float) -> Any | None:
        """Record CTD_* `var`; returns a copy of the sample when `var` is CTD_TEMPERATURE (its
        mail time becomes the sample time), else None. The caller computes the missing
        fields (salinity, depth, sound speed, density)."""
        field, factor = CTD_FIELDS[var]
        setattr(self.sample, field, value * factor)
        if var != CTD_TRIGGER:
            return None
        self.sample.time = time
        sample = frontseat_pb.CTDSample()
        sample.CopyFrom(self.sample)
        sample.global_fix.lat = self.lat
        sample.global_fix.lon = self.lon
        return sample


def ready_posts(status: Any) -> list[Post]:
    """FRONTSEAT_READY (frontseat accepting commands) and BACKSEAT_READY (helm driving), 1 or 0."""
    return [
        (
            "FRONTSEAT_READY",
            float(status.frontseat_state == frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS),
        ),
        ("BACKSEAT_READY", float(status.helm_state == frontseat_pb.HELM_DRIVE)),
    ]


# Bluefin extra commands from MOOS (pub_sub_bf_commands): variable -> BluefinCommand. goby3's
# documentation also names PENDING_SURFACE (a GPS request), which no goby3 code defines or
# subscribes to: nothing here either (QUIRKS.md Q-BLUEFIN-11).
_BFCMD = frontseat_pb.BluefinExtraCommands
BLUEFIN_COMMAND_VARS = {
    "BUOYANCY_CONTROL": _BFCMD.BUOYANCY_ADJUST,
    "TRIM_CONTROL": _BFCMD.TRIM_ADJUST,
    "FRONTSEAT_BHVOFF": _BFCMD.CANCEL_CURRENT_BEHAVIOR,
    "FRONTSEAT_SILENT": _BFCMD.SILENT_MODE,
    "BACKSEAT_ABORT": _BFCMD.ABORT_MISSION,
}
# these three only act on a true string ("true"/"1", any case, spaces trimmed)
_ONLY_WHEN_TRUE = frozenset({"BUOYANCY_CONTROL", "TRIM_CONTROL", "FRONTSEAT_BHVOFF"})


def _truthy(text: str) -> bool:
    return text.strip().lower() in ("true", "1")


class BluefinCommands:
    """The Bluefin command variables, each post -> a CommandRequest (or None)."""

    def __init__(self, ids: RequestIds | None = None) -> None:
        self.ids = ids if ids is not None else RequestIds()

    def update(self, var: str, text: str, number: float | None) -> Any | None:
        """`text`: the post as a string ("" for a double, as MOOS gives it); `number`: the
        double, None for a string. BUOYANCY_CONTROL / TRIM_CONTROL / FRONTSEAT_BHVOFF command
        only when true; FRONTSEAT_SILENT always (SILENT when true, else NORMAL);
        BACKSEAT_ABORT always (SUCCESSFUL_MISSION for a double whose integer part is 0, else
        ABORT_WITH_ERRORS)."""
        if var in _ONLY_WHEN_TRUE and not _truthy(text):
            return None
        request = self.ids.request()
        extra = request.Extensions[frontseat_pb.BLUEFIN_COMMAND]
        extra.command = BLUEFIN_COMMAND_VARS[var]
        if var == "FRONTSEAT_SILENT":
            extra.silent_mode = _BFCMD.SILENT if _truthy(text) else _BFCMD.NORMAL
        elif var == "BACKSEAT_ABORT":
            success = number is not None and math.isfinite(number) and int(number) == 0
            extra.abort_reason = _BFCMD.SUCCESSFUL_MISSION if success else _BFCMD.ABORT_WITH_ERRORS
        return request


def bluefin_report_posts(data: Any) -> list[Post]:
    """TRIM_REPORT `status=<n>,error=<n>,trim_pitch=<deg>,trim_roll=<deg>` and BUOYANCY_REPORT
    `status=<n>,error=<n>,buoyancy=<N>` for Bluefin trim/buoyancy status in `data` (numbers as
    C++ streams print them: 6 significant digits)."""
    if not data.HasExtension(frontseat_pb.BLUEFIN_DATA):
        return []
    extra = data.Extensions[frontseat_pb.BLUEFIN_DATA]
    posts: list[Post] = []
    if extra.HasField("trim_status"):
        trim = extra.trim_status
        posts.append(
            (
                "TRIM_REPORT",
                f"status={trim.status},error={trim.error},"
                f"trim_pitch={trim.pitch_trim_degrees:g},trim_roll={trim.roll_trim_degrees:g}",
            )
        )
    if extra.HasField("buoyancy_status"):
        boy = extra.buoyancy_status
        posts.append(
            (
                "BUOYANCY_REPORT",
                f"status={boy.status},error={boy.error},buoyancy={boy.buoyancy_newtons:g}",
            )
        )
    return posts


ACOMMS_RAW_VARS = {"ACOMMS_RAW_INCOMING": True, "ACOMMS_RAW_OUTGOING": False}  # var -> incoming


def modem_raw_data(raw: Any, incoming: bool) -> Any:
    """InterfaceData carrying a ModemRaw as Bluefin's micro_modem_raw_in (incoming) or _out."""
    data = frontseat_pb.InterfaceData()
    extra = data.Extensions[frontseat_pb.BLUEFIN_DATA]
    (extra.micro_modem_raw_in if incoming else extra.micro_modem_raw_out).CopyFrom(raw)
    return data
