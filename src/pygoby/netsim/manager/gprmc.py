"""The manager's optional ``$GPRMC`` output.

For each ``gps_out`` entry of the configuration, every nav forwarded for that modem port is
written to a serial port as a ``$GPRMC`` sentence stamped with the manager's own clock (not the
nav's time).
"""

from __future__ import annotations

import datetime
import logging
import math
from collections.abc import Callable

from pygoby.netsim.manager.protocol import EnvironmentNavUpdate, NavUpdate
from pygoby.protobuf.netsim.messages.manager_config_pb2 import NetSimManagerConfig
from pygoby.util.clock import Clock
from pygoby.util.nmea import with_checksum

log = logging.getLogger(__name__)

KNOTS_PER_MPS = 1.94384


def _degrees_minutes(value: float, degree_digits: int) -> str:
    """ddmm.mmmm / dddmm.mmmm, each part truncated (floor) in double arithmetic."""
    magnitude = abs(value)
    degrees = math.floor(magnitude)
    minutes = (magnitude - degrees) * 60
    whole = math.floor(minutes)
    fraction = math.floor((minutes - whole) * 10000)
    return f"{degrees:0{degree_digits}d}{whole:02d}.{fraction:04d}"


def gprmc_sentence(nav: NavUpdate, utc_seconds: float) -> str:
    """The sentence (with ``*checksum\\r\\n``) for a NavUpdate at manager time utc_seconds."""
    when = datetime.datetime.fromtimestamp(utc_seconds, datetime.UTC)
    body = ",".join(
        (
            "GPRMC",
            when.strftime("%H%M%S.%f"),
            "A",
            _degrees_minutes(nav.lat, 2),
            "N" if nav.lat >= 0 else "S",
            _degrees_minutes(nav.lon, 3),
            "E" if nav.lon >= 0 else "W",
            f"{nav.speed * KNOTS_PER_MPS:.1f}",
            f"{nav.heading:.1f}",
            when.strftime("%d%m%y"),
            "000.0",
            "E",
        )
    )
    return with_checksum(f"${body}") + "\r\n"


class GpsOutputs:
    """Writes $GPRMC for the configured ports; use `on_nav_update` as a manager nav listener."""

    def __init__(self, writers: dict[int, Callable[[bytes], object]], clock: Clock) -> None:
        self._writers = writers
        self._clock = clock

    @classmethod
    def open_serial(cls, config: NetSimManagerConfig, clock: Clock) -> GpsOutputs:
        """Open every `gps_out` serial port of a NetSimManagerConfig (pyserial URLs work too)."""
        import serial  # only needed when gps_out is configured

        writers = {}
        for entry in config.gps_out:
            port = serial.serial_for_url(entry.serial.port, baudrate=entry.serial.baud or 4800)
            writers[entry.modem_tcp_port] = port.write
        return cls(writers, clock)

    def on_nav_update(self, update: EnvironmentNavUpdate) -> None:
        write = self._writers.get(update.nav.modem_tcp_port)
        if write is None:
            return
        try:
            write(gprmc_sentence(update.nav, self._clock.now()).encode())
        except OSError as exc:
            log.warning("GPRMC output for port %d failed: %s", update.nav.modem_tcp_port, exc)
