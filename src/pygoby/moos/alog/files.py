"""Reading and writing .alog files (the I/O around pygoby.moos.alog.format).

* `AlogFile(path)`: iterate its entries (plain or `.gz`), binary values fetched from the
  `.blog` beside it; damaged lines are skipped and counted (`reader.bad_lines`). `scan(start)`
  gives each entry's byte offset too, and starts at one of them (liaison's log index).
* `AlogSink`: the writer pLogger uses: the app thread hands it lines and never waits on the
  disk; a thread writes them, flushes at least twice a second, starts a new file past
  `max_bytes`, and counts the lines it had to drop when its bounded buffer was full.
"""

from __future__ import annotations

import gzip
import logging
import os
import shutil
import threading
import zlib
from collections.abc import Callable, Generator, Iterator
from pathlib import Path
from typing import IO

from pygoby.moos.alog.format import AlogEntry, AlogReader, binary_tag, decode_line

log = logging.getLogger(__name__)

FLUSH_PERIOD = 0.5  # s: a kill -9 loses at most about this much
DEFAULT_MAX_PENDING = 200_000  # lines waiting for the disk before new ones are dropped
HEADER_LINES = 10  # the banner is within a file's first lines
MAX_LINE_BYTES = 16 << 20  # longer lines are damage (a file without newlines must not fill memory)
# what ends reading a file early: a truncated or garbled .gz (a logger killed mid-write), a disk
READ_ERRORS = (OSError, EOFError, zlib.error)


def open_text_or_gz(path: str | os.PathLike[str]) -> IO[bytes]:
    path = Path(path)
    if path.suffix == ".gz":
        return gzip.open(path, "rb")  # type: ignore[return-value]
    return open(path, "rb")


class AlogFile:
    """The entries of one .alog (`.alog.gz` too), streamed: memory does not grow with its size."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.reader = AlogReader()
        self.blogs = BlogFiles(self.path.parent)

    @property
    def log_start(self) -> float:
        """The banner's LOGSTART (UNIX time; 0 when the file has none)."""
        if self.reader.log_start is None and self.reader.lines == 0:
            header = AlogReader()
            try:
                with open_text_or_gz(self.path) as stream:
                    for raw, _ in zip(stream, range(HEADER_LINES), strict=False):
                        header.feed(decode_line(raw))
            except READ_ERRORS:
                pass
            return header.log_start or 0.0
        return self.reader.log_start or 0.0

    def __iter__(self) -> Iterator[AlogEntry]:
        for _, _, entry in self._read():
            if entry is not None:
                yield entry

    def lines(self) -> Iterator[tuple[str, AlogEntry | None]]:
        """Every line (without its newline) with its entry, or None for a `%%` line, a
        continuation of a multi-line value or damage; over-long lines are only counted."""
        for _, text, entry in self._read():
            yield text, entry

    def scan(self, start: int = 0) -> Generator[tuple[int, AlogEntry], None, None]:
        """(byte offset of its line, entry) for each entry from the line that starts at byte
        `start` (0, or an offset this method gave). The banner is read first whatever `start`,
        so that its data-type and binary markings apply. In a `.gz`, getting to `start` means
        decompressing what lies before it."""
        for offset, _, entry in self._read(start):
            if entry is not None:
                yield offset, entry

    def _read(self, start: int = 0) -> Iterator[tuple[int, str, AlogEntry | None]]:
        """(byte offset, text, entry or None) of each line from byte `start`."""
        self.reader = AlogReader()  # each pass counts afresh
        self.blogs = BlogFiles(self.path.parent)
        try:
            with open_text_or_gz(self.path) as stream:
                offset = 0
                if start > 0:
                    for _ in range(HEADER_LINES):
                        raw = stream.readline(MAX_LINE_BYTES)
                        if raw.startswith(b"%%"):
                            self.reader.feed(decode_line(raw))
                    stream.seek(start)
                    offset = start
                while raw := stream.readline(MAX_LINE_BYTES):
                    line_offset, offset = offset, offset + len(raw)
                    if len(raw) == MAX_LINE_BYTES and not raw.endswith(b"\n"):
                        while (rest := stream.readline(MAX_LINE_BYTES)) and rest[-1:] != b"\n":
                            offset += len(rest)
                        offset += len(rest)
                        self.reader.skip_line()
                        continue
                    text = decode_line(raw).rstrip("\r\n")
                    yield line_offset, text, self.blogs.feed(self.reader, text)
        except READ_ERRORS as err:
            # a truncated .gz (a logger killed mid-write) ends the log where it breaks
            log.warning("%s: stopped reading: %s", self.path, err)
        finally:
            self.blogs.close()

    @property
    def unresolved_binary(self) -> int:
        return self.blogs.unresolved


class BlogFiles:
    """The .blog files beside an .alog, opened when an entry first names one: `resolve(entry)`
    replaces a `<MOOS_BINARY>` reference by the bytes it points at (counted in `unresolved`
    when the file or the bytes are missing)."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        self.unresolved = 0
        self._open: dict[str, IO[bytes] | None] = {}

    def feed(self, reader: AlogReader, line: str) -> AlogEntry | None:
        """`reader.feed(line)`, a binary value's bytes fetched from its .blog."""
        entry = reader.feed(line)
        if entry is not None and entry.binary_ref is not None:
            self.resolve(entry)
        return entry

    def resolve(self, entry: AlogEntry) -> None:
        assert entry.binary_ref is not None
        name, offset, size = entry.binary_ref
        if name not in self._open:
            try:
                self._open[name] = open(self.directory / Path(name).name, "rb")  # noqa: SIM115
            except OSError:
                self._open[name] = None
        blog = self._open[name]
        data = b""
        if blog is not None:
            blog.seek(offset)
            data = blog.read(size)
        if len(data) == size:
            entry.value = data
            entry.binary_ref = None
        else:
            self.unresolved += 1

    def close(self) -> None:
        for blog in self._open.values():
            if blog is not None:
                blog.close()
        self._open.clear()


class AlogSink:
    """Writes an .alog (and its .blog for binary values) from a background thread.

    `put_line(text)` queues a formatted line; `put_binary(prefix, data)` a binary value (its
    .alog line names the .blog offset, known only when written). Both return False and count
    the line in `dropped` when `max_pending` lines are already waiting. Past `max_bytes`, the
    .alog is closed and `<root>_<n>.alog` started with the same banner and LOGSTART.
    """

    def __init__(
        self,
        directory: Path,
        root: str,
        banner_of: Callable[[str], str],
        *,
        compress: bool = False,
        max_bytes: int = 0,
        max_pending: int = DEFAULT_MAX_PENDING,
    ) -> None:
        self.directory = directory
        self.root = root
        self._banner_of = banner_of  # file name -> banner text
        self.compress = compress
        self.max_bytes = max_bytes
        self.max_pending = max_pending
        self.dropped = 0
        self.written = 0
        self.files: list[Path] = []
        self._pending: list[str | tuple[str, bytes]] = []
        self._cond = threading.Condition()
        self._closing = False
        self._error: OSError | None = None
        self._alog: IO[bytes] | None = None
        self._alog_bytes = 0
        self._blog: IO[bytes] | None = None
        self.blog_name = f"{root}.blog"
        self._open_alog()
        self._thread = threading.Thread(target=self._run, name=f"alog-{root}", daemon=True)
        self._thread.start()

    @property
    def alog_path(self) -> Path:
        return self.files[-1]

    @property
    def error(self) -> OSError | None:
        """The disk error that stopped writing, if any."""
        return self._error

    def put_line(self, line: str) -> bool:
        return self._put(line)

    def put_binary(self, prefix: str, data: bytes) -> bool:
        return self._put((prefix, data))

    def _put(self, item: str | tuple[str, bytes]) -> bool:
        with self._cond:
            if len(self._pending) >= self.max_pending or self._error is not None:
                self.dropped += 1
                return False
            self._pending.append(item)
            return True

    def close(self) -> None:
        with self._cond:
            self._closing = True
            self._cond.notify()
        self._thread.join()
        for stream in (self._alog, self._blog):
            if stream is not None:
                stream.close()
        self._alog = self._blog = None

    # -- the writer thread ---------------------------------------------------------------------

    def _open_alog(self) -> None:
        n = len(self.files)
        name = f"{self.root}.alog" if n == 0 else f"{self.root}_{n}.alog"
        path = self.directory / (name + ".gz" if self.compress else name)
        if self._alog is not None:
            self._alog.close()
        stream: IO[bytes] = (
            gzip.open(path, "wb") if self.compress else open(path, "wb")  # type: ignore[assignment]  # noqa: SIM115
        )
        header = self._banner_of(str(self.directory / name)).encode()
        stream.write(header)
        self._alog = stream
        self._alog_bytes = len(header)
        self.files.append(path)

    def _run(self) -> None:
        while True:
            with self._cond:
                if not self._pending and not self._closing:
                    self._cond.wait(FLUSH_PERIOD)
                batch, self._pending = self._pending, []
                closing = self._closing
            if batch and self._error is None:
                try:
                    self._write(batch)
                except OSError as err:
                    self._error = err
                    self.dropped += len(batch)
                    log.error("alog writing stopped: %s", err)
            if closing:
                return

    def _write(self, batch: list[str | tuple[str, bytes]]) -> None:
        for item in batch:
            if isinstance(item, str):
                line = item.encode("utf-8", "surrogateescape")
            else:
                prefix, data = item
                blog = self._open_blog()
                head = prefix.encode("utf-8", "surrogateescape")
                blog.write(head)
                offset = blog.tell()
                blog.write(data + b"\n")
                # pLogger ends a binary value's line right after the tag: no trailing space
                line = head + binary_tag(self.blog_name, offset, len(data)).encode() + b"\n"
            if self.max_bytes and self._alog_bytes + len(line) > self.max_bytes:
                self._open_alog()
            assert self._alog is not None
            self._alog.write(line)
            self._alog_bytes += len(line)
        assert self._alog is not None
        self._alog.flush()
        if self._blog is not None:
            self._blog.flush()
        self.written += len(batch)

    def _open_blog(self) -> IO[bytes]:
        if self._blog is None:
            self._blog = open(self.directory / self.blog_name, "wb")  # noqa: SIM115
        return self._blog


def make_log_directory(candidates: list[Path], logger: logging.Logger) -> Path | None:
    """The first of `candidates` that exists or can be made (a warning for each that cannot)."""
    for directory in candidates:
        try:
            directory.mkdir(parents=True, exist_ok=True)
            return directory
        except OSError as err:
            logger.warning("cannot make the log directory %s: %s", directory, err)
    return None


def copy_with_banner(original: str | os.PathLike[str], copy: Path, header: str) -> None:
    """`original` copied to `copy` under a banner (pLogger's ._moos copy of the mission)."""
    with open(copy, "w") as out, open(original) as source:
        out.write(header)
        shutil.copyfileobj(source, out)
