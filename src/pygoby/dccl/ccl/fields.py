"""The REMUS CCL field encodings (WHOI's CCL, as C++ DCCL's legacy CCL library computes them).

Plain functions from a value to its raw unsigned field and back, usable without any DCCL
machinery (a REMUS CCL frame builder uses them directly). Each `encode_*` returns the raw bits
(an int of the field's width); each `decode_*` takes them. The arithmetic is the reference's,
step for step: float (32-bit) variables are rounded with `f32` where the C code stores a float,
and a conversion to an integer type behaves as x86-64 does (truncation toward zero; NaN and
values out of the 32-bit (or 64-bit) range become the "integer indefinite" 0x80000000...),
keeping the low bits the C type holds. So even odd inputs (negative headings, NaN, huge
depths) give the bytes a C++ peer sends.

Widths: lat/lon 24, time/date 24, heading 8, depth 13 or 16 (the caller's choice), velocity 8,
speed 8, watts 8, GFI/pitch/oil 16, hi-res altitude 16, salinity 8, temperature 8, sound
speed 8, fix age 8; the REMUS Ranger's BCD fields (pREMUSCodec's WhoiUtil): lat/lon 40
(`DDD`, sign nibble, `MM.MMMM`), any number of decimal digits (`encode_bcd`).
"""

from __future__ import annotations

import math

from pygoby.dccl.codecs.numeric import f32

_INT32_MIN = -(2**31)
_INT64_MIN = -(2**63)
_LATLON_SCALE = float(0x7FFFFF) / 180.0  # raw steps per degree
_LATLON_STEP = 180.0 / float(0x7FFFFF)  # degrees per raw step

SPEED_MODE_RPM = 0
SPEED_MODE_MSEC = 1
SPEED_MODE_KNOTS = 2


def cvtt32(x: float) -> int:
    """x86-64 conversion of a float/double to a 32-bit integer (cvttsd2si, cvttss2si)."""
    if x != x or not -2147483649.0 < x < 2147483648.0:
        return _INT32_MIN
    return int(x)


def cvtt64(x: float) -> int:
    """x86-64 conversion of a double to a 64-bit integer."""
    if x != x or not -9223372036854777856.0 < x < 9223372036854775808.0:
        return _INT64_MIN
    return int(x)


def _signed8(raw: int) -> int:
    raw &= 0xFF
    return raw - 0x100 if raw & 0x80 else raw


# ------------------------------------------------------------------ latitude / longitude
def encode_latlon(degrees: float) -> int:
    """Degrees to 24 bits (two's complement, 0x7FFFFF = 180 degrees, ~2 m at the equator)."""
    scaled = degrees * _LATLON_SCALE
    scaled += 0.5 if scaled > 0.0 else -0.5
    return cvtt64(scaled) & 0xFFFFFF


def decode_latlon(raw: int) -> float:
    raw &= 0xFFFFFF
    if raw & 0x800000:
        raw -= 0x1000000
    return float(raw) * _LATLON_STEP


# ------------------------------------------------------------------ time and date
def _days_from_civil(year: int, month: int, day: int) -> int:
    """Days since 1970-01-01 of a proleptic Gregorian date (month 1..12)."""
    year -= month <= 2
    era = year // 400
    yoe = year - era * 400
    doy = (153 * (month + (-3 if month > 2 else 9)) + 2) // 5 + day - 1
    doe = yoe * 365 + yoe // 4 - yoe // 100 + doy
    return era * 146097 + doe - 719468


def _civil_from_days(days: int) -> tuple[int, int, int]:
    days += 719468
    era = days // 146097
    doe = days - era * 146097
    yoe = (doe - doe // 1460 + doe // 36524 - doe // 146096) // 365
    doy = doe - (365 * yoe + yoe // 4 - yoe // 100)
    mp = (5 * doy + 2) // 153
    day = doy - (153 * mp + 2) // 5 + 1
    month = mp + (3 if mp < 10 else -9)
    return yoe + era * 400 + (month <= 2), month, day


def timegm(year: int, month: int, day: int, hour: int, minute: int, second: int) -> int:
    """UNIX seconds of a UTC date and time; out-of-range parts carry over (as C timegm does:
    month 0 is December of the year before, day 0 the last day of the month before)."""
    year += (month - 1) // 12
    month = (month - 1) % 12 + 1
    days = _days_from_civil(year, month, 1) + day - 1
    return days * 86400 + hour * 3600 + minute * 60 + second


def utc_year(seconds: float) -> int:
    return _civil_from_days(math.floor(seconds) // 86400)[0]


def utc_parts(seconds: int) -> tuple[int, int, int, int, int]:
    """(month, day, hour, minute, second) of a UNIX time (whole seconds, UTC)."""
    days, rest = divmod(seconds, 86400)
    _, month, day = _civil_from_days(days)
    hour, rest = divmod(rest, 3600)
    minute, second = divmod(rest, 60)
    return month, day, hour, minute, second


def pack_time_date(month: int, day: int, hour: int, minute: int, second: int) -> int:
    """The 24 bits: month 4, day 5, hour 5, minute 6, seconds / 4 (4)."""
    raw = second >> 2 | minute << 4 | hour << 10 | day << 15 | month << 20
    return raw & 0xFFFFFF


def encode_time_date(microseconds: int) -> int:
    """UNIX time (microseconds) to 24 bits (`pack_time_date`); the year is not sent."""
    return pack_time_date(*utc_parts((microseconds & 0xFFFFFFFFFFFFFFFF) // 1_000_000))


def time_date_parts(raw: int) -> tuple[int, int, int, int, int]:
    """(month, day, hour, minute, second) as sent (not checked: month may be 0 or 13..15)."""
    return (raw >> 20 & 0xF, raw >> 15 & 0x1F, raw >> 10 & 0x1F, raw >> 4 & 0x3F, (raw & 0xF) * 4)


def decode_time_date(raw: int, year: int) -> int:
    """24 bits to UNIX time in microseconds, in the given UTC year (the receiver's current year,
    as the reference uses; parts out of range carry over as with timegm)."""
    month, day, hour, minute, second = time_date_parts(raw)
    return timegm(year, month, day, hour, minute, second) * 1_000_000 & 0xFFFFFFFFFFFFFFFF


# ------------------------------------------------------------------ heading, speeds, power
def encode_heading(degrees: float) -> int:
    """Degrees to 8 bits (360/255 degree steps)."""
    return cvtt32(f32(degrees) * 255.0 / 360.0 + 0.5) & 0xFF


def decode_heading(raw: int) -> float:
    """A double, as WhoiUtil returns it (a DCCL float field keeps it as a float)."""
    return float(raw & 0xFF) * 360.0 / 255.0


def encode_velocity(meters_per_second: float) -> int:
    """m/s to 8 bits (2.5 cm/s steps, signed)."""
    return cvtt32(f32(meters_per_second) * 25.0 + 0.5) & 0xFF


def decode_velocity(raw: int) -> float:
    return f32(_signed8(raw) / 25.0)


def encode_speed(speed: float, mode: int) -> int:
    """A speed to 8 bits (signed): RPM mode sends the value itself clamped to +-127 (the
    reference does not divide by 20 although the receiver multiplies by 20); m/s (and knots,
    treated as m/s) send 1/30 m/s steps."""
    speed = f32(speed)
    if mode != SPEED_MODE_RPM:
        speed = f32(speed * 30.0)
    if speed > 127:
        return 127
    if speed < -127:
        return 0x81
    speed = f32(speed + 0.5) if speed > 0.0 else f32(speed - 0.5)
    return cvtt32(speed) & 0xFF


def decode_speed(raw: int, mode: int) -> float:
    value = _signed8(raw)
    if mode == SPEED_MODE_RPM:
        return f32(value * 20.0)
    if mode == SPEED_MODE_MSEC:
        return f32(value / 30.0)
    return 0.0  # knots: not decoded by the modem codec


def encode_watts(volts: float, amps: float = 1.0) -> int:
    """Power (volts x amps) to 8 bits of 4 W."""
    watts = f32(f32(f32(volts) * f32(amps)) * 0.25)
    if watts > 255:
        return 255
    if watts < 0:
        return 0
    return cvtt32(watts) & 0xFF


def decode_watts(raw: int) -> float:
    return f32(float(raw & 0xFF) * 4.0)


# ------------------------------------------------------------------ depth and altitude
def encode_depth(meters: float) -> int:
    """Depth to 16 bits: 0-100 m in 10 cm, 100-200 m in 20 cm, 200-1000 m in 50 cm,
    1000-6000 m in 1 m steps (values up to 8100). Keep the low bits a narrower field holds."""
    depth = f32(meters)
    if depth < 0:
        return 0
    if depth < 100:
        value = (depth + 0.05) / 0.1
    elif depth < 200:
        value = (f32(depth - 100) + 0.1) / 0.2 + 1000
    elif depth < 1000:
        value = (f32(depth - 200) + 0.25) * 2.0 + 1500
    elif depth < 6000:
        value = (f32(depth - 1000) + 0.5) + 3100
    else:
        return 8100
    return cvtt32(value) & 0xFFFF


def decode_depth(raw: int) -> float:
    depth = raw & 0x1FFF
    if depth <= 1000:
        return f32(depth * 0.1)
    if depth <= 1500:
        return f32((depth - 1000) * 0.2 + 100.0)
    if depth <= 3100:
        return f32((depth - 1500) * 0.5 + 200.0)
    if depth <= 8100:
        return f32((depth - 3100) + 1000.0)
    return 6000.0


def encode_hires_altitude(meters: float) -> int:
    """Altitude to 16 bits of 1 cm (0 to 655.35 m)."""
    alt = f32(f32(meters) * 100.0)
    if alt > 65535.0:
        return 0xFFFF
    if alt < 0:
        return 0
    return cvtt32(alt) & 0xFFFF


def decode_hires_altitude(raw: int) -> float:
    return f32((raw & 0xFFFF) / 100.0)


# ------------------------------------------------------------------ GFI, pitch and oil
def encode_gfi_pitch_oil(gfi: float, pitch: float, oil: float) -> int:
    """Ground fault (0-100 %, 5 bits), oil (0-100 %, 5 bits) and pitch (+-90 degrees, 6 bits)
    in 16 bits."""
    gfi, pitch, oil = f32(gfi), f32(pitch), f32(oil)
    if gfi < 0:
        result = 0
    elif gfi > 100:
        result = 31
    else:
        result = cvtt32(gfi * 31.0 / 100.0)
    if oil < 0:
        pass
    elif oil > 100:
        result |= 31 << 5
    else:
        result |= cvtt32(f32(oil * 0.31)) << 5
    if pitch > 90 or pitch < -90:
        result |= 0x8000  # +-90 degrees both become -32 steps
    else:
        scaled = f32(pitch * 0.35)
        if scaled > 0:
            scaled = f32(scaled + 0.5)
        elif scaled < 0:
            scaled = f32(scaled - 0.5)
        result |= cvtt32(scaled) << 10 & 0xFC00
    return result & 0xFFFF


def decode_gfi_pitch_oil(raw: int) -> tuple[float, float, float]:
    """(gfi, pitch, oil); gfi comes back as a whole number of percent."""
    raw &= 0xFFFF
    gfi = float(cvtt64((raw & 0x1F) * 100.0 / 31.0) & 0xFFFF)
    oil = f32((raw >> 5 & 0x1F) * 100.0 / 31.0)
    steps = raw >> 10
    if steps & 0x20:
        steps -= 0x40
    pitch = f32(steps * 180.0 / 63.0)
    return gfi, pitch, oil


# ------------------------------------------------------------------ CTD
def encode_salinity(psu: float) -> int:
    """Salinity 20-45.5 to 8 bits of 0.1 (below 20: 0)."""
    salinity = f32(psu)
    if salinity < 20.0:
        return 0
    output = f32((salinity - 20.0) * 10.0)
    if output > 255:
        return 255
    return cvtt32(output) & 0xFF


def decode_salinity(raw: int) -> float:
    raw &= 0xFF
    if raw == 0:
        return 0.0
    return f32(raw / 10.0 + 20.0)


def encode_temperature(celsius: float) -> int:
    """Temperature -4 to 36 degrees C to 8 bits of 40/256 degree."""
    temperature = f32(celsius)
    if temperature < -4:
        return 0
    temperature = f32(f32(temperature + 4) * 256.0 / 40.0 + 0.5)
    if temperature > 255:
        return 255
    return cvtt32(temperature) & 0xFF


def decode_temperature(raw: int) -> float:
    return f32((raw & 0xFF) * 40.0 / 256.0 - 4.0)


def encode_sound_speed(meters_per_second: float) -> int:
    """Sound speed 1425-1552.5 m/s to 8 bits of 0.5 m/s (not clamped: other values wrap)."""
    return cvtt32((f32(meters_per_second) - 1425.0) * 2) & 0xFF


def decode_sound_speed(raw: int) -> float:
    return f32((raw & 0xFF) * 0.5 + 1425.0)


# ------------------------------------------------------------------ fix age
FIX_AGE_STEP = 4  # seconds per raw step


def encode_fix_age(seconds: int) -> int:
    """Seconds to 8 bits of 4 s, at most 255 steps (the step count is taken modulo 256 first,
    as the reference's unsigned char arithmetic does)."""
    return min(255, (seconds // FIX_AGE_STEP) & 0xFF)


def decode_fix_age(raw: int) -> int:
    return FIX_AGE_STEP * (raw & 0xFF)


# ------------------------------------------------------------------ REMUS Ranger (BCD)
BCD_POSITIVE = 0xF  # sign nibble we send for north/east (a receiver reads only 0xC/0xD)
BCD_NEGATIVE = 0xD  # south/west (0xC is read as negative too)
_MINUTE_DIGITS = 10_000  # MM.MMMM: 4 decimals of a minute


def encode_bcd(value: int, digits: int) -> int:
    """A non-negative integer as `digits` BCD nibbles, most significant first (ValueError if it
    does not fit)."""
    if not 0 <= value < 10**digits:
        raise ValueError(f"{value} does not fit in {digits} decimal digits")
    raw = 0
    for shift in range(digits):
        value, digit = divmod(value, 10)
        raw |= digit << 4 * shift
    return raw


def bcd_digits(raw: int, digits: int) -> list[int]:
    """The nibbles of `raw`, most significant first (a nibble above 9 is not a digit)."""
    return [raw >> 4 * shift & 0xF for shift in reversed(range(digits))]


def decode_bcd(raw: int, digits: int) -> int:
    """BCD nibbles to their value; a nibble above 9 counts with its face value, as the
    reference's arithmetic does (callers check `bcd_digits` first to reject those)."""
    value = 0
    for digit in bcd_digits(raw, digits):
        value = value * 10 + digit
    return value


def encode_ranger_latlon(degrees: float) -> int:
    """Degrees to 40 bits: `DDD`, a sign nibble, `MMMMMM` (minutes x 10^4), most significant
    nibble first."""
    magnitude = abs(degrees)
    ten_thousandths = round(magnitude * 60 * _MINUTE_DIGITS)
    whole, minutes = divmod(ten_thousandths, 60 * _MINUTE_DIGITS)
    sign = BCD_NEGATIVE if degrees < 0 and ten_thousandths else BCD_POSITIVE
    return encode_bcd(whole, 3) << 28 | sign << 24 | encode_bcd(minutes, 6)


def decode_ranger_latlon(raw: int) -> float:
    """40 bits to degrees, summed digit by digit as the reference does (same last bit)."""
    d100, d10, d1, sign, m10, m1, m01, m001, m0001, m00001 = bcd_digits(raw, 10)
    degrees = d100 * 100.0 + d10 * 10.0 + d1 * 1.0
    minutes = m10 * 10.0 + m1 * 1.0 + m01 * 0.1 + m001 * 0.01 + m0001 * 0.001 + m00001 * 0.0001
    return (degrees + minutes / 60.0) * (-1.0 if sign in (0xC, 0xD) else 1.0)
