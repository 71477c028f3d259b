"""Loading Python modules named in configuration (plugins, generated message code)."""

from __future__ import annotations

import importlib
import importlib.util
import sys
import zlib
from pathlib import Path
from types import ModuleType


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
