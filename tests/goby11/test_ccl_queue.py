"""Goby 1.1 raw CCL queues in the QueueManager (spec acomms.md §5.8)."""

from __future__ import annotations

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue import QueueError, QueueManager
from pygoby.acomms.queue.ccl import dccl_first_byte, goby11_time
from pygoby.dccl import Codec
from pygoby.util.clock import VirtualClock
from tests.acomms.queue_helpers import PROTO, entry, manager

STATE = bytes([14]) + bytes(range(1, 32))  # a 32-byte REMUS MDAT_STATE-like frame


def ccl_cfg(ccl_id=14, name="Remus_State", **options):
    cfg = acomms_pb.V1QueueConfig(name=name, **options)
    cfg.key.type, cfg.key.id = acomms_pb.QUEUE_CCL, ccl_id
    return cfg


def frame(data: bytes, dest: int = 2):
    out = acomms_pb.V1ModemDataTransmission(data=data)
    out.base.dest = dest
    return out


def request(dest=2, max_bytes=32):
    return acomms_pb.ModemTransmission(
        src=1, dest=dest, type=acomms_pb.DATA, max_num_frames=1, max_frame_bytes=max_bytes
    )


@pytest.fixture
def clock():
    return VirtualClock(1_300_000_000.0)


def test_ccl_frame_travels_alone_and_arrives_on_its_queue(clock):
    q1, (Status, *_) = manager(
        clock,
        modem_id=1,
        entries=[entry("Status", ack=False)],
        queue=[ccl_cfg(ack=False, value_base=10)],
    )
    q2, _ = manager(clock, modem_id=2, entries=[entry("Status", ack=False)], queue=[ccl_cfg()])
    q1.push_message(Status(src=1, dest=2, value=5))
    q1.push_ccl(14, frame(STATE))
    clock.advance(10)
    first = request()
    q1.handle_modem_data_request(first)
    assert list(first.frame) == [STATE]  # the CCL queue won, nothing after it
    second = request()
    q1.handle_modem_data_request(second)
    assert second.frame[0][0] == dccl_first_byte(20)  # then the DCCL message
    got_ccl, got_dccl = [], []
    q2.signal_receive_ccl.connect(got_ccl.append)
    q2.signal_receive.connect(got_dccl.append)
    for sent in (first, second):
        sent.time = acomms_pb.now_us(clock.now())
        q2.handle_modem_receive(sent)
    (received,) = got_ccl
    assert bytes(received.data) == STATE
    assert (received.base.src, received.base.dest, received.queue_key.id) == (1, 2, 14)
    assert received.queue_key.type == acomms_pb.QUEUE_CCL
    assert received.base.time == goby11_time(clock.now()) == "2011-Mar-13 07:06:50"
    assert [g.value for g in got_dccl] == [5]


def test_a_dccl_message_winning_first_keeps_the_ccl_frame_out_of_its_frame(clock):
    q1, (Status, *_) = manager(
        clock,
        modem_id=1,
        entries=[entry("Status", ack=False, value_base=10)],
        queue=[ccl_cfg(ack=False)],
    )
    q1.push_message(Status(src=1, dest=2, value=5))
    q1.push_ccl(14, frame(bytes([14, 1, 2])))
    clock.advance(10)
    sent = request(max_bytes=64)
    q1.handle_modem_data_request(sent)
    assert sent.frame[0][0] == dccl_first_byte(20) and 14 not in sent.frame[0][1:2]
    assert len(q1.ccl_queues[14]) == 1


def test_frames_for_other_modems_and_unknown_first_bytes(clock, caplog):
    q2, _ = manager(clock, modem_id=2, queue=[ccl_cfg()])
    got = []
    q2.signal_receive_ccl.connect(got.append)
    q2.handle_modem_receive(
        acomms_pb.ModemTransmission(src=1, dest=3, type=acomms_pb.DATA, frame=[STATE])
    )
    assert got == []
    q2.handle_modem_receive(
        acomms_pb.ModemTransmission(src=1, dest=0, type=acomms_pb.DATA, frame=[STATE])
    )
    assert len(got) == 1
    q2.handle_modem_receive(
        acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DATA, frame=[bytes([15, 1])])
    )
    assert len(got) == 1 and "cannot decode DCCL" in caplog.text


def test_push_checks(clock):
    q, _ = manager(clock, queue=[ccl_cfg()])
    with pytest.raises(QueueError, match="starts with byte 2, not the queue's CCL id 14"):
        q.push_ccl(14, frame(bytes([2, 2, 3, 4])))
    with pytest.raises(QueueError, match="the frame is empty"):
        q.push_ccl(14, frame(b""))
    with pytest.raises(QueueError, match="no CCL queue with id 2"):
        q.push_ccl(2, frame(bytes([2])))


def test_ccl_and_dccl_ids_that_cannot_be_told_apart_are_refused(clock):
    with pytest.raises(QueueError, match="CCL id 40 is also the first byte of DCCL id 20"):
        manager(clock, entries=[entry("Status")], queue=[ccl_cfg(40)])
    queue = QueueManager(Codec(clock=clock), clock)
    queue.set_cfg(acomms_pb.QueueManagerConfig(modem_id=1, queue=[ccl_cfg(40)]))
    status = queue.codec.load_proto(PROTO, "pygoby.test.acomms.Status")
    with pytest.raises(QueueError, match="DCCL id 20 starts its frames with byte 40"):
        queue.add_queue(entry("Status"), status)
    dccl = acomms_pb.V1QueueConfig(name="x")
    dccl.key.type, dccl.key.id = 1, 3
    with pytest.raises(QueueError, match="queue blocks configure CCL queues"):
        manager(clock, queue=[dccl])
    with pytest.raises(QueueError, match="not a byte"):
        manager(clock, queue=[ccl_cfg(300)])


def test_first_bytes_of_dccl_ids():
    assert [dccl_first_byte(i) for i in (0, 7, 20, 127, 128, 300)] == [0, 14, 40, 254, 1, 89]


def test_acks_expiry_and_loopback(clock):
    q, _ = manager(clock, modem_id=1, queue=[ccl_cfg(ack=True, ttl=30)])
    acked, expired, looped = [], [], []
    q.signal_ack.connect(lambda ack, original: acked.append(bytes(original.data)))
    q.signal_expire.connect(lambda original: expired.append(bytes(original.data)))
    q.signal_receive_ccl.connect(looped.append)
    q.push_ccl(14, frame(STATE, dest=2))
    clock.advance(1)
    sent = request()
    q.handle_modem_data_request(sent)
    assert sent.ack_requested and len(q.ccl_queues[14]) == 1  # waits for the ack
    q.handle_modem_receive(
        acomms_pb.ModemTransmission(src=2, dest=1, type=acomms_pb.ACK, acked_frame=[0])
    )
    assert acked == [STATE] and len(q.ccl_queues[14]) == 0
    q.push_ccl(14, frame(bytes([14, 9]), dest=2))
    clock.advance(31)
    q.do_work()
    assert expired == [bytes([14, 9])]
    q.push_ccl(14, frame(bytes([14, 7]), dest=1))
    assert [bytes(t.data) for t in looped] == [bytes([14, 7])] and len(q.ccl_queues[14]) == 0
