"""The `<NAME>_STATUS` line a MOOS application posts every couple of seconds, in CMOOSApp's
form (MOOSApp.cpp's status string): uptime, CPU load, memory, what it publishes and
subscribes to."""

from __future__ import annotations

import math
import resource
import time
from collections.abc import Iterable

STATUS_PERIOD = 2.0  # s of the app's clock between two status posts


class StatusReport:
    """Makes the status line when it is due; CPU load is measured between two lines."""

    def __init__(self, period: float = STATUS_PERIOD) -> None:
        self.period = period
        self._last = -math.inf
        self._last_cpu = (time.process_time(), time.monotonic())

    def due(self, now: float) -> bool:
        if now - self._last < self.period:
            return False
        self._last = now
        return True

    def cpu_load(self) -> float:
        """Percent of one CPU this process used since the previous call."""
        cpu_now, wall_now = time.process_time(), time.monotonic()
        cpu = 100.0 * (cpu_now - self._last_cpu[0]) / max(wall_now - self._last_cpu[1], 1e-6)
        self._last_cpu = (cpu_now, wall_now)
        return cpu

    def line(
        self, name: str, uptime: float, published: Iterable[str], subscribed: Iterable[str]
    ) -> str:
        usage = resource.getrusage(resource.RUSAGE_SELF)
        publishing = "".join(f"{v}," for v in sorted(published))
        subscribing = "".join(f"{v}," for v in sorted(subscribed))
        return (
            f"AppErrorFlag=false,Uptime={uptime:g},cpuload={self.cpu_load():.4g},"
            f"memory_kb={usage.ru_maxrss},memory_max_kb={usage.ru_maxrss:.4g},"
            f'MOOSName={name},Publishing="{publishing}",Subscribing="{subscribing}"'
        )
