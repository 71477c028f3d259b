"""The persistent queue (a pygoby addition): every queued message also kept in one SQLite file,
so that what was queued survives a restart of the process, kill -9 included.

    queue_cfg { persistent_queue_file: "pAcommsHandler_queue.sqlite" }   # pAcommsHandler

    store = QueueStore("queue.sqlite")          # sans MOOS
    restored = queue_manager.attach_store(store)

A message is recorded when it is queued and deleted when the queue lets go of it: sent (no ack
requested), acknowledged, expired, pushed out by `max_queue` or flushed. Each change is one
transaction of a durable SQLite file (pygoby.util.sqlite.open_durable, as the store server), so
after a crash the file holds exactly the messages that were still queued. On start the
messages are queued again, oldest first, with their original time: an expired one expires at
once (ACOMMS_EXPIRE), one that was sent and awaited its ack is sent again (until acked).

The file is locked for as long as it is open: a second process naming the same file is refused.
"""

from __future__ import annotations

import logging
import os
import sqlite3
from dataclasses import dataclass

from pygoby.acomms.errors import QueueError
from pygoby.acomms.queue.queue import MessageQueue, QueuedItem
from pygoby.util.sqlite import DEFAULT_LOCK_TIMEOUT, open_durable

log = logging.getLogger(__name__)

SCHEMA_VERSION = 1
_SCHEMA = """
CREATE TABLE IF NOT EXISTS queued (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    queue TEXT NOT NULL,          -- the queue's name (the DCCL type; CCL:<name> for CCL queues)
    message BLOB NOT NULL,        -- the message, protobuf-serialized
    encoded BLOB NOT NULL,        -- the bytes sent for it (DCCL, or the CCL frame)
    src INTEGER NOT NULL,
    dest INTEGER NOT NULL,
    time INTEGER NOT NULL,        -- microseconds since the epoch (its TIMESTAMP, else queuing time)
    ack_requested INTEGER NOT NULL
);
"""


@dataclass(frozen=True, slots=True)
class StoredItem:
    key: int
    queue: str
    message: bytes
    encoded: bytes
    src: int
    dest: int
    time: int
    ack_requested: bool


class QueueStore:
    """The SQLite file of a persistent queue (a `QueueJournal` for every queue of a manager).

    QueueError when the file cannot be opened, is not a queue file or is in use by another
    process. A failure to write later (a full disk) is logged as an error and the queue goes
    on in memory: the message is still sent, it is only not durable."""

    def __init__(
        self, path: str | os.PathLike[str], lock_timeout: float = DEFAULT_LOCK_TIMEOUT
    ) -> None:
        self.path = os.fspath(path)
        db = None
        try:
            db = open_durable(self.path, lock_timeout)
            # held until closed: one process per file (a second one gets "database is locked")
            db.execute("PRAGMA locking_mode=EXCLUSIVE")
            with db:
                db.execute("BEGIN EXCLUSIVE")
                version = db.execute("PRAGMA user_version").fetchone()[0]
                if version not in (0, SCHEMA_VERSION):
                    raise QueueError(
                        f"persistent queue {self.path}: schema version {version}, "
                        f"this pygoby reads {SCHEMA_VERSION}"
                    )
                db.execute(_SCHEMA)
                db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
                # a damaged page would otherwise surface later, in the middle of a read
                problems = [
                    line
                    for (text,) in db.execute("PRAGMA quick_check(3)")
                    for line in text.splitlines()
                    if line != "ok" and not line.startswith("*** in database")
                ]
                if problems:
                    more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
                    raise sqlite3.DatabaseError(problems[0] + more)
        except (sqlite3.Error, QueueError) as exc:
            if db is not None:
                db.close()
            if isinstance(exc, QueueError):
                raise
            if "locked" in str(exc):
                why = "in use by another process"
            else:
                why = (
                    f"{exc}: the file is damaged or not a queue file; move it aside to start "
                    "with an empty queue (the messages in it are lost)"
                )
            raise QueueError(f"persistent queue {self.path}: {why}") from None
        self.db = db

    def close(self) -> None:
        self.db.close()

    def items(self) -> list[StoredItem]:
        """Everything stored, oldest first."""
        rows = self.db.execute(
            "SELECT id, queue, message, encoded, src, dest, time, ack_requested FROM queued ORDER BY id"
        ).fetchall()
        return [
            StoredItem(key, queue, message, encoded, src, dest, time, bool(ack))
            for key, queue, message, encoded, src, dest, time, ack in rows
        ]

    def forget(self, key: int) -> None:
        self._write("DELETE FROM queued WHERE id = ?", (key,))

    # QueueJournal ------------------------------------------------------------------------------

    def added(self, queue: MessageQueue, item: QueuedItem) -> None:
        cursor = self._write(
            "INSERT INTO queued (queue, message, encoded, src, dest, time, ack_requested)"
            " VALUES (?, ?, ?, ?, ?, ?, ?)",
            (
                queue.name,
                item.msg.SerializeToString(),
                item.encoded,
                item.src,
                item.dest,
                item.time,
                int(item.ack_requested),
            ),
        )
        if cursor is not None:
            item.key = cursor.lastrowid

    def removed(self, queue: MessageQueue, item: QueuedItem) -> None:
        if item.key is not None:
            self.forget(item.key)

    def cleared(self, queue: MessageQueue) -> None:
        self._write("DELETE FROM queued WHERE queue = ?", (queue.name,))

    def _write(self, sql: str, args: tuple) -> sqlite3.Cursor | None:
        try:
            with self.db:
                return self.db.execute(sql, args)
        except sqlite3.Error as exc:
            log.error(
                "persistent queue %s: cannot record a change (%s); the queue goes on in "
                "memory only for it",
                self.path,
                exc,
            )
            return None
