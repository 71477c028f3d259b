"""A Goby MOOS application's log (spec goby-moos-apps.md section 2.8): the terminal at
`common.verbosity`, and with `common.log` a text file `<name>_<community>_<UTC stamp>.txt` in
`common.log_path` (else ./) at `common.log_verbosity`, with a `<name>_<community>_latest.txt`
symlink to the newest one.

    handlers = AppLogHandlers.open(log, name, common)   # attached to `log` and pygoby.moos
    ...
    handlers.close()
"""

from __future__ import annotations

import contextlib
import logging
import sys
import time
from pathlib import Path
from typing import Any

from pygoby.errors import ConfigError

# goby.util.protobuf.GLogConfig.Verbosity -> logging level
VERBOSITY_LEVELS = {1: logging.CRITICAL + 10, 2: logging.WARNING, 4: logging.INFO,
                    5: logging.DEBUG, 6: logging.DEBUG, 7: logging.DEBUG}  # fmt: skip

# The library's own log lines (client connection, ...) go to the app's handlers too.
LIBRARY_LOGGER = "pygoby.moos"


def terminal_handler(name: str, verbosity: int) -> logging.Handler:
    terminal = logging.StreamHandler(sys.stdout)
    terminal.setLevel(VERBOSITY_LEVELS.get(verbosity, logging.INFO))
    terminal.setFormatter(logging.Formatter(f"{name} [%(asctime)s]: %(message)s"))
    return terminal


def file_handler(path: Path, verbosity: int) -> logging.Handler:
    handler = logging.FileHandler(path)
    handler.setLevel(VERBOSITY_LEVELS.get(verbosity, logging.DEBUG))
    handler.setFormatter(logging.Formatter("[ %(asctime)s ] {%(levelname)s}: %(message)s"))
    return handler


def open_log_file(name: str, common: Any, log: logging.Logger) -> Path:
    """Create the log file (in common.log_path, else ./) and point the _latest symlink at it;
    ConfigError when neither folder is writable."""
    base = f"{name.replace('/', '_')}_{common.community}"
    stamp = "" if common.log_omit_file_timestamp else "_" + time.strftime("%Y%m%dT%H%M%S", time.gmtime())
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

    def __init__(self, log: logging.Logger, handlers: list[logging.Handler]) -> None:
        self.log = log
        self.handlers = handlers

    @classmethod
    def open(cls, log: logging.Logger, name: str, common: Any) -> AppLogHandlers:
        """Set up `log` (an app's logger) for the configuration `common` (GobyMOOSAppConfig)."""
        log.setLevel(logging.DEBUG)
        log.propagate = False
        handlers = [terminal_handler(name, common.verbosity)]
        if common.log:
            handlers.append(file_handler(open_log_file(name, common, log), common.log_verbosity))
        for handler in handlers:
            log.addHandler(handler)
            logging.getLogger(LIBRARY_LOGGER).addHandler(handler)
        return cls(log, handlers)

    def close(self) -> None:
        for handler in self.handlers:
            self.log.removeHandler(handler)
            logging.getLogger(LIBRARY_LOGGER).removeHandler(handler)
            handler.close()
        self.handlers = []
