"""What iNetSimManager reports to netsim_manager, sans-I/O.

`NavReporter` collects a vehicle's navigation variables (NAV_LAT/NAV_LONG, or NAV_X/NAV_Y in
the local UTM frame of an origin; NAV_DEPTH, NAV_SPEED, NAV_HEADING) and builds the vehicle's
`NavUpdate` for its modem port once a position and a depth are known (speed and heading default
to 0 until reported). `receive_stats(transmission)` turns the Micro-Modem receive statistics in
a driver reception (`ModemTransmission` with `$CACST` data) into netsim `ReceiveStats`, as
netsim_tool does: `packet_success` is `mode == RECEIVE_GOOD`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping

from pygoby.acomms import messages as acomms_pb
from pygoby.netsim.manager.protocol import NavUpdate, ReceiveStats
from pygoby.util.geodesy import UTMGeodesy

log = logging.getLogger(__name__)

RECEIVE_GOOD = 0


class NavReporter:
    def __init__(
        self,
        modem_tcp_port: int,
        origin: tuple[float, float] | None = None,
        modem_ports: Mapping[int, int] | None = None,
        port_of_id_offset: int = 61999,
    ) -> None:
        self.modem_tcp_port = modem_tcp_port
        self.geodesy = UTMGeodesy(*origin) if origin is not None else None
        self.modem_ports = dict(modem_ports or {})
        self.port_of_id_offset = port_of_id_offset
        self.values: dict[str, float] = {}
        self.time = -math.inf  # of the newest value
        self._nav_class = NavUpdate
        self._stats_class = ReceiveStats

    def set_origin(self, lat: float, lon: float) -> None:
        self.geodesy = UTMGeodesy(lat, lon)

    def update(self, name: str, value: float, time: float) -> None:
        """`name`: one of lat, lon, x, y, depth, speed, heading. Non-finite values are ignored."""
        if not math.isfinite(value):
            log.warning("ignoring non-finite %s = %r", name, value)
            return
        self.values[name] = value
        self.time = max(self.time, time)

    def position(self) -> tuple[float, float] | None:
        v = self.values
        if "lat" in v and "lon" in v:
            return v["lat"], v["lon"]
        if "x" in v and "y" in v and self.geodesy is not None:
            lat, lon = self.geodesy.to_geo(v["x"], v["y"])
            if math.isfinite(lat) and math.isfinite(lon):
                return lat, lon
        return None

    def nav_update(self) -> NavUpdate | None:
        """The vehicle's NavUpdate, or None while its position or depth is unknown."""
        position = self.position()
        if position is None or "depth" not in self.values:
            return None
        return self._nav_class(
            modem_tcp_port=self.modem_tcp_port,
            time=self.time,
            lat=position[0],
            lon=position[1],
            depth=self.values["depth"],
            speed=self.values.get("speed", 0.0),
            heading=self.values.get("heading", 0.0) % 360.0,
        )

    def port_of(self, modem_id: int) -> int:
        return self.modem_ports.get(modem_id, self.port_of_id_offset + modem_id)

    def receive_stats(self, transmission: acomms_pb.ModemTransmission) -> list[ReceiveStats]:
        """One ReceiveStats per $CACST in a driver reception (none for other transmissions)."""
        if not transmission.HasExtension(acomms_pb.MM_TRANSMISSION):
            return []
        stats = []
        for stat in transmission.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat:
            if not stat.IsInitialized():
                log.warning("skipping incomplete receive statistics: %s", stat)
                continue
            report = self._stats_class(
                modem_tcp_port=self.modem_tcp_port,
                tx_modem_tcp_port=self.port_of(stat.source),
                packet_success=stat.mode == RECEIVE_GOOD,
            )
            report.mm_stats.ParseFromString(stat.SerializeToString())
            stats.append(report)
        return stats
