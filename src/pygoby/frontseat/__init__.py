"""pygoby.frontseat"""

from pygoby.frontseat.errors import (
    AbcConfigError,
    DriverLoadError,
    FrontSeatDriverError,
    FrontSeatError,
    FrontSeatFatalError,
    SimulatorProtocolError,
)

__all__ = [
    "AbcConfigError",
    "DriverLoadError",
    "FrontSeatDriverError",
    "FrontSeatError",
    "FrontSeatFatalError",
    "SimulatorProtocolError",
]
