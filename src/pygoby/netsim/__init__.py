"""pygoby.netsim: a netsim-compatible acoustic network simulator.

* `protocol`: the NETSIM line protocol (sans-I/O codec).
* `config`, `manager`, `server`: netsim_manager (request checks, latest position per modem
  port, asyncio TCP server, the `netsim_manager` console script); `gprmc`: its $GPRMC output.
* `client`: the vehicle side of the manager interface (asyncio, reconnecting).
* `channel`: the packet-level acoustic channel the modem emulators use.
"""

from pygoby.netsim.errors import (
    LineError,
    LineTooLongError,
    MissingSeparatorError,
    NetsimError,
    ScenarioError,
    UnknownNameError,
)

__all__ = [
    "LineError",
    "LineTooLongError",
    "MissingSeparatorError",
    "NetsimError",
    "ScenarioError",
    "UnknownNameError",
]
