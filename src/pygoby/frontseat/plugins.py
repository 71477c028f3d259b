"""Finding and loading an iFrontSeat driver (spec goby-moos-apps.md 5.1).

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

import importlib
import re
from collections.abc import Callable, Mapping
from importlib.metadata import EntryPoint, entry_points
from typing import Any

from pygoby.frontseat.errors import DriverLoadError
from pygoby.frontseat.interface import InterfaceBase
from pygoby.util.clock import Clock

ENTRY_POINT_GROUP = "pygoby.frontseat_drivers"
DRIVER_ENV_VAR = "IFRONTSEAT_DRIVER_LIBRARY"
DEFAULT_FACTORY = "frontseat_driver_load"

_UPSTREAM_LIBRARY = re.compile(r"(?:.*/)?libgoby_frontseat_(?P<name>\w+?)\.so(?:\.\d+)*")
_MODULE_PATH = re.compile(r"[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*(?::[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*)?")


def _entry_points() -> dict[str, EntryPoint]:
    return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}


def available_drivers() -> list[str]:
    """Names of the installed drivers (entry points), sorted."""
    return sorted(_entry_points())


def _found() -> str:
    names = available_drivers()
    return f"drivers found: {', '.join(names) if names else '(none)'}"


def canonical_name(name: str) -> str:
    """The driver name for `name`: an upstream library name maps to the part after
    `libgoby_frontseat_` (e.g. `libgoby_frontseat_basic_simulator.so.30` -> `basic_simulator`);
    anything else is returned trimmed."""
    name = name.strip()
    upstream = _UPSTREAM_LIBRARY.fullmatch(name)
    return upstream.group("name") if upstream else name


def driver_name_from(env: Mapping[str, str], config_value: str | None) -> str:
    """The driver to load: $IFRONTSEAT_DRIVER_LIBRARY wins over the configuration value."""
    for value in (env.get(DRIVER_ENV_VAR), config_value):
        if value and value.strip():
            return value.strip()
    raise DriverLoadError(
        f"no frontseat driver given: set the environment variable {DRIVER_ENV_VAR} "
        f"(or driver_library in the configuration); {_found()}"
    )


def _factory_from_module(spec: str) -> Callable[..., Any]:
    module_name, _, attr = spec.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name and (module_name == exc.name or module_name.startswith(exc.name + ".")):
            raise DriverLoadError(
                f"unknown frontseat driver {spec!r} (neither an installed driver nor an "
                f"importable module); {_found()}"
            ) from exc
        raise DriverLoadError(f"cannot import driver module {module_name!r}: {exc}") from exc
    except Exception as exc:  # the driver module itself is broken
        raise DriverLoadError(f"cannot import driver module {module_name!r}: {exc!r}") from exc
    factory: Any = module
    for part in (attr or DEFAULT_FACTORY).split("."):
        factory = getattr(factory, part, None)
        if factory is None:
            raise DriverLoadError(
                f"driver module {module_name!r} has no {attr or DEFAULT_FACTORY!r} factory"
            )
    if not callable(factory):
        raise DriverLoadError(f"{spec!r}: {attr or DEFAULT_FACTORY!r} is not callable")
    return factory


def _resolve_factory(name: str) -> tuple[str, Callable[..., Any]]:
    canonical = canonical_name(name)
    entry_point = _entry_points().get(canonical)
    if entry_point is not None:
        try:
            return canonical, entry_point.load()
        except Exception as exc:
            raise DriverLoadError(
                f"cannot load frontseat driver {canonical!r} ({entry_point.value}): {exc!r}"
            ) from exc
    if _MODULE_PATH.fullmatch(canonical):
        return canonical, _factory_from_module(canonical)
    raise DriverLoadError(f"unknown frontseat driver {name!r}; {_found()}")


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
