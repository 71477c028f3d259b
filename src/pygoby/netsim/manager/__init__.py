"""netsim_manager: the NETSIM line protocol, the manager's request processing and its TCP server.

* `protocol`: the NETSIM line protocol (sans-I/O codec).
* `config`, `core`, `server`: netsim_manager (request checks, latest position per modem port,
  asyncio TCP server, the `netsim_manager` console script); `gprmc`: its $GPRMC output.
* `client`: the vehicle side of the manager interface (asyncio, reconnecting).
* `navreporter`: what iNetSimManager reports to the manager (sans-I/O).
"""

__all__ = [
    "client",
    "config",
    "core",
    "gprmc",
    "navreporter",
    "protocol",
    "server",
]
