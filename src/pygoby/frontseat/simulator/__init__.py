"""The basic (ABC) frontseat simulator: wire protocol, sans-I/O core, asyncio TCP server."""

from pygoby.frontseat.simulator.core import BasicFrontSeatSimulator
from pygoby.frontseat.simulator.protocol import Command, Nav, Start, format_line, parse_line
from pygoby.util.modules import lazy_exports

# (the server module runs as `python -m pygoby.frontseat.simulator.server`: not imported here)
__getattr__, __dir__ = lazy_exports(
    globals(), {"SimulatorServer": "pygoby.frontseat.simulator.server"}
)

__all__ = [
    "BasicFrontSeatSimulator",
    "Command",
    "Nav",
    "SimulatorServer",
    "Start",
    "format_line",
    "parse_line",
]
