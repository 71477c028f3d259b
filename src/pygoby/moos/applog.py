"""A Goby MOOS application's log: the terminal at
`common.verbosity`, and with `common.log` a text file `<name>_<community>_<UTC stamp>.txt` in
`common.log_path` (else ./) at `common.log_verbosity`, with a `<name>_<community>_latest.txt`
symlink to the newest one. Both get the app's own lines and every group of the library (the
`pygoby` loggers: queue, MAC, driver traffic, ...), in goby's layout (pygoby.util.glog).

    handlers = AppLogHandlers.open(log, name, common)   # attached to `log` and `pygoby`
    ...
    handlers.close()

`terminal=` replaces the terminal handler (show_gui's live view).
"""

from __future__ import annotations

import contextlib
import logging
import sys
import time
from pathlib import Path
from typing import Any

from pygoby.errors import ConfigError
from pygoby.util.glog import DEBUG1, LIBRARY_ROOT, GobyFormatter, level_for

# The library's log lines (client connection, queue, MAC, driver traffic) go to the app's
# handlers too.
LIBRARY_LOGGER = LIBRARY_ROOT


class QuietStreamHandler(logging.StreamHandler):
    """A terminal handler that stops writing once its reader has gone (`| head`)."""

    def emit(self, record: logging.LogRecord) -> None:
        if self.stream is not None:
            super().emit(record)

    def handleError(self, record: logging.LogRecord) -> None:  # noqa: N802 - logging's name
        if isinstance(sys.exc_info()[1], BrokenPipeError):
            self.stream = None
            return
        super().handleError(record)


def terminal_handler(name: str, verbosity: int) -> logging.Handler:
    terminal = QuietStreamHandler(sys.stdout)
    terminal.setLevel(level_for(verbosity))
    terminal.setFormatter(GobyFormatter(name, colour=sys.stdout.isatty()))
    return terminal


def file_handler(path: Path, verbosity: int) -> logging.Handler:
    handler = logging.FileHandler(path)
    handler.setLevel(level_for(verbosity))
    handler.setFormatter(GobyFormatter())
    return handler


def open_log_file(name: str, common: Any, log: logging.Logger) -> Path:
    """Create the log file (in common.log_path, else ./) and point the _latest symlink at it;
    ConfigError when neither folder is writable."""
    base = f"{name.replace('/', '_')}_{common.community}"
    stamp = (
        ""
        if common.log_omit_file_timestamp
        else "_" + time.strftime("%Y%m%dT%H%M%S", time.gmtime())
    )
    for directory in (Path(common.log_path), Path(".")):
        path = directory / f"{base}{stamp}.txt"
        try:
            path.touch()
        except OSError:
            log.warning("cannot write a log file in %s; trying ./", directory)
            continue
        if not common.log_omit_latest_symlink and stamp:
            _link_latest(directory / f"{base}_latest.txt", path)
        return path
    raise ConfigError(f"cannot open a log file in {common.log_path} or ./")


def _link_latest(latest: Path, path: Path) -> None:
    with contextlib.suppress(OSError):
        latest.unlink(missing_ok=True)
        latest.symlink_to(path.name)


class AppLogHandlers:
    """The handlers of one running app's log, attached to its logger and the library's."""

    def __init__(
        self,
        log: logging.Logger,
        handlers: list[logging.Handler],
        library_level: int,
        propagate: bool = True,
    ) -> None:
        self.log = log
        self.handlers = handlers
        self._library_level = library_level  # restored on close
        self._propagate = propagate  # restored on close

    @classmethod
    def open(
        cls, log: logging.Logger, name: str, common: Any, terminal: logging.Handler | None = None
    ) -> AppLogHandlers:
        """Set up `log` (an app's logger) for the configuration `common` (GobyMOOSAppConfig)."""
        handlers = [terminal if terminal is not None else terminal_handler(name, common.verbosity)]
        if common.log:
            handlers.append(file_handler(open_log_file(name, common, log), common.log_verbosity))
        # warnings always pass (as without any configuration: other handlers may want them);
        # below that, only the levels some handler shows are made at all
        lowest = min(*(handler.level for handler in handlers), logging.WARNING)
        log.setLevel(min(lowest, DEBUG1))  # the app's own lines are few: all reach handlers
        propagate, log.propagate = log.propagate, False
        library = logging.getLogger(LIBRARY_LOGGER)
        saved = library.level
        if library.getEffectiveLevel() > lowest:  # the groups' lines must reach the handlers
            library.setLevel(lowest)
        for handler in handlers:
            log.addHandler(handler)
            library.addHandler(handler)
        return cls(log, handlers, saved, propagate)

    def close(self) -> None:
        library = logging.getLogger(LIBRARY_LOGGER)
        for handler in self.handlers:
            self.log.removeHandler(handler)
            library.removeHandler(handler)
            handler.close()
        self.handlers = []
        library.setLevel(self._library_level)
        self.log.propagate = self._propagate
