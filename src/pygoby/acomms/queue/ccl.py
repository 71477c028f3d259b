"""Goby 1.1 raw CCL queues (Goby 1.1's `queue_cfg.queue` entries with a CCL id).

A CCL queue holds frames whose first byte is its CCL id (e.g. 14 for a REMUS MDAT_STATE). A CCL
frame always travels alone, as the first and only message of a modem frame; a received frame
whose first byte is the id of a configured CCL queue goes to that queue's listeners, every
other frame is DCCL. Queued items carry the Goby 1.1 `ModemDataTransmission` they came from.
"""

from __future__ import annotations

import datetime as dt

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue.queue import MessageQueue

MAX_CCL_ID = 255


class CCLQueue(MessageQueue):
    """A MessageQueue of raw frames (no DCCL type, no roles)."""

    @property
    def name(self) -> str:
        return self.entry.protobuf_name


def queue_entry(cfg: acomms_pb.V1QueueConfig) -> acomms_pb.QueuedMessageEntry:
    """The QueuedMessageEntry holding a Goby 1.1 QueueConfig's options (for the contest)."""
    return acomms_pb.QueuedMessageEntry(
        protobuf_name=f"CCL:{cfg.name}",
        ack=cfg.ack,
        blackout_time=cfg.blackout_time,
        max_queue=cfg.max_queue,
        newest_first=cfg.newest_first,
        value_base=cfg.value_base,
        ttl=cfg.ttl,
    )


def dccl_first_byte(dccl_id: int) -> int:
    """The first byte of a DCCL message with this id (the default DCCL id codec: one byte
    `id << 1` below 128, else two bytes `id << 1 | 1`, little-endian)."""
    return (dccl_id << 1 | (1 if dccl_id >= 128 else 0)) & 0xFF


def goby11_time(seconds: float) -> str:
    """UTC time as Goby 1.1 wrote ModemMsgBase.time (boost::posix_time's operator<<)."""
    moment = dt.datetime.fromtimestamp(seconds, dt.UTC)
    text = moment.strftime("%Y-%b-%d %H:%M:%S")
    return text + (f".{moment.microsecond:06d}" if moment.microsecond else "")


def received(transmission: acomms_pb.ModemTransmission, data: bytes, ccl_id: int, frame: int):
    """The Goby 1.1 ModemDataTransmission of a received CCL frame."""
    out = acomms_pb.V1ModemDataTransmission(
        data=data, frame=frame, ack_requested=transmission.ack_requested
    )
    out.base.src, out.base.dest = transmission.src, transmission.dest
    out.base.rate = max(transmission.rate, 0)
    out.base.time = goby11_time(transmission.time / 1e6)
    out.queue_key.type, out.queue_key.id = acomms_pb.QUEUE_CCL, ccl_id
    return out
