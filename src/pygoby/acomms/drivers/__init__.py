"""Modem drivers (all derive from pygoby.acomms.driver_base.ModemDriverBase) and the one registry
that picks them, used by pAcommsHandler for `driver_cfg` and every `listen_driver_cfg`.

A DriverConfig names its driver by

* `driver_type`: pygoby's built-in driver for that DriverType (`BUILTIN_DRIVERS`), else an
  installed driver registered under the DriverType's name in the entry point group
  `pygoby.acomms_drivers` (a package can provide, say, `DRIVER_IRIDIUM`);
* `driver_name` (goby3's plug-in drivers): an entry point of that name, else a module listed in
  `$PACOMMSHANDLER_PLUGINS` (module paths or `.py` files separated by `;`, `:` or `,`) whose
  `goby_driver_name()` returns it; its `goby_make_driver` makes the driver.

Every factory is called as `factory(clock)` and returns an unstarted driver. Third-party
packages register theirs in their pyproject.toml:

    [project.entry-points."pygoby.acomms_drivers"]
    my_modem = "my_package.driver:make_driver"       # driver_cfg { driver_name: "my_modem" }
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverBase
from pygoby.acomms.errors import DriverNotFoundError
from pygoby.util.clock import Clock
from pygoby.util.libraries import is_shared_library
from pygoby.util.plugins import PluginGroup, import_object

__all__ = [
    "BUILTIN_DRIVERS",
    "ENTRY_POINT_GROUP",
    "PLUGINS_ENV",
    "driver_factory",
    "implemented_types",
    "make_driver",
]

ENTRY_POINT_GROUP = "pygoby.acomms_drivers"
PLUGINS_ENV = "PACOMMSHANDLER_PLUGINS"
PLUGIN_NAME_FUNCTION = "goby_driver_name"
PLUGIN_FACTORY = "goby_make_driver"

# DriverType name -> "module:Class" (imported when first used)
BUILTIN_DRIVERS = {
    "DRIVER_NONE": "pygoby.acomms.driver_base:NoDriver",
    "DRIVER_WHOI_MICROMODEM": "pygoby.acomms.drivers.micromodem:MMDriver",
    "DRIVER_ABC_EXAMPLE_MODEM": "pygoby.acomms.drivers.abc:ABCDriver",
    "DRIVER_UFIELD_SIM_DRIVER": "pygoby.acomms.drivers.ufield:UFldDriver",
    "DRIVER_STORE_SERVER": "pygoby.acomms.drivers.store_server:StoreServerDriver",
    "DRIVER_UDP": "pygoby.acomms.drivers.udp:UDPDriver",
    "DRIVER_UDP_MULTICAST": "pygoby.acomms.drivers.udp_multicast:UDPMulticastDriver",
}

Factory = Callable[[Clock | None], ModemDriverBase]
_DRIVER_TYPE = acomms_pb.DriverType.DESCRIPTOR


INSTALLED = PluginGroup(ENTRY_POINT_GROUP, "modem driver", PLUGIN_FACTORY, DriverNotFoundError)


def driver_type_name(cfg: acomms_pb.DriverConfig) -> str:
    return _DRIVER_TYPE.values_by_number[cfg.driver_type].name


def implemented_types() -> list[str]:
    """The DriverType names that can be used: built-ins and installed ones."""
    types = set(BUILTIN_DRIVERS) | {
        n for n in INSTALLED.names() if n in _DRIVER_TYPE.values_by_name
    }
    return [v.name for v in _DRIVER_TYPE.values if v.name in types]


def driver_factory(cfg: acomms_pb.DriverConfig) -> Factory:
    """The factory of the driver `cfg` (DriverConfig) selects; DriverNotFoundError otherwise."""
    if cfg.WhichOneof("driver") == "driver_name":
        return plugin_factory(cfg.driver_name)
    type_name = driver_type_name(cfg)
    builtin = BUILTIN_DRIVERS.get(type_name)
    if builtin is not None:
        return import_object(builtin)
    installed = INSTALLED.entry_point(type_name)
    if installed is not None:
        return installed
    raise DriverNotFoundError(
        f"driver_type {type_name} is not implemented in pygoby; available: "
        f"{', '.join(implemented_types())} (or a driver_name of {ENTRY_POINT_GROUP} "
        f"entry points or ${PLUGINS_ENV} modules)"
    )


def plugin_factory(name: str) -> Factory:
    """`driver_name`: the entry point `name`, else the $PACOMMSHANDLER_PLUGINS module whose
    `goby_driver_name()` is `name`."""
    installed = INSTALLED.entry_point(name)
    if installed is not None:
        return installed
    listed = [p.strip() for p in re.split(r"[;:,]", os.environ.get(PLUGINS_ENV, "")) if p.strip()]
    compiled = [p for p in listed if is_shared_library(p)]
    for spec in listed:
        if spec in compiled:
            continue
        module = INSTALLED.import_module(spec)
        namer = getattr(module, PLUGIN_NAME_FUNCTION, None)
        if namer is not None and namer() == name:
            return INSTALLED.attribute(module, PLUGIN_FACTORY, spec)
    hint = ""
    if compiled:
        hint = (
            f"; ${PLUGINS_ENV} lists compiled C++ plug-ins ({', '.join(compiled)}), which pygoby "
            "cannot load: list Python modules or .py files there"
        )
    raise DriverNotFoundError(
        f"no driver plugin named {name!r}: not an entry point of {ENTRY_POINT_GROUP} "
        f"({', '.join(INSTALLED.names()) or 'none installed'}) nor the goby_driver_name() of a "
        f"module in ${PLUGINS_ENV} ({', '.join(listed) or 'empty'}){hint}"
    )


def make_driver(cfg: acomms_pb.DriverConfig, clock: Clock | None = None) -> ModemDriverBase:
    """A driver instance for `cfg` (DriverConfig), not started."""
    return driver_factory(cfg)(clock)
