"""Loading Python modules: those named in configuration (plugins, generated message code), and
the names a package exports from its submodules on first use (`lazy_exports`)."""

from __future__ import annotations

import importlib
import importlib.util
import sys
import zlib
from collections.abc import Callable, Mapping, MutableMapping
from pathlib import Path
from types import ModuleType
from typing import Any


def import_module_or_file(name: str) -> ModuleType:
    """A Python module given by importable name or by the path of a .py file (driver plugins,
    and `load_shared_library` modules of generated message code); each is loaded once."""
    path = Path(name)
    if path.suffix != ".py":
        return importlib.import_module(name)
    resolved = path.resolve()
    module_name = f"pygoby_loaded_{resolved.stem}_{zlib.crc32(str(resolved).encode()):08x}"
    if module_name in sys.modules:
        return sys.modules[module_name]
    spec = importlib.util.spec_from_file_location(module_name, resolved)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot load {name}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module  # before running it, as an import does (dataclasses need it)
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[module_name]
        raise
    return module


def lazy_exports(
    package_globals: MutableMapping[str, Any], exports: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """`__getattr__` and `__dir__` (PEP 562) for a package that exports `name` from the module
    `exports[name]` without importing that module until the name is first used: importing one
    light submodule (a CLI registering its commands, a console script) must not import the
    whole package. `from package import name` works as for an eager import."""
    package = package_globals["__name__"]

    def __getattr__(name: str) -> Any:  # noqa: N807 - the module hook's name
        source = exports.get(name)
        if source is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(source), name)
        package_globals[name] = value  # (found directly from now on)
        return value

    def __dir__() -> list[str]:  # noqa: N807 - the module hook's name
        return sorted({*package_globals, *exports})

    return __getattr__, __dir__
