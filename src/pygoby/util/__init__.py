"""Small shared utilities: clocks, geodesy, NMEA, line-based I/O, signals (import each from its
module). Their errors (`pygoby.util.errors`) are exported here."""

from pygoby.util.errors import LinkClosedError, NMEAChecksumError, NMEAError, NMEAFormatError

__all__ = ["LinkClosedError", "NMEAChecksumError", "NMEAError", "NMEAFormatError"]
