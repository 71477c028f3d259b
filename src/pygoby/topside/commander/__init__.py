"""The command composer shared by iCommander and liaison (library, no UI code).

    from pygoby.topside.commander import CommandSet, Commander

    commands = CommandSet.from_pacommshandler(cfg, find=mission.find_file)
    commander = Commander(commands, community="topside", now=time.time, publish=post)

See `commander.Commander` for drafts, specials, preview/send, ack tracking and save files.
"""

from pygoby.topside.commander.commander import (
    KEY_VALUE,
    MULTIPLEX,
    Commander,
    Draft,
    Notice,
    Outgoing,
    SentRecord,
)
from pygoby.topside.commander.fields import FieldSpec
from pygoby.topside.commander.messageset import AcommsVariables, CommandSet, CommandType
from pygoby.topside.errors import CommanderError, FieldValueError, SaveFileError, SpecialError

__all__ = [
    "KEY_VALUE",
    "MULTIPLEX",
    "AcommsVariables",
    "CommandSet",
    "CommandType",
    "Commander",
    "CommanderError",
    "Draft",
    "FieldSpec",
    "FieldValueError",
    "Notice",
    "Outgoing",
    "SaveFileError",
    "SentRecord",
    "SpecialError",
]
