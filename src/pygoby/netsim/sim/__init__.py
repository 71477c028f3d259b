"""The acoustic network simulation behind `pygoby netsim run`.

* `scenario`: the scenario file and what it means.
* `simulation`: the whole network in one process on a virtual clock; `realtime`: the same on
  the wall clock, over TCP.
* `physics_channel`: the Micro-Modem emulators' channel backed by `netsim.channel`'s physics;
  `range_link`: the same physics for one sender and one receiver (iModemSim's multicast channel).
"""

__all__ = [
    "physics_channel",
    "range_link",
    "realtime",
    "scenario",
    "simulation",
]
