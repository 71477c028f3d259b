"""One clock abstraction for live runs, deterministic tests and faster-than-real-time simulation.

Everything that needs the time takes a Clock. `WallClock` reads the system clock; `VirtualClock`
only moves when told to (tests, discrete-event simulation).
"""

from __future__ import annotations

import time
from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    def now(self) -> float:
        """Seconds since the UNIX epoch (UTC)."""
        ...


class WallClock:
    """The system clock, optionally warped (MOOS time warp: time runs `warp` times faster)."""

    def __init__(self, warp: float = 1.0) -> None:
        if warp <= 0:
            raise ValueError("time warp must be positive")
        self.warp = warp
        self._start_real = time.time()

    def now(self) -> float:
        if self.warp == 1.0:
            return time.time()
        real = time.time()
        return self._start_real + (real - self._start_real) * self.warp


class VirtualClock:
    """A clock that stands still until advanced."""

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)

    def now(self) -> float:
        return self._now

    def set(self, t: float) -> None:
        if t < self._now:
            raise ValueError(f"virtual time cannot go backwards ({t} < {self._now})")
        self._now = float(t)

    def advance(self, dt: float) -> None:
        self.set(self._now + dt)
