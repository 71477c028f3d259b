"""The NETSIM line codec against every protocol vector, plus fuzzing of the line decoder."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from netsim_vectors import by_id, from_vector_dict, of_kind, to_vector_dict

from pygoby.netsim.manager.protocol import (
    LEGACY_REQUEST_NAME,
    REQUEST_NAME,
    LineDecoder,
    LineTooLongError,
    MissingSeparatorError,
    ReceivedMessage,
    UnknownNameError,
    b64decode_libb64,
    b64encode,
    encode_line,
    request_class,
    request_names,
    response_class,
    response_names,
)
from tests.hypothesis_profiles import examples


def _accepted(direction: str):
    return request_names() if direction == "request" else response_names()


def _class(direction: str):
    return request_class() if direction == "request" else response_class()


@pytest.mark.parametrize("vector", of_kind("line"), ids=lambda v: v["id"])
def test_line_decodes_to_vector(vector):
    decoder = LineDecoder(_accepted(vector["direction"]))
    (event,) = decoder.feed(vector["line"].encode())
    assert isinstance(event, ReceivedMessage)
    assert event.name == vector["name"]
    assert event.legacy is vector["legacy_name"]
    assert event.parse_error is None
    assert event.message.SerializePartialToString().hex() == vector["payload_hex"]
    assert to_vector_dict(event.message) == vector["decoded"]


@pytest.mark.parametrize("vector", of_kind("line"), ids=lambda v: v["id"])
def test_line_encodes_exactly(vector):
    message = from_vector_dict(_class(vector["direction"]), vector["decoded"])
    assert encode_line(message, vector["name"]).decode() == vector["line"]


def test_seed_example_values():
    """The seed document's two lines decode to the values spec §3.7 gives."""
    decoder = LineDecoder({**request_names(), **response_names()})
    request, response = decoder.feed(
        (by_id("seed-request")["line"] + by_id("seed-response")["line"]).encode()
    )
    assert request.message.id == 66
    (nav,) = request.message.nav
    assert (nav.modem_tcp_port, nav.time, nav.lat, nav.lon) == (
        62003,
        1605032069.3209999,
        71.17647166666667,
        -142.40123666666668,
    )
    assert (nav.depth, nav.speed, nav.heading) == (0.3, 0.001108602724153247, 15.0)
    assert response.message.request_id == 65
    assert response.message.status == response_class().UPDATE_ACCEPTED


def test_default_name_is_the_current_packaged_name():
    message = request_class()(id=3)
    assert encode_line(message).startswith(b"NETSIM|" + REQUEST_NAME.encode() + b"|")


@pytest.mark.parametrize("vector", of_kind("base64_decode"), ids=lambda v: v["id"])
def test_base64_decode_like_libb64(vector):
    assert b64decode_libb64(vector["input"].encode()).hex() == vector["bytes_hex"]


def test_base64_encode_is_single_line_form():
    (vector,) = of_kind("base64_encode")
    data = bytes.fromhex(vector["bytes_hex"])
    assert b64encode(data).decode() == vector["wire_form"]
    assert b64decode_libb64(vector["libb64_output"].encode()) == data


@pytest.mark.parametrize("vector", of_kind("parse"), ids=lambda v: v["id"])
def test_parse_vectors_at_manager_and_client(vector):
    raw = vector["raw"].encode()
    is_response = vector["manager_responds"] is None
    events = LineDecoder(response_names() if is_response else request_names()).feed(raw)
    if vector["name"] is None and vector["raw"].strip() == "":
        assert events == []
        return
    (event,) = events
    if vector["dispatch"] is False:
        assert isinstance(event, (UnknownNameError, MissingSeparatorError))
        if vector["name"] is not None:
            assert isinstance(event, UnknownNameError)
            assert event.name == vector["name"].encode()
        return
    # dispatched: True, or "legacy" (pygoby accepts the legacy name too)
    assert isinstance(event, ReceivedMessage)
    assert event.name == vector["name"]
    assert event.message.SerializePartialToString().hex() == vector["payload_hex"]
    assert to_vector_dict(event.message) == vector["decoded"]
    assert event.legacy is (vector["dispatch"] == "legacy")


def test_partial_payload_is_reported_and_kept():
    (event,) = LineDecoder(request_names()).feed(b"NETSIM|" + REQUEST_NAME.encode() + b"|CAf/\n")
    assert event.parse_error is not None
    assert event.message.id == 7


def test_line_without_separators_resyncs_on_next_line():
    good = encode_line(request_class()(id=5))
    events = LineDecoder(request_names()).feed(b"hello\n" + good)
    assert isinstance(events[0], MissingSeparatorError)
    assert events[1].message.id == 5


def test_response_name_is_unknown_to_a_manager():
    line = encode_line(response_class()(request_id=1, status=1))
    (event,) = LineDecoder(request_names()).feed(line)
    assert isinstance(event, UnknownNameError)


def test_ten_megabyte_line_is_discarded_without_buffering():
    decoder = LineDecoder(request_names(), max_line_length=1 << 20)
    chunk = b"A" * 65536
    events = []
    for _ in range(160):  # 10 MiB with no newline
        events += decoder.feed(chunk)
        assert decoder.buffered <= decoder.max_line_length
    events += decoder.feed(b"tail|of|it\n" + encode_line(request_class()(id=9)))
    assert [type(e) for e in events] == [LineTooLongError, ReceivedMessage]
    assert events[1].message.id == 9


def test_long_line_ending_inside_the_same_chunk():
    decoder = LineDecoder(request_names(), max_line_length=100)
    events = decoder.feed(b"x" * 500 + b"\n" + encode_line(request_class()(id=1)))
    assert [type(e) for e in events] == [LineTooLongError, ReceivedMessage]


def test_byte_at_a_time_equals_whole_stream():
    stream = b"".join(
        encode_line(request_class()(id=i), LEGACY_REQUEST_NAME if i % 2 else None) for i in range(5)
    )
    decoder = LineDecoder(request_names())
    events = [e for b in stream for e in decoder.feed(bytes([b]))]
    assert [e.message.id for e in events] == list(range(5))
    assert [e.legacy for e in events] == [False, True, False, True, False]


_tokens = st.sampled_from(
    [
        b"NETSIM",
        b"|",
        b"\n",
        b"\r",
        REQUEST_NAME.encode(),
        LEGACY_REQUEST_NAME.encode(),
        b"CAA=",
        b"////",
        b"=",
        b" ",
        b"\xff\x00",
    ]
)


@settings(max_examples=examples(200), deadline=None)
@given(
    garbage=st.lists(st.one_of(st.binary(max_size=64), _tokens), max_size=30),
    cuts=st.lists(st.integers(min_value=0, max_value=2000), max_size=8),
)
def test_fuzz_garbage_then_a_good_line_always_decodes(garbage, cuts):
    """Whatever came before and however TCP split it, the line after a newline decodes."""
    good = encode_line(request_class()(id=4242))
    stream = b"".join(garbage) + b"\n" + good
    decoder = LineDecoder(request_names(), max_line_length=256)
    events = []
    start = 0
    for cut in sorted(c for c in cuts if c < len(stream)):
        events += decoder.feed(stream[start:cut])
        start = cut
        assert decoder.buffered <= 256
    events += decoder.feed(stream[start:])
    last = events[-1]
    assert isinstance(last, ReceivedMessage) and last.message.id == 4242
    for event in events[:-1]:
        assert isinstance(
            event, (ReceivedMessage, LineTooLongError, MissingSeparatorError, UnknownNameError)
        )


@settings(max_examples=examples(200), deadline=None)
@given(st.binary(max_size=300))
def test_fuzz_base64_decoder_total(data):
    decoded = b64decode_libb64(data)
    assert b64decode_libb64(b64encode(decoded)) == decoded
