"""The frontseat interface (goby3's iFrontSeat library, usable without MOOS): the interface
state machine every driver shares, the driver plugins, the ABC and Bluefin drivers and their simulators.

    from pygoby.frontseat import load_driver
    from pygoby.frontseat import messages as frontseat_pb
    driver = load_driver("basic_simulator", frontseat_pb.Config(...), clock)
    driver.signal_state_change.connect(print)
    driver.do_work()                      # once per tick

Modules: messages (the goby3 protobuf messages and enum values), interface (`InterfaceBase`,
the state machine), plugins (drivers by name), drivers (the ABC and Bluefin drivers), simulator (the basic
frontseat simulator), bluefin (the Bluefin SPI sentences and Huxley simulator), ctd, helm and legacy (the iFrontSeat app's conversions), errors (the
FrontSeatError family; `messages.FrontSeatError` is goby3's enum of frontseat error codes).
"""

from pygoby.frontseat.errors import (
    AbcConfigError,
    BluefinConfigError,
    DriverLoadError,
    FrontSeatDriverError,
    FrontSeatError,
    FrontSeatFatalError,
    SimulatorProtocolError,
)
from pygoby.frontseat.interface import InterfaceBase
from pygoby.frontseat.plugins import available_drivers, load_driver

__all__ = [
    "AbcConfigError",
    "BluefinConfigError",
    "DriverLoadError",
    "FrontSeatDriverError",
    "FrontSeatError",
    "FrontSeatFatalError",
    "InterfaceBase",
    "SimulatorProtocolError",
    "available_drivers",
    "load_driver",
]
