"""What the QueueManager tells the operator, in goby3's queue groups (pygoby.util.glog) for its
modem id:

* `goby::acomms::queue::out::<id>` VERBOSE: one line per transmission it fills (slot, src->dest,
  rate, frames, bytes, the messages, ack); DEBUG1 a slot with nothing to send.
* `goby::acomms::queue::in::<id>` VERBOSE: one line per reception (the messages decoded, ack)
  and per acknowledgement; warnings for frames that do not decode; DEBUG1 messages dropped as
  not for this node.
* `goby::acomms::queue::push::<id>` VERBOSE: each push (queue size, priority), a message
  dropped by max_queue; DEBUG1 loopbacks and messages for this node.
* `goby::acomms::queue::pop::<id>` VERBOSE: each message given to a frame and each expiry.
* `goby::acomms::queue::priority::<id>` DEBUG2: every priority contest, queue by queue.
"""

from __future__ import annotations

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue.queue import MessageQueue, QueuedItem
from pygoby.util.glog import DEBUG1, DEBUG2, VERBOSE, group_logger


def _ack_text(requested: bool) -> str:
    return "ack requested" if requested else "no ack"


def _names(names: list[str]) -> str:
    return ", ".join(names) if names else "nothing decoded"


class QueueLog:
    def __init__(self, modem_id: int) -> None:
        prefix = "goby::acomms::queue::"
        self.out, self.into, self.push, self.pop, self.priority = (
            group_logger(f"{prefix}{kind}::{modem_id}")
            for kind in ("out", "in", "push", "pop", "priority")
        )

    # -- push / pop / expiry --------------------------------------------------------------------

    def pushed(self, queue: MessageQueue, item: QueuedItem, now: float) -> None:
        if self.push.isEnabledFor(VERBOSE):
            limit = queue.entry.max_queue
            self.push.log(
                VERBOSE,
                "pushed %s (%d->%d, %d B, %s): queue size %d%s, priority %.3g",
                queue.name,
                item.src,
                item.dest,
                len(item.encoded),
                _ack_text(item.ack_requested),
                len(queue),
                f"/{limit}" if limit else "",
                queue.priority(now),
            )

    def dropped(self, queue: MessageQueue, victim: QueuedItem) -> None:
        which = "oldest" if queue.entry.newest_first else "newest"
        self.push.log(
            VERBOSE,
            "%s queue full (max_queue %d): dropped the %s message (%d->%d)",
            queue.name,
            queue.entry.max_queue,
            which,
            victim.src,
            victim.dest,
        )

    def not_queued(self, name: str, why: str) -> None:
        if self.push.isEnabledFor(DEBUG1):
            self.push.log(DEBUG1, "%s: %s", name, why)

    def not_delivered(self, name: str, why: str) -> None:
        if self.into.isEnabledFor(DEBUG1):
            self.into.log(DEBUG1, "%s: %s", name, why)

    def popped(self, queue: MessageQueue, item: QueuedItem, frame: int, priority: float) -> None:
        if self.pop.isEnabledFor(VERBOSE):
            then = "kept until acknowledged" if item.ack_requested else "removed"
            self.pop.log(
                VERBOSE,
                "popped %s (%d->%d, %d B) for frame %d at priority %.3g; %s; queue size %d",
                queue.name,
                item.src,
                item.dest,
                len(item.encoded),
                frame,
                priority,
                then,
                len(queue),
            )

    def expired(self, queue: MessageQueue, item: QueuedItem) -> None:
        self.pop.log(
            VERBOSE,
            "expired %s (%d->%d) after its ttl of %g s; queue size %d",
            queue.name,
            item.src,
            item.dest,
            queue.entry.ttl,
            len(queue),
        )

    # -- transmissions ----------------------------------------------------------------------

    def transmission(self, request: acomms_pb.ModemTransmission, names: list[str]) -> None:
        if not names:
            if self.out.isEnabledFor(DEBUG1):
                self.out.log(
                    DEBUG1,
                    "slot %d (%d->%d, rate %d): nothing to send",
                    request.slot_index,
                    request.src,
                    request.dest,
                    request.rate,
                )
            return
        if not self.out.isEnabledFor(VERBOSE):
            return
        size = sum(len(frame) for frame in request.frame)
        self.out.log(
            VERBOSE,
            "transmit slot %d: %d->%d, rate %d, %d frame(s), %d B: %s (%s)",
            request.slot_index,
            request.src,
            request.dest,
            request.rate,
            len(request.frame),
            size,
            ", ".join(names),
            _ack_text(request.ack_requested),
        )

    def reception(self, transmission: acomms_pb.ModemTransmission, names: list[str]) -> None:
        if self.into.isEnabledFor(VERBOSE):
            size = sum(len(frame) for frame in transmission.frame)
            self.into.log(
                VERBOSE,
                "received %d->%d, rate %d, %d frame(s), %d B: %s (%s)",
                transmission.src,
                transmission.dest,
                transmission.rate,
                len(transmission.frame),
                size,
                _names(names),
                _ack_text(transmission.ack_requested),
            )

    def acknowledged(self, ack: acomms_pb.ModemTransmission, names: list[str]) -> None:
        if self.into.isEnabledFor(VERBOSE):
            what = "acknowledges " + ", ".join(names) if names else "no message waits for them"
            self.into.log(
                VERBOSE,
                "received ACK %d->%d for frame(s) %s: %s",
                ack.src,
                ack.dest,
                list(ack.acked_frame),
                what,
            )

    def ack_for_another(self, ack: acomms_pb.ModemTransmission, modem_id: int) -> None:
        self.into.warning("ignoring an ACK for modem %d (we are %d)", ack.dest, modem_id)

    def undecodable(self, offset: int, error: Exception) -> None:
        where = "frame dropped" if offset == 0 else "rest of frame dropped"
        self.into.warning("cannot decode DCCL message at byte %d (%s): %s", offset, where, error)

    # -- the priority contest (DEBUG2) ---------------------------------------------------------

    @property
    def contests(self) -> bool:
        return self.priority.isEnabledFor(DEBUG2)

    def contest(
        self,
        request: acomms_pb.ModemTransmission,
        frame_used: int,
        entries: list[tuple[str, str]],
        winner,
    ) -> None:
        """`entries`: (queue name, "priority P" or why it could not take part)."""
        lines = "; ".join(f"{name}: {state}" for name, state in entries) or "no queues"
        self.priority.log(
            DEBUG2,
            "contest for %d->%d (%d B used): %s -> winner %s",
            request.src,
            request.dest,
            frame_used,
            lines,
            winner.name if winner is not None else "none",
        )
