"""Priority queue throughput with 100,000 queued messages (`make bench`).

The contest visits queues, not messages, so a data request costs the same with 10 or 100,000
messages waiting; push costs one DCCL encode.
"""

import importlib.util
from pathlib import Path

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.util.clock import VirtualClock

# the test DCCL types and queue set-up shared with tests/acomms (loaded by path: the test
# folder's package name would clash with the PyPI `acomms` package)
_HELPERS = Path(__file__).resolve().parents[1] / "tests" / "acomms" / "queue_helpers.py"
_spec = importlib.util.spec_from_file_location("acomms_queue_helpers", _HELPERS)
_helpers = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_helpers)
entry, manager = _helpers.entry, _helpers.manager

QUEUED = 100_000


def _loaded_manager(ack: bool):
    clock = VirtualClock(1_700_000_000.0)
    qm, (Status, _Bulk, _Note) = manager(
        clock,
        entries=[
            entry("Status", ack=ack, max_queue=0, ttl=0),
            entry("Bulk", ack=ack, max_queue=0, ttl=0, value_base=2),
        ],
    )
    template = Status(src=1, dest=2, value=1)
    for i in range(QUEUED):
        template.value = i % 1000
        qm.push_message(template)
    return clock, qm, Status


@pytest.fixture(scope="module")
def loaded():
    return _loaded_manager(ack=False)


def test_pop_one_frame_with_100k_queued(benchmark, loaded):
    clock, qm, _ = loaded

    def pop():
        clock.advance(0.001)
        request = acomms_pb.ModemTransmission(src=1, dest=-1, max_num_frames=1, max_frame_bytes=32)
        qm.handle_modem_data_request(request)
        return request

    request = benchmark(pop)
    assert request.frame[0]
    assert qm.size(20) > QUEUED // 2  # still ~100k queued while measuring


def test_push_with_100k_queued(benchmark, loaded):
    _clock, qm, Status = loaded
    msg = Status(src=1, dest=2, value=3)
    benchmark(qm.push_message, msg)
    assert qm.size(20) > QUEUED // 2


def test_acked_pop_and_ack_with_100k_queued(benchmark):
    clock, qm, _ = _loaded_manager(ack=True)
    frame = iter(range(10**9))

    def pop_and_ack():
        clock.advance(0.001)
        n = next(frame)
        request = acomms_pb.ModemTransmission(
            src=1, dest=-1, max_num_frames=1, max_frame_bytes=32, frame_start=n
        )
        qm.handle_modem_data_request(request)
        qm.handle_modem_receive(
            acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=2, dest=1, acked_frame=[n])
        )

    benchmark(pop_and_ack)
    assert qm.size(20) < QUEUED


@pytest.mark.parametrize("direction", ["serialize", "parse"])
def test_rudics_largest_packet(benchmark, direction):
    """One store-server packet at the size limit (64 KiB): the longest the server's event loop
    is held by one request's framing (the digit-by-digit conversion took ~4 s)."""
    import os

    from pygoby.acomms.rudics import max_data_bytes, parse_rudics_packet, serialize_rudics_packet

    data = os.urandom(max_data_bytes())
    if direction == "serialize":
        benchmark.pedantic(serialize_rudics_packet, (data,), rounds=3)
    else:
        packet = serialize_rudics_packet(data)
        assert benchmark.pedantic(parse_rudics_packet, (packet,), rounds=3) == data
