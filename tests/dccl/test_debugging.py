"""Debugging generated DCCL code: tracebacks with source, field-named slots, the per-field trace."""

from __future__ import annotations

import linecache
import logging
import textwrap
import traceback
from pathlib import Path

import pytest

from pygoby.dccl import Codec, DcclDecodeError, DcclEncodeError, FieldCodec, FixedWidthCodec
from pygoby.util.clock import VirtualClock
from tests.dccl.vectors import VectorCodecs, message_class, parse_text, read_jsonl

HEADER = 'syntax = "proto2";\nimport "dccl/option_extensions.proto";\npackage dbg;\n'
PARTS = ("encode_head", "encode_body", "decode_head", "decode_body")


def load(tmp_path: Path, body: str, name: str, codec: Codec):
    path = tmp_path / f"{name.lower()}.proto"
    path.write_text(HEADER + textwrap.dedent(body))
    return codec.load_proto(path, f"dbg.{name}")


def traceback_text(exc: BaseException) -> str:
    return "".join(traceback.format_exception(exc))


def test_a_failing_field_shows_the_generated_line_under_the_type_name() -> None:
    cls = message_class("example.proto", "example.Tiny")
    with pytest.raises(DcclEncodeError) as caught:
        Codec(strict=True).encode(cls(a=9))
    text = traceback_text(caught.value)
    assert 'File "<dccl example.Tiny encode_body>", line ' in text
    assert "in encode_body\n    acc |= enc_a(m0.a, strict) << pos\n" in text


class RefusingCodec(FixedWidthCodec):
    """A user codec whose decoder rejects the raw value 1 (with a plain ValueError)."""

    bits = 1

    def to_raw(self, value, strict) -> int:
        return 1

    def from_raw(self, raw: int):
        raise ValueError(f"raw value {raw} refused")


def test_a_failing_user_codec_on_decode_shows_its_field(tmp_path: Path) -> None:
    codec = Codec()
    codec.registry.register("dbg.refusing", ["uint32"], RefusingCodec)
    cls = load(
        tmp_path,
        """
        message Refused { option (dccl.msg) = { id: 3 max_bytes: 4 codec_version: 4 };
          required uint32 depth = 1 [(dccl.field).codec = 'dbg.refusing']; }""",
        "Refused",
        codec,
    )
    with pytest.raises(DcclDecodeError, match="raw value 1 refused") as caught:
        codec.decode(codec.encode(cls(depth=1)))
    text = traceback_text(caught.value)
    assert 'File "<dccl dbg.Refused decode_body>"' in text
    assert "v = dec_depth(b >> pos & 1)\n" in text


def test_source_is_kept_per_part_and_registered_with_linecache() -> None:
    codec = Codec()
    compiled = codec.compiled(codec.load(message_class("example.proto", "example.Example")))
    assert set(compiled.source) == set(PARTS)
    for part in PARTS:
        lines = compiled.source[part].splitlines()
        assert lines[0].startswith(f"# example.Example: {part.replace('_', ' the ')}.")
        assert f"def {part}(" in compiled.source[part]
        assert "_trace" not in compiled.source[part]  # without trace: no hooks at all
        filename = f"<dccl example.Example {part}>"
        assert [linecache.getline(filename, n + 1).rstrip("\n") for n in range(len(lines))] == lines
    body = compiled.source["encode_body"]
    assert "#   enc_temperature = NumericCodec.to_raw for example.Example.temperature" in body
    assert "acc |= enc_pos_lat(m_pos.lat, strict) << pos" in body
    assert "for v_readings in vals_readings:" in body
    assert "v = dec_pos_depth(b >> pos & 1023)" in compiled.source["decode_body"]


def test_slot_names_follow_nested_and_repeated_fields_and_stay_unique(tmp_path: Path) -> None:
    codec = Codec()
    cls = load(
        tmp_path,
        """
        message Inner { optional uint32 lat = 1 [(dccl.field) = { min: 0 max: 7 }]; }
        message Names { option (dccl.msg) = { id: 4 max_bytes: 16 codec_version: 4 };
          optional Inner pos = 1;
          optional uint32 pos_lat = 2 [(dccl.field) = { min: 0 max: 7 }];
          repeated Inner list = 3 [(dccl.field).max_repeat = 2];
          repeated uint32 values = 4 [(dccl.field) = { min: 0 max: 3 max_repeat: 2 }]; }""",
        "Names",
        codec,
    )
    source = codec.compiled(cls).source
    assert "acc |= enc_pos_lat(m_pos.lat, strict) << pos" in source["encode_body"]
    assert "acc |= enc_pos_lat_2(m0.pos_lat, strict) << pos" in source["encode_body"]
    assert "acc |= enc_list_lat(m_list.lat, strict) << pos" in source["encode_body"]
    assert "acc |= enc_values(v_values, strict) << pos" in source["encode_body"]
    assert "v = dec_pos_lat_2(b >> pos & 15)" in source["decode_body"]
    msg = cls(pos={"lat": 1}, pos_lat=2, list=[{"lat": 3}, {"lat": 4}], values=[1, 2])
    assert codec.decode(codec.encode(msg)) == msg


class FailingCodec(FieldCodec):
    """A variable-size user codec that cannot encode anything."""

    def encode(self, value, strict):
        raise ValueError("cannot encode this")

    def min_size(self) -> int:
        return 0

    def max_size(self) -> int:
        return 8


class ParityCodec(FixedWidthCodec):
    bits = 1

    def to_raw(self, value, strict) -> int:
        return value & 1

    def from_raw(self, raw: int) -> int:
        return raw


def test_two_codecs_generating_different_code_for_one_type_keep_their_own_source(
    tmp_path: Path,
) -> None:
    proto = """
        message Twice { option (dccl.msg) = { id: 5 max_bytes: 4 codec_version: 4 };
          required uint32 n = 1 [(dccl.field).codec = 'dbg.twice']; }"""
    parity, failing = Codec(), Codec()
    parity.registry.register("dbg.twice", ["uint32"], ParityCodec)
    failing.registry.register("dbg.twice", ["uint32"], FailingCodec)
    cls = load(tmp_path, proto, "Twice", parity)
    failing.load(cls)
    assert parity.encode(cls(n=3)).hex() == "0a01"
    with pytest.raises(DcclEncodeError, match="cannot encode this") as caught:
        failing.encode(cls(n=3))
    text = traceback_text(caught.value)
    assert 'File "<dccl dbg.Twice encode_body #2>"' in text
    assert "in encode_body\n    r, n = enc_n(m0.n, strict)\n" in text
    parity_source = "".join(linecache.getlines("<dccl dbg.Twice encode_body>"))
    assert parity_source == parity.compiled(cls).source["encode_body"]
    assert "acc |= enc_n(m0.n, strict) << pos\n" in parity_source


def trace_lines(caplog) -> list[str]:
    lines = [r.getMessage() for r in caplog.records if r.name == "pygoby.dccl.trace"]
    caplog.clear()
    return lines


def test_trace_logs_each_field_with_its_value_and_bits(caplog) -> None:
    cls = message_class("example.proto", "example.Tiny")
    codec = Codec(trace=True)
    caplog.set_level(logging.DEBUG, logger="pygoby.dccl.trace")
    data = codec.encode(cls(a=5, b=3, c=True))
    assert data.hex() == "042501"
    assert trace_lines(caplog) == [
        "encode example.Tiny head: (id) = 2 (8 bits: 00000100)",
        "encode example.Tiny body: a = 5 (3 bits: 101)",
        "encode example.Tiny body: b = 3 (4 bits: 0100)",  # raw 4: the value + 1 (0 = not set)
        "encode example.Tiny body: c = True (2 bits: 10)",
    ]
    assert codec.decode(bytes.fromhex("040500")) == cls(a=5)
    records = [r for r in caplog.records if r.name == "pygoby.dccl.trace"]
    assert [(r.dccl_field, r.dccl_value, r.dccl_bits) for r in records] == [
        ("(id)", 2, 8),
        ("a", 5, 3),
        ("b", None, 4),
        ("c", None, 2),
    ]
    assert records[2].getMessage() == "decode example.Tiny body: b = not set (4 bits: 0000)"


def test_trace_shows_enum_names_nested_and_repeated_fields(caplog) -> None:
    codec = Codec(trace=True)
    cls = codec.load(message_class("example.proto", "example.Example"))
    caplog.set_level(logging.DEBUG, logger="pygoby.dccl.trace")
    codec.encode(
        cls(
            count=1,
            temperature=2,
            flag=True,
            mode=5,
            readings=[1, 2],
            pos={"lat": 41.5, "lon": -70.25},
        )
    )
    lines = trace_lines(caplog)
    assert "encode example.Example body: mode = MODE_TRANSIT (2 bits: 10)" in lines
    assert "encode example.Example body: flag = True (1 bit: 1)" in lines
    assert "encode example.Example body: readings = [1, 2] (19 bits: 0000001000000001010)" in lines
    assert (
        "encode example.Example body: pos.lat = 41.5 (25 bits: 0110010001010011100110000)" in lines
    )
    nested = [line for line in lines if ": pos" in line]
    assert [line.split(" = ")[0] for line in nested] == [
        "encode example.Example body: pos.lat",
        "encode example.Example body: pos.lon",
        "encode example.Example body: pos.depth",
        "encode example.Example body: pos",
    ]
    assert nested[-1].startswith(
        "encode example.Example body: pos = {lat: 41.5 lon: -70.25} (62 bits"
    )


def test_without_trace_nothing_is_logged_even_at_debug(caplog) -> None:
    cls = message_class("example.proto", "example.Tiny")
    codec = Codec()
    caplog.set_level(logging.DEBUG, logger="pygoby.dccl.trace")
    codec.decode(codec.encode(cls(a=5, b=3, c=True)))
    assert trace_lines(caplog) == []


ENCODE_VECTORS = [r for r in read_jsonl("vectors.jsonl") if r["hex"] is not None]


@pytest.mark.e2e  # (every vector, traced: long for the edit loop)
def test_every_vector_through_a_traced_codec(caplog) -> None:
    """The traced variant gives the same bytes and messages as the fast one, and its top-level
    lines (fields, oneof cases, id) account for every bit of the head and of the body."""
    codecs = VectorCodecs(trace=True)
    caplog.set_level(logging.DEBUG, logger="pygoby.dccl.trace")
    for record in ENCODE_VECTORS:
        if record.get("decode_now") is None:
            codec = codecs.get(record["proto"], record["passphrase"])
        else:  # decoding time fields depends on the receiver's clock
            clock = VirtualClock(float(record["decode_now"]))
            codec = Codec(passphrase=record["passphrase"], clock=clock, trace=True)
        codec.strict = record["strict"]
        cls = message_class(record["proto"], record["message"])
        compiled = codec.compiled(cls)
        caplog.clear()
        data = codec.encode(parse_text(cls, record["text"]))
        assert data.hex() == record["hex"], record
        decoded = codec.decode(data, cls)
        assert decoded == parse_text(cls, record["decoded"]), record
        for action in ("encode", "decode"):
            bits = {"head": 0, "body": 0}
            for r in caplog.records:
                if r.getMessage().startswith(action) and "." not in r.dccl_field:
                    bits[r.getMessage().split()[2].rstrip(":")] += r.dccl_bits
            assert (bits["head"] + 7) // 8 == compiled.head_bytes, (action, record)
            assert (bits["body"] + 7) // 8 == len(data) - compiled.head_bytes, (action, record)
