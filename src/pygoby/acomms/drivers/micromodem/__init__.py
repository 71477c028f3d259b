"""WHOI Micro-Modem NMEA driver."""

from pygoby.acomms.drivers.micromodem.driver import MMDriver
from pygoby.acomms.drivers.micromodem.rates import RATE_FRAME_BYTES, RATE_NUM_FRAMES

__all__ = ["RATE_FRAME_BYTES", "RATE_NUM_FRAMES", "MMDriver"]
