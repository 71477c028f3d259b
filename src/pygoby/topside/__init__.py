"""Topside operator tools: the command composer (`commander`), iCommander in the terminal
(`icommander`) and liaison in the browser (`liaison`), and pAcommsHandler's configuration and
message set they share with pAcommsHandler (`acomms_config`). Layer: above acomms and moos,
below apps. `errors`: the TopsideError family."""

from pygoby.topside.errors import (
    CommanderError,
    FieldValueError,
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
        "AcommsMessageSet": "pygoby.topside.acomms_config",
        "CommandSet": "pygoby.topside.commander",
        "Commander": "pygoby.topside.commander",
        "ICommanderTUI": "pygoby.topside.icommander",
        "Liaison": "pygoby.topside.liaison",
        "LiaisonState": "pygoby.topside.liaison",
        "WebServer": "pygoby.topside.liaison",
        "read_acomms_config": "pygoby.topside.acomms_config",
    },
)

__all__ = [
    "AcommsMessageSet",
    "CommandSet",
    "Commander",
    "CommanderError",
    "FieldValueError",
    "ICommanderTUI",
    "Liaison",
    "LiaisonState",
    "SaveFileError",
    "ScopeFilterError",
    "SpecialError",
    "TooManyStreamsError",
    "TopsideError",
    "WebServer",
    "read_acomms_config",
]
