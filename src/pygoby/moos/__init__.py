"""MOOS for pygoby: the V10 wire protocol, an asyncio client, an embedded MOOSDB, .moos files,
the pAntler-style launcher and the Goby MOOS application base.

    from pygoby.moos import MOOSClient, MOOSDB, MOOSMessage
    from pygoby.moos.app import GobyMOOSApp        # base class of Goby MOOS applications

Modules: protocol (sans-I/O codec and handshake), dbcore (sans-I/O DB semantics), db (asyncio
server), client (asyncio client), timewarp (MOOS time), moosfile (.moos reader), app
(GobyMOOSApp: mail dispatch, ticks, timers, publish/subscribe) with appconfig (its
configuration), appcli (its command line), applog (its log files) and appstatus (its
<NAME>_STATUS posts), antler (launcher), cli (`pygoby moosdb|moos|antler`), errors (the
MoosError family; configuration problems are `pygoby.errors.ConfigError`s).
"""

from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.errors import (
    AntlerError,
    BlockSyntaxError,
    MissionFileError,
    MoosError,
    MoosProtocolError,
    MoosRefusedError,
)
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.timewarp import moos_clock

__all__ = [
    "MOOSDB",
    "AntlerError",
    "BlockSyntaxError",
    "MOOSClient",
    "MOOSMessage",
    "MissionFile",
    "MissionFileError",
    "MoosError",
    "MoosProtocolError",
    "MoosRefusedError",
    "moos_clock",
]
