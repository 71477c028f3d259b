"""REMUS CCL frames: the 32-byte messages of WHOI's Compact Control Language that REMUS vehicles
exchange through Micro-Modems, as typed objects. No MOOS needed.

    data = State(latitude=42.35, longitude=-70.95, heading=45, depth=111).encode()  # 32 bytes
    state = State.decode(data)      # CCLFrameError: too short, wrong id, field out of range
    frame = decode_frame(data)      # by the id byte (byte 0): Redirect, Position, State, Ranger

The field encodings are the functions of `pygoby.dccl.ccl.fields`, the ones C++ DCCL's legacy
CCL codecs use, so a State or Redirect frame has the bytes C++ DCCL encodes for
CCLMDATState / CCLMDATRedirect with the same values. Where Goby 1.1's pREMUSCodec (the other
source of these frames) differed, this module follows C++ DCCL and says so:

* State est_velocity and Redirect speeds are rounded to the nearest step (1.1 truncated);
* Redirect speeds are m/s (x30) whatever the thrust-mode bits of `speed_depth_flags` say, as
  Goby 1.1 did; C++ DCCL scales a speed whose bit says RPM differently, so the bytes are equal
  when both bits say m/s (`THRUST_MPS_TRANSIT | THRUST_MPS_SURVEY`);
* latitude/longitude are sign-extended (Goby 1.1's decoder was not, which biased negative
  values by about 4.3e-5 degrees; fixed: QUIRKS.md Q-APPS-19);
* Redirect row_length keeps all 16 bits (1.1's decoder kept 13).

Inputs beyond a field's range follow C++ DCCL too: depths saturate at 0 and 6000 m, speeds at
+-127 steps, GFI and oil at 0 and 100 %, and a pitch of +90 degrees or more wraps to -91.4
(6 signed bits). Values a field cannot hold at all (a latitude beyond +-90, a velocity beyond
its byte, an integer out of its bytes) raise CCLEncodeError.

Multi-byte fields are little-endian, except the Ranger's BCD fields (most significant digit
first). Frames longer than 32 bytes are read up to byte 31; a frame may be shorter than 32 bytes
as long as it holds every field its type reads (the rest counts as zeros).

Alert and Alert2 carry OASIS array contacts; the REMUS CCL definitions give no id for them (Goby 1.1
decoded whatever arrived on their variables), so their id byte is a field (`mode`, default
MDAT_OASIS).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from dataclasses import fields as dataclass_fields
from typing import Any, ClassVar, NamedTuple, Self

from pygoby.dccl.ccl import fields
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError

FRAME_BYTES = 32
MDAT_REDIRECT = 7
MDAT_POSITION = 8
MDAT_STATE = 14
MDAT_RANGER = 16
MDAT_OASIS = 31

THRUST_MPS_TRANSIT = 0x08  # speed_depth_flags bits C++ DCCL reads as "transit speed in m/s"
THRUST_MPS_SURVEY = 0x80  # ... and "survey speed in m/s"

LATLON_STEP = 180.0 / 0x7FFFFF  # degrees per step of a 24-bit latitude/longitude
_VELOCITY_LIMITS = (-128 / 25, 127 / 25)  # est_velocity: a signed byte of 2.5 cm/s
_MAX_DEPTH_RAW = 8100  # 6000 m


class CCLFrameError(DcclDecodeError):
    """A frame that cannot be read: too short, another frame's id, or a field out of range."""


class CCLEncodeError(DcclEncodeError):
    """A value a frame cannot carry (out of the field's range, not finite)."""


class TimeDate(NamedTuple):
    """UTC month, day, hour, minute and second; the second travels in 4 s steps, the year not
    at all."""

    month: int = 1
    day: int = 1
    hour: int = 0
    minute: int = 0
    second: int = 0

    @classmethod
    def at(cls, unix_seconds: float) -> TimeDate:
        return cls(*fields.utc_parts(math.floor(unix_seconds)))


class GFIPitchOil(NamedTuple):
    gfi: float = 0.0  # ground fault, percent (whole percents after decoding)
    pitch: float = 0.0  # degrees, +-90
    oil: float = 0.0  # oil compensation remaining, percent


# ------------------------------------------------------------------ the layout machinery
@dataclass(frozen=True)
class _Field:
    """One field: the bytes it occupies (least significant first), optionally a bit range of
    them, and its conversions. `decode(raw, raws)` also sees the raw values of the fields
    before it; `check(raw)` names what is out of range (None if nothing is)."""

    name: str
    at: tuple[int, ...]
    encode: Callable[[Any], int]
    decode: Callable[[int], Any]
    check: Callable[[int], str | None] | None = None
    shift: int = 0
    bits: int | None = None

    @property
    def mask(self) -> int:
        return (1 << (self.bits if self.bits is not None else 8 * len(self.at))) - 1

    def read(self, data: bytes) -> int:
        word = sum(data[i] << 8 * k for k, i in enumerate(self.at))
        return word >> self.shift & self.mask

    def write(self, out: bytearray, raw: int) -> None:
        word = (raw & self.mask) << self.shift
        for k, i in enumerate(self.at):
            out[i] |= word >> 8 * k & 0xFF

    def shifted(self, offset: int, prefix: str) -> _Field:
        return _Field(
            prefix + self.name,
            tuple(i + offset for i in self.at),
            self.encode,
            self.decode,
            self.check,
            self.shift,
            self.bits,
        )


def _finite(name: str, value: float) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise CCLEncodeError(f"{name} = {value!r} is not a number") from None
    if not math.isfinite(number):
        raise CCLEncodeError(f"{name} = {value} is not a finite number")
    return number


def _whole(name: str, value: int, low: int, high: int) -> int:
    try:
        whole = int(value)
    except (TypeError, ValueError, OverflowError):
        raise CCLEncodeError(f"{name} = {value!r} is not an integer") from None
    if whole != value or not low <= whole <= high:
        raise CCLEncodeError(f"{name} = {value!r} is not an integer in {low}..{high}")
    return whole


def _uint(name: str, at: tuple[int, ...], bits: int | None = None, shift: int = 0) -> _Field:
    limit = (1 << (bits if bits is not None else 8 * len(at))) - 1

    return _Field(
        name, at, lambda value: _whole(name, value, 0, limit), int, shift=shift, bits=bits
    )


def _latlon(name: str, at: tuple[int, ...], limit: float) -> _Field:
    def encode(degrees: float) -> int:
        if not -limit <= _finite(name, degrees) <= limit:
            raise CCLEncodeError(f"{name} = {degrees} is beyond +-{limit:g} degrees")
        return fields.encode_latlon(degrees)

    def check(raw: int) -> str | None:
        degrees = fields.decode_latlon(raw)  # (+-90 itself encodes as one step beyond)
        return (
            f"{degrees:.6f} is beyond +-{limit:g} degrees"
            if abs(degrees) > limit + LATLON_STEP
            else None
        )

    return _Field(name, at, encode, fields.decode_latlon, check)


def _heading(name: str, at: tuple[int, ...]) -> _Field:
    def encode(degrees: float) -> int:
        return fields.encode_heading(_finite(name, degrees) % 360.0)

    return _Field(name, at, encode, fields.decode_heading)


def _depth_check(raw: int) -> str | None:
    return f"raw depth {raw} is beyond {_MAX_DEPTH_RAW} (6000 m)" if raw > _MAX_DEPTH_RAW else None


def _depth(name: str, at: tuple[int, ...], bits: int | None = None) -> _Field:
    return _Field(
        name,
        at,
        lambda m: fields.encode_depth(_finite(name, m)),
        fields.decode_depth,
        _depth_check,
        bits=bits,
    )


def _speed_mps(name: str, at: tuple[int, ...]) -> _Field:
    def encode(mps: float) -> int:
        return fields.encode_speed(_finite(name, mps), fields.SPEED_MODE_MSEC)

    return _Field(name, at, encode, lambda raw: fields.decode_speed(raw, fields.SPEED_MODE_MSEC))


def _velocity(name: str, at: tuple[int, ...]) -> _Field:
    low, high = _VELOCITY_LIMITS

    def encode(mps: float) -> int:
        if not low <= _finite(name, mps) <= high:
            raise CCLEncodeError(f"{name} = {mps} m/s is outside {low:g}..{high:g}")
        return fields.encode_velocity(mps)

    return _Field(name, at, encode, fields.decode_velocity)


def _time_date_problem(month: int, day: int, hour: int, minute: int, second: int) -> str | None:
    if (
        1 <= month <= 12
        and 1 <= day <= 31
        and 0 <= hour <= 23
        and 0 <= minute <= 59
        and 0 <= second <= 59
    ):
        return None
    return f"month {month} day {day} {hour:02d}:{minute:02d}:{second:02d} is not a date and time"


def _time_date(name: str, at: tuple[int, ...]) -> _Field:
    def encode(value: TimeDate) -> int:
        parts = [
            _whole(f"{name}.{part}", v, 0, 59)
            for part, v in zip(TimeDate._fields, TimeDate(*value), strict=True)
        ]
        if problem := _time_date_problem(*parts):
            raise CCLEncodeError(f"{name}: {problem}")
        return fields.pack_time_date(*parts)

    return _Field(
        name,
        at,
        encode,
        lambda raw: TimeDate(*fields.time_date_parts(raw)),
        lambda raw: _time_date_problem(*fields.time_date_parts(raw)),
    )


def _bcd_check(digits: int) -> Callable[[int], str | None]:
    def check(raw: int) -> str | None:
        bad = [d for d in fields.bcd_digits(raw, digits) if d > 9]
        return f"nibble 0x{bad[0]:X} is not a decimal digit" if bad else None

    return check


def _bcd(name: str, at: tuple[int, ...], scale: float) -> _Field:
    """A non-negative decimal number in BCD, `scale` per step (0.1 for 0.1 m/s)."""
    digits = 2 * len(at)

    def encode(value: float) -> int:
        steps = round(_finite(name, value) / scale)
        try:
            return fields.encode_bcd(steps, digits)
        except ValueError:
            raise CCLEncodeError(
                f"{name} = {value} does not fit {digits} digits of {scale:g}"
            ) from None

    def decode(raw: int) -> float:
        return fields.decode_bcd(raw, digits) * scale

    return _Field(name, at, encode, decode, _bcd_check(digits))


def _ranger_latlon(name: str, at: tuple[int, ...], limit: float) -> _Field:
    digit_check = _bcd_check(10)
    sign_nibble = 3  # DDD, sign, MMMMMM: the sign is the 4th nibble from the top

    def encode(degrees: float) -> int:
        if not -limit <= _finite(name, degrees) <= limit:
            raise CCLEncodeError(f"{name} = {degrees} is beyond +-{limit:g} degrees")
        return fields.encode_ranger_latlon(degrees)

    def check(raw: int) -> str | None:
        digits = fields.bcd_digits(raw, 10)
        del digits[sign_nibble]
        if any(d > 9 for d in digits):
            return digit_check(raw & ~(0xF << 24))
        minutes = fields.decode_bcd(raw & 0xFFFFFF, 6) / 10_000
        if minutes >= 60:
            return f"{minutes:.4f} minutes is not below 60"
        degrees = abs(fields.decode_ranger_latlon(raw))
        return f"{degrees:.6f} is beyond +-{limit:g} degrees" if degrees > limit else None

    return _Field(name, at, encode, fields.decode_ranger_latlon, check)


def _bytes_at(start: int, count: int) -> tuple[int, ...]:
    return tuple(range(start, start + count))


# ------------------------------------------------------------------ frames
class CCLFrame:
    """Base of the frame types: `encode()` -> 32 bytes, `decode(data)` -> the typed frame."""

    ID: ClassVar[int | None]  # byte 0; None: the frame's `mode` field holds it
    NAME: ClassVar[str]
    LAYOUT: ClassVar[tuple[_Field, ...]]

    @classmethod
    def min_bytes(cls) -> int:
        """The shortest frame holding every field this type reads."""
        return max(max(f.at) for f in cls.LAYOUT) + 1

    def _flat(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in dataclass_fields(self)}  # type: ignore[arg-type]

    @classmethod
    def _from_flat(cls, values: dict[str, Any]) -> Self:
        return cls(**values)

    def encode(self) -> bytes:
        out = bytearray(FRAME_BYTES)
        if self.ID is not None:
            out[0] = self.ID
        values = self._flat()
        for f in self.LAYOUT:
            f.write(out, f.encode(values[f.name]))
        return bytes(out)

    @classmethod
    def decode(cls, data: bytes) -> Self:
        data = bytes(data[:FRAME_BYTES])
        if len(data) < cls.min_bytes():
            raise CCLFrameError(
                f"{cls.NAME}: {len(data)}-byte frame, needs at least {cls.min_bytes()}"
            )
        if cls.ID is not None and data[0] != cls.ID:
            raise CCLFrameError(f"{cls.NAME}: the frame's id is {data[0]}, not {cls.ID}")
        data = data.ljust(FRAME_BYTES, b"\0")
        values = {}
        for f in cls.LAYOUT:
            raw = f.read(data)
            if f.check is not None and (reason := f.check(raw)) is not None:
                raise CCLFrameError(f"{cls.NAME} {f.name}: {reason}")
            values[f.name] = f.decode(raw)
        return cls._from_flat(values)


@dataclass
class State(CCLFrame):
    """MDAT_STATE (14): a REMUS vehicle's position and status."""

    latitude: float = 0.0
    longitude: float = 0.0
    fix_age: int = 0  # seconds, 4 s steps, at most 1020
    time: TimeDate = field(default_factory=TimeDate)
    heading: float = 0.0
    depth: float = 0.0
    mission_mode: int = 0  # 3 bits (CCLMDATState.MissionMode)
    faults: int = 0  # 32 fault bits
    faults_2: int = 0
    mission_leg: int = 0
    est_velocity: float = 0.0  # m/s
    objective_index: int = 0
    watts: float = 0.0
    lat_goal: float = 0.0
    lon_goal: float = 0.0
    battery_percent: int = 0
    gfi_pitch_oil: GFIPitchOil = field(default_factory=GFIPitchOil)

    ID = MDAT_STATE
    NAME = "MDAT_STATE"


def _fix_age_encode(seconds: int) -> int:
    return fields.encode_fix_age(_whole("fix_age (s)", seconds, 0, 255 * fields.FIX_AGE_STEP))


def _gfi_pitch_oil_encode(value: GFIPitchOil) -> int:
    return fields.encode_gfi_pitch_oil(*(_finite("gfi_pitch_oil", x) for x in GFIPitchOil(*value)))


State.LAYOUT = (
    _latlon("latitude", (1, 2, 3), 90.0),
    _latlon("longitude", (4, 5, 6), 180.0),
    _Field("fix_age", (7,), _fix_age_encode, fields.decode_fix_age),
    _time_date("time", (8, 9, 10)),
    _heading("heading", (11,)),
    _depth("depth", (12, 13), bits=13),
    _uint("mission_mode", (12, 13), bits=3, shift=13),
    _uint("faults", (14, 15, 16, 17)),
    _uint("faults_2", (18,)),
    _uint("mission_leg", (19,)),
    _velocity("est_velocity", (20,)),
    _uint("objective_index", (21,)),
    _Field("watts", (22,), lambda w: fields.encode_watts(_finite("watts", w)), fields.decode_watts),
    _latlon("lat_goal", (23, 24, 25), 90.0),
    _latlon("lon_goal", (26, 27, 28), 180.0),
    _uint("battery_percent", (29,)),
    _Field(
        "gfi_pitch_oil",
        (30, 31),
        _gfi_pitch_oil_encode,
        lambda raw: GFIPitchOil(*fields.decode_gfi_pitch_oil(raw)),
    ),
)


@dataclass
class Redirect(CCLFrame):
    """MDAT_REDIRECT (7): send a vehicle to a new place and survey pattern."""

    latitude: float = 0.0  # centre of the search area
    longitude: float = 0.0
    message_number: int = 0
    speed_depth_flags: int = THRUST_MPS_TRANSIT | THRUST_MPS_SURVEY
    transit_depth: float = 0.0
    transit_speed: float = 0.0  # m/s
    transit_command: int = 0
    survey_depth: float = 0.0
    survey_speed: float = 0.0  # m/s
    survey_command: int = 0
    num_rows: int = 0
    row_length: int = 0  # metres
    spacing_0: int = 0  # metres
    spacing_1: int = 0
    row_heading: float = 0.0
    start_latitude: float = 0.0  # acknowledgements only: where the redirect started
    start_longitude: float = 0.0

    ID = MDAT_REDIRECT
    NAME = "MDAT_REDIRECT"


Redirect.LAYOUT = (
    _uint("message_number", (1,)),
    _latlon("latitude", (2, 3, 4), 90.0),
    _latlon("longitude", (5, 6, 7), 180.0),
    _uint("speed_depth_flags", (8,)),
    _depth("transit_depth", (9, 10)),
    _speed_mps("transit_speed", (11,)),
    _uint("transit_command", (12,)),
    _depth("survey_depth", (13, 14)),
    _speed_mps("survey_speed", (15,)),
    _uint("survey_command", (16,)),
    _uint("num_rows", (17,)),
    _uint("row_length", (18, 19)),
    _uint("spacing_0", (20,)),
    _uint("spacing_1", (21,)),
    _heading("row_heading", (22,)),
    _latlon("start_latitude", (23, 24, 25), 90.0),
    _latlon("start_longitude", (26, 27, 28), 180.0),
)


@dataclass
class Ranger(CCLFrame):
    """MDAT_RANGER (16): a position report in BCD (as pREMUSCodec reads it: lat bytes 1-5,
    lon 6-10, speed 18, heading 19-20, depth 28 (thousands, hundreds) and 23 (tens, ones))."""

    latitude: float = 0.0
    longitude: float = 0.0
    speed: float = 0.0  # 0.1 steps, 0..9.9
    heading: float = 0.0  # 0.1 degree steps
    depth: float = 0.0  # whole metres, 0..9999

    ID = MDAT_RANGER
    NAME = "MDAT_RANGER"


Ranger.LAYOUT = (
    _ranger_latlon("latitude", (5, 4, 3, 2, 1), 90.0),
    _ranger_latlon("longitude", (10, 9, 8, 7, 6), 180.0),
    _bcd("speed", (18,), 0.1),
    _bcd("heading", (20, 19), 0.1),
    _bcd("depth", (23, 28), 1.0),
)

POSITION_TYPES = {
    0: "Disabled",
    1: "Ship's pole",
    2: "Gateway Buoy",
    3: "Transponder",
    4: "Vehicle position",
    5: "Last",
}
POSITION_INVALID = 0x80  # or'd into the type: the position is (temporarily) invalid
LABEL_BYTES = 13


def _position_type_check(raw: int) -> str | None:
    return (
        None if raw & POSITION_INVALID or raw in POSITION_TYPES else f"unknown position type {raw}"
    )


def _label_encode(label: str) -> int:
    data = label.encode("latin-1", errors="replace")
    if len(data) > LABEL_BYTES or b"\0" in data:
        raise CCLEncodeError(f"label {label!r} is not up to {LABEL_BYTES} characters without NUL")
    return int.from_bytes(data.ljust(LABEL_BYTES, b"\0"), "little")


def _label_decode(raw: int) -> str:
    return raw.to_bytes(LABEL_BYTES, "little").split(b"\0", 1)[0].decode("latin-1")


@dataclass
class Position(CCLFrame):
    """MDAT_POSITION (8): where a ship, buoy, transponder or vehicle is."""

    latitude: float = 0.0
    longitude: float = 0.0
    type: int = 4  # POSITION_TYPES (Vehicle position), possibly | POSITION_INVALID
    label: str = ""

    ID = MDAT_POSITION
    NAME = "MDAT_POSITION"

    @property
    def type_name(self) -> str:
        """Goby 1.1's name of the type ("Invalid" when flagged invalid)."""
        return "Invalid" if self.type & POSITION_INVALID else POSITION_TYPES[self.type]


Position.LAYOUT = (
    _Field("type", (1,), _uint("type", (1,)).encode, int, _position_type_check),
    _latlon("latitude", (2, 3, 4), 90.0),
    _latlon("longitude", (5, 6, 7), 180.0),
    _Field("label", _bytes_at(15, LABEL_BYTES), _label_encode, _label_decode),
)


@dataclass
class AlertContact:
    """An OASIS contact of an Alert frame."""

    id: int = 0
    age: int = 0
    bearing: int = 0  # as sent (one byte)
    signature1: int = 0
    signature2: int = 0


@dataclass
class Alert2Contact:
    """An OASIS contact of an Alert2 frame: also a heading, relative to the vehicle or absolute
    (bit 7 of the age byte)."""

    id: int = 0
    age: int = 0  # 7 bits
    bearing: int = 0
    heading: float = 0.0
    absolute_heading: bool = False
    signature1: int = 0
    signature2: int = 0


_ALERT_CONTACT = (
    _uint("id", (0, 1)),
    _uint("age", (2,)),
    _uint("bearing", (3,)),
    _uint("signature1", (4,)),
    _uint("signature2", (5,)),
)
_ALERT2_CONTACT = (
    _uint("id", (0, 1)),
    _uint("age", (2,), bits=7),
    _Field("absolute_heading", (2,), int, bool, shift=7, bits=1),
    _uint("bearing", (3,)),
    _heading("heading", (4,)),
    _uint("signature1", (5,)),
    _uint("signature2", (6,)),
)
CONTACTS = 3


class _AlertBase(CCLFrame):
    """The contacts live in `contacts` (three of them); the layout names them c0_id, ..."""

    CONTACT: ClassVar[type]

    def _flat(self) -> dict[str, Any]:
        values = super()._flat()
        contacts = list(values.pop("contacts"))
        if len(contacts) != CONTACTS:
            raise CCLEncodeError(f"{self.NAME} carries {CONTACTS} contacts, not {len(contacts)}")
        for index, contact in enumerate(contacts):
            for name, value in vars(contact).items():
                values[f"c{index}_{name}"] = value
        return values

    @classmethod
    def _from_flat(cls, values: dict[str, Any]) -> Self:
        contacts = []
        for index in range(CONTACTS):
            prefix = f"c{index}_"
            mine = {k[len(prefix) :]: values.pop(k) for k in list(values) if k.startswith(prefix)}
            contacts.append(cls.CONTACT(**mine))
        return cls(contacts=contacts, **values)  # type: ignore[call-arg]  # (subclasses' field)


def _alert_layout(contact: tuple[_Field, ...], starts: tuple[int, ...]) -> tuple[_Field, ...]:
    return tuple(
        f.shifted(start, f"c{index}_") for index, start in enumerate(starts) for f in contact
    )


def _contacts(cls: type) -> Any:
    return field(default_factory=lambda: [cls() for _ in range(CONTACTS)])


@dataclass
class Alert(_AlertBase):
    """An OASIS alert: time, position, heading and three contacts."""

    oasis_time: int = 0  # OASIS timestamp (32 bits)
    latitude: float = 0.0
    longitude: float = 0.0
    heading: float = 0.0
    contacts: list[AlertContact] = _contacts(AlertContact)  # noqa: RUF009 (a default_factory)
    mode: int = MDAT_OASIS  # the id byte

    ID = None
    NAME = "CCL alert"
    CONTACT = AlertContact


_ALERT_HEAD = (  # both alert forms: id byte, OASIS time, position
    _uint("mode", (0,)),
    _uint("oasis_time", (1, 2, 3, 4)),
    _latlon("latitude", (5, 6, 7), 90.0),
    _latlon("longitude", (8, 9, 10), 180.0),
)
Alert.LAYOUT = (
    *_ALERT_HEAD,
    _heading("heading", (11,)),
    *_alert_layout(_ALERT_CONTACT, (12, 18, 24)),
)


@dataclass
class Alert2(_AlertBase):
    """An OASIS alert, second form: contacts with headings."""

    oasis_time: int = 0
    latitude: float = 0.0
    longitude: float = 0.0
    contacts: list[Alert2Contact] = _contacts(Alert2Contact)  # noqa: RUF009 (a default_factory)
    mode: int = MDAT_OASIS

    ID = None
    NAME = "CCL alert2"
    CONTACT = Alert2Contact


Alert2.LAYOUT = (
    *_ALERT_HEAD,
    *_alert_layout(_ALERT2_CONTACT, (11, 18, 25)),
)

BY_ID: dict[int, type[CCLFrame]] = {cls.ID: cls for cls in (Redirect, Position, State, Ranger)}


def decode_frame(data: bytes) -> CCLFrame:
    """The frame whose id byte names it (Redirect, Position, State, Ranger); CCLFrameError for
    an empty frame or another id."""
    if not data:
        raise CCLFrameError("empty frame")
    cls = BY_ID.get(data[0])
    if cls is None:
        raise CCLFrameError(
            f"unknown CCL id {data[0]} (known: {', '.join(map(str, sorted(BY_ID)))})"
        )
    return cls.decode(data)


__all__ = [
    "BY_ID",
    "FRAME_BYTES",
    "LATLON_STEP",
    "MDAT_OASIS",
    "MDAT_POSITION",
    "MDAT_RANGER",
    "MDAT_REDIRECT",
    "MDAT_STATE",
    "POSITION_INVALID",
    "POSITION_TYPES",
    "THRUST_MPS_SURVEY",
    "THRUST_MPS_TRANSIT",
    "Alert",
    "Alert2",
    "Alert2Contact",
    "AlertContact",
    "CCLEncodeError",
    "CCLFrame",
    "CCLFrameError",
    "GFIPitchOil",
    "Position",
    "Ranger",
    "Redirect",
    "State",
    "TimeDate",
    "decode_frame",
]
