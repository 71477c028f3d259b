"""Time intervals, half-duplex and ranging arithmetic."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Interval:
    start: float
    end: float

    def overlaps(self, other: Interval) -> bool:
        """Touching ends do not overlap."""
        return other.start < self.end and other.end > self.start


def reception_interval(t_start: float, owtt: float, duration: float) -> Interval:
    return Interval(t_start + owtt, t_start + owtt + duration)


def lost_to_half_duplex(reception: Interval, own_transmissions: list[Interval]) -> bool:
    """A modem cannot receive while it transmits (and a transmission aborts a reception)."""
    return any(reception.overlaps(tx) for tx in own_transmissions)


def two_way_round_trip(owtt_out: float, owtt_back: float, turnaround: float) -> float:
    return owtt_out + turnaround + owtt_back


def two_way_reported_owtt(round_trip: float, turnaround: float) -> float:
    """What the originating modem reports ($CAMPR): (round trip - turnaround) / 2."""
    return (round_trip - turnaround) / 2


def synchronous_owtt(arrival_time: float) -> float:
    """One-way ranging with PPS-synchronised clocks and transmissions on whole seconds: only
    the fraction of a second is known (ambiguous by whole seconds)."""
    return arrival_time - math.floor(arrival_time)
