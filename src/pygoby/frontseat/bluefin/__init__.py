"""The Bluefin Standard Payload Interface: sentence codec and a Huxley simulator (sans-I/O core
and TCP server). The iFrontSeat driver is pygoby.frontseat.drivers.bluefin."""

from pygoby.frontseat.bluefin.simulator import HuxleyOptions, HuxleySimulator
from pygoby.util.modules import lazy_exports

# (the server module runs as `pygoby bluefin_frontseat_simulator`: not imported here)
__getattr__, __dir__ = lazy_exports(globals(), {"HuxleyServer": "pygoby.frontseat.bluefin.server"})

__all__ = ["HuxleyOptions", "HuxleyServer", "HuxleySimulator"]
