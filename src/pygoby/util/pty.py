"""Pseudo-terminals with stable names: virtual serial lines for emulated modems.

* `PtyPair(path_a, path_b)`: two pseudo-terminals joined back to back (what
  `socat pty,raw,echo=0,link=/tmp/ttyLOOPA1 pty,raw,echo=0,link=/tmp/ttyLOOPA2` makes, and what
  Goby 1.1's missions expect): bytes written to one path are read from the other. The relay
  runs in the asyncio loop of the process that made the pair.
* `PtyEnd(path)`: one pseudo-terminal whose slave device is linked at `path`; the owner reads
  and writes the master directly (e.g. an emulated modem).

The links are symbolic links to /dev/pts/N. A lock file beside them (`.<name>.lock`), held for
the owner's life, tells a live pair from links left by a process that died: `claim` replaces
stale links and refuses live ones. `partner_of("/tmp/ttyLOOPA1")` is "/tmp/ttyLOOPA2" (and back).
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import fcntl
import logging
import os
import tty
from pathlib import Path

from pygoby.util.errors import PtyError

log = logging.getLogger(__name__)

READ_SIZE = 4096


def partner_of(path: str | os.PathLike[str]) -> Path | None:
    """The other end of a Goby 1.1 loopback name: `...1` <-> `...2`; None for other names."""
    p = Path(path)
    if p.name.endswith("1"):
        return p.with_name(p.name[:-1] + "2")
    if p.name.endswith("2"):
        return p.with_name(p.name[:-1] + "1")
    return None


def _lock_path(paths: list[Path]) -> Path:
    names = "+".join(sorted(p.name for p in paths))
    return paths[0].parent / f".{names}.lock"


class _Claim:
    """An exclusive lock on a set of link names, held until `release`."""

    def __init__(self, paths: list[Path]) -> None:
        self.paths = paths
        self.lock_path = _lock_path(paths)
        self._fd: int | None = None

    def acquire(self) -> None:
        fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(fd)
            if err.errno in (errno.EWOULDBLOCK, errno.EACCES):
                raise PtyError(
                    err.errno, f"{', '.join(map(str, self.paths))} belong to a running process"
                ) from None
            raise
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd

    def release(self) -> None:
        if self._fd is not None:
            with contextlib.suppress(OSError):
                self.lock_path.unlink()
            os.close(self._fd)
            self._fd = None


def is_live(path: str | os.PathLike[str]) -> bool:
    """Whether `path` is a link made by a running PtyPair/PtyEnd (or any existing device that
    is not one of our links)."""
    p = Path(path)
    if not p.is_symlink():
        return p.exists()
    partner = partner_of(p)
    candidates = [[p, partner]] if partner is not None else []
    candidates.append([p])
    for paths in candidates:
        lock = _lock_path(paths)
        if not lock.exists():
            continue
        try:
            fd = os.open(lock, os.O_RDWR)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return True  # held: the owner runs
        finally:
            os.close(fd)
    return False


def _replace_link(link: Path, target: str) -> None:
    if link.is_symlink() or link.exists():
        if not link.is_symlink():
            raise PtyError(errno.EEXIST, f"{link} exists and is not a link; not replacing it")
        log.info("removing stale link %s -> %s", link, os.readlink(link))
        link.unlink()
    link.symlink_to(target)


def _open_pty() -> tuple[int, int, str]:
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    os.set_blocking(master, False)
    return master, slave, os.ttyname(slave)


class PtyEnd:
    """One pty, its slave linked at `path`. Keep using `master` (non-blocking, raw)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.master = -1
        self._slave = -1  # kept open: the master never sees a hang-up between clients
        self._claim = _Claim([self.path])

    def open(self) -> PtyEnd:
        self._claim.acquire()
        try:
            self.master, self._slave, device = _open_pty()
            _replace_link(self.path, device)
        except BaseException:
            self.close()
            raise
        return self

    def close(self) -> None:
        if self.master >= 0:
            with contextlib.suppress(OSError):
                if self.path.is_symlink():
                    self.path.unlink()
            for fd in (self.master, self._slave):
                with contextlib.suppress(OSError):
                    os.close(fd)
            self.master = self._slave = -1
        self._claim.release()


class PtyPair:
    """Two ptys relayed back to back, linked at `path_a` and `path_b`, inside the running
    asyncio loop (`await pair.start()` ... `pair.close()`)."""

    def __init__(self, path_a: str | os.PathLike[str], path_b: str | os.PathLike[str]) -> None:
        self.paths = (Path(path_a), Path(path_b))
        self._claim = _Claim(list(self.paths))
        self._fds: list[tuple[int, int]] = []  # (master, slave) per end
        self._attached = False
        self.dropped = 0  # bytes dropped because nobody read the other end

    def open(self) -> PtyPair:
        """Make the ptys and the links (PtyError if a running process owns them)."""
        self._claim.acquire()
        try:
            for path in self.paths:
                master, slave, device = _open_pty()
                self._fds.append((master, slave))
                _replace_link(path, device)
        except BaseException:
            self.close()
            raise
        return self

    def attach(self) -> None:
        """Start relaying in the running asyncio loop."""
        loop = asyncio.get_running_loop()
        (a, _), (b, _) = self._fds
        loop.add_reader(a, self._relay, a, b)
        loop.add_reader(b, self._relay, b, a)
        self._attached = True

    def start(self) -> PtyPair:
        """open() and attach()."""
        self.open()
        self.attach()
        return self

    def _relay(self, source: int, sink: int) -> None:
        try:
            data = os.read(source, READ_SIZE)
        except OSError:
            return
        try:
            written = os.write(sink, data)
        except BlockingIOError:
            written = 0
        except OSError:
            return
        self.dropped += len(data) - written  # the reader is away and its buffer is full

    def close(self) -> None:
        if self._attached:
            with contextlib.suppress(RuntimeError):
                loop = asyncio.get_running_loop()
                for master, _ in self._fds:
                    loop.remove_reader(master)
            self._attached = False
        for path in self.paths:
            with contextlib.suppress(OSError):
                if path.is_symlink() and self._fds:
                    path.unlink()
        for master, slave in self._fds:
            for fd in (master, slave):
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._fds = []
        self._claim.release()


def open_serial(path: str | os.PathLike[str]) -> int:
    """A tty device (or a link to one) opened raw and non-blocking, for reading and writing."""
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    try:
        tty.setraw(fd)
    except OSError:
        os.close(fd)
        raise
    return fd
