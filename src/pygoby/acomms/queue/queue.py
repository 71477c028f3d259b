"""One queue per DCCL type: items in push order, ack waits, priority.

Items live in a deque in push order. Removing one from the middle (an acknowledged item) only
marks it; marked items are dropped when they reach either end, so push, pop from either end and
removal are amortised O(1). Looking for the next item skips items awaiting an ack, and those are
few (they are released at every data request).

A queue with a `journal` (pygoby.acomms.queue.persist: the optional persistent queue) tells it
of every item it takes in and lets go of, whatever the reason (sent, acknowledged, expired,
pushed out by max_queue, flushed).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Protocol

from google.protobuf.message import Message

from pygoby.protobuf.goby.acomms.protobuf.manipulator_pb2 import Manipulator
from pygoby.protobuf.goby.acomms.protobuf.queue_pb2 import QueuedMessageEntry

Manip = Manipulator.DESCRIPTOR.values_by_name


@dataclass(eq=False, slots=True)
class QueuedItem:
    msg: Message
    encoded: bytes
    src: int
    dest: int
    time: int  # µs
    ack_requested: bool
    removed: bool = False
    last_sent: float | None = None
    waiting_frame: int | None = None
    key: int | None = None  # its record in the queue's journal, once recorded


class QueueJournal(Protocol):
    """Where a queue records what it holds (pygoby.acomms.queue.persist.QueueStore)."""

    def added(self, queue: MessageQueue, item: QueuedItem) -> None: ...

    def removed(self, queue: MessageQueue, item: QueuedItem) -> None: ...

    def cleared(self, queue: MessageQueue) -> None: ...


@dataclass(eq=False)
class MessageQueue:
    entry: QueuedMessageEntry
    dccl_id: int
    created: float
    roles: dict = field(default_factory=dict)
    waiting: dict[int, list[QueuedItem]] = field(default_factory=dict)  # frame -> items
    last_send_time: float = 0.0
    message_class: type[Message] | None = None  # the type of its items' messages
    journal: QueueJournal | None = None
    _items: deque[QueuedItem] = field(default_factory=deque)
    _live: int = 0

    def __post_init__(self) -> None:
        self.last_send_time = self.created
        self.manipulators = frozenset(self.entry.manipulator)

    def has(self, manipulator: str) -> bool:
        return Manip[manipulator].number in self.manipulators

    @property
    def name(self) -> str:
        return self.entry.protobuf_name

    def __len__(self) -> int:
        return self._live

    def items(self) -> list[QueuedItem]:
        """The queued items, oldest first (a copy: O(n), for inspection only)."""
        return [item for item in self._items if not item.removed]

    @property
    def waiting_count(self) -> int:
        return sum(len(v) for v in self.waiting.values())

    def push(self, item: QueuedItem) -> QueuedItem | None:
        """Append; returns the item erased by max_queue, if any."""
        self._items.append(item)
        self._live += 1
        limit = self.entry.max_queue
        victim = None
        if limit and self._live > limit:
            victim = self.front() if self.entry.newest_first else item
            assert victim is not None
        if self.journal is not None and item.key is None and victim is not item:
            self.journal.added(self, item)
        if victim is not None:
            self.remove(victim)
        return victim

    def front(self) -> QueuedItem | None:
        items = self._items
        while items and items[0].removed:
            items.popleft()
        return items[0] if items else None

    def back(self) -> QueuedItem | None:
        items = self._items
        while items and items[-1].removed:
            items.pop()
        return items[-1] if items else None

    def next_item(self) -> QueuedItem | None:
        """The item to send next: newest (newest_first) or oldest, skipping ack waits."""
        if self.entry.newest_first:
            self.back()
            ordered = reversed(self._items)
        else:
            self.front()
            ordered = iter(self._items)
        for item in ordered:
            if not item.removed and item.waiting_frame is None:
                return item
        return None

    def remove(self, item: QueuedItem) -> None:
        if item.removed:
            return
        item.removed = True
        self._live -= 1
        self._unwait(item)
        if self.journal is not None and item.key is not None:
            self.journal.removed(self, item)
        self.front()
        self.back()

    def clear(self) -> None:
        for item in self._items:
            item.removed = True
        self._items.clear()
        self._live = 0
        self.waiting.clear()
        if self.journal is not None:
            self.journal.cleared(self)

    def _unwait(self, item: QueuedItem) -> None:
        if item.waiting_frame is not None:
            waiters = self.waiting.get(item.waiting_frame, [])
            if item in waiters:
                waiters.remove(item)
                if not waiters:
                    del self.waiting[item.waiting_frame]
            item.waiting_frame = None

    def wait_for_ack(self, item: QueuedItem, frame: int) -> None:
        item.waiting_frame = frame
        self.waiting.setdefault(frame, []).append(item)

    def clear_stale_waits(self, frame_start: int, now: float, minimum_wait: float) -> None:
        for frame in list(self.waiting):
            for item in list(self.waiting[frame]):
                sent = item.last_sent if item.last_sent is not None else now
                if frame >= frame_start or now - sent >= minimum_wait:
                    self._unwait(item)

    def priority(self, now: float) -> float:
        ttl = self.entry.ttl
        if ttl == 0:  # documented infinite life, constant priority (Q-ACOMMS-2)
            return self.entry.value_base
        return self.entry.value_base * (now - self.last_send_time) / ttl

    def expired_front(self, now_us: int) -> QueuedItem | None:
        ttl = self.entry.ttl
        item = self.front()
        if item is None or ttl == 0:
            return None
        return item if item.time + ttl * 1_000_000 < now_us else None
