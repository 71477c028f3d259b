"""$CACST / $CAXST statistics sentences <-> ReceiveStatistics / TransmitStatistics (§7.12)."""

from __future__ import annotations

import datetime as dt
import functools
import logging
import operator
from collections.abc import Mapping

from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.util.errors import NMEAFormatError
from pygoby.util.nmea import NMEASentence, parse_ints

log = logging.getLogger(__name__)

# ReceiveStatistics fields in $CACST order after the TOA and clock mode (v0 fields 4..29)
_CST_INT_FIELDS = (
    "mfd_peak", "mfd_power", "mfd_ratio", "spl", "shf_agn", "shf_ainpshift", "shf_ainshift",
    "shf_mfdshift", "shf_p2bshift", "rate", "source", "dest", "psk_error_code", "packet_type",
    "number_frames", "number_bad_frames", "snr_rss", "snr_in", "snr_out", "snr_symbols",
    "mse_equalizer", "data_quality_factor", "doppler", "stddev_noise", "carrier_freq", "bandwidth",
)  # fmt: skip
_DOPPLER = _CST_INT_FIELDS.index("doppler")  # the one decimal among them
# the fields format_cst prints, read at once from a ReceiveStatistics or from a mapping
_cst_head_attributes = operator.attrgetter("mode", "time")
_cst_head_items = operator.itemgetter("mode", "time")
_cst_tail_attributes = operator.attrgetter("clock_mode", *_CST_INT_FIELDS)
_cst_tail_items = operator.itemgetter("clock_mode", *_CST_INT_FIELDS)
# enum fields among them whose out-of-range values become -1 (the enums' INVALID value)
_CST_ENUM_RANGES = {"psk_error_code": (0, 6), "packet_type": (1, 5)}


# (the statistics of one packet repeat its time of arrival: remembered for a moment)
@functools.lru_cache(maxsize=16)
def parse_toa(text: str, today: dt.date) -> int:
    """`hhmmss.ffff` on `today` (UTC) -> microseconds since the epoch."""
    whole, _, frac = text.partition(".")
    if len(whole) != 6 or not whole.isdigit() or (frac and not frac.isdigit()):
        raise NMEAFormatError(f"bad time of arrival {text!r}")
    hour, minute_second = divmod(int(whole), 10000)  # (one int() instead of three)
    minute, second = divmod(minute_second, 100)
    if hour > 23 or minute > 59 or second > 59:
        dt.time(hour, minute, second)  # the ValueError a datetime would raise
    day = today.toordinal() - _EPOCH_ORDINAL
    seconds = day * 86400 + hour * 3600 + minute * 60 + second
    micros = int(round(float("0." + frac) * 1e6)) if frac else 0
    return seconds * 1_000_000 + micros


_EPOCH_ORDINAL = dt.date(1970, 1, 1).toordinal()


def cst_offset(sentence: NMEASentence) -> tuple[int, int]:
    """(version, offset): version-0 layout has no version field; >= 6 has one (Quirk A7)."""
    first = sentence.as_int(1)
    return (first, 1) if first >= 6 else (0, 0)


def clock_mode_from_field(value: int, new_bitfield: bool) -> int:
    if not new_bitfield:
        return value if 0 <= value <= 3 else -1
    rtc, pps = value & 0x3, (value >> 2) & 0x7
    sync = pps == 3
    good = rtc in (2, 3)
    return (2 if sync else 0) + (1 if good else 0)


def parse_cst(sentence: NMEASentence, today: dt.date, new_clock_bitfield: bool = False):
    """A $CACST sentence -> ReceiveStatistics (fields up to a short sentence's end)."""
    return acomms_pb.ReceiveStatistics(**cst_fields(sentence, today, new_clock_bitfield))


def cst_fields(sentence: NMEASentence, today: dt.date, new_clock_bitfield: bool = False) -> dict:
    """The fields of `parse_cst`'s ReceiveStatistics by name: `repeated.add(**fields)` adds
    them to a message without building and copying one (one constructor call with every field
    is also much faster than setting them one by one)."""
    version, off = cst_offset(sentence)
    mode = sentence.as_int(1 + off)
    fields = {
        "version": version,
        "mode": mode if 0 <= mode <= 2 else -1,
        "time": parse_toa(sentence[2 + off], today),
        "clock_mode": clock_mode_from_field(sentence.as_int(3 + off), new_clock_bitfield),
    }
    start = 4 + off
    texts = sentence.fields[start : start + len(_CST_INT_FIELDS)]
    fields.update(zip(_CST_INT_FIELDS, _cst_numbers(sentence, start, texts), strict=False))
    for name, (lo, hi) in _CST_ENUM_RANGES.items():
        value = fields.get(name)
        if value is not None and not lo <= value <= hi:
            fields[name] = -1
    if len(texts) < len(_CST_INT_FIELDS):
        log.warning(
            "short $CACST (%d fields): stopped at %s", len(sentence), _CST_INT_FIELDS[len(texts)]
        )
    return fields


def add_cst(stats, sentence: NMEASentence, today: dt.date, new_clock_bitfield: bool = False):
    """Append `parse_cst`'s ReceiveStatistics to the repeated field `stats` and return it.

    A link's statistics recur: sentences that differ only in their time of arrival are parsed
    once (the other fields are kept as a message, copied in C), then only the TOA is read.
    Nothing is appended when the sentence is bad (the errors of `cst_fields`)."""
    version, off = cst_offset(sentence)
    fields = sentence.fields
    key = (new_clock_bitfield, fields[: 2 + off], fields[3 + off :])
    template = _cst_templates.get(key)
    if template is None:
        template = acomms_pb.ReceiveStatistics(**cst_fields(sentence, today, new_clock_bitfield))
        # (short sentences are not remembered: their warning is logged every time)
        if len(fields) == 4 + off + len(_CST_INT_FIELDS):
            if len(_cst_templates) >= _CST_TEMPLATES_LIMIT:
                _cst_templates.clear()
            _cst_templates[key] = template
        time = template.time
    else:
        time = parse_toa(fields[2 + off], today)
    stat = stats.add()
    stat.CopyFrom(template)
    stat.time = time
    return stat


# ReceiveStatistics without a meaningful time, by the other fields of their $CACST sentence
_cst_templates: dict[tuple, Message] = {}
_CST_TEMPLATES_LIMIT = 4096


def _cst_numbers(sentence: NMEASentence, start: int, texts: tuple[str, ...]) -> list:
    """`texts` (the fields from index `start`) as numbers: integers, but a decimal doppler."""
    try:
        return [
            *parse_ints(texts[:_DOPPLER]),
            *map(float, texts[_DOPPLER : _DOPPLER + 1]),
            *parse_ints(texts[_DOPPLER + 1 :]),
        ]
    except ValueError:
        # the error as_int / as_float give, naming the first field that is not a number
        for i in range(len(texts)):
            (sentence.as_float if i == _DOPPLER else sentence.as_int)(start + i)
        raise


def format_cst(stat, version: int = 0) -> NMEASentence:
    """ReceiveStatistics -> $CACST (used by the emulator). `stat` may also be a mapping of
    the field names to values (what the emulator has: no message to build and read back)."""
    return NMEASentence.parse(cst_text(stat, version))


def cst_text(stat, version: int = 0) -> str:
    """The text of `format_cst` (without checksum), for a caller that only prints it: numbers
    only, so there is nothing to validate."""
    # (dict first: it matches at once, where the Mapping ABC check is slow)
    mapping = isinstance(stat, (dict, Mapping))
    mode, time = (_cst_head_items if mapping else _cst_head_attributes)(stat)
    return cst_head(mode, time, version) + cst_tail(stat)


def cst_head(mode: int, time: int, version: int = 0) -> str:
    """The start of a $CACST text, up to the comma after the time of arrival (`time`, in
    microseconds since the epoch): the part that changes with every packet."""
    return ",".join(cst_head_fields(mode, time, version)) + ","


@functools.lru_cache(maxsize=16, typed=True)  # (the statistics of one packet share a time)
def cst_head_fields(mode: int, time: int, version: int = 0) -> tuple[str, ...]:
    """The fields of `cst_head`: token, version (from 6 on), mode, time of arrival."""
    if type(time) is int and 0 <= time < _EXACT_TIME_LIMIT:
        # what the datetime below gives, in integers (time / 1e6 is within 0.5 us of the
        # exact value up to 2**33 s, so datetime's rounding gives back `time` exactly)
        seconds, micros = divmod(time, 1_000_000)
        minutes, second = divmod(seconds, 60)
        hours, minute = divmod(minutes, 60)
        hour = hours % 24
    else:
        toa = dt.datetime.fromtimestamp(time / 1e6, dt.UTC)
        hour, minute, second, micros = toa.hour, toa.minute, toa.second, toa.microsecond
    toa_text = _TOA % (hour, minute, second, micros // 100)
    mode_text = str(int(mode))  # (what %d prints, as in the tail)
    if version >= 6:
        return ("$CACST", f"{version:d}", mode_text, toa_text)
    return ("$CACST", mode_text, toa_text)


_EXACT_TIME_LIMIT = 2**33 * 1_000_000  # us (year 2242)


def cst_tail(stat) -> str:
    """The rest of the $CACST text after `cst_head` (clock mode, then the numbers from
    mfd_peak to bandwidth), from a ReceiveStatistics or a mapping of the field names: a link's
    statistics recur, so a caller may keep this part."""
    # one %-format (%d prints int(value)): much faster than building the sentence field by field
    get = _cst_tail_items if isinstance(stat, (dict, Mapping)) else _cst_tail_attributes
    return _CST_TAIL % get(stat)


_TOA = "%02d%02d%02d.%04d"
_CST_TAIL = "%d," + ",".join("%.1f" if name == "doppler" else "%d" for name in _CST_INT_FIELDS)


# $CAXST v0 field order after date and time
_XST_FIELDS = (
    "clock_mode", "mode", "probe_length", "bandwidth", "carrier_freq", "rate", "source", "dest",
    "ack_requested", "number_frames_expected", "number_frames_sent", "packet_type",
    "number_bytes",
)  # fmt: skip


def parse_xst(sentence: NMEASentence):
    first = sentence.as_int(1)
    version, off = (0, 0) if first > 19_700_000 else (first, 1)
    date, time = sentence[1 + off], sentence[2 + off]
    start = 3 + off
    present = min(len(_XST_FIELDS), max(0, len(sentence) - start))
    fields = dict(zip(_XST_FIELDS[:present], sentence.as_ints(start, start + present), strict=True))
    for name, (lo, hi) in _XST_ENUM_RANGES.items():
        value = fields.get(name)
        if value is not None and not lo <= value <= hi:
            fields[name] = -1
    if "ack_requested" in fields:
        fields["ack_requested"] = bool(fields["ack_requested"])
    # (one constructor call: setting the fields one by one is several times slower)
    stat = acomms_pb.TransmitStatistics(version=version, date=date, time=time, **fields)
    if present < len(_XST_FIELDS):
        log.warning("short $CAXST (%d fields): stopped at %s", len(sentence), _XST_FIELDS[present])
    return stat


# enum fields of $CAXST whose out-of-range values become -1 (the enums' INVALID value)
_XST_ENUM_RANGES = {"mode": (0, 4), "clock_mode": (0, 3), "packet_type": (1, 5)}


def format_xst(
    when: float, rate: int, src: int, dest: int, ack: bool, frames: int, nbytes: int
) -> NMEASentence:
    t = dt.datetime.fromtimestamp(when, dt.UTC)
    packet_type = 1 if rate == 0 else 3
    # (what %Y%m%d and %H%M%S print, several times faster than strftime)
    return NMEASentence.build(
        "$CAXST",
        [f"{t.year}{t.month:02d}{t.day:02d}",
         f"{t.hour:02d}{t.minute:02d}{t.second:02d}.{t.microsecond // 100:04d}",
         0, 0, 0, 5000, 25000, rate, src, dest, ack, frames, frames, packet_type, nbytes],
    )  # fmt: skip
