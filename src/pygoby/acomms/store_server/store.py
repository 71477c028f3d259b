"""The store: every outbox transmission with its source, destination and arrival time, plus
each client's read position, in one SQLite file (so nothing is lost across restarts)."""

from __future__ import annotations

import sqlite3
from pathlib import Path

from pygoby.acomms import messages as acomms_pb

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

    def exchange(self, request, now: float):
        """Store the request's outbox; answer with what the requester has not seen yet.

        That is every stored transmission from another source that arrived after the
        requester's previous request (for a first request: within the maximum look-back)."""
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
            rows = self.db.execute(
                "SELECT id, data FROM transmission WHERE id > ? AND src != ? AND arrival >= ?"
                " ORDER BY id",
                (last_id, request.modem_id, now - self.max_lookback),
            ).fetchall()
            newest = self.db.execute("SELECT COALESCE(MAX(id), 0) FROM transmission").fetchone()[0]
            self.db.execute(
                "INSERT INTO client (modem_id, last_id) VALUES (?, ?) "
                "ON CONFLICT(modem_id) DO UPDATE SET last_id = excluded.last_id",
                (request.modem_id, newest),
            )
        response = acomms_pb.StoreServerResponse(modem_id=request.modem_id)
        if request.HasField("request_id"):
            response.request_id = request.request_id
        for _, data in rows:
            response.inbox.add().ParseFromString(data)
        return response
