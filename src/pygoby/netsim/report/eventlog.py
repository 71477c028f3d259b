"""The simulator's event log: one JSON object per line (tx, rx, position, ...).

Written by `EventLogWriter` (an `on_event` sink for `PhysicsChannel` and the simulation runner),
read back by `read_events` for `pygoby netsim report`. Field meanings are documented where the
events are made (`pygoby.netsim.sim.physics_channel`, `pygoby.netsim.sim.simulation`).
"""

from __future__ import annotations

import json
import logging
from collections.abc import Iterator
from pathlib import Path
from typing import IO

log = logging.getLogger(__name__)


class EventLogWriter:
    """Appends events as JSON lines; usable as a callback (`writer(event)`)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file: IO[str] | None = open(self.path, "w", encoding="utf-8")  # noqa: SIM115
        self.count = 0

    def __call__(self, event: dict) -> None:
        if self._file is None:
            raise ValueError(f"event log {self.path} is closed")
        self._file.write(json.dumps(event, separators=(",", ":")) + "\n")
        self.count += 1

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def __enter__(self) -> EventLogWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def iter_events(path: str | Path) -> Iterator[dict]:
    """The events of a log, in order; lines that are not JSON objects are logged and skipped."""
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            try:
                event = json.loads(line)
            except json.JSONDecodeError as exc:
                log.warning("%s:%d: not JSON (%s); skipped", path, number, exc.msg)
                continue
            if not isinstance(event, dict) or not isinstance(event.get("event"), str):
                log.warning("%s:%d: not an event object; skipped", path, number)
                continue
            yield event


def read_events(path: str | Path) -> list[dict]:
    return list(iter_events(path))
