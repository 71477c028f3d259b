"""UTM on WGS84 relative to a local origin, as goby3's UTMGeodesy does it (through PROJ).

The zone comes from the origin longitude only (no Norway/Svalbard exceptions, no +south), so
southern northings are simply negative offsets from the origin.
"""

from __future__ import annotations

import math

from pyproj import Transformer


def utm_zone(lon: float) -> int:
    return math.floor((lon + 180.0) / 6.0) % 60 + 1


class UTMGeodesy:
    """Local (x, y) metres east/north of (lat0, lon0) <-> (lat, lon) degrees."""

    def __init__(self, lat_origin: float, lon_origin: float) -> None:
        self.lat_origin = lat_origin
        self.lon_origin = lon_origin
        self.zone = utm_zone(lon_origin)
        self._transformer = Transformer.from_crs(
            "+proj=latlong +ellps=WGS84",
            f"+proj=utm +ellps=WGS84 +zone={self.zone}",
            always_xy=True,
        )
        self.easting0, self.northing0 = self._transformer.transform(lon_origin, lat_origin)

    def to_local(self, lat: float, lon: float) -> tuple[float, float]:
        """(x, y) of a point; NaN if either input is NaN or out of range."""
        if not (math.isfinite(lat) and math.isfinite(lon)):
            return math.nan, math.nan
        easting, northing = self._transformer.transform(lon, lat)
        if not (math.isfinite(easting) and math.isfinite(northing)):
            return math.nan, math.nan
        return easting - self.easting0, northing - self.northing0

    def to_geo(self, x: float, y: float) -> tuple[float, float]:
        """(lat, lon) of a local point; NaN if either input is NaN."""
        if not (math.isfinite(x) and math.isfinite(y)):
            return math.nan, math.nan
        lon, lat = self._transformer.transform(
            x + self.easting0, y + self.northing0, direction="INVERSE"
        )
        if not (math.isfinite(lat) and math.isfinite(lon)):
            return math.nan, math.nan
        return lat, lon
