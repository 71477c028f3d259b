"""Shared set-up for queue tests and benchmarks: a Codec with the test DCCL types."""

from __future__ import annotations

from pathlib import Path

from pygoby.acomms import messages as m
from pygoby.acomms.queue import QueueManager
from pygoby.dccl import Codec

PROTO = Path(__file__).with_name("protos") / "acomms_queue_test.proto"
Role = m.QueuedMessageEntry.Role


def load_types(codec: Codec):
    return tuple(
        codec.load_proto(PROTO, f"pygoby.test.acomms.{n}") for n in ("Status", "Bulk", "Note")
    )


def entry(name: str, roles: bool = True, **options):
    e = m.QueuedMessageEntry(protobuf_name=f"pygoby.test.acomms.{name}", **options)
    if roles:
        e.role.add(type=Role.SOURCE_ID, field="src")
        e.role.add(type=Role.DESTINATION_ID, field="dest")
    return e


def manager(clock, modem_id=1, entries=(), **cfg):
    codec = Codec(clock=clock)
    types = load_types(codec)
    qm = QueueManager(codec, clock)
    qm.set_cfg(m.QueueManagerConfig(modem_id=modem_id, **cfg))
    for e in entries:
        qm.add_queue(e)
    return qm, types
