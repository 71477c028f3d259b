"""Shared set-up for queue tests and benchmarks: a Codec with the test DCCL types."""

from __future__ import annotations

from pathlib import Path

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue import QueueManager
from pygoby.dccl import Codec

PROTO = Path(__file__).with_name("protos") / "acomms_queue_test.proto"
Role = acomms_pb.QueuedMessageEntry.Role


def load_types(codec: Codec):
    return tuple(
        codec.load_proto(PROTO, f"pygoby.test.acomms.{n}") for n in ("Status", "Bulk", "Note")
    )


def entry(name: str, roles: bool = True, **options):
    e = acomms_pb.QueuedMessageEntry(protobuf_name=f"pygoby.test.acomms.{name}", **options)
    if roles:
        e.role.add(type=Role.SOURCE_ID, field="src")
        e.role.add(type=Role.DESTINATION_ID, field="dest")
    return e


def manager(clock, modem_id=1, entries=(), **cfg):
    codec = Codec(clock=clock)
    types = load_types(codec)
    qm = QueueManager(codec, clock)
    qm.set_cfg(acomms_pb.QueueManagerConfig(modem_id=modem_id, **cfg))
    for e in entries:
        qm.add_queue(e)
    return qm, types


def status_link(clock, d1, d2):
    """Drivers d1 (modem 1) and d2 (modem 2), each bound to a queue manager with a Status queue.

    Returns (q1, q2, Status, got, acked): `got` collects what q2 receives, `acked` the `value`
    of each of q1's messages that was acknowledged."""
    from pygoby.acomms.bind import bind

    q1, (status_cls, *_) = manager(clock, modem_id=1, entries=[entry("Status")])
    q2, _ = manager(clock, modem_id=2, entries=[entry("Status")])
    bind(d1, q1)
    bind(d2, q2)
    got, acked = [], []
    q2.signal_receive.connect(got.append)
    q1.signal_ack.connect(lambda ack, original: acked.append(original.value))
    return q1, q2, status_cls, got, acked
