"""The decoder corner cases where pygoby used to differ from C++ DCCL 4.2 (found by
differential fuzzing; the recorded corpus is in test_decode_corpus.py)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from google.protobuf import text_format

from pygoby.dccl import Codec, DcclDecodeError, DcclError
from pygoby.dccl.rawtext import extend_raw_strings, set_raw_string
from tests.dccl.recorded import TEST_PROTOS, loader

AGREE = TEST_PROTOS / "agree.proto"


@pytest.fixture
def codec() -> Codec:
    return Codec(loader=loader())


def cls_of(codec: Codec, name: str):
    return codec.load_proto(AGREE, f"agree.{name}")


# ------------------------------------------------------------------ 1. count above max_repeat
def test_message_count_above_max_repeat_is_rejected(codec) -> None:
    cls = cls_of(codec, "Rep4")
    # id 90, then the 2-bit count of `msgs` (max_repeat 2) says 3
    data = bytes([90 << 1, 0b11]) + bytes(4)
    with pytest.raises(DcclDecodeError, match="exceeds max_repeat"):
        codec.decode(data, cls)


def test_scalar_count_above_max_repeat_is_read(codec) -> None:
    cls = cls_of(codec, "Rep4")
    # msgs count 0 (2 bits), nums count 3 (2 bits) with max_repeat 2: three values are read
    nums = 0b00 | 0b11 << 2 | 0b01 << 4 | 0b10 << 6
    decoded = codec.decode(bytes([90 << 1, nums, 0b11, 0]), cls)
    assert list(decoded.nums) == [1, 2, 3]


def test_v3_message_count_above_max_repeat_is_rejected(codec) -> None:
    cls = cls_of(codec, "Rep3")
    with pytest.raises(DcclDecodeError):
        codec.decode(bytes([91 << 1, 0b111]) + bytes(8), cls)  # 3-bit count 7, max_repeat 5


# ------------------------------------------------------------------ 2. v2 empty sub-messages
def test_v2_embedded_message_with_nothing_set_is_cleared(codec) -> None:
    cls = cls_of(codec, "Empty2")
    msg = cls()
    msg.req.SetInParent()  # required, but nothing inside: sent as "not set" everywhere
    msg.holder.leaf.SetInParent()
    decoded = codec.decode(codec.encode(msg), cls)
    assert not decoded.HasField("req") and not decoded.HasField("opt")
    assert not decoded.HasField("holder")
    msg.req.a = 2
    msg.holder.n = 1
    decoded = codec.decode(codec.encode(msg), cls)
    assert decoded.req.a == 2 and decoded.holder.n == 1 and not decoded.holder.HasField("leaf")


# ------------------------------------------------------------------ 3. strings that are not UTF-8
@pytest.mark.parametrize("name", ["Text", "Text3", "Text2"])
def test_non_utf8_string_decodes_to_the_raw_bytes_and_encodes_back(codec, name) -> None:
    cls = cls_of(codec, name)
    msg = cls(r="abc") if name == "Text" else cls()
    raw = b"A\xff\xa9Z"  # not UTF-8
    set_raw_string(msg, cls.DESCRIPTOR.fields_by_name["s"], raw)
    data = codec.encode(msg)
    decoded = codec.decode(data, cls)
    assert decoded.s == raw  # the bytes a C++ peer sees (Python protobuf gives them as bytes)
    assert codec.encode(decoded) == data
    assert 's: "A\\377\\251Z"' in text_format.MessageToString(decoded)


def test_non_utf8_repeated_strings_keep_their_order(codec) -> None:
    cls = cls_of(codec, "Text")
    msg = cls(r="x")
    extend_raw_strings(msg, cls.DESCRIPTOR.fields_by_name["l"], ["ab", b"\xc3d"], 0)
    data = codec.encode(msg)
    decoded = codec.decode(data, cls)
    assert list(decoded.l) == ["ab", b"\xc3d"]  # a cut two-byte character kept as is
    assert codec.encode(decoded) == data


def test_proto3_string_that_is_not_utf8_is_a_decode_error(tmp_path: Path) -> None:
    path = tmp_path / "p3.proto"
    path.write_text(
        textwrap.dedent("""\
        syntax = "proto3";
        import "dccl/option_extensions.proto";
        package p3;
        message T {
          option (dccl.msg) = { id: 7 max_bytes: 16 codec_version: 4 };
          string s = 1 [(dccl.field).max_length = 4];
        }
    """)
    )
    codec = Codec()
    cls = codec.load_proto(path, "p3.T")
    data = codec.encode(cls(s="\u00ff"))  # the bytes c3 bf, after a 3-bit length
    bad = bytearray(data)
    bad[2] ^= 0b1000  # the top bit of the second string byte (body bit 19): c3 3f, not UTF-8
    with pytest.raises(DcclError, match="not UTF-8"):
        codec.decode(bytes(bad), cls)
