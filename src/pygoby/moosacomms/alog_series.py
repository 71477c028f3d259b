"""What `pygoby log plot` draws, read from a mission's .alog files (no plotting here, so the
series can be checked on their own).

* transmissions and receptions per modem: ModemTransmission on pAcommsHandler's
  MODEM_TRANSMIT (the sender is its `src`) and MODEM_RECEIVE (the receiver is the logging
  vehicle's modem: its MODEM_ID post, else the mission's modem_id);
* link quality per receiving modem: SNR in/out and the equalizer's MSE of every `$CACST` on
  RAW_INCOMING, read by the Micro-Modem driver's own parser;
* acknowledged and expired messages by type: the `@PB[type]` values of ACK_ORIGINAL and EXPIRE;
* vehicle tracks: NAV_X/NAV_Y (metres), else NAV_LAT/NAV_LONG (degrees), one track per file,
  only the logging vehicle's own posts (not those forwarded from other communities), named
  after the file's community (else the file).

Times are seconds after the earliest LOGSTART of the files. Values that do not parse are
skipped and counted in `skipped` (by variable), never raised.
"""

from __future__ import annotations

import datetime as dt
import os
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem.statistics import parse_cst
from pygoby.moos.alog.files import AlogFile
from pygoby.moos.alog.tools import db_community
from pygoby.moos.appconfig import prefixed_var_names
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import TranslatorError, parse_for_moos
from pygoby.moos.translator.techniques import split_prefix
from pygoby.moosacomms.acomms_config import acomms_config_or_defaults
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import (
    pAcommsHandlerConfig,
)
from pygoby.util.errors import NMEAError
from pygoby.util.nmea import NMEASentence

Points = list[tuple[float, float]]  # (time or x, value or y)
MODEM_ID_VAR = "MODEM_ID"  # pAcommsHandler posts its modem id at start-up
CST_PREFIX = "$CACST"


@dataclass
class AcommsVariables:
    """The variables the series come from: a pAcommsHandler's names and modem id."""

    transmit: str
    receive: str
    raw_in: str
    acked: str
    expired: str
    modem_id: int | None = None

    @classmethod
    def of(cls, cfg: pAcommsHandlerConfig, modem_id: int | None = None) -> AcommsVariables:
        names = prefixed_var_names(cfg.moos_var)
        return cls(
            names["driver_transmit"],
            names["driver_receive"],
            names["driver_raw_msg_in"],
            names["queue_ack_original_msg"],
            names["queue_expire"],
            modem_id,
        )

    @classmethod
    def of_mission(cls, path: str | os.PathLike[str] | None, block: str) -> AcommsVariables:
        """From `block` of the mission at `path`; pAcommsHandler's defaults without one."""
        if path is None:
            return cls.of(pAcommsHandlerConfig())
        cfg = acomms_config_or_defaults(MissionFile.read(path), block)
        return cls.of(cfg, cfg.modem_id if cfg.HasField("modem_id") else None)


@dataclass
class Track:
    units: str  # "m" (NAV_X/NAV_Y) or "deg" (NAV_LONG/NAV_LAT)
    points: Points = field(default_factory=list)  # (x or longitude, y or latitude)


@dataclass
class LogSeries:
    start: float = 0.0  # UTC of the earliest LOGSTART; times below are seconds after it
    # modem id -> (time, transmission type name)
    transmissions: dict[int, list[tuple[float, str]]] = field(default_factory=dict)
    receptions: dict[int, list[tuple[float, str]]] = field(default_factory=dict)
    # receiving modem id -> (time, dB)
    snr_in: dict[int, Points] = field(default_factory=dict)
    snr_out: dict[int, Points] = field(default_factory=dict)
    mse: dict[int, Points] = field(default_factory=dict)
    # message type -> times
    acked: dict[str, list[float]] = field(default_factory=dict)
    expired: dict[str, list[float]] = field(default_factory=dict)
    tracks: dict[str, Track] = field(default_factory=dict)  # by vehicle (the file's label)
    skipped: Counter[str] = field(default_factory=Counter)


def log_series(paths: Iterable[str | os.PathLike[str]], variables: AcommsVariables) -> LogSeries:
    """The series of all `paths` (each file one logging vehicle)."""
    logs = [AlogFile(path) for path in paths]
    series = LogSeries()
    # a file without LOGSTART (0) is put at the others' start, not 50 years before them
    starts = [log.log_start for log in logs]
    series.start = min((start for start in starts if start > 0), default=0.0)
    for log, start in zip(logs, starts, strict=True):
        _read_file(log, start - series.start if start > 0 else 0.0, variables, series)
    return series


def _read_file(log: AlogFile, offset: float, var: AcommsVariables, series: LogSeries) -> None:
    own_modem = var.modem_id
    today = dt.datetime.fromtimestamp(log.log_start, dt.UTC).date()  # for $CACST times of day
    nav: dict[str, float] = {}
    track_name = Path(log.path).stem
    community: str | None = None
    for entry in log:
        t = entry.time + offset
        name, value = entry.name, entry.value
        if name == MODEM_ID_VAR and isinstance(value, float):
            own_modem = int(value)
        elif name in (var.transmit, var.receive):
            transmission = acomms_pb.ModemTransmission()
            if not _parsed(value, transmission):
                series.skipped[name] += 1
                continue
            kind = acomms_pb.ModemTransmission.TransmissionType.Name(transmission.type)
            if name == var.transmit:
                series.transmissions.setdefault(transmission.src, []).append((t, kind))
            else:
                receiver = own_modem if own_modem is not None else transmission.dest
                series.receptions.setdefault(receiver, []).append((t, kind))
        elif name == var.raw_in:
            _read_cst(t, name, value, own_modem, today, series)
        elif name in (var.acked, var.expired):
            prefixed = split_prefix(value) if isinstance(value, str | bytes) else None
            if prefixed is None:
                series.skipped[name] += 1
                continue
            table = series.acked if name == var.acked else series.expired
            table.setdefault(prefixed[0], []).append(t)
        elif name in NAV_VARIABLES and isinstance(value, float) and not entry.community:
            nav[name] = value
            _add_track_point(series, track_name, nav, name)
        elif community is None:
            community = db_community(entry.source)
    # the vehicle's name: its community (its MOOSDB posts as MOOSDB_<community>)
    if community and track_name in series.tracks and community not in series.tracks:
        series.tracks[community] = series.tracks.pop(track_name)


NAV_VARIABLES = ("NAV_X", "NAV_Y", "NAV_LAT", "NAV_LONG")


def _add_track_point(series: LogSeries, track_name: str, nav: dict[str, float], name: str) -> None:
    """A point each time one coordinate changes while the other is known; a file with NAV_X
    and NAV_Y is tracked in metres, and its NAV_LAT/NAV_LONG are then ignored."""
    if name in ("NAV_X", "NAV_Y"):
        pair, units = ("NAV_X", "NAV_Y"), "m"
    else:
        pair, units = ("NAV_LONG", "NAV_LAT"), "deg"
    if pair[0] not in nav or pair[1] not in nav:
        return
    track = series.tracks.get(track_name)
    if track is None:
        track = series.tracks[track_name] = Track(units)
    elif track.units != units:
        if units == "deg":
            return  # metres win
        track.units, track.points = units, []
    point = (nav[pair[0]], nav[pair[1]])
    if not track.points or track.points[-1] != point:
        track.points.append(point)


def _read_cst(
    t: float,
    name: str,
    value: str | float | bytes,
    own_modem: int | None,
    today: dt.date,
    series: LogSeries,
) -> None:
    raw = acomms_pb.ModemRaw()
    if not _parsed(value, raw):
        series.skipped[name] += 1
        return
    line = raw.raw.decode("ascii", "replace")
    if not line.startswith(CST_PREFIX):
        return  # the driver's other sentences
    try:
        stat = parse_cst(NMEASentence.parse(line), today)
    except (NMEAError, ValueError, IndexError):
        series.skipped[name] += 1
        return
    receiver = own_modem if own_modem is not None else stat.dest
    series.snr_in.setdefault(receiver, []).append((t, float(stat.snr_in)))
    series.snr_out.setdefault(receiver, []).append((t, float(stat.snr_out)))
    series.mse.setdefault(receiver, []).append((t, float(stat.mse_equalizer)))


def _parsed(value: float | str | bytes, message: Message) -> bool:
    """Whether `value` (as pAcommsHandler posts a message: protobuf text) filled `message`; a
    double or a text that does not parse did not."""
    if isinstance(value, float):
        return False
    try:
        parse_for_moos(value, message)
    except TranslatorError:
        return False
    return True
