"""Modem drivers (all derive from pygoby.acomms.driver_base.ModemDriverBase)."""

from __future__ import annotations

import importlib

from pygoby.acomms.driver_base import ModemDriverBase
from pygoby.acomms.errors import ModemDriverError

__all__ = ["DRIVER_CLASSES", "make_driver"]

# DriverType value -> "module:Class"
DRIVER_CLASSES = {
    1: "pygoby.acomms.driver_base:NoDriver",
    2: "pygoby.acomms.drivers.micromodem:MMDriver",
    3: "pygoby.acomms.drivers.abc:ABCDriver",
    4: "pygoby.acomms.drivers.ufield:UFldDriver",
    5: "pygoby.acomms.drivers.store_server:StoreServerDriver",
    6: "pygoby.acomms.drivers.udp:UDPDriver",
    11: "pygoby.acomms.drivers.udp_multicast:UDPMulticastDriver",
}


def make_driver(cfg, clock=None, **kwargs) -> ModemDriverBase:
    """A driver instance for `cfg.driver_type` (not started). `kwargs` go to the constructor
    (e.g. `publish=` for the uField driver)."""
    target = DRIVER_CLASSES.get(cfg.driver_type)
    if target is None:
        from pygoby.acomms import messages as acomms_pb

        raise ModemDriverError(
            f"driver type {cfg.driver_type} is not implemented",
            acomms_pb.ModemDriverStatus.INVALID_CONFIGURATION,
        )
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)(clock=clock, **kwargs)
