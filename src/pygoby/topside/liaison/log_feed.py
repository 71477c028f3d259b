"""liaison over a recorded mission: the pages' state at any time of an .alog, and a player that
moves that time with a Clock (no MOOSDB, no asyncio: the web layer calls `LogPlayer.update`
once per tick).

* `LogIndex.build(path)`: one streaming pass over the log: its span, its entry and damaged-line
  counts, and checkpoints (byte offset, log time) about every `spacing` seconds of log time.
* `LogFeed`: the Scope, Acomms and Map models at log time `t`: `seek(t)` aims, `step(budget)`
  applies at most `budget` entries towards it (so one request or tick never reads the whole
  log), `advance(dt)` aims further on.
* `LogPlayer`: play, pause, speed and seek, the log time following `clock.now()` while playing;
  each `update` steps the feed for at most `work_seconds`.

What is bounded: the index holds at most `max_checkpoints` checkpoints (past that, every other
one is dropped and the spacing doubles); the feed keeps the pages' saved state at most at
`max_snapshots` of them (compressed; spread out the same way), each the size of what the pages
keep (the Scope's rows with their history, the Acomms page's recent rows, the Map's tracks).
Going back rebuilds the pages from the nearest saved checkpoint at or before the time (the
log's start when none is): what is read again is at most the log between two saved
checkpoints. The log itself is never held in memory: a 0.9 GB log of 11M lines took 33 s to
index and 71 MB of memory, and a jump back from 60000 s to 30000 s of it 1.1 s. (A .alog.gz
cannot be seeked into: getting to a checkpoint decompresses the file up to it.)
"""

from __future__ import annotations

import bisect
import math
import os
import time
from collections.abc import Generator
from dataclasses import dataclass, field
from pathlib import Path

from pygoby.moos import protocol as p
from pygoby.moos.alog.files import HEADER_LINES, MAX_LINE_BYTES, AlogFile, open_text_or_gz
from pygoby.moos.alog.format import AlogEntry, AlogReader, decode_line
from pygoby.moos.alog.tools import db_community
from pygoby.topside.errors import LogControlError, LogFileError
from pygoby.topside.liaison.state import LiaisonState
from pygoby.util.clock import Clock

DEFAULT_SPACING = 10.0  # s of log time between checkpoints
MAX_CHECKPOINTS = 4096
MAX_SNAPSHOTS = 32
STEP_BUDGET = 1_000  # entries per step: ~6 ms at the ~6 us an entry costs (read, parse, pages)
WORK_SECONDS = 0.08  # of reading per tick at most: ticks are 0.2 s apart by default
SPEEDS = (1.0, 2.0, 5.0, 10.0, 30.0, 100.0, 1000.0)


@dataclass(frozen=True)
class Checkpoint:
    """The entry at byte `offset`; every entry before it has a log time <= `time`, so the
    pages' state at any log time >= `time` is reached by going on from here."""

    time: float
    offset: int


@dataclass
class LogIndex:
    """What one pass over an .alog learns. Times are seconds since LOGSTART (the file's own)."""

    path: Path
    log_start: float
    community: str  # of the log's MOOSDB (its MOOSDB_<community> posts), "" when none posted
    end_time: float  # the latest entry's time: the slider's end
    entries: int
    bad_lines: int
    spacing: float
    checkpoints: list[Checkpoint] = field(default_factory=list)

    @classmethod
    def build(
        cls,
        path: str | os.PathLike[str],
        spacing: float = DEFAULT_SPACING,
        max_checkpoints: int = MAX_CHECKPOINTS,
    ) -> LogIndex:
        """Index `path`; LogFileError when it is missing, unreadable or not an .alog."""
        path = Path(path)
        _check_readable(path)
        log = AlogFile(path)
        checkpoints = [Checkpoint(-math.inf, 0)]  # the start: before every entry
        latest, mark, entries, community = -math.inf, math.inf, 0, ""
        for offset, entry in log.scan():
            if latest >= mark:  # (never before the first entry: the start is checkpoint 0)
                checkpoints.append(Checkpoint(latest, offset))
                mark = latest + spacing
                if len(checkpoints) > max_checkpoints:
                    checkpoints = checkpoints[::2]  # keeps the start
                    spacing *= 2
            latest = max(latest, entry.time)
            entries += 1
            if entries == 1:
                mark = latest + spacing
            if not community:
                community = db_community(entry.source) or ""
        return cls(
            path,
            log.log_start,
            community,
            max(latest, 0.0),
            entries,
            log.reader.bad_lines,
            spacing,
            checkpoints,
        )

    def checkpoint_before(self, t: float) -> int:
        """The index of the last checkpoint whose state comes before log time `t`."""
        # their times are running maxima of the entries' times: sorted
        return max(bisect.bisect_right(self.checkpoints, t, key=lambda c: c.time) - 1, 0)


def _check_readable(path: Path) -> None:
    """LogFileError unless `path` is a readable file whose first lines look like an .alog (a
    `%%` banner line or a `TIME VAR SOURCE VALUE` entry): refused before its whole pass."""
    if not path.exists():
        raise LogFileError(f"{path}: no such file")
    if not path.is_file():
        raise LogFileError(f"{path}: not a file")
    reader = AlogReader()
    try:
        with open_text_or_gz(path) as stream:
            # bounded lines: a file without newlines must not be read whole here
            head = [stream.readline(MAX_LINE_BYTES) for _ in range(HEADER_LINES)]
    except OSError as err:
        raise LogFileError(f"{path}: cannot read ({err.strerror or err})") from None
    except EOFError as err:
        raise LogFileError(f"{path}: cannot read ({err})") from None
    if not head[0]:
        raise LogFileError(f"{path}: empty")
    looks_like_alog = False
    for raw in head:
        text = decode_line(raw)
        looks_like_alog |= reader.feed(text) is not None or text.startswith("%%")
    if not looks_like_alog:
        raise LogFileError(f"{path}: not a MOOS .alog (no %% banner and no TIME VAR SOURCE line)")


class LogFeed:
    """The pages of `state` at a log time of `index`'s log. Applies each entry as the MOOS mail
    liaison's live feed gets (the time made UNIX time with LOGSTART, `community` for entries
    the log does not mark as another community's)."""

    def __init__(
        self,
        index: LogIndex,
        state: LiaisonState,
        community: str = "",
        max_snapshots: int = MAX_SNAPSHOTS,
    ) -> None:
        self.index = index
        self.state = state
        self.community = community
        self.max_snapshots = max_snapshots
        self.log = AlogFile(index.path)
        self.target = 0.0  # the log time asked for
        self.applied = 0  # entries applied since the state was last rebuilt (for tests, bench)
        self._stride = 1  # snapshots are kept at checkpoints whose index it divides
        self._snapshots: dict[int, bytes] = {0: state.save_pages()}
        self._entries: Generator[tuple[int, AlogEntry], None, None] | None = None
        self._next: tuple[int, AlogEntry] | None = None  # the next entry to apply
        self._offset = 0.0  # ... its byte offset (past the end: infinite)
        self._latest = -math.inf  # the latest log time applied
        self._checkpoint = 0  # the next checkpoint to save the state at
        self._restore(0)

    # -- where the state is ------------------------------------------------------------------
    @property
    def time(self) -> float:
        """The log time the pages show: the target once reached, else how far they got."""
        if self.caught_up:
            return self.target
        return max(self._latest, 0.0)

    @property
    def caught_up(self) -> bool:
        return self._next is None or self._next[1].time > self.target

    @property
    def saved_checkpoints(self) -> list[int]:
        """The checkpoints (indices into the index's) whose pages' state is kept."""
        return sorted(self._snapshots)

    @property
    def bad_lines(self) -> int:
        """Damaged lines met since the state was last rebuilt."""
        return self.log.reader.bad_lines

    # -- moving ------------------------------------------------------------------------------
    def seek(self, t: float) -> None:
        """Aim at log time `t` (clamped to the log's span); `step` gets there. Going back, or
        past a saved checkpoint, starts again from the nearest saved checkpoint before `t`."""
        t = min(max(t, 0.0), self.index.end_time)
        self.target = t
        saved = self._saved_before(t)
        at = self.index.checkpoints[saved].offset
        if self._latest > t or at > self._offset:
            self._restore(saved)

    def advance(self, dt: float) -> None:
        self.seek(self.target + dt)

    def step(self, budget: int = STEP_BUDGET) -> bool:
        """Apply at most `budget` entries towards the target; True when the pages show it."""
        checkpoints = self.index.checkpoints
        for _ in range(budget):
            if self.caught_up:
                return True
            assert self._next is not None
            offset, entry = self._next
            k = self._checkpoint
            while k < len(checkpoints) and checkpoints[k].offset <= offset:
                if checkpoints[k].offset == offset:
                    self._save(k)  # the state before this entry: the checkpoint's
                k += 1
            self._checkpoint = k
            self.state.show(self._message(entry))
            self.applied += 1
            self._latest = max(self._latest, entry.time)
            self._read_next()
        return self.caught_up

    def run_to(self, t: float) -> None:
        """`seek(t)` and every `step` it takes (tests, benchmarks: the web layer steps per tick)."""
        self.seek(t)
        while not self.step():
            pass

    def close(self) -> None:
        if self._entries is not None:
            self._entries.close()

    # -- inside -------------------------------------------------------------------------------
    def _message(self, entry: AlogEntry) -> p.MOOSMessage:
        return p.notify(
            entry.name,
            entry.value,
            time=self.index.log_start + entry.time,
            src=entry.source,
            src_aux=entry.source_aux,
            community=entry.community or self.community,
        )

    def _read_next(self) -> None:
        assert self._entries is not None
        self._next = next(self._entries, None)
        self._offset = math.inf if self._next is None else self._next[0]

    def _saved_before(self, t: float) -> int:
        """The last checkpoint at or before `t` whose state is saved."""
        k = self.index.checkpoint_before(t)
        while k not in self._snapshots:
            k -= 1  # 0 (the start) is always saved
        return k

    def _save(self, k: int) -> None:
        if k % self._stride or k in self._snapshots:
            return
        self._snapshots[k] = self.state.save_pages()
        if len(self._snapshots) > self.max_snapshots:
            self._stride *= 2
            self._snapshots = {i: s for i, s in self._snapshots.items() if i % self._stride == 0}

    def _restore(self, k: int) -> None:
        self.state.restore_pages(self._snapshots[k])
        checkpoint = self.index.checkpoints[k]
        self.close()
        self._entries = self.log.scan(checkpoint.offset)
        self._read_next()
        self._latest = checkpoint.time
        self._checkpoint = k + 1  # the next checkpoint to save at
        self.applied = 0


class LogPlayer:
    """Play, pause, speed and seek over a `LogFeed`, its log time following `clock` while
    playing (a VirtualClock in tests). `update()` once per tick moves the feed."""

    def __init__(self, feed: LogFeed, clock: Clock, work_seconds: float = WORK_SECONDS) -> None:
        """`work_seconds`: how long one `update` may read the log (measured on the process's
        performance counter, not `clock`: it bounds the work, whatever the log time does)."""
        self.feed = feed
        self.clock = clock
        self.work_seconds = work_seconds
        self.playing = False
        self.speed = 1.0
        self._anchor = (clock.now(), 0.0)  # (clock time, log time) when play or seek was last

    def play(self) -> None:
        if self.feed.target >= self.feed.index.end_time:
            self.feed.seek(0.0)  # played to the end: from the start again
        self.playing = True
        self._anchor = (self.clock.now(), self.feed.target)

    def pause(self) -> None:
        self.update()
        self.playing = False

    def set_speed(self, speed: float) -> None:
        if speed not in SPEEDS:
            speeds = ", ".join(f"{s:g}" for s in SPEEDS)
            raise LogControlError(f"speed {speed:g} is not one of {speeds}")
        self.update()
        self.speed = speed
        self._anchor = (self.clock.now(), self.feed.target)

    def seek(self, t: float) -> None:
        if not math.isfinite(t):
            raise LogControlError("a log time is a finite number of seconds")
        self.feed.seek(t)
        self._anchor = (self.clock.now(), self.feed.target)

    def update(self) -> None:
        """Aim the feed at the playing time (the end pauses), then step it towards it for at
        most `work_seconds` (at least one step): a long jump takes several updates, and the
        server answers requests between them."""
        if self.playing:
            started, from_time = self._anchor
            t = from_time + (self.clock.now() - started) * self.speed
            if t >= self.feed.index.end_time:
                t, self.playing = self.feed.index.end_time, False
            self.feed.seek(t)
        deadline = time.perf_counter() + self.work_seconds
        while not self.feed.step() and time.perf_counter() < deadline:
            pass

    def status(self) -> dict:
        """The log bar's view: the file's name (never its folder), span, time, controls."""
        index, feed = self.feed.index, self.feed
        return {
            "file": index.path.name,
            "community": feed.community,  # the vehicle whose NAV_* the Map draws
            "log_start": index.log_start,
            "duration": index.end_time,
            "time": round(feed.time, 3),
            "target": round(feed.target, 3),
            "caught_up": feed.caught_up,
            "playing": self.playing,
            "speed": self.speed,
            "speeds": list(SPEEDS),
            "entries": index.entries,
            "bad_lines": index.bad_lines,
        }
