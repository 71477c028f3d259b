"""MOOS .alog files: the format (pygoby.moos.alog.format), reading and writing them
(pygoby.moos.alog.files), pLogger's configuration (logger_config) and `pygoby log`'s tools."""

from pygoby.moos.alog.files import AlogFile, AlogSink
from pygoby.moos.alog.format import AlogEntry, AlogFormatter, AlogReader, banner
from pygoby.moos.alog.tools import LogToolError

__all__ = [
    "AlogEntry",
    "AlogFile",
    "AlogFormatter",
    "AlogReader",
    "AlogSink",
    "LogToolError",
    "banner",
]
