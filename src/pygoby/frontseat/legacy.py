"""iFrontSeat's legacy MOOS variables, sans I/O.

* `nav_posts(node_status)`: the NAV_* doubles (and GPS_UPDATE_RECEIVED) for one navigation
  solution of the frontseat (`publish_nav`).
* `DesiredCourseCommands`: the helm's DESIRED_* doubles accumulated into one DesiredCourse; each
  DESIRED_SPEED yields a CommandRequest (`subscribe_desired`).
* `CtdSamples`: CTD_* doubles accumulated into one CTDSample; each CTD_TEMPERATURE yields a
  sample placed at the last navigation fix (`subscribe_ctd`).
* `ready_posts(status)`: FRONTSEAT_READY / BACKSEAT_READY for an interface status
  (`publish_fs_bs_ready`).

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


class DesiredCourseCommands:
    """The helm's desired course, one variable at a time."""

    def __init__(self) -> None:
        self.course = frontseat_pb.DesiredCourse()
        self.requests = 0

    def update(self, var: str, value: float, time: float) -> Any | None:
        """Record DESIRED_* `var`; returns the CommandRequest to post when `var` is
        DESIRED_SPEED (its mail time becomes the course time), else None."""
        setattr(self.course, DESIRED_FIELDS[var], value)
        if var != DESIRED_TRIGGER:
            return None
        self.course.time = time
        request = frontseat_pb.CommandRequest(
            response_requested=True, request_id=LEGACY_REQUEST_ID_BASE + self.requests
        )
        request.desired_course.CopyFrom(self.course)
        self.requests += 1
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
