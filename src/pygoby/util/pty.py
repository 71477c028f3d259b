"""Pseudo-terminals with stable names: virtual serial lines for emulated modems.

`PtyEnd(path)`: a pseudo-terminal whose slave device is linked at `path` (e.g.
`/tmp/ttyLOOPA1`, what a mission's `serial_port` names); the owner reads and writes `master`
(raw, non-blocking). A lock file beside the link (`.<name>.lock`), held while the end is open,
tells a live link from one left behind by a process that died: `open` replaces a stale link
and refuses one a running process owns (PtyError).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import tty
from pathlib import Path


class PtyError(OSError):
    """The link cannot be made (a running process owns it, or the path is not a link)."""


class PtyEnd:
    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.master = -1
        self._slave = -1  # kept open: the master never sees a hang-up between clients
        self._lock = -1

    def open(self) -> PtyEnd:
        lock_path = self.path.with_name(f".{self.path.name}.lock")
        lock = os.open(lock_path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(lock)
            if exc.errno in (errno.EWOULDBLOCK, errno.EACCES):
                raise PtyError(exc.errno, f"{self.path} belongs to a running process") from None
            raise
        self._lock = lock
        try:
            self.master, self._slave = os.openpty()
            for fd in (self.master, self._slave):
                tty.setraw(fd)
            os.set_blocking(self.master, False)
            if self.path.is_symlink():
                self.path.unlink()  # (stale: its owner's lock was free)
            elif self.path.exists():
                raise PtyError(errno.EEXIST, f"{self.path} exists and is not a link")
            self.path.symlink_to(os.ttyname(self._slave))
        except BaseException:
            self.close()
            raise
        return self

    def close(self) -> None:
        if self.master >= 0:
            with contextlib.suppress(OSError):
                if self.path.is_symlink() and os.readlink(self.path) == os.ttyname(self._slave):
                    self.path.unlink()
        for fd in (self.master, self._slave):
            if fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self.master = self._slave = -1
        if self._lock >= 0:
            with contextlib.suppress(OSError):
                self.path.with_name(f".{self.path.name}.lock").unlink()
            os.close(self._lock)
            self._lock = -1
