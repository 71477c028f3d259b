"""Bluefin Standard Payload Interface sentences (SPI 1.8+), sans-I/O: building, parsing and the
field formats (time of day, latitude/longitude, numbers).

The sentences are NMEA-0183 (`pygoby.util.nmea`): the vehicle (Huxley) talks as `$BF...`, the
payload (the backseat) as `$BP...`, each ends with `*HH` and "\\r\\n". Field 1 of every sentence
but `$BPLOG` is the time it was sent, `hhmmss.sss` UTC.

Formats, as goby3's Bluefin driver writes and reads them:

* time of day: `hhmmss.sss`, exactly three decimals (milliseconds truncated): some Huxley
  versions insist on three. Read back onto the UTC date of a reference time.
* latitude `ddmm.mmmm` + `N`/`S`, longitude `dddmm.mmmm` + `E`/`W` (degrees, decimal minutes).
* numbers the payload writes: integers as they are, other doubles with 17 significant digits
  (C++'s `boost::lexical_cast<std::string>(double)`, e.g. 1.5 -> `1.5`, 0.1 ->
  `0.10000000000000001`), so a value round-trips exactly.
* a text value containing commas becomes several fields (goby3 splits it the same way).
"""

from __future__ import annotations

import calendar
import math
import time
from collections.abc import Iterable

from pygoby.util.errors import NMEAError, NMEAFormatError
from pygoby.util.nmea import NMEASentence

TALKER_VEHICLE = "BF"
TALKER_PAYLOAD = "BP"

# What each sentence is, for the `description` of the Raw messages iFrontSeat posts (SPI names).
DESCRIPTIONS: dict[str, str] = {
    "$BFMSC": "Payload Mission Command",
    "$BFSHT": "Payload Shutdown",
    "$BFBDL": "Begin Data Logging",
    "$BFSDL": "Stop Data Logging",
    "$BFTOP": "Topside Message",
    "$BFDVT": "Begin/End DVL External Triggering",
    "$BFVER": "Vehicle Interface Version",
    "$BFNVG": "Navigation Update",
    "$BFNVR": "Velocity and Rate Update",
    "$BFTEL": "Telemetry Status",
    "$BFSVS": "Sound Velocity",
    "$BFRCM": "Raw Compass Data",
    "$BFRDP": "Raw Depth Sensor Data",
    "$BFRVL": "Raw Vehicle Speed",
    "$BFRBS": "Battery Voltage",
    "$BFMBS": "Begin New Behavior",
    "$BFMBE": "End Behavior",
    "$BFMIS": "Mission Status",
    "$BFERC": "Elevator and Rudder Data",
    "$BFDVL": "Raw DVL Data",
    "$BFDV2": "Raw DVL Data, Extended",
    "$BFIMU": "Raw IMU Data",
    "$BFCTD": "Raw CTD Sensor Data",
    "$BFRNV": "Relative Navigation Position",
    "$BFPIT": "Pitch Servo Positions",
    "$BFCNV": "Cartesian Relative Navigation Position",
    "$BFPLN": "Mission Plan Element",
    "$BFACK": "Message Acknowledgement",
    "$BFTRM": "Trim Status",
    "$BFBOY": "Buoyancy Status",
    "$BFCMA": "Communications Medium Access",
    "$BFCPS": "Communications Packet Sent",
    "$BFCPR": "Communications Packet Received Data",
    "$BFCTL": "Backseat Control",
    "$BPSMC": "Confirm Mission Start",
    "$BPLOG": "Logging Control",
    "$BPSTS": "Payload Status Message",
    "$BPTOP": "Request to Send Data Topside",
    "$BPDVR": "Request to Change DVL Triggering Method",
    "$BPTRK": "Request Additional Trackline",
    "$BPRTC": "Request Additional Trackcircle",
    "$BPRGP": "Request Additional GPS Hits",
    "$BPRCN": "Cancel Requested Behavior",
    "$BPRCE": "Cancel Current Mission Element",
    "$BPRCA": "Cancel All Requested Behaviors",
    "$BPRCB": "Cancel Current Behavior",
    "$BPRMB": "Modify Current Behavior",
    "$BPEMB": "End Behavior Modify",
    "$BPTMR": "Topside Message Relay",
    "$BPCTD": "Raw CTD Sensor Data",
    "$BPABT": "Abort Mission",
    "$BPKIL": "Kill Mission",
    "$BPMSG": "Log Message",
    "$BPRMP": "Request Mission Plan",
    "$BPSEM": "Start Empty Mission",
    "$BPNPU": "Navigation Position Update",
    "$BPSIL": "Silent Mode",
    "$BPTRM": "Request Trim Adjustment Behavior",
    "$BPBOY": "Request Buoyancy Adjustment Behavior",
    "$BPVER": "Payload Interface Version",
    "$BPSUS": "Suspend Mission",
    "$BPCON": "Continue",
    "$BPRES": "Resume Mission",
    "$BPSPD": "Hull Relative Speed Limit",
    "$BPSAN": "Set Sonar Angle",
    "$BPGHP": "Go To Hull Position",
    "$BPGBP": "Go to Bottom Position",
    "$BPRNS": "Reset Relative Navigation",
    "$BPRBO": "Hull Relative Bearing Offset",
    "$BPCPD": "Communications Packet Data",
    "$BPDCL": "DCCL message for Huxley",
    "$BPVEL": "Corrected velocity measurements",
}


# -- field formats --------------------------------------------------------------------------


def number(value: float | int) -> str:
    """A number as goby3 writes it: integers plainly, doubles with 17 significant digits."""
    if isinstance(value, int):
        return str(value)
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.17g}"


def time_of_day(t: float) -> str:
    """UNIX time `t` -> `hhmmss.sss` (UTC, milliseconds truncated)."""
    millis = math.floor(t * 1000.0) % 86_400_000
    seconds, ms = divmod(millis, 1000)
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours:02d}{minutes:02d}{secs:02d}.{ms:03d}"


def parse_time_of_day(text: str, reference: float) -> float | None:
    """`hhmmss[.s...]` on the UTC date of UNIX time `reference` -> UNIX time; None when the
    text is not a time of day (as goby3, which gives "not a date-time" then)."""
    text = text.strip()
    whole, _, fraction = text.partition(".")
    if len(whole) < 6 or not whole.isdigit() or (fraction and not fraction.isdigit()):
        return None
    hours, minutes, secs = int(whole[-6:-4]), int(whole[-4:-2]), int(whole[-2:])
    if hours > 23 or minutes > 59 or secs > 60:
        return None
    day = time.gmtime(math.floor(reference))
    midnight = calendar.timegm((day.tm_year, day.tm_mon, day.tm_mday, 0, 0, 0))
    return (
        midnight
        + hours * 3600
        + minutes * 60
        + secs
        + (float("0." + fraction) if fraction else 0.0)
    )


def latitude(lat: float) -> tuple[str, str]:
    """Degrees -> (`ddmm.mmmm`, `N`|`S`)."""
    return _degrees_minutes(abs(lat), 2), "S" if lat < 0 else "N"


def longitude(lon: float) -> tuple[str, str]:
    """Degrees -> (`dddmm.mmmm`, `E`|`W`)."""
    return _degrees_minutes(abs(lon), 3), "W" if lon < 0 else "E"


def _degrees_minutes(value: float, degree_digits: int) -> str:
    ten_thousandths = round(value * 600_000)  # minutes * 10^4
    degrees, minutes = divmod(ten_thousandths, 600_000)
    return f"{degrees:0{degree_digits}d}{minutes // 10_000:02d}.{minutes % 10_000:04d}"


def parse_angle(text: str, hemisphere: str, degree_digits: int, negative: str) -> float:
    """`ddmm.mmmm` (degree_digits 2) or `dddmm.mmmm` (3) and its hemisphere -> degrees (negative
    for `negative`, i.e. S or W); NaN when the field has no more than the degree digits, as goby3
    reads an empty position. NMEAFormatError when the digits are not a number."""
    if len(text) <= 2:
        return math.nan
    try:
        degrees = float(text[:degree_digits])
        minutes = float(text[degree_digits:])
    except ValueError:
        raise NMEAFormatError(f"not a position: {text!r}") from None
    value = degrees + minutes / 60.0
    return -value if hemisphere == negative else value


# -- sentences ----------------------------------------------------------------------------------


def build(token: str, values: Iterable[object]) -> NMEASentence:
    """A sentence from its token (`$BPRMB`) and values: numbers per `number()`, strings split at
    their commas. NMEAError for a value holding `*`, CR or LF."""
    fields: list[str] = []
    for value in values:
        if isinstance(value, str):
            fields.extend(value.split(","))
        elif isinstance(value, bool):
            fields.append("1" if value else "0")
        elif isinstance(value, (int, float)):
            fields.append(number(value))
        else:
            raise TypeError(f"cannot put {value!r} in a sentence")
    return NMEASentence.build(token, fields)


def parse(line: str) -> NMEASentence:
    """One received line -> its sentence (a checksum, if present, must match). NMEAError
    otherwise."""
    return NMEASentence.parse(line)


def parse_unchecked(line: str) -> NMEASentence:
    """A sentence another process wants written (IFS_RAW_OUT): a checksum it carries is not
    checked, only replaced (goby3 ignores it too)."""
    text = line.strip()
    star = text.rfind("*")
    if star != -1 and star == len(text) - 3:
        text = text[:star]
    return NMEASentence.parse(text)


def field(sentence: NMEASentence, index: int) -> str:
    """Field `index`; NMEAFormatError when the sentence is too short."""
    if index >= len(sentence):
        raise NMEAFormatError(f"{sentence.fields[0]} has no field {index}: {sentence.message()!r}")
    return sentence[index]


def optional_float(sentence: NMEASentence, index: int) -> float | None:
    """Field `index` as a number, None when empty; NMEAFormatError when missing or not a number."""
    text = field(sentence, index).strip()
    if not text:
        return None
    try:
        return float(text)
    except ValueError:
        raise NMEAFormatError(f"field {index} of {sentence.message()!r} is not a number") from None


def required_float(sentence: NMEASentence, index: int) -> float:
    value = optional_float(sentence, index)
    if value is None:
        raise NMEAFormatError(f"field {index} of {sentence.message()!r} is empty")
    return value


def required_int(sentence: NMEASentence, index: int) -> int:
    field(sentence, index)
    return sentence.as_int(index)


__all__ = [
    "DESCRIPTIONS",
    "NMEAError",
    "NMEASentence",
    "build",
    "field",
    "latitude",
    "longitude",
    "number",
    "optional_float",
    "parse",
    "parse_angle",
    "parse_time_of_day",
    "parse_unchecked",
    "required_float",
    "required_int",
    "time_of_day",
]
