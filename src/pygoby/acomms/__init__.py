"""goby-acomms: moving DCCL messages over slow, lossy acoustic links.

Layers (all sans-I/O cores advanced by `do_work()` against a pygoby.util.clock.Clock; signals
are synchronous `pygoby.util.signal.Signal`s with `connect`/`disconnect`/`emit`):

* `pygoby.acomms.messages`: protobuf classes (ModemTransmission, DriverConfig, QueueManagerConfig,
  MACConfig, MACUpdate, NetworkAck, Micro-Modem / UDP / ABC / store-server / uField extensions as
  `MM_TRANSMISSION`, `MM_CONFIG`, `UDP_CONFIG`, ...).
* `pygoby.acomms.queue.QueueManager(codec, clock)`: `set_cfg`, `add_queue(entry, cls=None)`,
  `push_message(msg)`, `handle_modem_data_request(transmission)`,
  `handle_modem_receive(transmission)`, `flush_queue`, `do_work()` (expiry); signals
  `signal_receive(msg)`, `signal_ack(ack, original)`, `signal_expire(original)`,
  `signal_queue_size_change(QueueSize)`, `signal_data_on_demand(request, msg)`, and routing hooks.
* `pygoby.acomms.mac.MACManager(clock)`: `startup(MACConfig)`, `restart`, `shutdown`, `update`,
  `apply_update(MACUpdate)`, `handle_modem_receive` (auto-discovery), `do_work()`; signals
  `signal_initiate_transmission(slot)`, `signal_slot_start(slot)`.
* Drivers (`pygoby.acomms.driver_base.ModemDriverBase`): `startup(DriverConfig)`, `shutdown`,
  `do_work`, `handle_initiate_transmission`, `report`; signals `signal_receive`,
  `signal_transmit_result`, `signal_data_request`, `signal_modify_transmission`,
  `signal_raw_incoming/outgoing`. `pygoby.acomms.drivers.make_driver(cfg, clock)` picks one.
* `pygoby.acomms.bind.bind(driver, queue, mac)` wires them; `pygoby.acomms.route` routes.
* `pygoby.acomms.handler.AcommsHandler(cfg, clock, loader)`: drivers, MAC, queue and DCCL wired
  together as pAcommsHandler wires them, without MOOS.
* `pygoby.acomms.mmsim`: the Micro-Modem emulator and its pluggable acoustic channel.
* `pygoby.acomms.errors`: the AcommsError family.

The classes and functions named above (and the errors) are also importable from
`pygoby.acomms` itself (see `__all__`).
"""

from pygoby.acomms.errors import (
    ABCParseError,
    AcommsError,
    DriverConfigError,
    DriverNotFoundError,
    HandlerError,
    ModemDriverError,
    QueueError,
    RoleError,
    RudicsPacketError,
    StoreServerAuthError,
)
from pygoby.util.modules import lazy_exports

# imported on first use: importing one acomms module (the mmsim server, a driver) must not
# import the whole stack
__getattr__, __dir__ = lazy_exports(
    globals(),
    {
        "AcommsHandler": "pygoby.acomms.handler",
        "MACManager": "pygoby.acomms.mac",
        "ModemDriverBase": "pygoby.acomms.driver_base",
        "QueueManager": "pygoby.acomms.queue",
        "RouteManager": "pygoby.acomms.route",
        "bind": "pygoby.acomms.bind",
        "make_driver": "pygoby.acomms.drivers",
        "unbind": "pygoby.acomms.bind",
    },
)

__all__ = [
    "ABCParseError",
    "AcommsError",
    "AcommsHandler",
    "DriverConfigError",
    "DriverNotFoundError",
    "HandlerError",
    "MACManager",
    "ModemDriverBase",
    "ModemDriverError",
    "QueueError",
    "QueueManager",
    "RoleError",
    "RouteManager",
    "RudicsPacketError",
    "StoreServerAuthError",
    "bind",
    "make_driver",
    "unbind",
]
