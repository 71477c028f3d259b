"""pygoby.netsim: a netsim-compatible acoustic network simulator.

* `manager/`: netsim_manager — the NETSIM line protocol, request processing, the TCP server and
  `netsim_manager` console script, its $GPRMC output, the vehicle-side client and what
  iNetSimManager reports.
* `channel/`: the packet-level acoustic channel physics (geometry, sound speed, absorption,
  levels, frame-error models).
* `sim/`: `pygoby netsim run` — scenarios, the simulation on a virtual clock or in real time,
  the modem emulators' channel backed by `channel/`, and its one-sender-one-receiver form
  (`range_link`, for iModemSim's multicast channel).
* `report/`: the event log a simulation writes and `pygoby netsim report`'s plots of it.
* `sweep/`: parameter sweeps of scenarios.
* `cli`: the `pygoby netsim` subcommands; `errors`: the NetsimError family.
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
        "ManagerServer": "pygoby.netsim.manager.server",
        "NetSimClient": "pygoby.netsim.manager.client",
        "NetSimManager": "pygoby.netsim.manager.core",
        "PhysicsChannel": "pygoby.netsim.sim.physics_channel",
        "RealTimeRun": "pygoby.netsim.sim.realtime",
        "Simulation": "pygoby.netsim.sim.simulation",
        "load_scenario": "pygoby.netsim.sim.scenario",
        "parse_config": "pygoby.netsim.manager.config",
        "parse_scenario": "pygoby.netsim.sim.scenario",
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
