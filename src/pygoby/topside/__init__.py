"""Topside operator tools: the command composer (`commander`), iCommander in the terminal
(`icommander`) and liaison in the browser (`liaison`); pAcommsHandler's configuration and message
set they read is `pygoby.moosacomms.acomms_config`. Layer: above moosacomms, below apps.
`errors`: the TopsideError family."""

from pygoby.topside.errors import (
    CommanderError,
    FieldValueError,
    LogControlError,
    LogFileError,
    SaveFileError,
    ScopeFilterError,
    SpecialError,
    TooManyStreamsError,
    TopsideError,
)
from pygoby.util.modules import lazy_exports

# imported on first use: the terminal and web front ends need textual / starlette
__getattr__, __dir__ = lazy_exports(
    globals(),
    {
        "CommandSet": "pygoby.topside.commander",
        "Commander": "pygoby.topside.commander",
        "ICommanderTUI": "pygoby.topside.icommander",
        "Liaison": "pygoby.topside.liaison",
        "LiaisonState": "pygoby.topside.liaison",
        "WebServer": "pygoby.topside.liaison",
    },
)

__all__ = [
    "CommandSet",
    "Commander",
    "CommanderError",
    "FieldValueError",
    "ICommanderTUI",
    "Liaison",
    "LiaisonState",
    "LogControlError",
    "LogFileError",
    "SaveFileError",
    "ScopeFilterError",
    "SpecialError",
    "TooManyStreamsError",
    "TopsideError",
    "WebServer",
]
