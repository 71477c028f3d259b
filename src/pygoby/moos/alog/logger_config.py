"""pLogger's ProcessConfig block, read as MOOS's pLogger reads it (names case-insensitive)."""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from pygoby.errors import ConfigError
from pygoby.moos.moosfile import Setting, parse_number

# pLogger registers a `Log = VAR` without `@ period` with this interval (s)
DEFAULT_LOG_PERIOD = 2.0
MIN_SYNC_PERIOD = 0.1
# pLogger options pygoby's pLogger reads but does not act on (a warning says so)
UNSUPPORTED = {
    "dynamicsynclogcolumns": "PLOGGER_CMD's dynamic .slog columns are not supported",
    "wildcardexclusionlog": "the .xlog of excluded variables is not written",
}
_SIZE = re.compile(r"(\d+(?:\.\d*)?)\s*([kKmMgG]?)[bB]?")
_SIZE_UNITS = {"": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30}


@dataclass
class LogRequest:
    """One `Log = VAR @ period [NOSYNC]` line."""

    var: str
    period: float = DEFAULT_LOG_PERIOD
    sync: bool = True


@dataclass
class LoggerConfig:
    file: str = "MOOSLog"
    path: str = "./"
    file_time_stamp: bool = True
    utc_log_directories: bool = False
    async_log: bool = True
    sync_log: bool = False
    sync_period: float = 1.0
    wildcard_logging: bool = False
    wildcard_patterns: list[str] = field(default_factory=list)
    wildcard_omit: list[str] = field(default_factory=lambda: ["MISSION_FILE"])
    logs: list[LogRequest] = field(default_factory=list)
    summary_file: str = "./.LastOpenedMOOSLogDirectory"
    compress: bool = False
    double_precision: int = 5
    log_aux_src: bool = False
    mark_external: bool = False
    mark_data_type: bool = False
    mark_binary: bool = False
    max_alog_bytes: int = 0
    warnings: list[str] = field(default_factory=list)

    def directory_name(self, now: float | None = None) -> str:
        """`File` with pLogger's `_D_M_YYYY_____HH_MM_SS` stamp (local time, or UTC)."""
        if not self.file_time_stamp:
            return self.file
        stamp = time.time() if now is None else now
        t = time.gmtime(stamp) if self.utc_log_directories else time.localtime(stamp)
        return (
            f"{self.file}_{t.tm_mday}_{t.tm_mon}_{t.tm_year}_____"
            f"{t.tm_hour:02d}_{t.tm_min:02d}_{t.tm_sec:02d}"
        )


# the true/false settings: option name (lower case) -> LoggerConfig attribute
_FLAG_SETTINGS = {
    "filetimestamp": "file_time_stamp",
    "utclogdirectories": "utc_log_directories",
    "asynclog": "async_log",
    "wildcardlogging": "wildcard_logging",
    "compressalogs": "compress",
    "logauxsrc": "log_aux_src",
    "markexternalcommunitymessages": "mark_external",
    "markdatatype": "mark_data_type",
    "markdataasbinary": "mark_binary",
}


def _bool(value: str) -> bool | None:
    lowered = value.strip().lower()
    return {"true": True, "1": True, "yes": True, "false": False, "0": False, "no": False}.get(
        lowered
    )


def parse_log_request(value: str) -> LogRequest:
    var, _, rest = value.partition("@")
    request = LogRequest(var.strip())
    words = rest.replace(",", " ").split()
    if words:
        period = parse_number(words[0])
        if period is not None:
            request.period = period
    request.sync = "NOSYNC" not in rest.upper()
    return request


def read_logger_config(
    params: Sequence[Setting],
    error: Callable[[str, Setting], ConfigError],
    global_log_path: str | None = None,
) -> LoggerConfig:
    """The settings of a pLogger block; `error(reason, setting)` builds a located ConfigError."""
    cfg = LoggerConfig()

    def flag(setting: Setting) -> bool:
        value = _bool(setting.value)
        if value is None:
            raise error(f"must be true or false, not {setting.value!r}", setting)
        return value

    for s in params:
        key = s.name.lower()
        if (attribute := _FLAG_SETTINGS.get(key)) is not None:
            setattr(cfg, attribute, flag(s))
        elif key == "file":
            cfg.file = s.value.strip()
        elif key == "path":
            cfg.path = s.value.strip()
        elif key == "synclog":
            on, _, period = s.value.replace(" ", "").partition("@")
            cfg.sync_log = on.lower() == "true"
            if period:
                number = parse_number(period)
                if number is None:
                    raise error(f"period must be a number, not {period!r}", s)
                cfg.sync_period = max(number, MIN_SYNC_PERIOD)
        elif key == "wildcardpattern":
            cfg.wildcard_patterns += [p.strip() for p in s.value.split(",") if p.strip()]
        elif key == "wildcardomitpattern":
            cfg.wildcard_omit += [p.strip() for p in s.value.split(",") if p.strip()]
        elif key == "log":
            request = parse_log_request(s.value)
            if not request.var:
                raise error("needs a variable name (Log = VAR @ period [NOSYNC])", s)
            if any(r.var == request.var for r in cfg.logs):
                cfg.warnings.append(f"Log = {request.var} given twice; the first one is used")
            else:
                cfg.logs.append(request)
        elif key == "loggingdirectorysummaryfile":
            cfg.summary_file = s.value.strip()
        elif key == "doubleprecision":
            number = parse_number(s.value)
            if number is None or number < 0 or number != int(number) or number > 20:
                raise error(f"must be a whole number of decimals (0-20), not {s.value!r}", s)
            cfg.double_precision = int(number)
        elif key == "maxalogsize":
            match = _SIZE.fullmatch(s.value.strip())
            if match is None:
                raise error(f"must be a size such as 500M, not {s.value!r}", s)
            cfg.max_alog_bytes = int(float(match[1]) * _SIZE_UNITS[match[2].lower()])
        elif key in UNSUPPORTED:
            cfg.warnings.append(f"line {s.line}: {s.name}: {UNSUPPORTED[key]}; ignored")
        else:
            cfg.warnings.append(f"line {s.line}: unknown option {s.name!r} ignored")
    if global_log_path:
        cfg.path = global_log_path
    cfg.path = cfg.path.rstrip("/") or "/"
    if not cfg.wildcard_logging and not cfg.logs:
        cfg.warnings.append("nothing to log: no Log = VAR lines and WildCardLogging is off")
    return cfg
