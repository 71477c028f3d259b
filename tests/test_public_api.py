"""Every package declares its public API in `__all__`, and every name there can be imported."""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import pygoby

PACKAGES = ["pygoby"] + [
    info.name for info in pkgutil.walk_packages(pygoby.__path__, "pygoby.") if info.ispkg
]


@pytest.mark.parametrize("name", PACKAGES)
def test_package_declares_and_provides_its_public_api(name):
    package = importlib.import_module(name)
    exported = package.__all__
    assert exported and len(set(exported)) == len(exported)
    for public in exported:
        if not hasattr(package, public):  # a submodule (as `from package import *` imports it)
            importlib.import_module(f"{name}.{public}")
        assert getattr(package, public) is not None, f"{name}.{public}"
    assert set(exported) <= set(dir(package))


def test_lazy_exports_are_the_submodules_objects():
    from pygoby.acomms import QueueManager
    from pygoby.acomms.queue.manager import QueueManager as defined
    from pygoby.netsim import Simulation
    from pygoby.netsim.sim.simulation import Simulation as simulation_defined

    assert QueueManager is defined and Simulation is simulation_defined
    with pytest.raises(AttributeError, match="has no attribute 'NoSuchThing'"):
        pygoby.netsim.NoSuchThing  # noqa: B018 - the attribute access is the test
    with pytest.raises(ImportError):
        from pygoby.acomms import NoSuchThing  # noqa: F401


RUNNABLE = [  # modules with a `__main__` block (console scripts, `python -m ...`)
    info.name
    for info in pkgutil.walk_packages(pygoby.__path__, "pygoby.")
    if not info.ispkg
    and 'if __name__ == "__main__":' in Path(importlib.util.find_spec(info.name).origin).read_text()
]


def test_packages_do_not_import_their_runnable_modules():
    """`python -m package.module` warns (and may misbehave) when the package's __init__ has
    imported the module already; the lazy exports keep such modules out of the __init__s."""
    assert "pygoby.frontseat.simulator.server" in RUNNABLE
    check = (
        "import importlib, sys\n"
        f"for name in {RUNNABLE!r}:\n"
        "    importlib.import_module(name.rpartition('.')[0])\n"
        f"print(sorted(set({RUNNABLE!r}) & set(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", check], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
