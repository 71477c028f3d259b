"""Plug-ins found by name: one resolver for every kind (iFrontSeat drivers, modem drivers).

A plug-in is named by either

* an entry point of the kind's group (installed packages register theirs in their
  `pyproject.toml`, e.g. `[project.entry-points."pygoby.acomms_drivers"]`), or
* a module path `pkg.mod` or `pkg.mod:attr`, or a `.py` file `path/to/driver.py[:attr]` (the
  attribute defaults to the kind's factory name).

    DRIVERS = PluginGroup("pygoby.acomms_drivers", "modem driver", "goby_make_driver")
    factory = DRIVERS.resolve("my_driver")      # the group's error class when not found

Upstream library names (`libgoby_frontseat_abc.so.30`) are mapped to names by the caller first
(pygoby.util.libraries), so this module knows nothing about any kind in particular.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from types import ModuleType
from typing import Any

from pygoby.util.errors import PluginError
from pygoby.util.modules import import_module_or_file

_DOTTED = re.compile(r"[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*")


def split_spec(name: str) -> tuple[str, str] | None:
    """`pkg.mod:attr` / `file.py:attr` / `pkg.mod` / `file.py` -> (module or file, attr or "");
    None when `name` is neither a module path nor a .py file."""
    head, sep, tail = name.rpartition(":")
    base, attr = (head, tail) if sep and _DOTTED.fullmatch(tail) else (name, "")
    if base.endswith(".py") or _DOTTED.fullmatch(base):
        return base, attr
    return None


@dataclass(frozen=True)
class PluginGroup:
    """The plug-ins of one kind: `group` (entry points), `kind` (for messages), `default_attr`
    (the factory looked up in a module given by path), `error` (the class raised)."""

    group: str
    kind: str
    default_attr: str
    error: type[Exception] = PluginError

    def installed(self) -> dict[str, EntryPoint]:
        return {ep.name: ep for ep in entry_points(group=self.group)}

    def names(self) -> list[str]:
        """Names of the installed plug-ins (entry points), sorted."""
        return sorted(self.installed())

    def found(self) -> str:
        """`<kind>s found: a, b` for error messages."""
        return f"{self.kind}s found: {', '.join(self.names()) or '(none)'}"

    def entry_point(self, name: str) -> Any | None:
        """The object of the entry point `name`; None when there is no such entry point."""
        entry = self.installed().get(name)
        if entry is None:
            return None
        try:
            return entry.load()
        except Exception as exc:
            raise self.error(f"cannot load {self.kind} {name!r} ({entry.value}): {exc!r}") from exc

    def resolve(self, name: str) -> Callable[..., Any]:
        """The factory called `name`: an entry point, else a module path or `.py` file with an
        optional `:attr`; the group's error class, saying what went wrong, otherwise."""
        name = name.strip()
        found = self.entry_point(name)
        if found is not None:
            return found
        spec = split_spec(name)
        if spec is None:
            raise self.error(f"unknown {self.kind} {name!r}; {self.found()}")
        module, attr = spec
        return self.attribute(self.import_module(module), attr or self.default_attr, name)

    def import_module(self, spec: str) -> ModuleType:
        """Import a module path or a `.py` file; one that does not exist is "unknown"."""
        try:
            return import_module_or_file(spec)
        except ModuleNotFoundError as exc:
            if exc.name and (spec == exc.name or spec.startswith(exc.name + ".")):
                raise self.error(
                    f"unknown {self.kind} {spec!r} (neither an installed {self.kind} nor an "
                    f"importable module); {self.found()}"
                ) from exc
            raise self.error(f"cannot import {self.kind} module {spec!r}: {exc}") from exc
        except FileNotFoundError as exc:
            raise self.error(f"cannot load {self.kind} {spec!r}: no such file") from exc
        except Exception as exc:  # the plug-in's module itself is broken
            raise self.error(f"cannot import {self.kind} module {spec!r}: {exc!r}") from exc

    def attribute(self, module: ModuleType, attr: str, spec: str) -> Callable[..., Any]:
        target: Any = module
        for part in attr.split("."):
            target = getattr(target, part, None)
            if target is None:
                raise self.error(f"{self.kind} module {spec!r} has no {attr!r} factory")
        if not callable(target):
            raise self.error(f"{spec!r}: {attr!r} is not callable")
        return target


def import_object(spec: str) -> Any:
    """`"pkg.mod:Name"` -> the object (tables of built-ins imported when first used)."""
    module, _, name = spec.partition(":")
    return getattr(importlib.import_module(module), name)
