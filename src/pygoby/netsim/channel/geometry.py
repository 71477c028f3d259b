"""Positions, ranges and travel times.

Positions are geographic (lat/lon degrees, depth metres positive down); horizontal ranges are
WGS-84 geodesics (pyproj). Between position reports a node is dead-reckoned with its speed and
heading (degrees true, clockwise from north).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

from pyproj import Geod

from pygoby.protobuf.netsim.messages.netsim_pb2 import NavUpdate

WGS84 = Geod(ellps="WGS84")


@dataclass(frozen=True)
class NavFix:
    """A node's reported state at time `time` (UNIX seconds)."""

    lat: float
    lon: float
    depth: float
    time: float = 0.0
    speed: float = 0.0  # m/s over ground
    heading: float = 0.0  # degrees true

    @classmethod
    def from_nav(cls, nav: NavUpdate) -> NavFix:
        """From a netsim NavUpdate."""
        return cls(nav.lat, nav.lon, nav.depth, nav.time, nav.speed, nav.heading)

    def at(self, t: float) -> NavFix:
        """Dead-reckoned to time t (straight line along the heading, on the ellipsoid)."""
        # (direct constructor calls: dataclasses.replace is several times slower)
        distance = self.speed * (t - self.time)
        if distance == 0:
            if t == self.time:
                return self  # frozen: the same position
            return NavFix(self.lat, self.lon, self.depth, t, self.speed, self.heading)
        lon, lat, _ = WGS84.fwd(self.lon, self.lat, self.heading, distance)
        return NavFix(lat, lon, self.depth, t, self.speed, self.heading)


def dead_reckoning_offset(speed: float, heading_deg: float, dt: float) -> tuple[float, float]:
    """(east, north) displacement in metres after dt seconds."""
    angle = math.radians(90.0 - heading_deg)
    return speed * dt * math.cos(angle), speed * dt * math.sin(angle)


def horizontal_range(a: NavFix, b: NavFix) -> tuple[float, float]:
    """(distance m, azimuth deg from a to b) along the WGS-84 geodesic."""
    if 0.0 in (a.lon, a.lat, b.lon, b.lat):  # (-0.0 would share a memo key with 0.0)
        azimuth, _, distance = WGS84.inv(a.lon, a.lat, b.lon, b.lat)
        return distance, azimuth
    return _geodesic(a.lon, a.lat, b.lon, b.lat)


# Fixed nodes ask for the same geodesics again and again (a 100-node network: 9,900 links).
@functools.lru_cache(maxsize=1 << 16)
def _geodesic(lon_a: float, lat_a: float, lon_b: float, lat_b: float) -> tuple[float, float]:
    azimuth, _, distance = WGS84.inv(lon_a, lat_a, lon_b, lat_b)
    return distance, azimuth


def slant_range(a: NavFix, b: NavFix) -> float:
    distance, _ = horizontal_range(a, b)
    return math.hypot(distance, a.depth - b.depth)


def owtt(range_m: float, sound_speed: float) -> float:
    """One-way travel time, seconds."""
    return range_m / sound_speed


def arrival_delay(
    range_at: Callable[[float], float],
    sound_speed: float,
    iterations: int = 4,
) -> float:
    """Travel time to a moving receiver: solve r(tau) = c * tau by fixed-point iteration.

    `range_at(tau)` is the range from the transmitter (at transmit time) to the receiver tau
    seconds after transmission; the static value r(0)/c is the starting guess.
    """
    tau = range_at(0.0) / sound_speed
    for _ in range(iterations):
        tau = range_at(tau) / sound_speed
    return tau


def closing_speed(tx: NavFix, rx: NavFix) -> float:
    """Rate (m/s) at which the range between two dead-reckoned nodes shrinks (positive closing)."""
    if tx.speed == 0 and rx.speed == 0:
        return 0.0  # what the ranges below give for two fixed nodes, without four geodesics
    dt = 1.0
    return slant_range(tx, rx) - slant_range(tx.at(tx.time + dt), rx.at(rx.time + dt))


def doppler_frequency(f_tx: float, v_closing: float, sound_speed: float) -> float:
    return f_tx * (1 + v_closing / sound_speed)
