"""SQLite files that must not lose what they were told: the store server's mailbox and
pAcommsHandler's persistent queue open them the same way."""

from __future__ import annotations

import os
import sqlite3

DEFAULT_LOCK_TIMEOUT = 5.0  # s


def open_durable(
    path: str | os.PathLike[str], lock_timeout: float = DEFAULT_LOCK_TIMEOUT
) -> sqlite3.Connection:
    """A connection whose committed transactions survive a crash of the process (kill -9) and
    of the machine: a rollback journal (journal_mode=DELETE) synchronised to the disk at every
    commit (synchronous=FULL). Write in `with connection:` blocks (one transaction each).
    Waits up to `lock_timeout` s for another connection's lock (then sqlite3.OperationalError)."""
    db = sqlite3.connect(os.fspath(path), timeout=lock_timeout)
    db.execute("PRAGMA journal_mode=DELETE")
    db.execute("PRAGMA synchronous=FULL")
    return db
