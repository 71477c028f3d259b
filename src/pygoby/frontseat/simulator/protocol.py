"""The basic (ABC) frontseat simulator's wire protocol.

ASCII lines `KEY,NAME:VALUE,NAME:VALUE,...` terminated by "\\r\\n" (the terminator is the link's
business; these functions see lines without it). `parse_line` splits a line into a `Message`;
`Start`, `Nav` and `Command` are the typed messages with their exact text forms, shared by the
simulator and the driver so both ends agree on one definition.

Parsing follows the upstream splitter (whitespace trimmed at both ends of the line, split on
",", the first element is the key, each other element split on ":"; the first occurrence of a
name wins) but is stricter where upstream silently produced garbage: a field with no ":" or
more than one, a missing required field, a value that is not a finite decimal number, and
out-of-range START parameters all raise `SimulatorProtocolError` instead of yielding NaN or
INT_MAX.

Number formats reproduce C++ iostreams (default float format = printf "%.<precision>g", so no
trailing zeros, "1e-05" exponent forms, "-0" for negative zero): NAV with precision 10, CMD
with the default precision 6. START prints its doubles with the fewest significant digits
(at least 6) that read back as the same double: upstream prints them with precision 6,
which moves a configured start of 44.0888889 to 44.0889 (~10 m); values with at most six
significant digits print exactly as upstream.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from pygoby.frontseat.errors import SimulatorProtocolError

# What C++ isspace() (boost::trim in the default locale) strips; str.strip() would also take
# latin-1 characters such as NBSP.
WHITESPACE = " \t\n\v\f\r"

KEY_START = "START"
KEY_CTRL = "CTRL"
KEY_NAV = "NAV"
KEY_CMD = "CMD"

CTRL_PAYLOAD = "CTRL,STATE:PAYLOAD"  # frontseat accepts backseat commands
CTRL_IDLE = "CTRL,STATE:IDLE"  # mission over
CTRL_AUV = "CTRL,STATE:AUV"  # frontseat in control (understood by the driver, never sent)
CMD_OK = "CMD,RESULT:OK"
CMD_ERROR = "CMD,RESULT:ERROR"

_DECIMAL = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_INTEGER = re.compile(r"[+-]?\d{1,10}")
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1


def format_g(value: float, precision: int = 6) -> str:
    """`value` as a C++ ostream prints it in the default float format with `precision`."""
    return f"{value:.{precision}g}"


def format_round_trip(value: float) -> str:
    """The shortest `%g` form (at least 6 significant digits) that reads back as `value`."""
    for precision in range(6, 18):
        text = format_g(value, precision)
        if float(text) == value:
            return text
    return format_g(value, 17)


def parse_decimal(text: str, what: str) -> float:
    """A finite decimal number (digits, optional point and exponent); no NaN, inf or spaces."""
    if _DECIMAL.fullmatch(text) is None:
        raise SimulatorProtocolError(f"{what}: {text!r} is not a decimal number")
    value = float(text)
    if not math.isfinite(value):
        raise SimulatorProtocolError(f"{what}: {text!r} is out of range")
    return value


def parse_int32(text: str, what: str) -> int:
    if _INTEGER.fullmatch(text) is None:
        raise SimulatorProtocolError(f"{what}: {text!r} is not an integer")
    value = int(text)
    if not INT32_MIN <= value <= INT32_MAX:
        raise SimulatorProtocolError(f"{what}: {text!r} is out of the 32-bit integer range")
    return value


@dataclass(frozen=True)
class Message:
    """One parsed line: its key and its NAME -> VALUE fields (values are the raw text)."""

    key: str
    fields: Mapping[str, str]

    def require(self, name: str) -> str:
        try:
            return self.fields[name]
        except KeyError:
            raise SimulatorProtocolError(f"{self.key} without {name}") from None

    def number(self, name: str) -> float:
        return parse_decimal(self.require(name), f"{self.key} {name}")

    def integer(self, name: str) -> int:
        return parse_int32(self.require(name), f"{self.key} {name}")


def parse_line(line: str) -> Message:
    """Split `KEY,NAME:VALUE,...` (surrounding whitespace ignored). Raises SimulatorProtocolError."""
    key, *elements = line.strip(WHITESPACE).split(",")
    fields: dict[str, str] = {}
    for element in elements:
        parts = element.split(":")
        if len(parts) != 2:
            raise SimulatorProtocolError(f"field {element!r} of {key!r} is not NAME:VALUE")
        fields.setdefault(parts[0], parts[1])
    return Message(key, fields)


def format_line(key: str, fields: Mapping[str, str]) -> str:
    return ",".join([key, *(f"{name}:{value}" for name, value in fields.items())])


# START's optional fields: (wire name, attribute, integer?)
_START_OPTIONAL = (
    ("DURATION", "duration", True),
    ("FREQ", "freq", True),
    ("ACCEL", "accel", False),
    ("HDG_RATE", "hdg_rate", False),
    ("Z_RATE", "z_rate", False),
    ("WARP", "warp", True),
)


@dataclass(frozen=True)
class Start:
    """START: (re)initialise the simulator. Only lat and lon are required on the wire."""

    lat: float
    lon: float
    duration: int = 0  # seconds; 0 = no limit
    freq: int = 10  # control loop, Hz
    accel: float = 0.5  # m/s^2
    hdg_rate: float = 45.0  # deg/s
    z_rate: float = 2.0  # m/s
    warp: int = 1  # run this many times faster than real time

    def __post_init__(self) -> None:
        if not (math.isfinite(self.lat) and -90.0 <= self.lat <= 90.0):
            raise SimulatorProtocolError(f"START LAT {self.lat} is not a latitude")
        if not math.isfinite(self.lon):
            raise SimulatorProtocolError(f"START LON {self.lon} is not a longitude")
        if self.freq <= 0:
            raise SimulatorProtocolError(f"START FREQ must be positive, not {self.freq}")
        if self.warp <= 0:
            raise SimulatorProtocolError(f"START WARP must be positive, not {self.warp}")
        for name, rate in (
            ("ACCEL", self.accel),
            ("HDG_RATE", self.hdg_rate),
            ("Z_RATE", self.z_rate),
        ):
            if not (math.isfinite(rate) and rate >= 0):
                raise SimulatorProtocolError(f"START {name} must be zero or positive, not {rate}")

    @classmethod
    def from_message(cls, msg: Message) -> Start:
        optional: dict[str, Any] = {
            attr: msg.integer(name) if is_int else msg.number(name)
            for name, attr, is_int in _START_OPTIONAL
            if name in msg.fields
        }
        return cls(lat=msg.number("LAT"), lon=msg.number("LON"), **optional)

    def to_line(self) -> str:
        """All eight fields, as the driver sends them."""
        return format_line(
            KEY_START,
            {
                "LAT": format_round_trip(self.lat),
                "LON": format_round_trip(self.lon),
                "DURATION": str(self.duration),
                "FREQ": str(self.freq),
                "ACCEL": format_round_trip(self.accel),
                "HDG_RATE": format_round_trip(self.hdg_rate),
                "Z_RATE": format_round_trip(self.z_rate),
                "WARP": str(self.warp),
            },
        )


@dataclass(frozen=True)
class Nav:
    """NAV: the simulated vehicle's navigation (degrees, metres, m/s)."""

    lat: float
    lon: float
    depth: float
    heading: float
    speed: float

    NAMES = ("LAT", "LON", "DEPTH", "HEADING", "SPEED")

    @classmethod
    def from_message(cls, msg: Message) -> Nav:
        return cls(*(msg.number(name) for name in cls.NAMES))

    def to_line(self) -> str:
        values = (self.lat, self.lon, self.depth, self.heading, self.speed)
        return format_line(
            KEY_NAV, {name: format_g(v, 10) for name, v in zip(self.NAMES, values, strict=True)}
        )


@dataclass(frozen=True)
class Command:
    """CMD from the backseat: the desired course (degrees, m/s, metres)."""

    heading: float
    speed: float
    depth: float

    @classmethod
    def from_message(cls, msg: Message) -> Command:
        return cls(msg.number("HEADING"), msg.number("SPEED"), msg.number("DEPTH"))

    def to_line(self) -> str:
        return format_line(
            KEY_CMD,
            {
                "HEADING": format_g(self.heading),
                "SPEED": format_g(self.speed),
                "DEPTH": format_g(self.depth),
            },
        )
