"""The sans-I/O MOOS codec against every recorded vector, plus framing limits and fuzzing."""

from __future__ import annotations

import contextlib
import json
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.moos import protocol as p
from tests.hypothesis_profiles import examples


def _load(vectors_dir, name):
    with open(vectors_dir / "moos" / name) as f:
        return [json.loads(line) for line in f if line.strip()]


def _msg_from_record(rec) -> p.MOOSMessage:
    return p.MOOSMessage(
        msg_type=rec["msg_type"],
        data_type=rec["data_type"],
        key=rec["key"],
        time=rec["time"],
        dval=rec["dval"],
        dval2=rec["dval2"],
        sval=bytes.fromhex(rec["sval_hex"]),
        src=rec["src"],
        src_aux=rec["src_aux"],
        community=rec["community"],
        id=rec["id"],
    )


def _check_fields(msg: p.MOOSMessage, rec) -> None:
    for name in ("msg_type", "data_type", "key", "src", "src_aux", "community", "id"):
        assert getattr(msg, name) == rec[name], name
    for name in ("time", "dval", "dval2"):
        assert getattr(msg, name) == rec[name], name
    assert msg.sval == bytes.fromhex(rec["sval_hex"])
    if rec["sval"] is not None and msg.data_type != p.BINARY:
        assert msg.string == rec["sval"]


def test_every_single_message_vector_round_trips(vectors_dir):
    records = _load(vectors_dir, "messages.jsonl")
    assert len(records) >= 27
    for rec in records:
        raw = bytes.fromhex(rec["hex"])
        msg, end = p.decode_message(raw)
        assert end == len(raw) == rec["msg_len"]
        _check_fields(msg, rec)
        assert p.encode_message(_msg_from_record(rec)) == raw
        assert msg.encoded_size() == len(raw)


def test_every_session_packet_round_trips(vectors_dir):
    units = _load(vectors_dir, "sessions.jsonl")
    packets = [u for u in units if u["unit"] == "packet"]
    assert len(packets) > 100
    for unit in packets:
        raw = bytes.fromhex(unit["hex"])
        msgs = p.decode_packet(raw)
        dec = unit["decoded"]
        assert len(msgs) == dec["n_msgs"] == len(dec["msgs"])
        for msg, rec in zip(msgs, dec["msgs"], strict=True):
            _check_fields(msg, rec)
        assert p.encode_packet(_msg_from_record(r) for r in dec["msgs"]) == raw
        # the framer cuts the same packet out of a byte-at-a-time stream
        framer = p.PacketFramer()
        out = []
        for i in range(len(raw)):
            buf, spans = framer.feed(raw[i : i + 1])
            out.extend(buf[start:end] for start, end in spans)
        assert out == [raw] and framer.buffered == 0


def test_protocol_string_matches_recording(vectors_dir):
    units = _load(vectors_dir, "sessions.jsonl")
    good = next(
        u for u in units if u["unit"] == "protocol_string" and "bad_protocol" not in u["tags"]
    )
    assert bytes.fromhex(good["hex"]) == p.PROTOCOL_STRING
    assert p.check_protocol_string(p.PROTOCOL_STRING)
    assert p.check_protocol_string(p.PROTOCOL_STRING.lower())
    bad = next(u for u in units if "bad_protocol" in u["tags"] and u["unit"] == "protocol_string")
    assert not p.check_protocol_string(bytes.fromhex(bad["hex"]))
    assert not p.check_protocol_string(p.PROTOCOL_STRING[:20])


def test_builders_match_recorded_bytes(vectors_dir):
    by_seq = {u["seq"]: u for u in _load(vectors_dir, "sessions.jsonl")}
    hs = p.decode_packet(bytes.fromhex(by_seq[1]["hex"]))[0]
    built = p.handshake_message("uPokeDB", hs.time)
    assert p.encode_packet([built]) == bytes.fromhex(by_seq[1]["hex"])
    w = p.decode_packet(bytes.fromhex(by_seq[2]["hex"]))[0]
    assert p.encode_packet(
        [p.welcome_message("alpha", "localhost", w.time, w.dval)]
    ) == bytes.fromhex(by_seq[2]["hex"])
    assert p.welcome_hostname(w) == "localhost"
    t = p.decode_packet(bytes.fromhex(by_seq[96]["hex"]))[0]
    assert p.encode_packet([p.timing_message(t.time)]) == bytes.fromhex(by_seq[96]["hex"])
    k = p.decode_packet(bytes.fromhex(by_seq[110]["hex"]))[0]
    assert p.encode_packet(
        [p.poison_message(p.name_in_use_reason("dup"), k.time)]
    ) == bytes.fromhex(by_seq[110]["hex"])
    pub = p.decode_packet(bytes.fromhex(by_seq[10]["hex"]))
    built = [
        p.notify("FOO", 3.5, time=pub[0].time, src="uPokeDB", msg_id=9),
        p.notify("BAR", "hello", time=pub[1].time, src="uPokeDB", msg_id=10),
    ]
    assert p.encode_packet(built) == bytes.fromhex(by_seq[10]["hex"])
    blob = p.decode_packet(bytes.fromhex(by_seq[94]["hex"]))[1]
    assert blob.value == b"\x00\xff\x10"
    rebuilt = p.notify("BLOB", blob.value, time=blob.time, src="wildprobe", msg_id=4)
    assert p.encode_message(rebuilt) == p.encode_message(blob)


def test_wildcard_sval_round_trip(vectors_dir):
    by_seq = {u["seq"]: u for u in _load(vectors_dir, "sessions.jsonl")}
    star = p.decode_packet(bytes.fromhex(by_seq[29]["hex"]))[4]
    assert star.msg_type == p.WILDCARD_REGISTER
    app, var, interval = p.parse_wildcard_sval(star.sval)
    assert (app, var) == ("u*", "*_DEPTH")
    assert p.wildcard_sval(app, var, interval) == star.sval
    assert p.format_interval(1e-05) == "1e-05"
    assert p.parse_wildcard_sval(b" VarPattern= X* ,AppPattern=a") == ("a", "X*", 0.0)
    assert p.parse_wildcard_sval(b"AppPattern=*,VarPattern=*,Interval=abc")[2] == 0.0


@pytest.mark.parametrize(
    ("pattern", "name", "expected"),
    [
        ("*", "", True),
        ("NAV_*", "NAV_X", True),
        ("NAV_?", "NAV_XY", False),
        ("*_DEPTH", "NAV_DEPTH", True),
        ("[ab]", "a", False),
        ("[ab]", "[ab]", True),
        ("nav*", "NAV_X", False),
        ("", "", True),
        ("", "X", False),
        ("a.c", "abc", False),
    ],
)
def test_wildcard_match(pattern, name, expected):
    assert p.wildcard_match(pattern, name) is expected


def _reference_glob(pattern: str, name: str) -> bool:
    """MOOSWildCmp's meaning by dynamic programming: can pattern[:i] match name[:j]?"""
    row = [True] + [False] * len(name)
    for c in pattern:
        if c == "*":
            row = [any(row[: j + 1]) for j in range(len(name) + 1)]
        else:
            row = [False] + [row[j] and c in ("?", name[j]) for j in range(len(name))]
    return row[-1]


@settings(max_examples=examples(2000), deadline=None)
@given(st.text("ab*?", max_size=8), st.text("abc", max_size=10))
def test_glob_agrees_with_the_definition(pattern, name):
    assert p.Glob(pattern).match(name) is _reference_glob(pattern, name)


@pytest.mark.timeout(10)  # a backtracking matcher takes hours here (issue 16, item 1)
def test_glob_has_no_catastrophic_backtracking():
    name = "a" * 200
    for pattern in ("*a*a*a*a*a*a*a*a*a*a*b", "*?a*?a*?a*?a*?a*?a*?a*?a*b", "a*" * 50 + "b"):
        assert not p.Glob(pattern).match(name)
    assert p.Glob("*a*a*a*a*a*a*a*a*a*a").match(name)


@settings(max_examples=examples(1000), deadline=None)
@given(st.text("a?*", max_size=30), st.text("ab", max_size=40))
def test_glob_with_many_question_marks_agrees_with_the_definition(pattern, name):
    assert p.Glob(pattern).match(name) is _reference_glob(pattern, name)


@pytest.mark.timeout(10)  # a match cost len(name) x len(pattern) steps: ~21 s here (issue 25, 1)
def test_glob_matching_is_linear_in_the_name():
    name = "a" * 30_000
    for pattern in ("*" + "?" * 2000 + "X*", "*" + "a?" * 1000 + "X*", "*?a?*" * 300 + "X"):
        assert not p.Glob(pattern).match(name)
    assert p.Glob("*" + "?" * 2000 + "a*").match(name)


def test_rejects_malformed_packets():
    good = p.encode_packet([p.notify("X", 1.0, time=1.0, src="a")])
    with pytest.raises(p.MoosProtocolError):
        p.decode_packet(good[:-1])
    with pytest.raises(p.MoosProtocolError):
        p.decode_packet(struct.pack("<iiB", 5, 1, 0))
    with pytest.raises(p.MoosProtocolError):
        p.decode_packet(struct.pack("<iiB", 9, -1, 0))
    with pytest.raises(p.MoosProtocolError):  # trailing garbage
        p.decode_packet(struct.pack("<iiB", len(good) + 3, 1, 0) + good[9:] + b"abc")
    with pytest.raises(p.MoosProtocolError):  # string length past the message end
        bad = bytearray(good)
        bad[9 + 10 : 9 + 14] = struct.pack("<i", 10_000)
        p.decode_packet(bytes(bad))
    with pytest.raises(ValueError):
        p.encode_packet([])


def test_framer_refuses_oversized_packet_from_its_header():
    framer = p.PacketFramer(max_packet_size=1000)
    with pytest.raises(p.MoosProtocolError, match="exceeds the limit"):
        framer.feed(struct.pack("<iiB", 2**31 - 1, 1, 0))


def test_unknown_types_are_passed_up():
    msg = p.MOOSMessage(msg_type="Z", data_type="?", key="k")
    assert p.decode_message(p.encode_message(msg))[0] == msg


def test_notify_types():
    assert p.notify("A", 2, time=0).data_type == p.DOUBLE
    assert p.notify("A", "s", time=0).value == "s"
    assert p.notify("A", b"\0", time=0).data_type == p.BINARY
    with pytest.raises(TypeError):
        p.notify("A", True, time=0)
    odd = p.notify("A", "caf\udce9", time=0)  # undecodable byte survives
    assert odd.sval == b"caf\xe9" and odd.string == "caf\udce9"


@settings(max_examples=examples(200), deadline=None)
@given(st.binary(max_size=300))
def test_fuzz_decode_packet_never_crashes(data):
    with contextlib.suppress(p.MoosProtocolError):
        p.decode_packet(data)


@settings(max_examples=examples(200), deadline=None)
@given(st.lists(st.binary(max_size=80), max_size=5))
def test_fuzz_framer_never_crashes(chunks):
    framer = p.PacketFramer(max_packet_size=500)
    try:
        for chunk in chunks:
            buf, spans = framer.feed(chunk)
            for start, end in spans:
                with contextlib.suppress(p.MoosProtocolError):
                    p.decode_packet(buf, start, end)
    except p.MoosProtocolError:
        pass


@settings(max_examples=examples(300), deadline=None)
@given(st.lists(st.integers(1, 40), max_size=30), st.integers(1, 6))
def test_framer_cuts_a_stream_cut_anywhere(cuts, n_packets):
    """However TCP cuts the stream, the framer gives back the packets, each exactly once."""
    packets = [
        p.encode_packet([p.notify(f"K{i}", float(j), time=1.0) for j in range(i % 3 + 1)])
        for i in range(n_packets)
    ]
    stream = b"".join(packets)
    framer = p.PacketFramer()
    out, pos = [], 0
    for cut in [*cuts, len(stream)]:
        buf, spans = framer.feed(stream[pos : pos + cut])
        out.extend(buf[start:end] for start, end in spans)
        pos += cut
        if pos >= len(stream):
            break
    assert out == packets and framer.buffered == 0


_text = st.text(max_size=20)


@settings(max_examples=examples(200), deadline=None)
@given(
    st.builds(
        p.MOOSMessage,
        msg_type=st.sampled_from("NRU*/QT.iWK"),
        data_type=st.sampled_from("DSB~"),
        key=_text,
        time=st.floats(allow_nan=False),
        dval=st.floats(allow_nan=False),
        dval2=st.floats(allow_nan=False),
        sval=st.binary(max_size=40),
        src=_text,
        src_aux=_text,
        community=_text,
        id=st.integers(-(2**31), 2**31 - 1),
    )
)
def test_fuzz_round_trip(msg):
    assert p.decode_packet(p.encode_packet([msg])) == [msg]
