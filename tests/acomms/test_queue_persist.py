"""The persistent queue (queue_cfg.persistent_queue_file), sans I/O: a QueueManager whose
process "restarts" is a new manager on the same SQLite file. What was queued comes back with
its time; what was acknowledged, sent without ack, expired, pushed out or flushed does not.
The kill -9 of a real pAcommsHandler is in tests/apps/test_pacommshandler_persist.py."""

from __future__ import annotations

import logging
import sqlite3

import pytest
from google.protobuf import text_format
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.handler import AcommsHandler, HandlerError
from pygoby.acomms.queue import QueueError
from pygoby.acomms.queue.persist import QueueStore
from pygoby.util.clock import VirtualClock
from tests.hypothesis_profiles import examples

from .queue_helpers import Role, entry, manager

T0 = 1_700_000_000.0


@pytest.fixture
def clock():
    return VirtualClock(T0)


def restart(clock, path, entries):
    """A new manager on the file, as a restarted process makes it; (manager, types, expired)."""
    qm, types = manager(clock, entries=entries)
    expired = []
    qm.signal_expire.connect(lambda msg: expired.append(msg.value))
    qm.attach_store(QueueStore(path))
    return qm, types, expired


def sent_values(qm, Status, frame_start=0):
    """The values of what the next one-message data request carries."""
    one = len(qm.codec.encode(Status(src=1, dest=2, value=1, time=T0)))
    r = acomms_pb.ModemTransmission(
        src=-1, dest=-1, max_num_frames=1, frame_start=frame_start, max_frame_bytes=one
    )
    qm.handle_modem_data_request(r)
    return [qm.codec.decode(r.frame[0]).value] if r.frame[0] else []


def ack(qm, frame):
    qm.handle_modem_receive(
        acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=2, dest=1, acked_frame=[frame])
    )


def test_queued_messages_come_back_once_and_acked_ones_do_not(clock, tmp_path):
    path = tmp_path / "queue.sqlite"
    entries = [entry("Status", max_queue=10, ttl=600)]
    entries[0].role.add(type=Role.TIMESTAMP, field="time")
    qm, (Status, *_), _ = restart(clock, path, entries)
    for value in (1, 2, 3):
        qm.push_message(Status(src=1, dest=2, value=value, time=T0 + value))
    clock.advance(1)
    assert sent_values(qm, Status) == [3]  # newest first; awaiting its ack
    ack(qm, 0)  # 3 is delivered
    qm.store.close()  # the process dies (a closed connection or a killed process: same file)

    clock.advance(10)
    qm, (Status, *_), expired = restart(clock, path, entries)
    assert qm.size(20) == 2 and expired == []
    item = qm.queues[20].items()[0]
    assert (item.msg.value, item.msg.time, item.src, item.dest, item.ack_requested) == (
        1,
        T0 + 1,
        1,
        2,
        True,
    )
    assert item.time == int((T0 + 1) * 1e6)
    assert sent_values(qm, Status) == [2]
    ack(qm, 0)
    assert sent_values(qm, Status, frame_start=1) == [1]  # not acked: stays stored
    qm.store.close()

    qm, (Status, *_), _ = restart(clock, path, entries)
    assert [i.msg.value for i in qm.queues[20].items()] == [1]  # sent once, never acked
    ack_frame = 0
    assert sent_values(qm, Status) == [1]
    ack(qm, ack_frame)
    qm.store.close()
    qm, _, _ = restart(clock, path, entries)
    assert qm.size(20) == 0


def test_expired_while_away_expires_at_restart_and_is_never_sent(clock, tmp_path):
    path = tmp_path / "queue.sqlite"
    entries = [entry("Status", ttl=60)]
    entries[0].role.add(type=Role.TIMESTAMP, field="time")
    qm, (Status, *_), _ = restart(clock, path, entries)
    qm.push_message(Status(src=1, dest=2, value=5))
    qm.push_message(Status(src=1, dest=2, value=6, time=T0 + 50))
    qm.store.close()
    clock.advance(61)  # 5 (queued at T0) has expired; 6 (T0 + 50) has not
    qm, (Status, *_), expired = restart(clock, path, entries)
    assert expired == [5] and [i.msg.value for i in qm.queues[20].items()] == [6]
    qm.store.close()
    assert [s.queue for s in QueueStore(path).items()] == ["pygoby.test.acomms.Status"]


def test_sent_without_ack_pushed_out_and_flushed_are_forgotten(clock, tmp_path):
    path = tmp_path / "queue.sqlite"
    entries = [entry("Status", ack=False, max_queue=2), entry("Bulk")]
    qm, (Status, Bulk, _), _ = restart(clock, path, entries)
    for value in (1, 2, 3):  # max_queue 2, newest first: 1 is pushed out
        qm.push_message(Status(src=1, dest=2, value=value))
    qm.push_message(Bulk(src=1, dest=2, payload=b"x"))
    stored = {(s.queue.rsplit(".", 1)[1]) for s in qm.store.items()}
    assert stored == {"Status", "Bulk"} and len(qm.store.items()) == 3
    clock.advance(1)
    qm.queues[21].entry.value_base = 0.001  # let Status win the next slot
    assert sent_values(qm, Status) == [3]  # no ack requested: gone once sent
    qm.flush_queue(acomms_pb.QueueFlush(dccl_id=21))
    assert [Status.FromString(s.message).value for s in qm.store.items()] == [2]
    qm.store.close()
    qm, _, _ = restart(clock, path, entries)
    assert (qm.size(20), qm.size(21)) == (1, 0)


def test_a_type_no_longer_configured_stays_stored(clock, tmp_path, caplog):
    path = tmp_path / "queue.sqlite"
    qm, (_, Bulk, _), _ = restart(clock, path, [entry("Status"), entry("Bulk")])
    qm.push_message(Bulk(src=1, dest=2, payload=b"keep"))
    qm.store.close()
    with caplog.at_level(logging.WARNING):
        qm, _, _ = restart(clock, path, [entry("Status")])
    assert "a stored pygoby.test.acomms.Bulk is kept, but not sent" in caplog.text
    qm.store.close()
    qm, _, _ = restart(clock, path, [entry("Status"), entry("Bulk")])
    assert qm.size(21) == 1


def test_one_process_per_file_and_not_a_queue_file(clock, tmp_path):
    path = tmp_path / "queue.sqlite"
    first = QueueStore(path)
    with pytest.raises(QueueError, match="queue.sqlite: in use by another process"):
        QueueStore(path, lock_timeout=0.1)
    first.close()
    QueueStore(path).close()  # free again
    other = tmp_path / "other.sqlite"
    with sqlite3.connect(other) as db:
        db.execute("PRAGMA user_version = 7")
    with pytest.raises(QueueError, match="schema version 7"):
        QueueStore(other)
    text = tmp_path / "notes.txt"
    text.write_text("not a database at all " * 100)
    with pytest.raises(QueueError, match="notes.txt"):
        QueueStore(text)


PAGE = 4096  # SQLite's default page size


def _queue_file_of_several_pages(path) -> int:
    """A queue file whose table spans several b-tree pages; its number of pages."""
    store = QueueStore(path)
    with store.db:
        store.db.executemany(
            "INSERT INTO queued (queue, message, encoded, src, dest, time, ack_requested)"
            " VALUES ('Status', ?, ?, 1, 2, ?, 0)",
            [(b"m" * 100, b"e" * 50, k) for k in range(300)],
        )
    store.close()
    return path.stat().st_size // PAGE


@settings(
    max_examples=examples(25),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(page=st.integers(2, 1000), garbage=st.binary(min_size=7, max_size=64))
def test_a_damaged_inner_page_is_a_one_line_error(tmp_path_factory, page, garbage):
    # issue 25, item 10: a page of the file overwritten (its header first: a page type SQLite
    # does not know) used to surface as a sqlite3.DatabaseError traceback at start
    path = tmp_path_factory.mktemp("damaged") / "queue.sqlite"
    pages = _queue_file_of_several_pages(path)
    page = 2 + page % (pages - 1)
    data = bytearray(path.read_bytes())
    data[(page - 1) * PAGE : (page - 1) * PAGE + 1 + len(garbage)] = b"\xff" + garbage
    path.write_bytes(data)
    with pytest.raises(QueueError, match="queue.sqlite: .*move it aside") as caught:
        QueueStore(path)
    assert "\n" not in str(caught.value)


def test_pacommshandler_names_the_damaged_queue_file(tmp_path):
    path = tmp_path / "queue.sqlite"
    pages = _queue_file_of_several_pages(path)
    data = bytearray(path.read_bytes())
    data[PAGE * (pages - 1) : PAGE * (pages - 1) + 8] = b"\xff" * 8  # the last page's header
    path.write_bytes(data)
    from pygoby.apps.pacommshandler import pAcommsHandler

    cfg = pAcommsHandler.load_config_class()()
    text_format.Merge(f'modem_id: 1 queue_cfg {{ persistent_queue_file: "{path}" }}', cfg)
    handler = AcommsHandler(cfg, clock=VirtualClock(T0))
    with pytest.raises(HandlerError, match=r"^queue_cfg persistent_queue_file: persistent queue "):
        handler.configure_queue(lambda name: acomms_pb.ModemTransmission)


def test_a_failed_write_is_logged_and_the_queue_goes_on(clock, tmp_path, caplog):
    path = tmp_path / "queue.sqlite"
    qm, (Status, *_), _ = restart(clock, path, [entry("Status")])
    qm.store.db.execute("DROP TABLE queued")  # what a full disk or a corrupted file would do
    with caplog.at_level(logging.ERROR):
        qm.push_message(Status(src=1, dest=2, value=9))
    assert "cannot record a change" in caplog.text
    assert qm.size(20) == 1
    clock.advance(1)
    assert sent_values(qm, Status) == [9]
