"""The DCCL Python API: loading rules, user codecs, clocks, sizes and IDs."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from pygoby.dccl import (
    Codec,
    CodecRegistry,
    DcclDecodeError,
    DcclEncodeError,
    DcclLoadError,
    FixedWidthCodec,
    register_codec,
)
from pygoby.dccl.registry import DEFAULT_REGISTRY
from pygoby.util.clock import VirtualClock
from tests.dccl.vectors import message_class

HEADER = 'syntax = "proto2";\nimport "dccl/option_extensions.proto";\npackage t;\n'


def load(tmp_path: Path, body: str, name: str, codec: Codec | None = None):
    path = tmp_path / f"{name.lower()}.proto"
    path.write_text(HEADER + textwrap.dedent(body))
    codec = codec or Codec()
    return codec, codec.load_proto(path, f"t.{name}")


@pytest.mark.parametrize(
    ("body", "reason"),
    [
        ("message M { option (dccl.msg) = { max_bytes: 4 codec_version: 4 }; }", "missing"),
        ("message M { option (dccl.msg) = { id: 1 codec_version: 4 }; }", "max_bytes"),
        ("message M { option (dccl.msg) = { id: 1 max_bytes: 4 }; }", "codec_version"),
        (
            "message M { option (dccl.msg) = { id: 40000 max_bytes: 4 codec_version: 4 }; }",
            "0..32767",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 2 codec_version: 4 };"
            " required uint32 a = 1 [(dccl.field) = { min: 0 max: 255 }];"
            " required uint32 b = 2 [(dccl.field) = { min: 0 max: 1 }]; }",
            "max_bytes 2",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 4 };"
            " required uint32 a = 1 [(dccl.field).max = 3]; }",
            "min",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 4 };"
            " required double a = 1 [(dccl.field) = { min: 0 max: 1 resolution: 0.3 }]; }",
            "multiple of the resolution",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 4 };"
            " required double a = 1 [(dccl.field) = { min: 0 max: 1 resolution: 0.5 precision: 1 }]; }",
            "not both",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 300 codec_version: 2 };"
            " optional string s = 1 [(dccl.field).max_length = 256]; }",
            "exceeds 255",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 4 };"
            " repeated uint32 r = 1 [(dccl.field) = { min: 0 max: 3 }]; }",
            "max_repeat",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 4 };"
            " optional string s = 1 [(dccl.field) = { max_length: 4 in_head: true }]; }",
            "fixed size",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 3 };"
            " oneof o { uint32 a = 1 [(dccl.field) = { min: 0 max: 3 }]; bool b = 2; } }",
            "oneof",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 4 };"
            " optional bool b = 1 [(dccl.field).codec = 'dccl.static']; }",
            "no codec named",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 2 };"
            " optional int32 p = 1 [(dccl.field) = { codec: 'dccl.presence' min: 0 max: 3 }]; }",
            "no codec named",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 4 };"
            " optional int32 p = 1 [(dccl.field) = { codec: 'dccl.static' static_value: 'x' }]; }",
            "static_value",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 8 codec_version: 4 };"
            " optional uint32 h = 1 [(dccl.field) = { codec: 'dccl.hash' min: 0 max: 256 }]; }",
            "dccl.hash needs",
        ),
        (
            "message M { option (dccl.msg) = { id: 1 max_bytes: 64 codec_version: 4 };"
            " optional M next = 1; }",
            "recursive",
        ),
    ],
)
def test_invalid_definitions_fail_to_load(tmp_path: Path, body: str, reason: str) -> None:
    with pytest.raises(DcclLoadError, match=reason):
        load(tmp_path, body, "M")


def test_max_bytes_exactly_enough_loads(tmp_path: Path) -> None:
    _, cls = load(
        tmp_path,
        "message M { option (dccl.msg) = { id: 1 max_bytes: 3 codec_version: 4 };"
        " required uint32 a = 1 [(dccl.field) = { min: 0 max: 255 }];"
        " required uint32 b = 2 [(dccl.field) = { min: 0 max: 1 }]; }",
        "M",
    )
    assert cls(a=1, b=1).a == 1


def test_duplicate_ids_are_refused(tmp_path: Path) -> None:
    codec, _ = load(
        tmp_path, "message A { option (dccl.msg) = { id: 9 max_bytes: 4 codec_version: 4 }; }", "A"
    )
    with pytest.raises(DcclLoadError, match="already used"):
        load(
            tmp_path,
            "message B { option (dccl.msg) = { id: 9 max_bytes: 4 codec_version: 4 }; }",
            "B",
            codec,
        )


def test_required_field_missing_is_an_encode_error() -> None:
    cls = message_class("example.proto", "example.Tiny")
    with pytest.raises(DcclEncodeError, match="required fields are not set: a"):
        Codec().encode(cls(b=1))


def test_strict_mode_refuses_out_of_range() -> None:
    cls = message_class("example.proto", "example.Tiny")
    assert Codec().encode(cls(a=9)).hex() == "040000"
    with pytest.raises(DcclEncodeError, match="out of range"):
        Codec(strict=True).encode(cls(a=9))


def test_id_size_and_decode_by_id() -> None:
    codec = Codec()
    tiny = codec.load(message_class("example.proto", "example.Tiny"))
    long_id = codec.load(message_class("example.proto", "example.LongId"))
    data = codec.encode(tiny(a=5, b=3, c=True))
    assert codec.id(data) == 2
    assert codec.id(bytes.fromhex("d1072302")) == 1000
    assert codec.size(tiny(a=5)) == 3 == codec.max_size(tiny)
    assert codec.type_of(data) is tiny
    assert isinstance(codec.decode(data), tiny)
    assert long_id.DESCRIPTOR.full_name == "example.LongId"


def test_decode_prefix_splits_concatenated_messages() -> None:
    codec = Codec()
    cls = codec.load(message_class("example.proto", "example.Example"))
    first = cls(count=1, temperature=2, flag=True, mode=5, name="ab")
    second = cls(count=3, temperature=4, flag=False, mode=5, readings=[1, 2])
    data = codec.encode(first) + codec.encode(second)
    msg1, used = codec.decode_prefix(data)
    msg2, used2 = codec.decode_prefix(data[used:])
    assert (msg1, msg2) == (first, second)
    assert used + used2 == len(data)


def test_unknown_id_and_wrong_type_are_decode_errors() -> None:
    codec = Codec()
    tiny = codec.load(message_class("example.proto", "example.Tiny"))
    with pytest.raises(DcclDecodeError, match="no message type with id 3"):
        codec.decode(bytes.fromhex("06250100"))
    codec.load(message_class("example.proto", "example.LongId"))
    with pytest.raises(DcclDecodeError, match="not the id 2"):
        codec.decode(bytes.fromhex("d10723022540001027"), tiny)


def test_time_codec_uses_the_injected_clock() -> None:
    cls = message_class("example.proto", "example.LongId")
    clock = VirtualClock(1_700_000_000)
    codec = Codec(clock=clock)
    data = codec.encode(cls(src=3, dest=17, t=1_700_000_000))
    assert codec.decode(data).t == 1_700_000_000
    clock.set(1_700_000_000 + 86400 * 3)  # three days later the same bits mean three days later
    assert codec.decode(data).t == 1_700_000_000 + 86400 * 3


def test_encryption_keeps_header_clear() -> None:
    cls = message_class("example.proto", "example.LongId")
    codec = Codec(passphrase="my secret", clock=VirtualClock(1_700_000_000))
    data = codec.encode(cls(src=3, dest=17, payload=b"\x01\x02", t=1_700_000_000))
    assert data.hex() == "d10723025d66fced5d"
    exempt = Codec(passphrase="my secret", do_not_encrypt_ids=[1000])
    assert exempt.encode(cls(src=3, dest=17, payload=b"\x01\x02", t=1_700_000_000)).hex() == (
        "d10723022540001027"
    )


class ParityCodec(FixedWidthCodec):
    """A user codec: one bit, the parity of an integer (decodes as 0 or 1)."""

    bits = 1

    def __init__(self, info) -> None:
        super().__init__(info)
        self.to_raw = lambda v, strict: (v or 0) & 1
        self.from_raw = lambda raw: raw


PARITY_USER = (
    "message P { option (dccl.msg) = { id: 5 max_bytes: 4 codec_version: 4 };"
    " required uint32 n = 1 [(dccl.field).codec = 'my.parity'];"
    " required uint32 m = 2 [(dccl.field) = { min: 0 max: 7 }]; }"
)


def test_user_codec_selected_by_name(tmp_path: Path) -> None:
    codec = Codec()
    codec.registry.register("my.parity", ["uint32"], ParityCodec)
    _, cls = load(tmp_path, PARITY_USER, "P", codec)
    data = codec.encode(cls(n=7, m=5))
    assert data.hex() == "0a0b"  # id 5; n parity 1 (bit 0), m 5 (bits 1-3)
    assert codec.decode(data) == cls(n=1, m=5)


def test_a_codec_registered_on_one_codec_does_not_leak_into_another(tmp_path: Path) -> None:
    first, second = Codec(), Codec()
    first.registry.register("my.parity", ["uint32"], ParityCodec)
    load(tmp_path, PARITY_USER, "P", first)
    for other in (second, Codec()):  # made before and after the registration
        with pytest.raises(DcclLoadError, match="no codec named 'my.parity'"):
            load(tmp_path, PARITY_USER, "P", other)
    with pytest.raises(DcclLoadError, match="no codec named 'my.parity'"):
        DEFAULT_REGISTRY.resolve("my.parity", 4, "uint32")


def test_register_codec_adds_to_the_defaults_that_later_codecs_copy(tmp_path: Path) -> None:
    earlier = Codec()
    body = PARITY_USER.replace("my.parity", "test_api.global_parity")  # only this test uses it
    register_codec("test_api.global_parity", ["uint32"], ParityCodec)
    codec, cls = load(tmp_path, body, "P", Codec())
    assert codec.encode(cls(n=7, m=5)).hex() == "0a0b"
    with pytest.raises(DcclLoadError, match="no codec named 'test_api.global_parity'"):
        load(tmp_path, body, "P", earlier)


def test_a_codec_given_a_registry_uses_that_one(tmp_path: Path) -> None:
    registry = CodecRegistry()
    with pytest.raises(DcclLoadError, match="no codec named 'dccl.default4'"):
        load(tmp_path, PARITY_USER, "P", Codec(registry=registry))


def test_generated_python_classes_load(tmp_path: Path, monkeypatch) -> None:
    """Classes from protoc-generated *_pb2 modules work like run-time loaded ones."""
    from importlib import resources

    from grpc_tools import protoc

    from pygoby.protobuf import BUILTIN_PROTO_DIR
    from tests.dccl.vectors import DCCL_VECTORS

    well_known = resources.files("grpc_tools") / "_proto"
    args = ["protoc", f"-I{BUILTIN_PROTO_DIR}", f"-I{DCCL_VECTORS}", f"-I{well_known}"]
    args.append(f"--python_out={tmp_path}")
    assert protoc.main([*args, "dccl/option_extensions.proto", "example.proto"]) == 0
    monkeypatch.syspath_prepend(str(tmp_path))
    import example_pb2

    codec = Codec()
    codec.load(example_pb2.Tiny)
    data = codec.encode(example_pb2.Tiny(a=5, b=3, c=True))
    assert data.hex() == "042501"
    assert codec.decode(data) == example_pb2.Tiny(a=5, b=3, c=True)
    assert "example.Tiny" in codec.analyze(example_pb2.Tiny)


def test_in_head_inside_a_body_message_is_dropped_with_a_warning(caplog) -> None:
    """Spec §5.2 (vector ih.M4): the reference silently never sends such fields; we say so."""
    cls = message_class("inhead.proto", "ih.M4")
    with caplog.at_level("WARNING", logger="pygoby.dccl"):
        Codec().load(cls)
    assert "is in_head inside a sub-message that is not in the header" in caplog.text
