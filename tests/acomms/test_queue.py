"""QueueManager: priority contest, blackout, ttl, max_queue/newest_first, acks, packing, receive."""

import logging

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue import QueueError
from pygoby.acomms.queue.roles import RoleError
from pygoby.util.clock import VirtualClock
from tests.hypothesis_profiles import examples

from .queue_helpers import Role, entry, load_types, manager

T0 = 1_700_000_000.0


def request(dest=-1, frames=1, max_bytes=None, frame_start=0, **kw):
    r = acomms_pb.ModemTransmission(
        src=-1, dest=dest, max_num_frames=frames, frame_start=frame_start, **kw
    )
    if max_bytes is not None:
        r.max_frame_bytes = max_bytes
    return r


def fill(qm, **kw):
    r = request(**kw)
    qm.handle_modem_data_request(r)
    return r


def decoded(qm, frame):
    got = []
    qm.signal_receive.connect(got.append)
    qm.handle_modem_receive(acomms_pb.ModemTransmission(type=acomms_pb.DATA, frame=[frame]))
    qm.signal_receive.disconnect(got.append)
    return got


@pytest.fixture
def clock():
    return VirtualClock(T0)


def test_priority_contest_spec_example(clock):
    # spec §5.3: A (1, 1800) and B (4, 1000), both last sent 100 s ago -> B (0.4 > 0.056)
    qm, (Status, Bulk, _Note) = manager(
        clock,
        entries=[entry("Status", value_base=1, ttl=1800), entry("Bulk", value_base=4, ttl=1000)],
    )
    clock.advance(100)
    qm.push_message(Status(src=1, dest=2, value=1))
    qm.push_message(Bulk(src=1, dest=2, payload=b"b"))
    assert pytest.approx(qm.queues[20].priority(clock.now()), 1e-3) == 0.0556
    assert pytest.approx(qm.queues[21].priority(clock.now())) == 0.4
    one = len(qm.codec.encode(Bulk(src=1, dest=2, payload=b"b")))  # room for one message only
    r = fill(qm, max_bytes=one)
    assert qm.codec.id(r.frame[0]) == 21  # B wins, and its clock restarts
    r = fill(qm, max_bytes=one)
    assert qm.codec.id(r.frame[0]) == 20


def test_equal_priority_older_last_send_then_lowest_id(clock):
    qm, (Status, Bulk, _Note) = manager(clock, entries=[entry("Status"), entry("Bulk")])
    for _ in range(2):
        qm.push_message(Bulk(src=1, dest=2, payload=b"x"))
        qm.push_message(Status(src=1, dest=2, value=3))
    clock.advance(10)
    bulk = len(qm.codec.encode(Bulk(src=1, dest=2, payload=b"x")))
    first = fill(qm, max_bytes=bulk)
    assert qm.codec.id(first.frame[0]) == 20  # same P and time: lowest DCCL id
    clock.advance(10)
    # now Bulk has waited 20 s, Status 10 s: Bulk
    assert qm.codec.id(fill(qm, max_bytes=bulk).frame[0]) == 21


def test_blackout(clock):
    qm, (Status, *_) = manager(clock, entries=[entry("Status", blackout_time=30, ack=False)])
    for v in range(3):
        qm.push_message(Status(src=1, dest=2, value=v))
    clock.advance(29)
    assert fill(qm).frame[0] == b""  # blackout counts from the queue's creation
    clock.advance(2)
    one = len(qm.codec.encode(Status(src=1, dest=2, value=0)))
    assert len(fill(qm).frame[0]) == one  # one per frame: blackout again after a send
    clock.advance(10)
    assert fill(qm).frame[0] == b""  # in blackout
    clock.advance(21)
    assert len(fill(qm).frame[0]) == one


def test_ttl_expiry_and_infinite_ttl(clock):
    qm, (Status, Bulk, _Note) = manager(
        clock, entries=[entry("Status", ttl=60), entry("Bulk", ttl=0)]
    )
    expired = []
    qm.signal_expire.connect(expired.append)
    qm.push_message(Status(src=1, dest=2, value=1))
    clock.advance(30)
    qm.push_message(Status(src=1, dest=2, value=2))
    qm.push_message(Bulk(src=1, dest=2, payload=b"p"))
    clock.advance(31)
    qm.do_work()
    assert [x.value for x in expired] == [1]
    clock.advance(30)
    qm.do_work()
    assert [x.value for x in expired] == [1, 2]
    clock.advance(1e6)
    qm.do_work()
    assert qm.size(21) == 1  # ttl 0: never expires (Quirk A2, documented meaning)
    assert qm.queues[21].priority(clock.now()) == 1.0


@pytest.mark.parametrize(
    "newest_first, kept, order", [(True, [2, 3], [3, 2]), (False, [1, 2], [1, 2])]
)
def test_max_queue_and_newest_first(clock, newest_first, kept, order):
    qm, (Status, *_) = manager(
        clock, entries=[entry("Status", max_queue=2, newest_first=newest_first, ack=False)]
    )
    sizes = []
    qm.signal_queue_size_change.connect(lambda qs: sizes.append(qs.size))
    for v in (1, 2, 3):
        qm.push_message(Status(src=1, dest=2, value=v))
    assert sizes == [1, 2, 2]
    assert [i.msg.value for i in qm.queues[20].items()] == kept
    sent = []
    receiver, _ = manager(clock, modem_id=2, entries=[entry("Status")])
    for _ in range(2):
        clock.advance(1)
        sent += [x.value for x in decoded(receiver, fill(qm, max_bytes=7).frame[0])]
    assert sent == order


def test_ack_keeps_message_until_acknowledged_and_reoffers_it(clock):
    qm, (Status, *_) = manager(clock, entries=[entry("Status")])
    acks, sizes = [], []
    qm.signal_ack.connect(lambda ack, orig: acks.append((list(ack.acked_frame), orig.value)))
    qm.signal_queue_size_change.connect(lambda qs: sizes.append(qs.size))
    qm.push_message(Status(src=1, dest=2, value=7))
    clock.advance(1)
    r1 = fill(qm, frames=2)
    assert r1.ack_requested and r1.dest == 2 and r1.src == 1
    assert r1.frame[0] and r1.frame[1] == b"" and qm.size(20) == 1
    clock.advance(1)
    r2 = fill(qm, frame_start=2)  # no ack came: offered again
    assert r2.frame[0] == r1.frame[0]
    qm.handle_modem_receive(
        acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=2, dest=3, acked_frame=[2])
    )
    assert acks == [] and qm.size(20) == 1  # not for us
    qm.handle_modem_receive(
        acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=2, dest=1, acked_frame=[0])
    )
    assert acks == []  # the wait for frame 0 was released by the second request
    qm.handle_modem_receive(
        acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=2, dest=1, acked_frame=[2])
    )
    assert acks == [([2], 7)] and qm.size(20) == 0 and sizes[-1] == 0


def test_broadcast_never_requests_ack(clock):
    qm, (Status, *_) = manager(clock, entries=[entry("Status")])
    qm.push_message(Status(src=1, dest=0, value=1))
    clock.advance(1)
    r = fill(qm)
    assert not r.ack_requested and r.dest == 0 and qm.size(20) == 0


def test_packing_several_messages_per_frame_and_frames_per_packet(clock):
    qm, (Status, Bulk, _Note) = manager(
        clock, entries=[entry("Status", ack=False), entry("Bulk", ack=False)]
    )
    for v in range(5):
        qm.push_message(Status(src=1, dest=2, value=v))
    qm.push_message(Bulk(src=1, dest=2, payload=b"z" * 16))
    clock.advance(5)
    r = fill(qm, frames=3, max_bytes=32)
    assert all(len(f) <= 32 for f in r.frame)
    other, _ = manager(clock, modem_id=2, entries=[entry("Status"), entry("Bulk")])
    got = [x for f in r.frame for x in decoded(other, bytes(f))]
    assert sorted(x.value for x in got if x.DESCRIPTOR.name == "Status") == [0, 1, 2, 3, 4]
    assert [x.payload for x in got if x.DESCRIPTOR.name == "Bulk"] == [b"z" * 16]
    assert len(r.frame) == 3 and sum(1 for f in r.frame if f) == 2


def test_destination_and_ack_rules(clock):
    qm, (Status, *_) = manager(clock, entries=[entry("Status", newest_first=False)])
    qm.push_message(Status(src=1, dest=3, value=1))
    qm.push_message(Status(src=1, dest=2, value=2))
    clock.advance(1)
    assert fill(qm, dest=2).frame[0] == b""  # next item is for 3: skipped
    r = fill(qm, dest=3, ack_requested=False)
    assert r.frame[0] == b""  # needs an ack but the slot does not want one
    r = fill(qm, dest=3)
    assert [x.value for x in decoded(qm, bytes(r.frame[0]))] == []  # not for us (we are 1)


def test_receive_filters_and_manipulators(clock):
    Manip = acomms_pb.QueuedMessageEntry.DESCRIPTOR.fields_by_name[
        "manipulator"
    ].enum_type.values_by_name
    bulk = entry("Bulk")
    bulk.manipulator.append(Manip["PROMISCUOUS"].number)
    note = entry("Note", roles=False)
    note.manipulator.append(Manip["NO_DEQUEUE"].number)
    qm, (Status, Bulk, Note) = manager(clock, modem_id=2, entries=[entry("Status"), bulk, note])
    enc = qm.codec.encode
    frame = (
        enc(Status(src=1, dest=2, value=1))
        + enc(Status(src=1, dest=5, value=2))
        + enc(Bulk(src=1, dest=5, payload=b"p"))
        + enc(Note(value=3))
        + enc(Status(src=2, dest=0, value=4))
    )
    got = decoded(qm, frame)
    assert [(x.DESCRIPTOR.name, x.src) for x in got] == [("Status", 1), ("Bulk", 1)]


def test_push_to_self_loopback_and_errors(clock):
    Manip = acomms_pb.QueuedMessageEntry.DESCRIPTOR.fields_by_name[
        "manipulator"
    ].enum_type.values_by_name
    loop = entry("Bulk")
    loop.manipulator.extend([Manip["LOOPBACK"].number, Manip["NO_QUEUE"].number])
    qm, (Status, Bulk, Note) = manager(clock, entries=[entry("Status"), loop])
    got, acks = [], []
    qm.signal_receive.connect(got.append)
    qm.signal_ack.connect(lambda a, o: acks.append(a))
    qm.push_message(Status(src=1, dest=1, value=5))
    assert got[0].value == 5 and acks[0].src == acks[0].dest == 1 and qm.size(20) == 0
    qm.push_message(Bulk(src=1, dest=2))
    assert got[1].DESCRIPTOR.name == "Bulk" and qm.size(21) == 0
    with pytest.raises(QueueError, match="No queue exists"):
        qm.push_message(Note(value=1))


def test_on_demand(clock):
    Manip = acomms_pb.QueuedMessageEntry.DESCRIPTOR.fields_by_name[
        "manipulator"
    ].enum_type.values_by_name
    e = entry("Status", ack=False)
    e.manipulator.append(Manip["ON_DEMAND"].number)
    qm, (_Status, *_) = manager(clock, entries=[e])
    counter = iter(range(100))

    def make(req, msg):
        msg.src, msg.dest, msg.value = 1, 2, next(counter)

    qm.signal_data_on_demand.connect(make)
    clock.advance(1)
    r = fill(qm, max_bytes=7)
    assert [x.value for x in decoded(qm, bytes(r.frame[0]))] == []  # dest 2, we are 1
    other, _ = manager(clock, modem_id=2, entries=[entry("Status")])
    assert [x.value for x in decoded(other, bytes(r.frame[0]))] == [0]


def test_role_validation(clock):
    bad = entry("Status", roles=False)
    bad.role.add(type=Role.SOURCE_ID, field="nope")
    qm, _ = manager(clock)
    with pytest.raises(RoleError):
        qm.add_queue(bad)
    static = entry("Note", roles=False)
    static.role.add(type=Role.TIMESTAMP, setting=Role.STATIC, static_value=1)
    with pytest.raises(RoleError):
        qm.add_queue(static)


@pytest.mark.parametrize("bad_time", [float("nan"), float("inf")])
def test_non_finite_timestamp_is_a_role_error_and_keeps_the_queue(clock, bad_time):
    timed = entry("Status")
    timed.role.add(type=Role.TIMESTAMP, field="time")
    qm, (Status, *_) = manager(clock, entries=[timed])
    qm.push_message(Status(src=1, dest=2, time=T0, value=1))
    with pytest.raises(RoleError, match=r"TIMESTAMP field time is (nan|inf), not a time"):
        qm.push_message(Status(src=1, dest=2, time=bad_time, value=2))
    assert [x.value for x in decoded(qm_peer(clock), bytes(fill(qm).frame[0]))] == [1]


def qm_peer(clock):
    return manager(clock, modem_id=2, entries=[entry("Status")])[0]


def test_garbage_frames_are_logged_not_fatal(clock, caplog):
    qm, (Status, *_) = manager(clock, modem_id=2, entries=[entry("Status")])
    good = qm.codec.encode(Status(src=1, dest=2, value=9))
    with caplog.at_level(logging.WARNING):
        got = decoded(qm, good + b"\xff\xff\xff")
    assert [x.value for x in got] == [9] and "cannot decode" in caplog.text


@settings(max_examples=examples(200), deadline=None)
@given(st.binary(max_size=64))
def test_fuzz_receive_never_raises(data):
    qm, _ = FUZZ
    qm.handle_modem_receive(acomms_pb.ModemTransmission(type=acomms_pb.DATA, frame=[data]))


FUZZ = manager(VirtualClock(T0), modem_id=2, entries=[entry("Status"), entry("Bulk")])


def test_network_acks_for_configured_sources(clock):
    qm, (Status, *_) = manager(
        clock, entries=[entry("Status", ttl=60)], make_network_ack_for_src_id=[1]
    )
    got = []
    qm.signal_receive.connect(got.append)
    qm.push_message(Status(src=1, dest=2, value=1))
    qm.push_message(Status(src=1, dest=2, value=2))
    clock.advance(1)
    fill(qm, max_bytes=7)
    qm.handle_modem_receive(
        acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=2, dest=1, acked_frame=[0])
    )
    clock.advance(100)
    qm.do_work()
    kinds = [(a.ack_type, a.ack_src, a.message_src, a.message_dest, a.message_dccl_id) for a in got]
    assert kinds == [
        (acomms_pb.NetworkAck.ACK, 2, 1, 2, 20),
        (acomms_pb.NetworkAck.EXPIRE, 1, 1, 2, 20),
    ]


def test_encrypt_rules_per_peer(clock):
    rule = acomms_pb.QueueManagerConfig.EncryptRule
    q1, (Status, *_) = manager(
        clock,
        modem_id=1,
        entries=[entry("Status")],
        encrypt_rule=[rule(id=2, crypto_passphrase="two")],
    )
    q2, _ = manager(
        clock,
        modem_id=2,
        entries=[entry("Status")],
        encrypt_rule=[rule(id=1, crypto_passphrase="two")],
    )
    q2_wrong, _ = manager(
        clock,
        modem_id=2,
        entries=[entry("Status")],
        encrypt_rule=[rule(id=1, crypto_passphrase="other")],
    )
    msg = Status(src=1, dest=2, value=321)
    q1.push_message(msg)
    clock.advance(1)
    frame = bytes(fill(q1).frame[0])
    assert frame != q1.codec.encode(msg)  # the body is encrypted for peer 2
    assert [x.value for x in decoded(q2, frame)] == [321]
    assert [x.value for x in decoded(q2_wrong, frame)] != [321]


def test_loopback_as_sent_minimum_ack_wait_and_flush(clock):
    Manip = acomms_pb.QueuedMessageEntry.DESCRIPTOR.fields_by_name[
        "manipulator"
    ].enum_type.values_by_name
    e = entry("Status")
    e.manipulator.append(Manip["LOOPBACK_AS_SENT"].number)
    qm, (Status, *_) = manager(clock, entries=[e], minimum_ack_wait_seconds=10)
    looped = []
    qm.signal_receive.connect(looped.append)
    qm.push_message(Status(src=1, dest=2, value=1))
    assert looped == []
    clock.advance(1)
    first = fill(qm, frame_start=0)
    assert [x.value for x in looped] == [1]
    clock.advance(5)
    assert fill(qm, frame_start=1).frame[0] == b""  # still waiting: sent 5 s < 10 s ago
    clock.advance(6)
    assert fill(qm, frame_start=2).frame[0] == first.frame[0]  # released after 10 s
    sizes = []
    qm.signal_queue_size_change.connect(lambda qs: sizes.append((qs.dccl_id, qs.size)))
    qm.flush_queue(acomms_pb.QueueFlush(dccl_id=20))
    assert sizes == [(20, 0)] and qm.size(20) == 0


def test_unpack_frame_splits_packed_messages_and_stops_at_one_that_does_not_decode():
    """acomms.queue.frames.unpack_frame (the queue's receive path and the log tools): the
    messages one after another, each with its own bytes; bytes that do not decode end the
    frame and are reported at their offset."""
    from pygoby.acomms.queue.frames import unpack_frame
    from pygoby.dccl import Codec

    codec = Codec(clock=VirtualClock(1e9))
    status_cls, _bulk, note_cls = load_types(codec)
    status, note = status_cls(src=1, dest=2, value=7), note_cls(value=3)
    first, second = codec.encode(status), codec.encode(note)
    failures = []
    data = first + second + b"\xff\xff"
    unpacked = list(
        unpack_frame(data, lambda _rest: codec, lambda *failure: failures.append(failure))
    )
    assert [(msg.value, used) for msg, used in unpacked] == [(7, first), (3, second)]
    ((offset, error),) = failures
    assert offset == len(first) + len(second) and str(error)
    assert list(unpack_frame(b"", lambda _rest: codec, failures.append)) == []
