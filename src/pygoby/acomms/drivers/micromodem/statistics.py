"""$CACST / $CAXST statistics sentences <-> ReceiveStatistics / TransmitStatistics."""

from __future__ import annotations

import datetime as dt
import functools
import logging
import math
from collections.abc import Mapping
from typing import Any

from pygoby.acomms import messages as acomms_pb
from pygoby.util.errors import NMEAFormatError
from pygoby.util.nmea import NMEASentence

log = logging.getLogger(__name__)

# ReceiveStatistics fields in $CACST order after the TOA and clock mode (v0 fields 4..29)
_CST_FIELDS = (
    "mfd_peak",
    "mfd_power",
    "mfd_ratio",
    "spl",
    "shf_agn",
    "shf_ainpshift",
    "shf_ainshift",
    "shf_mfdshift",
    "shf_p2bshift",
    "rate",
    "source",
    "dest",
    "psk_error_code",
    "packet_type",
    "number_frames",
    "number_bad_frames",
    "snr_rss",
    "snr_in",
    "snr_out",
    "snr_symbols",
    "mse_equalizer",
    "data_quality_factor",
    "doppler",
    "stddev_noise",
    "carrier_freq",
    "bandwidth",
)
_DECIMAL = "doppler"  # the one field printed with a decimal
# enum fields whose out-of-range values become -1 (the enums' INVALID value)
_CST_ENUM_RANGES = {"psk_error_code": (0, 6), "packet_type": (1, 5)}
_EPOCH_ORDINAL = dt.date(1970, 1, 1).toordinal()


def parse_toa(text: str, today: dt.date) -> int:
    """A time of arrival -> microseconds since the epoch: `hhmmss[.f]` on `today` (UTC), or
    `YYYYMMDDhhmmss[.f]` (Micro-Modem 2 statistics from version 6 on) on its own date."""
    whole, _, frac = text.partition(".")
    if len(whole) not in (6, 14) or not whole.isdigit() or (frac and not frac.isdigit()):
        raise NMEAFormatError(f"bad time of arrival {text!r}")
    date, hms = divmod(int(whole), 1_000_000)
    hour, minute_second = divmod(hms, 10_000)
    minute, second = divmod(minute_second, 100)
    try:
        if hour > 23 or minute > 59 or second > 59:
            raise ValueError
        day = dt.date(date // 10_000, date // 100 % 100, date % 100) if whole[6:] else today
    except ValueError:
        raise NMEAFormatError(f"bad time of arrival {text!r}") from None
    seconds = (day.toordinal() - _EPOCH_ORDINAL) * 86400 + hour * 3600 + minute * 60 + second
    micros = round(float("0." + frac) * 1e6) if frac else 0
    return seconds * 1_000_000 + micros


def cst_offset(sentence: NMEASentence) -> tuple[int, int]:
    """(version, offset): version-0 layout has no version field; every version >= 6 has one
    (goby3 reads versions 7 and 8 at the version-0 offset: QUIRKS.md Q-ACOMMS-7)."""
    first = sentence.as_int(1)
    return (first, 1) if first >= 6 else (0, 0)


def clock_mode_from_field(value: int, new_bitfield: bool) -> int:
    if not new_bitfield:
        return value if 0 <= value <= 3 else -1
    rtc, pps = value & 0x3, (value >> 2) & 0x7
    return (2 if pps == 3 else 0) + (1 if rtc in (2, 3) else 0)


class CycleStatistics:
    """A $CACST as the values it prints: what an emulator hands a driver on an in-process link
    (the driver reads the values; the text is made only for a serial or TCP edge). The time of
    arrival `toa_us` (microseconds since the epoch, to the 100 us the text carries) and
    `clock_mode` (the field as printed: a bit field on newer Micro-Modem 2 firmware) are read as
    the text is: a version-0 time is a time of day on the reader's date. `values`: mfd_peak ..
    bandwidth in $CACST order, doppler to 0.1, the rest integers (see `cycle_statistics`)."""

    __slots__ = ("clock_mode", "mode", "toa_us", "values", "version")
    talker_id = "CA"
    sentence_id = "CST"

    def __init__(self, version: int, mode: int, toa_us: int, clock_mode: int, values: tuple):
        self.version, self.mode, self.clock_mode, self.values = version, mode, clock_mode, values
        self.toa_us = toa_us - toa_us % 100

    def time_on(self, today: dt.date) -> int:
        """The time of arrival as the text's reader gets it (parse_toa(toa_text(...)))."""
        if self.version >= 6:
            return self.toa_us
        return (today.toordinal() - _EPOCH_ORDINAL) * 86_400_000_000 + self.toa_us % 86_400_000_000

    def sentence(self) -> NMEASentence:
        head = (str(self.version),) if self.version >= 6 else ()
        return NMEASentence(
            (
                "$CACST",
                *head,
                str(self.mode),
                toa_text(self.toa_us, self.version >= 6),
                str(self.clock_mode),
                *(_CST_TAIL % self.values).split(","),
            )
        )

    @property
    def fields(self) -> tuple[str, ...]:
        return self.sentence().fields

    def message(self) -> str:
        return self.sentence().message()

    def __eq__(self, other: object) -> bool:
        return isinstance(other, CycleStatistics) and self.sentence() == other.sentence()

    __hash__ = None  # type: ignore[assignment]


_CST_TAIL = ",".join("%.1f" if name == _DECIMAL else "%d" for name in _CST_FIELDS)
CST_FIELD_INDEX = {name: i for i, name in enumerate(_CST_FIELDS)}
DOPPLER_INDEX = CST_FIELD_INDEX[_DECIMAL]


def cycle_statistics(stat: Mapping | object, version: int = 0) -> CycleStatistics:
    """ReceiveStatistics (or a mapping of its field names) -> the $CACST it prints. From version
    6 on the sentence carries its version and the date of the time of arrival (Micro-Modem 2)."""
    get = stat.__getitem__ if isinstance(stat, Mapping) else stat.__getattribute__
    return CycleStatistics(
        version,
        int(get("mode")),
        int(get("time")),
        int(get("clock_mode")),
        tuple(round(get(name), 1) if name == _DECIMAL else int(get(name)) for name in _CST_FIELDS),
    )


def format_cst(stat: Mapping | object, version: int = 0) -> NMEASentence:
    return cycle_statistics(stat, version).sentence()


def toa_text(time_us: int, with_date: bool = False) -> str:
    """Microseconds since the epoch -> `hhmmss.ffff` (`YYYYMMDDhhmmss.ffff` with the date)."""
    days, micros = divmod(int(time_us), 86_400_000_000)
    seconds, micros = divmod(micros, 1_000_000)
    hours, rest = divmod(seconds, 3600)
    text = _TOA % (hours, rest // 60, rest % 60, micros // 100)
    if with_date:
        day = dt.date.fromordinal(_EPOCH_ORDINAL + days)
        return _DATE % (day.year, day.month, day.day) + text
    return text


_DATE = "%04d%02d%02d"
_TOA = "%02d%02d%02d.%04d"


def cst_fields(
    sentence: NMEASentence | CycleStatistics, today: dt.date, new_clock_bitfield: bool = False
) -> dict:
    """The ReceiveStatistics fields of a $CACST, by name (up to a short sentence's end)."""
    if isinstance(sentence, CycleStatistics):
        version, mode, clock = sentence.version, sentence.mode, sentence.clock_mode
        time = sentence.time_on(today)
        fields = dict(zip(_CST_FIELDS, sentence.values, strict=True))
    else:
        version, off = cst_offset(sentence)
        mode, time = sentence.as_int(1 + off), parse_toa(sentence[2 + off], today)
        clock = sentence.as_int(3 + off)
        start = 4 + off
        present = min(len(_CST_FIELDS), max(0, len(sentence) - start))
        fields = {
            name: (sentence.as_float if name == _DECIMAL else sentence.as_int)(start + i)
            for i, name in enumerate(_CST_FIELDS[:present])
        }
        if present < len(_CST_FIELDS):
            log.warning(
                "short $CACST (%d fields): stopped at %s", len(sentence), _CST_FIELDS[present]
            )
    fields["version"] = version
    fields["mode"] = mode if 0 <= mode <= 2 else -1
    fields["time"] = time
    fields["clock_mode"] = clock_mode_from_field(clock, new_clock_bitfield)
    for name, (lo, hi) in _CST_ENUM_RANGES.items():
        if name in fields and not lo <= fields[name] <= hi:
            fields[name] = -1
    return fields


def parse_cst(
    sentence: NMEASentence | CycleStatistics, today: dt.date, new_clock_bitfield: bool = False
):
    """A $CACST -> ReceiveStatistics. NMEAFormatError or ValueError if it is bad."""
    return acomms_pb.ReceiveStatistics(**cst_fields(sentence, today, new_clock_bitfield))


def add_cst(
    stats,
    sentence: NMEASentence | CycleStatistics,
    today: dt.date,
    new_clock_bitfield: bool = False,
):
    """Append `parse_cst`'s ReceiveStatistics to the repeated field `stats` and return it
    (nothing is appended when the sentence is bad)."""
    if (
        isinstance(sentence, CycleStatistics)
        and math.copysign(1, sentence.values[DOPPLER_INDEX]) > 0
    ):
        # an emulated link's statistics recur: all but the time of arrival are converted once
        # (not with a Doppler of -0.0, which would share the memo's key with 0.0)
        time = sentence.time_on(today)
        stats.append(
            _without_toa(
                sentence.version,
                sentence.mode,
                sentence.clock_mode,
                sentence.values,
                new_clock_bitfield,
            )
        )
        stat = stats[-1]
        stat.time = time
        return stat
    stats.append(parse_cst(sentence, today, new_clock_bitfield))
    return stats[-1]


@functools.lru_cache(maxsize=1 << 14)
def _without_toa(version: int, mode: int, clock_mode: int, values: tuple, new_bitfield: bool):
    """parse_cst's ReceiveStatistics of a typed $CACST but its time (shared: copy it)."""
    typed = CycleStatistics(version, mode, 0, clock_mode, values)
    return parse_cst(typed, dt.date(1970, 1, 1), new_bitfield)


# $CAXST v0 field order after date and time
_XST_FIELDS = (
    "clock_mode",
    "mode",
    "probe_length",
    "bandwidth",
    "carrier_freq",
    "rate",
    "source",
    "dest",
    "ack_requested",
    "number_frames_expected",
    "number_frames_sent",
    "packet_type",
    "number_bytes",
)
# enum fields of $CAXST whose out-of-range values become -1 (the enums' INVALID value)
_XST_ENUM_RANGES = {"mode": (0, 4), "clock_mode": (0, 3), "packet_type": (1, 5)}


def parse_xst(sentence: NMEASentence):
    first = sentence.as_int(1)
    version, off = (0, 0) if first > 19_700_000 else (first, 1)
    date, time = sentence[1 + off], sentence[2 + off]
    start = 3 + off
    present = min(len(_XST_FIELDS), max(0, len(sentence) - start))
    fields: dict[str, Any] = dict(
        zip(_XST_FIELDS[:present], sentence.as_ints(start, start + present), strict=True)
    )
    for name, (lo, hi) in _XST_ENUM_RANGES.items():
        value = fields.get(name)
        if value is not None and not lo <= value <= hi:
            fields[name] = -1
    if "ack_requested" in fields:
        fields["ack_requested"] = bool(fields["ack_requested"])
    stat = acomms_pb.TransmitStatistics(version=version, date=date, time=time, **fields)
    if present < len(_XST_FIELDS):
        log.warning("short $CAXST (%d fields): stopped at %s", len(sentence), _XST_FIELDS[present])
    return stat


def format_xst(when: float, values: Mapping[str, int], version: int = 0) -> NMEASentence:
    """$CAXST for a transmission that started at `when` (s since the epoch); `values`: the
    TransmitStatistics fields after date and time, by name."""
    t = dt.datetime.fromtimestamp(when, dt.UTC)
    stamp = [f"{t:%Y%m%d}", f"{t:%H%M%S}.{t.microsecond // 100:04d}"]
    head = [str(version)] if version >= 6 else []
    return NMEASentence.build(
        "$CAXST", [*head, *stamp, *(str(int(values[name])) for name in _XST_FIELDS)]
    )
