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
    CommanderError,
    Draft,
    Notice,
    Outgoing,
    SentRecord,
)
from pygoby.topside.commander.fields import FieldSpec, FieldValueError
from pygoby.topside.commander.messageset import AcommsVariables, CommandSet, CommandType
from pygoby.topside.commander.savefile import SaveFileError
from pygoby.topside.commander.specials import SpecialError

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
