"""pREMUSCodec's translation, sans I/O: REMUS CCL frames
(pygoby.dccl.ccl.remus) to the Goby 1.1 MOOS strings and contact variables, and our NAV_* /
OUTGOING_COMMAND to State / Redirect frames. Numbers are printed as Goby 1.1's `as<string>`
prints them (doubles with 17 significant digits, integers plainly).

    reports = RemusReports(UTMGeodesy(lat0, lon0), ModemIdLookup.from_file(path))
    posts = reports.incoming("state", data, src=2, dest=1, now=t)   # [(var, value), ...]
    data = reports.state_frame(x, y, depth, speed, heading, now=t)
    dest, data = reports.redirect_command("MessageType=CCL_REDIRECT,...")  # or None

Bad frames and commands raise the CCL errors (CCLFrameError, CCLEncodeError) with the reason.
Where this differs from Goby 1.1 (all documented in the README's pREMUSCodec section): frames
are checked (1.1 decoded anything arriving on a variable), CCL_REDIRECT_IN's
DestinationPlatformId is the frame's destination (1.1 printed the sender there) and its
SpeedDepthFlags this frame's byte (1.1 appended every frame's flags to one string), Alert2
contact ages leave out the heading-type bit, and a command's missing values are errors or zeros
(1.1 kept the previous command's values).
"""

from __future__ import annotations

import math

from pygoby.dccl.ccl.remus import (
    Alert,
    Alert2,
    CCLEncodeError,
    CCLFrame,
    Position,
    Ranger,
    Redirect,
    State,
    TimeDate,
    decode_frame,
)
from pygoby.moos.translator.conversions import double_to_string17 as num
from pygoby.moos.translator.keyvalue import val_from_string
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.modem_id import ModemIdLookup

Posts = list[tuple[str, str | float]]
KINDS = ("state", "ranger", "redirect", "alert", "alert2")  # the incoming variables
VELOCITY_RANGE = (-5.12, 5.08)  # what a State's est_velocity byte holds (m/s)
NODE_REPORT_TAIL = ",LENGTH=4.0,MODE=NOMOOS,ALLSTOP=NotUsingIvP"  # not in REMUS frames


def key_values(pairs: list[tuple[str, object]]) -> str:
    return ",".join(f"{key}={value}" for key, value in pairs)


class RemusReports:
    """The translation for one vehicle (its datum and modem-id table)."""

    def __init__(self, geodesy: UTMGeodesy, lookup: ModemIdLookup) -> None:
        self.geodesy = geodesy
        self.lookup = lookup

    # ------------------------------------------------------------------ frames -> MOOS
    def incoming(self, kind: str, data: bytes, src: int, dest: int, now: float) -> Posts:
        """The posts for a frame that arrived on the `kind` variable (KINDS). Alert frames are
        read as their variable says; the others by their id byte."""
        frame: CCLFrame
        if kind == "alert":
            frame = Alert.decode(data)
        elif kind == "alert2":
            frame = Alert2.decode(data)
        else:
            frame = decode_frame(data)
        if isinstance(frame, State | Ranger):
            return self._position_report(frame, src, now)
        if isinstance(frame, Position):
            return self._position(frame, src, now)
        if isinstance(frame, Redirect):
            return [("CCL_REDIRECT_IN", redirect_text(frame, dest, now))]
        if isinstance(frame, Alert):
            return [("CCL_ALERT_IN", self._alert(frame, src))]
        assert isinstance(frame, Alert2)
        return [("CCL_ALERT2_IN", self._alert2(frame, src))]

    def _contacts(self, src: int, lat: float, lon: float, x: float, y: float, now: float) -> Posts:
        """The contact variables collision avoidance reads: <NAME>_NAV_*."""
        name = self.lookup.name(src).upper()
        return [
            (f"{name}_NAV_UTC", now),
            (f"{name}_NAV_X", x),
            (f"{name}_NAV_Y", y),
            (f"{name}_NAV_LAT", lat),
            (f"{name}_NAV_LONG", lon),
        ]

    def _position_report(self, frame: State | Ranger, src: int, now: float) -> Posts:
        lat, lon = frame.latitude, frame.longitude
        x, y = self.geodesy.to_local(lat, lon)
        speed = frame.est_velocity if isinstance(frame, State) else frame.speed
        status = [
            ("MessageType", "CCL_STATUS"),
            ("Node", src),
            ("Timestamp", num(now)),
            ("Latitude", num(lat)),
            ("Longitude", num(lon)),
            ("Speed", num(speed)),
            ("Heading", num(frame.heading)),
            ("Depth", num(frame.depth)),
        ]
        if isinstance(frame, State):
            gpo = frame.gfi_pitch_oil
            status += [
                ("GoalLatitude", num(frame.lat_goal)),
                ("GoalLongitude", num(frame.lon_goal)),
                ("Batterypercent", frame.battery_percent),
                ("GFI", num(gpo.gfi)),
                ("Pitch", num(gpo.pitch)),
                ("Oil", num(gpo.oil)),
            ]
        name = self.lookup.name(src)
        node_report = (
            key_values(
                [
                    ("NAME", name),
                    ("TYPE", self.lookup.type(src)),
                    ("MOOSDB_TIME", -1),
                    ("UTC_TIME", num(now)),
                    ("X", num(x)),
                    ("Y", num(y)),
                    ("LAT", num(lat)),
                    ("LON", num(lon)),
                    ("SPD", num(speed)),
                    ("HDG", num(frame.heading)),
                    ("YAW", num(frame.heading - 360)),
                    ("DEPTH", num(frame.depth)),
                ]
            )
            + NODE_REPORT_TAIL
        )
        upper = name.upper()
        return [
            ("STATUS_REPORT_IN", key_values(status)),
            *self._contacts(src, lat, lon, x, y, now),
            (f"{upper}_NAV_SPEED", speed),
            (f"{upper}_NAV_DEPTH", frame.depth),
            (f"{upper}_NAV_HEADING", frame.heading),
            ("NODE_REPORT", node_report),
        ]

    def _position(self, frame: Position, src: int, now: float) -> Posts:
        x, y = self.geodesy.to_local(frame.latitude, frame.longitude)
        text = key_values(
            [
                ("MessageType", "CCL_POSITION"),
                ("Node", src),
                ("Type", frame.type_name),
                ("Timestamp", num(now)),
                ("Latitude", num(frame.latitude)),
                ("Longitude", num(frame.longitude)),
                ("Label", frame.label),
            ]
        )
        return [
            ("CCL_POSITION_IN", text),
            *self._contacts(src, frame.latitude, frame.longitude, x, y, now),
        ]

    @staticmethod
    def _alert_head(kind: str, frame: Alert | Alert2, src: int) -> list[tuple[str, object]]:
        return [
            ("MessageType", kind),
            ("Node", src),
            ("Timestamp", num(float(frame.oasis_time))),
            ("Latitude", num(frame.latitude)),
            ("Longitude", num(frame.longitude)),
        ]

    def _alert(self, frame: Alert, src: int) -> str:
        pairs = [*self._alert_head("CCL_ALERT", frame, src), ("Heading", num(frame.heading))]
        for n, c in enumerate(frame.contacts, start=1):
            pairs += [
                (f"Contact{n}Id", c.id),
                (f"Contact{n}Age", c.age),
                (f"Contact{n}Bearing", c.bearing),
                (f"Contact{n}Signature1", c.signature1),
                (f"Contact{n}Signature2", c.signature2),
            ]
        return key_values(pairs)

    def _alert2(self, frame: Alert2, src: int) -> str:
        pairs = self._alert_head("CCL_ALERT2", frame, src)
        for n, c in enumerate(frame.contacts, start=1):
            pairs += [
                (f"Contact{n}Id", c.id),
                (f"Contact{n}Age", c.age),
                (f"Contact{n}Bearing", c.bearing),
                (f"Contact{n}HeadingType", "Absolute" if c.absolute_heading else "Vehicle"),
                (f"Contact{n}Heading", num(c.heading)),
                (f"Contact{n}Signature1", c.signature1),
                (f"Contact{n}Signature2", c.signature2),
            ]
        return key_values(pairs)

    # ------------------------------------------------------------------ MOOS -> frames
    def state_frame(
        self, x: float, y: float, depth: float, speed: float, heading: float, now: float
    ) -> bytes:
        """Our own State from NAV_* (local x/y converted with the datum) at `now`; the speed is
        limited to what the frame holds."""
        lat, lon = self.geodesy.to_geo(x, y)
        if math.isfinite(speed):
            speed = min(max(speed, VELOCITY_RANGE[0]), VELOCITY_RANGE[1])
        return State(
            latitude=lat,
            longitude=lon,
            time=TimeDate.at(now),
            heading=heading,
            depth=depth,
            est_velocity=speed,
        ).encode()

    @staticmethod
    def redirect_command(text: str) -> tuple[int, bytes] | None:
        """(destination, frame) of an OUTGOING_COMMAND `MessageType=CCL_REDIRECT,...`; None for
        any other command. Keys are case-insensitive; DestinationPlatformId, Latitude and
        Longitude are required, the other values default to 0 (SpeedDepthFlags: hex)."""
        if (val_from_string(text, "MessageType") or "").strip().upper() != "CCL_REDIRECT":
            return None

        def number(key: str, required: bool = False) -> float:
            value = val_from_string(text, key)
            if value is None:
                if required:
                    raise CCLEncodeError(f"CCL_REDIRECT command without {key}")
                return 0.0
            try:
                parsed = float(value)
            except ValueError:
                raise CCLEncodeError(f"CCL_REDIRECT {key}={value!r} is not a number") from None
            if not math.isfinite(parsed):
                raise CCLEncodeError(f"CCL_REDIRECT {key}={value!r} is not a finite number")
            return parsed

        def whole(key: str, required: bool = False) -> int:
            return int(number(key, required))  # truncated, as Goby 1.1's int(double)

        flags = (val_from_string(text, "SpeedDepthFlags") or "0").strip()
        try:
            speed_depth_flags = int(flags, 16)
        except ValueError:
            raise CCLEncodeError(
                f"CCL_REDIRECT SpeedDepthFlags={flags!r} is not hexadecimal"
            ) from None
        dest = whole("DestinationPlatformId", required=True)
        if dest < 0:
            raise CCLEncodeError(f"CCL_REDIRECT DestinationPlatformId={dest} is not a modem id")
        redirect = Redirect(
            latitude=number("Latitude", True),
            longitude=number("Longitude", True),
            speed_depth_flags=speed_depth_flags,
            transit_depth=number("TransitDepth"),
            transit_speed=number("TransitSpeed"),
            transit_command=whole("TransitCommand"),
            survey_depth=number("SurveyDepth"),
            survey_speed=number("SurveySpeed"),
            survey_command=whole("SurveyCommand"),
            num_rows=whole("NumberOfRows"),
            row_length=whole("RowLength"),
            spacing_0=whole("RowSpacing0"),
            spacing_1=whole("RowSpacing1"),
            row_heading=number("RowHeading"),
            start_latitude=number("StartLatitude"),
            start_longitude=number("StartLongitude"),
        )
        return dest, redirect.encode()


def redirect_text(frame: Redirect, dest: int, now: float) -> str:
    """CCL_REDIRECT_IN: the keys an OUTGOING_COMMAND takes, so it can be sent on again."""
    return key_values(
        [
            ("MessageType", "CCL_REDIRECT"),
            ("DestinationPlatformId", dest),
            ("Timestamp", num(now)),
            ("Latitude", num(frame.latitude)),
            ("Longitude", num(frame.longitude)),
            ("SpeedDepthFlags", f"{frame.speed_depth_flags:02X}"),
            ("TransitSpeed", num(frame.transit_speed)),
            ("TransitDepth", num(frame.transit_depth)),
            ("TransitCommand", frame.transit_command),
            ("SurveySpeed", num(frame.survey_speed)),
            ("SurveyDepth", num(frame.survey_depth)),
            ("SurveyCommand", frame.survey_command),
            ("NumberOfRows", frame.num_rows),
            ("RowLength", frame.row_length),
            ("RowSpacing0", frame.spacing_0),
            ("RowSpacing1", frame.spacing_1),
            ("RowHeading", num(frame.row_heading)),
            ("StartLatitude", num(frame.start_latitude)),
            ("StartLongitude", num(frame.start_longitude)),
        ]
    )
