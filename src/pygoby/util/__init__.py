"""Small shared utilities: clocks, signals, geodesy, kinematics, NMEA, line-based I/O, the
modem-id lookup. The light, widely used ones and the errors are exported here; import the
others (geodesy, nmea, linebased, aiorun, ...) from their modules."""

from pygoby.util.clock import Clock, VirtualClock, WallClock
from pygoby.util.errors import (
    LinkClosedError,
    MissingExtraError,
    NMEAChecksumError,
    NMEAError,
    NMEAFormatError,
    PluginError,
    PtyError,
)
from pygoby.util.modem_id import ModemIdLookup
from pygoby.util.signal import Signal

__all__ = [
    "Clock",
    "LinkClosedError",
    "MissingExtraError",
    "ModemIdLookup",
    "NMEAChecksumError",
    "NMEAError",
    "NMEAFormatError",
    "PluginError",
    "PtyError",
    "Signal",
    "VirtualClock",
    "WallClock",
]
