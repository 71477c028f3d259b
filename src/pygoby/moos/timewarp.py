"""MOOS time and time warp.

MOOS multiplies the whole epoch by the warp (`MOOSLocalTime() = UNIX time x warp`), so warped time
stamps are about warp x 1.8e9. Every process in a community must use the same warp.
`moos_clock(warp)` returns the Clock the client, DB and apps use for MOOS time; durations the
protocol measures in real time (keep-alive, timeouts) use the event loop's clock.
"""

from __future__ import annotations

import time

from pygoby.util.clock import Clock, WallClock

MAX_TIME_WARP = 400.0


class EpochWarpClock:
    """UNIX time multiplied by `warp`, as MOOS computes it."""

    def __init__(self, warp: float) -> None:
        if not 0 < warp <= MAX_TIME_WARP:
            raise ValueError(f"MOOS time warp must be in (0, {MAX_TIME_WARP:g}], not {warp}")
        self.warp = warp

    def now(self) -> float:
        return time.time() * self.warp


def moos_clock(warp: float = 1.0) -> Clock:
    return WallClock() if warp == 1.0 else EpochWarpClock(warp)


def clock_warp(clock: Clock) -> float:
    """The warp factor of a clock (1 when it has none): real sleeps are divided by it."""
    return float(getattr(clock, "warp", 1.0))
