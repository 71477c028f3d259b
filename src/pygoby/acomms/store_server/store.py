"""The store: every outbox transmission with its source, destination and arrival time, plus
each client's read position, in one SQLite file (so nothing is lost across restarts).

SQLite errors (a lock held by another process for longer than `lock_timeout_seconds`, a full
disk) come out of `exchange` as sqlite3.Error with nothing stored and nothing consumed: the
server answers the client with an error and the client sends again. `prune` deletes what can
no longer be served (older than the look-back) and what has been delivered (every possible
recipient has read past it) once it is older than the retention time.
"""

from __future__ import annotations

import logging
from pathlib import Path

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.errors import StoreServerAuthError
from pygoby.acomms.rudics import embedded_size
from pygoby.util.sqlite import open_durable

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
CREATE TABLE IF NOT EXISTS auth (
    modem_id INTEGER PRIMARY KEY,
    last_time REAL NOT NULL
);
"""
# delivered: its destination has read past it; a broadcast (dest <= 0): every other client has
_DELIVERED = """(
    (t.dest > 0 AND EXISTS (SELECT 1 FROM client c WHERE c.modem_id = t.dest AND c.last_id >= t.id))
    OR (t.dest <= 0 AND NOT EXISTS
        (SELECT 1 FROM client c WHERE c.modem_id != t.src AND c.last_id < t.id))
)"""


class TransmissionStore:
    def __init__(
        self,
        path: str | Path = ":memory:",
        max_lookback_seconds: float = 3600.0,
        retention_seconds: float = 3600.0,
        lock_timeout_seconds: float = 5.0,
    ) -> None:
        self.db = open_durable(path, lock_timeout_seconds)
        self.db.executescript(_SCHEMA)
        self.max_lookback = max_lookback_seconds
        self.retention = retention_seconds

    def prune(self, now: float) -> int:
        """Delete what nobody will be served again; returns how many transmissions."""
        with self.db:
            cursor = self.db.execute(
                f"DELETE FROM transmission AS t WHERE arrival < ? OR (arrival < ? AND {_DELIVERED})",
                (now - self.max_lookback, now - self.retention),
            )
        return cursor.rowcount

    def close(self) -> None:
        self.db.close()

    def exchange(
        self,
        request: acomms_pb.StoreServerRequest,
        now: float,
        max_response_bytes: int | None = None,
        auth_time: float | None = None,
    ):
        """Store the request's outbox; answer with what the requester has not seen yet.

        That is every stored transmission from another source that arrived after the
        requester's previous request (for a first request: within the maximum look-back), as
        many as fit in `max_response_bytes` of serialized response, oldest first; the rest
        comes with the next request. A single stored transmission too large for any response
        is skipped with a warning (it would otherwise block the requester's mail forever).
        `auth_time`: a signed request's time, which must be later than the last accepted one
        for the modem id (StoreServerAuthError otherwise)."""
        response = acomms_pb.StoreServerResponse(modem_id=request.modem_id)
        if request.HasField("request_id"):
            response.request_id = request.request_id
        budget = None if max_response_bytes is None else max_response_bytes - response.ByteSize()
        inbox: list[bytes] = []
        with self.db:
            if auth_time is not None:
                self._accept_auth_time(request.modem_id, auth_time)
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
                        log.warning(
                            "skipping stored transmission %d: %d bytes cannot fit in a response",
                            row_id,
                            len(data),
                        )
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

    def _accept_auth_time(self, modem_id: int, auth_time: float) -> None:
        row = self.db.execute("SELECT last_time FROM auth WHERE modem_id = ?", (modem_id,))
        last = row.fetchone()
        if last is not None and auth_time <= last[0]:
            raise StoreServerAuthError(
                f"request time {auth_time} is not after the last accepted, {last[0]}"
            )
        self.db.execute(
            "INSERT INTO auth (modem_id, last_time) VALUES (?, ?) "
            "ON CONFLICT(modem_id) DO UPDATE SET last_time = excluded.last_time",
            (modem_id, auth_time),
        )
