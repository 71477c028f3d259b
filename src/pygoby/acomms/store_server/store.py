"""The store: every outbox transmission with its source, destination and arrival time, plus
each client's read position, in one SQLite file (so nothing is lost across restarts)."""

from __future__ import annotations

import logging
import sqlite3
from pathlib import Path

from pygoby.acomms import messages as m
from pygoby.acomms.rudics import embedded_size

log = logging.getLogger(__name__)

_SCHEMA = """
CREATE TABLE IF NOT EXISTS transmission (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    src INTEGER NOT NULL,
    dest INTEGER NOT NULL,
    arrival REAL NOT NULL,
    data BLOB NOT NULL
);
CREATE TABLE IF NOT EXISTS client (
    modem_id INTEGER PRIMARY KEY,
    last_id INTEGER NOT NULL
);
"""


class TransmissionStore:
    def __init__(self, path: str | Path = ":memory:", max_lookback_seconds: float = 3600.0):
        self.db = sqlite3.connect(str(path))
        self.db.executescript(_SCHEMA)
        self.max_lookback = max_lookback_seconds

    def close(self) -> None:
        self.db.close()

    def exchange(self, request, now: float, max_response_bytes: int | None = None):
        """Store the request's outbox; answer with what the requester has not seen yet.

        That is every stored transmission from another source that arrived after the
        requester's previous request (for a first request: within the maximum look-back), as
        many as fit in `max_response_bytes` of serialized response, oldest first; the rest
        comes with the next request. A single stored transmission too large for any response
        is skipped with a warning (it would otherwise block the requester's mail forever)."""
        response = m.StoreServerResponse(modem_id=request.modem_id)
        if request.HasField("request_id"):
            response.request_id = request.request_id
        budget = None if max_response_bytes is None else max_response_bytes - response.ByteSize()
        inbox: list[bytes] = []
        with self.db:
            for t in request.outbox:
                self.db.execute(
                    "INSERT INTO transmission (src, dest, arrival, data) VALUES (?, ?, ?, ?)",
                    (t.src, t.dest, now, t.SerializeToString()),
                )
            row = self.db.execute(
                "SELECT last_id FROM client WHERE modem_id = ?", (request.modem_id,)
            ).fetchone()
            last_id = row[0] if row else 0
            newest = self.db.execute("SELECT COALESCE(MAX(id), 0) FROM transmission").fetchone()[0]
            rows = self.db.execute(
                "SELECT id, data FROM transmission WHERE id > ? AND src != ? AND arrival >= ?"
                " ORDER BY id",
                (last_id, request.modem_id, now - self.max_lookback),
            )
            for row_id, data in rows:  # read only as far as the response budget goes
                if budget is not None:
                    size = embedded_size(len(data))
                    if size > budget:
                        if inbox:
                            newest = row_id - 1  # the next response starts here
                            break
                        log.warning("skipping stored transmission %d: %d bytes cannot fit in "
                                    "a response", row_id, len(data))  # fmt: skip
                        continue
                    budget -= size
                inbox.append(data)
            self.db.execute(
                "INSERT INTO client (modem_id, last_id) VALUES (?, ?) "
                "ON CONFLICT(modem_id) DO UPDATE SET last_id = excluded.last_id",
                (request.modem_id, newest),
            )
        for data in inbox:
            response.inbox.add().ParseFromString(data)
        return response

