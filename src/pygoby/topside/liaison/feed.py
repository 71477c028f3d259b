"""The live pages' updates: one snapshot per tick for every open page, whatever the number of
streams, and to each stream only what changed since it was last sent something.

`PageSnapshots` (sans-I/O) builds the tick's snapshot of each page someone watches;
`ScopeStream` and `PageStream` remember what one stream was sent and answer the next message;
`LiveFeed` ticks them in asyncio and caps the number of open streams.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections import Counter
from collections.abc import AsyncIterator, Callable

from pygoby.topside.errors import TooManyStreamsError
from pygoby.topside.liaison.models import ScopeFilter
from pygoby.topside.liaison.state import LiaisonState

log = logging.getLogger("pygoby.liaison")
PAGES = ("scope", "commander", "acomms", "map")


def _json_default(value: object) -> object:
    return str(value)


class PageSnapshots:
    """The snapshot of each watched page at one tick: the Scope as one JSON text per row (rows
    whose value and rate did not change keep their text), the other pages as one JSON text."""

    def __init__(self, state: LiaisonState) -> None:
        self.state = state
        self.tick = 0
        self.now = 0.0
        self.scope_rows: dict[str, str] = {}
        self.pages: dict[str, str] = {}

    def build(self, watched: Counter[str]) -> None:
        self.tick += 1
        self.now = now = self.state.now()
        if watched["scope"]:
            self.scope_rows = self.state.scope.rows_json(now)
        for name in ("commander", "acomms", "map"):
            if watched[name]:
                view = self.state.page(name, now)
                self.pages[name] = json.dumps(view, default=_json_default)


class ScopeStream:
    """What one open Scope page was sent: the first message has every row it shows (`full`),
    the next ones the rows that changed and the names that went out of the filter."""

    def __init__(self, wanted: ScopeFilter) -> None:
        self.wanted = wanted
        self.sent: dict[str, str] | None = None

    def message(self, snapshots: PageSnapshots) -> str:
        shown = {k: v for k, v in snapshots.scope_rows.items() if self.wanted(k)}
        before = self.sent
        self.sent = shown
        if before is None:
            changed, removed = list(shown.values()), []
        else:
            changed = [v for k, v in shown.items() if before.get(k) != v]
            removed = [k for k in before if k not in shown]
        return (
            f'{{"now": {json.dumps(snapshots.now)}, "full": {json.dumps(before is None)}, '
            f'"count": {len(shown)}, "changed": [{", ".join(changed)}], '
            f'"removed": {json.dumps(removed)}}}'
        )


class PageStream:
    """What one open Commander, Acomms or Map page was sent: the page again when it changed."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.sent: str | None = None

    def message(self, snapshots: PageSnapshots) -> str | None:
        text = snapshots.pages.get(self.name)
        if text is None or text == self.sent:
            return None
        self.sent = text
        return text


class LiveFeed:
    """Ticks `PageSnapshots` every `period` seconds (`run`), and serves `stream`s, at most
    `max_streams` at once (past that, `admit` raises TooManyStreamsError). `before_tick`, if
    given, runs first at every tick (a log replay moving the state to the tick's time)."""

    def __init__(
        self,
        state: LiaisonState,
        period: float,
        max_streams: int,
        before_tick: Callable[[], None] | None = None,
    ) -> None:
        self.snapshots = PageSnapshots(state)
        self.before_tick = before_tick
        self.period = period
        self.max_streams = max_streams
        self.watched: Counter[str] = Counter()
        self._ticked = asyncio.Event()
        self._closed = False

    @property
    def open_streams(self) -> int:
        return sum(self.watched.values())

    def admit(self, name: str, filter_text: str = "") -> ScopeStream | PageStream:
        """A stream of page `name`, counted until `release`d. Raises TooManyStreamsError, and
        ScopeFilterError for a filter the Scope does not take."""
        if self.open_streams >= self.max_streams:
            raise TooManyStreamsError(
                f"liaison: {self.max_streams} live pages are open already (max_streams)"
            )
        stream = ScopeStream(ScopeFilter(filter_text)) if name == "scope" else PageStream(name)
        self.watched[name] += 1
        return stream

    def release(self, stream: ScopeStream | PageStream) -> None:
        name = "scope" if isinstance(stream, ScopeStream) else stream.name
        self.watched[name] -= 1

    async def stream(self, stream: ScopeStream | PageStream) -> AsyncIterator[str]:
        """Server-Sent Events for `stream`, one at most per tick, until the feed closes. A slow
        reader misses ticks, never queues them: its next message is against the newest one."""
        seen = self.snapshots.tick
        while not self._closed:
            while self.snapshots.tick == seen and not self._closed:
                await self._ticked.wait()
            if self._closed:
                return
            seen = self.snapshots.tick
            text = stream.message(self.snapshots)
            if text is not None:
                yield f"data: {text}\n\n"

    def tick(self) -> None:
        if self.before_tick is not None:
            self.before_tick()
        self.snapshots.build(self.watched)
        ticked, self._ticked = self._ticked, asyncio.Event()
        ticked.set()

    async def run(self, stopping: asyncio.Event) -> None:
        try:
            while not stopping.is_set():
                try:
                    self.tick()
                except Exception:  # a page that cannot be drawn must not end the others
                    log.exception("liaison: cannot build the pages' snapshot")
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(self.period):
                        await stopping.wait()
        finally:
            self._closed = True
            self._ticked.set()
