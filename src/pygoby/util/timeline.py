"""Things due at given times on one Clock: a sans-I/O scheduler.

Components that act later (an emulated modem ending a transmission, a channel delivering a
packet) put callbacks on a `Timeline`; whoever runs them calls `run_due()` — an asyncio loop
regularly, a discrete-event simulation at `next_time()` after moving its virtual clock there.
Callbacks due at the same time run in the order they were scheduled; a callback may schedule
more (those due already run in the same `run_due`).
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable

from pygoby.util.clock import Clock


class Timeline:
    def __init__(self, clock: Clock) -> None:
        self.clock = clock
        self._due: list[tuple[float, int, Callable[..., object], tuple]] = []
        self._order = itertools.count()

    def at(self, when: float, callback: Callable[..., object], *args: object) -> None:
        """Run `callback(*args)` once the clock reaches `when` (at once if it has)."""
        heapq.heappush(self._due, (when, next(self._order), callback, args))

    def next_time(self) -> float | None:
        return self._due[0][0] if self._due else None

    def run_due(self) -> None:
        due = self._due
        while due and due[0][0] <= self.clock.now():
            _, _, callback, args = heapq.heappop(due)
            callback(*args)

    def __len__(self) -> int:
        return len(self._due)
