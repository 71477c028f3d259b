"""Progress of a long run, for the operator: a rich progress bar on a terminal, else a plain line
at every tenth of the run once it has lasted a few seconds (logs and CI stay short). Used by
`pygoby netsim run` (simulated seconds) and `pygoby netsim sweep` (runs).

    with RunProgress("simulated", total=7200.0, unit="s") as progress:
        ...
        progress.update(done, messages=42)     # extra counts, shown as `messages 42`
    with RunProgress("runs", unit="runs") as progress:
        progress.update(done, total=total)     # the total may come with the first update

`update` is cheap enough to call often (it redraws at most every `REDRAW` seconds). The speed
counts from the first update (work already done before, e.g. a resumed sweep, does not count):
`720x real time` for simulated seconds, else `0.50 runs/s`; the ETA follows from it.
"""

from __future__ import annotations

import sys
import time
from typing import IO, Any

from pygoby.util.extras import needs_extra

REDRAW = 0.25  # wall seconds between redraws
PLAIN_AFTER = 3.0  # wall seconds before a run that is not on a terminal prints progress lines


class RunProgress:
    def __init__(
        self, label: str, total: float = 0.0, unit: str = "", stream: IO[str] | None = None
    ) -> None:
        self.label, self.total, self.unit = label, total, unit
        self.stream = stream if stream is not None else sys.stderr
        self._bar: Any = None
        self._task: Any = None
        self._started = time.monotonic()
        self._first: tuple[float, float] | None = None  # (time, done) at the first update
        self._last_draw = 0.0
        self._printed_tenth = -1

    def __enter__(self) -> RunProgress:
        self._started = time.monotonic()
        if self.stream.isatty():
            with needs_extra("sim", "progress bars"):  # imported only for a terminal
                from rich.console import Console
                from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

            self._bar = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                TextColumn("{task.completed:,.0f}/{task.total:,.0f} " + self.unit),
                TextColumn("{task.fields[extra]}"),
                TimeRemainingColumn(),
                console=Console(file=self.stream),
                transient=True,
            )
            self._bar.start()
            self._task = self._bar.add_task(self.label, total=self.total or None, extra="")
        return self

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.stop()

    def describe(self, done: float, **counts: float) -> str:
        """`messages 42, 3,400x real time, ETA 2 s`: the counts, the speed, the time left."""
        parts = [f"{name} {value:,.0f}" for name, value in counts.items()]
        since, first = self._first if self._first is not None else (self._started, 0.0)
        elapsed = time.monotonic() - since
        speed = (done - first) / elapsed if elapsed > 0 else 0.0
        parts.append(
            f"{speed:,.0f}x real time" if self.unit == "s" else f"{speed:,.2f} {self.unit}/s"
        )
        if speed > 0 and 0 < done < self.total:
            parts.append(f"ETA {(self.total - done) / speed:,.0f} s")
        return ", ".join(parts)

    def update(self, done: float, total: float | None = None, **counts: float) -> None:
        if total is not None:
            self.total = total
        now = time.monotonic()
        if self._first is None:
            self._first = (now, done)
        if now - self._last_draw < REDRAW and done < self.total:
            return
        self._last_draw = now
        if self._bar is not None:
            self._bar.update(
                self._task,
                completed=done,
                total=self.total or None,
                extra=self.describe(done, **counts),
            )
            return
        tenth = int(10 * done / self.total) if self.total > 0 else 10
        if tenth == self._printed_tenth or now - self._started < PLAIN_AFTER:
            return
        self._printed_tenth = tenth
        print(
            f"{self.label} {done:,.0f}/{self.total:,.0f} {self.unit} ({tenth * 10}%): "
            f"{self.describe(done, **counts)}",
            file=self.stream,
            flush=True,
        )
