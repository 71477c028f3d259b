"""Goby's verbosity levels and log groups on the standard `logging` module.

Levels: `VERBOSE` is logging.INFO, `DEBUG1` is logging.DEBUG, `DEBUG2` and `DEBUG3` are below it
(registered with logging under those names); `QUIET` is above CRITICAL. `VERBOSITY_LEVELS` maps
goby.util.protobuf.GLogConfig.Verbosity values to them.

Groups: goby3 tags each line with a group such as `goby::acomms::queue::push::1`. Here a group
is a logger under `pygoby` with the same parts (`pygoby.acomms.queue.push.1`), so a library user
routes or silences them with ordinary logging configuration, and `group_name(record.name)` gives
the group back for display:

    log = group_logger("goby::acomms::amac::1")       # logging.getLogger("pygoby.acomms.amac.1")
    if log.isEnabledFor(DEBUG2):
        log.log(DEBUG2, "slot %d starts", index)

`GobyFormatter` prints `<app> [<time>] {<group>}: <text>` (the terminal; in colour when asked)
or `[ <time> ] {<group>}: <text>` (log files), with goby's `(Warning): ` / `(Error): ` marks.
"""

from __future__ import annotations

import logging
import time

VERBOSE = logging.INFO
DEBUG1 = logging.DEBUG
DEBUG2 = logging.DEBUG - 2
DEBUG3 = logging.DEBUG - 4
QUIET = logging.CRITICAL + 10

logging.addLevelName(DEBUG2, "DEBUG2")
logging.addLevelName(DEBUG3, "DEBUG3")

# goby.util.protobuf.GLogConfig.Verbosity -> logging level
VERBOSITY_LEVELS = {1: QUIET, 2: logging.WARNING, 4: VERBOSE, 5: DEBUG1, 6: DEBUG2, 7: DEBUG3}
VERBOSITY_NAMES = {
    QUIET: "QUIET",
    logging.WARNING: "WARN",
    VERBOSE: "VERBOSE",
    DEBUG1: "DEBUG1",
    DEBUG2: "DEBUG2",
    DEBUG3: "DEBUG3",
}

LIBRARY_ROOT = "pygoby"
APP_LOGGERS = "pygoby.app."  # an application's own lines carry no group (as goby3's)
_GOBY = "goby"

# ANSI colours for groups (as goby3 colours its groups) and for warnings / errors
_GROUP_COLOURS = ("36", "32", "35", "34", "33", "96", "92", "95", "94", "93")
_RESET = "\x1b[0m"


def level_for(verbosity: int) -> int:
    """The logging level of a Verbosity enum value (VERBOSE for unknown values)."""
    return VERBOSITY_LEVELS.get(verbosity, VERBOSE)


def group_logger(group: str) -> logging.Logger:
    """The logger of a goby group: `goby::a::b::1` -> `pygoby.a.b.1`."""
    parts = [p for p in group.split("::") if p]
    if parts and parts[0] == _GOBY:
        parts = parts[1:]
    return logging.getLogger(".".join([LIBRARY_ROOT, *parts]))


def group_name(logger_name: str) -> str:
    """The goby group of a logger: `pygoby.a.b.1` -> `goby::a::b::1`; "" for an app's own
    logger; other loggers keep their name."""
    if logger_name.startswith(APP_LOGGERS):
        return ""
    if logger_name == LIBRARY_ROOT or logger_name.startswith(LIBRARY_ROOT + "."):
        return "::".join([_GOBY, *logger_name.split(".")[1:]])
    return logger_name


class GobyFormatter(logging.Formatter):
    """goby's line layout: `<app> [<time>] {<group>}: <text>` with `app`, else the file form
    `[ <time> ] {<group>}: <text>`. `colour` adds ANSI colours (group by name, warnings)."""

    def __init__(self, app: str | None = None, colour: bool = False) -> None:
        super().__init__()
        self.app = app
        self.colour = colour
        self._colours: dict[str, str] = {}

    def formatTime(self, record: logging.LogRecord, datefmt: str | None = None) -> str:  # noqa: N802
        stamp = time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(record.created))
        return f"{stamp}.{int(record.msecs):03d}"

    def _paint(self, code: str, text: str) -> str:
        return f"\x1b[{code}m{text}{_RESET}" if self.colour else text

    def format(self, record: logging.LogRecord) -> str:
        group = group_name(record.name)
        if group:
            code = self._colours.setdefault(
                group, _GROUP_COLOURS[len(self._colours) % len(_GROUP_COLOURS)]
            )
            group = self._paint(code, "{" + group + "}")
        text = record.getMessage()
        if record.exc_info:
            text += "\n" + self.formatException(record.exc_info)
        if record.levelno >= logging.ERROR:
            text = self._paint("31", "(Error): ") + text
        elif record.levelno >= logging.WARNING:
            text = self._paint("31", "(Warning): ") + text
        when = self.formatTime(record)
        head = f"{self.app} [{when}]" if self.app is not None else f"[ {when} ]"
        return f"{head} {group}: {text}" if group else f"{head}: {text}"
