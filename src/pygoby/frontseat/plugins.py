"""Finding and loading an iFrontSeat driver.

goby3 dlopen()s the shared library named by $IFRONTSEAT_DRIVER_LIBRARY and calls its
`frontseat_driver_load(Config*)`. Here a driver is named by either

* an entry point of the group `pygoby.frontseat_drivers` (installed packages register theirs;
  pygoby's own: `abc`, `basic_simulator`),
* an upstream library name such as `libgoby_frontseat_basic_simulator.so.30` (a path and
  version suffix allowed), which stands for the entry point after `libgoby_frontseat_`, or
* a module path `pkg.mod` or `pkg.mod:factory`; the factory defaults to the module's
  `frontseat_driver_load`.

The factory contract: `factory(cfg: Config, clock: Clock | None) -> InterfaceBase`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from pygoby.frontseat.errors import DriverLoadError
from pygoby.frontseat.interface import InterfaceBase
from pygoby.util.clock import Clock
from pygoby.util.libraries import FRONTSEAT_DRIVER, builtin_for
from pygoby.util.plugins import PluginGroup

ENTRY_POINT_GROUP = "pygoby.frontseat_drivers"
DRIVER_ENV_VAR = "IFRONTSEAT_DRIVER_LIBRARY"
DEFAULT_FACTORY = "frontseat_driver_load"


DRIVERS = PluginGroup(ENTRY_POINT_GROUP, "frontseat driver", DEFAULT_FACTORY, DriverLoadError)


def available_drivers() -> list[str]:
    """Names of the installed drivers (entry points), sorted."""
    return DRIVERS.names()


def canonical_name(name: str) -> str:
    """The driver name for `name`: an upstream library name maps to the part after
    `libgoby_frontseat_` (e.g. `libgoby_frontseat_basic_simulator.so.30` -> `basic_simulator`);
    anything else is returned trimmed."""
    builtin = builtin_for(name)
    if builtin is not None and builtin.kind == FRONTSEAT_DRIVER:
        return builtin.name
    return name.strip()


def driver_name_from(env: Mapping[str, str], config_value: str | None) -> str:
    """The driver to load: $IFRONTSEAT_DRIVER_LIBRARY wins over the configuration value."""
    for value in (env.get(DRIVER_ENV_VAR), config_value):
        if value and value.strip():
            return value.strip()
    raise DriverLoadError(
        f"no frontseat driver given: set the environment variable {DRIVER_ENV_VAR} "
        f"(or driver_library in the configuration); {DRIVERS.found()}"
    )


def _resolve_factory(name: str) -> tuple[str, Callable[..., Any]]:
    canonical = canonical_name(name)
    return canonical, DRIVERS.resolve(canonical)


def find_driver(name: str) -> Callable[..., Any]:
    """The factory of the driver called `name`, without making a driver. Importing a driver
    loads its configuration extension, so iFrontSeat calls this before it reads its
    configuration. DriverLoadError if there is no such driver."""
    return _resolve_factory(name)[1]


def load_driver(name: str, cfg: Any, clock: Clock | None = None) -> InterfaceBase:
    """Make the driver called `name` (entry point, upstream library name or module path) from
    the frontseat Config. Every failure is a DriverLoadError saying what went wrong."""
    canonical, factory = _resolve_factory(name)
    try:
        driver = factory(cfg, clock)
    except Exception as exc:
        raise DriverLoadError(f"frontseat driver {canonical!r} failed to start: {exc!r}") from exc
    if not isinstance(driver, InterfaceBase):
        raise DriverLoadError(
            f"frontseat driver {canonical!r} factory returned {type(driver).__name__}, "
            "not an InterfaceBase"
        )
    return driver
