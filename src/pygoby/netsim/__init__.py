"""pygoby.netsim: a netsim-compatible acoustic network simulator.

* `protocol`: the NETSIM line protocol (sans-I/O codec).
* `config`, `manager`, `server`: netsim_manager (request checks, latest position per modem
  port, asyncio TCP server, the `netsim_manager` console script); `gprmc`: its $GPRMC output.
* `client`: the vehicle side of the manager interface (asyncio, reconnecting).
* `channel`: the packet-level acoustic channel the modem emulators use; `physics_channel`: the
  emulators' channel backed by it.
* `scenario`, `sim`, `realtime`, `eventlog`, `report`: `pygoby netsim run|report` (a scenario
  file simulated on a virtual clock or in real time, its event log and report).
* `errors`: the NetsimError family.
"""

from pygoby.netsim.errors import (
    LineError,
    LineTooLongError,
    MissingSeparatorError,
    NetsimError,
    ScenarioError,
    UnknownNameError,
)
from pygoby.util.modules import lazy_exports

# imported on first use: `pygoby netsim --help` and netsim_manager must not import the simulator
__getattr__, __dir__ = lazy_exports(
    globals(),
    {
        "ManagerServer": "pygoby.netsim.server",
        "NetSimClient": "pygoby.netsim.client",
        "NetSimManager": "pygoby.netsim.manager",
        "PhysicsChannel": "pygoby.netsim.physics_channel",
        "RealTimeRun": "pygoby.netsim.realtime",
        "Simulation": "pygoby.netsim.sim",
        "load_scenario": "pygoby.netsim.scenario",
        "parse_config": "pygoby.netsim.config",
        "parse_scenario": "pygoby.netsim.scenario",
    },
)

__all__ = [
    "LineError",
    "LineTooLongError",
    "ManagerServer",
    "MissingSeparatorError",
    "NetSimClient",
    "NetSimManager",
    "NetsimError",
    "PhysicsChannel",
    "RealTimeRun",
    "ScenarioError",
    "Simulation",
    "UnknownNameError",
    "load_scenario",
    "parse_config",
    "parse_scenario",
]
