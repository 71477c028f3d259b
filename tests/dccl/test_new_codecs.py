"""Legacy CCL, dccl.arithmetic, dccl.native_protobuf, dynamic conditions, dccl.hash and the C++
library names: behaviour a user meets (the byte-for-byte agreement with C++ DCCL is in
test_recorded_vectors.py)."""

from __future__ import annotations

import builtins
import math
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from google.protobuf import text_format
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.dccl import Codec, DcclDecodeError, DcclError, DcclLoadError
from pygoby.dccl.arithmetic import load_model_file, model_class
from pygoby.dccl.ccl import CCL_MESSAGES, fields
from pygoby.dccl.codecs.numeric import f32
from pygoby.dccl.libraries import builtin_library, split_libraries
from pygoby.util.clock import VirtualClock
from tests.dccl.recorded import MODELS, TEST_PROTOS, loader
from tests.hypothesis_profiles import examples

HEADER = 'syntax = "proto2";\nimport "dccl/option_extensions.proto";\npackage t;\n'
STATE = "dccl.legacyccl.protobuf.CCLMDATState"


def load(tmp_path: Path, body: str, name: str, codec: Codec | None = None, extra_import: str = ""):
    path = tmp_path / f"{name.lower()}.proto"
    path.write_text(HEADER + extra_import + textwrap.dedent(body))
    codec = codec or Codec()
    return codec, codec.load_proto(path, f"t.{name}")


def arith_codec(*model_names: str) -> Codec:
    codec = Codec(loader=loader())
    for name in model_names or [p.stem for p in MODELS.glob("*.txt")]:
        codec.set_arithmetic_model(load_model_file(MODELS / f"{name}.txt"))
    return codec


# ------------------------------------------------------------------ legacy CCL
def test_ccl_state_is_a_32_byte_ccl_frame_and_switches_the_id_codec() -> None:
    codec = Codec(clock=VirtualClock(1_700_000_000))
    status = codec.load_proto(TEST_PROTOS / "cclmix.proto", "cclmix.Status")
    assert codec.encode(status(x=1.5))[:1] == b"\x04"  # default id codec: id 2
    cls = codec.load_proto("dccl/ccl/protobuf/ccl.proto", STATE)  # no include dir needed
    assert codec.id_codec == "dccl.ccl.id"
    assert codec.encode(status(x=1.5))[:2] == b"\x20\x04"  # DCCL among CCL: 0x20 first
    msg = cls(
        latitude=41.5,
        longitude=-70.25,
        fix_age=16,
        time_date=1_699_999_996_000_000,
        heading=90,
        depth=12.5,
        mission_mode=cls.NORMAL,
        faults=b"\0" * 4,
        faults_2=b"\0",
        mission_leg=2,
        est_velocity=1.2,
        objective_index=b"\0",
        watts=40,
        lat_goal=41.6,
        lon_goal=-70.2,
        battery_percent=80,
    )
    msg.gfi_pitch_oil.gfi, msg.gfi_pitch_oil.pitch, msg.gfi_pitch_oil.oil = 0, 3, 80
    data = codec.encode(msg)
    assert len(data) == 32 and data[0] == 0x0E  # MDAT_STATE mode byte
    decoded = codec.decode(data)
    assert abs(decoded.latitude - 41.5) < 1e-4 and decoded.depth == pytest.approx(12.5)
    assert decoded.time_date == 1_699_999_996_000_000  # same year as the receiver's clock
    assert codec.id(data) == 0x0CC1000E


def test_ccl_time_date_decodes_into_the_receivers_year() -> None:
    raw = fields.encode_time_date(1_360_620_606_000_000)  # 2013-02-11 22:10:06 UTC
    in_2023 = fields.decode_time_date(raw, 2023)
    assert in_2023 == 1_676_153_404_000_000  # 2023-02-11 22:10:04 (4 s steps)
    assert fields.time_date_parts(raw) == (2, 11, 22, 10, 4)


@given(st.floats(-179.99, 179.99))
def test_ccl_latlon_roundtrip(degrees: float) -> None:
    assert abs(fields.decode_latlon(fields.encode_latlon(degrees)) - degrees) <= 180.0 / 0x7FFFFF


@given(st.floats(0, 5999))
def test_ccl_depth_roundtrip_within_its_step(depth: float) -> None:
    depth = f32(depth)
    step = 0.1 if depth < 100 else 0.2 if depth < 200 else 0.5 if depth < 1000 else 1.0
    assert abs(fields.decode_depth(fields.encode_depth(depth)) - depth) <= step * 0.51 + 1e-3


@given(st.floats(allow_nan=True, allow_infinity=True, width=32))
def test_ccl_field_functions_take_any_float(value: float) -> None:
    for encode, bits in [
        (fields.encode_heading, 8),
        (fields.encode_velocity, 8),
        (fields.encode_watts, 8),
        (fields.encode_hires_altitude, 16),
        (fields.encode_salinity, 8),
        (fields.encode_temperature, 8),
        (fields.encode_sound_speed, 8),
        (fields.encode_depth, 16),
        (fields.encode_latlon, 24),
        (lambda v: fields.encode_speed(v, fields.SPEED_MODE_RPM), 8),
        (lambda v: fields.encode_gfi_pitch_oil(v, v, v), 16),
    ]:
        assert 0 <= encode(value) < 1 << bits


def test_ccl_speed_follows_the_thrust_mode() -> None:
    codec = Codec()
    cls = codec.load_proto("dccl/ccl/protobuf/ccl.proto", "dccl.legacyccl.protobuf.CCLMDATRedirect")
    msg = cls(
        transit_thrust_mode=cls.METERS_PER_SECOND,
        speed_transit=1.5,
        survey_thrust_mode=cls.RPM,
        speed_survey=50,
    )
    for name in (
        "message_number",
        "latitude",
        "longitude",
        "transit_vertical_mode",
        "survey_vertical_mode",
        "depth_goal_transit",
        "device_cmd_transit",
        "depth_goal_survey",
        "device_cmd_survey",
        "num_rows",
        "row_length",
        "spacing_0",
        "spacing_1",
        "heading",
        "lat_start",
        "lon_start",
    ):
        setattr(msg, name, getattr(msg, name))
    msg.spare = b"\0\0\0"
    decoded = codec.decode(codec.encode(msg))
    assert decoded.speed_transit == pytest.approx(1.5, abs=1 / 30)
    assert decoded.speed_survey == 1000  # RPM: the value is sent as is and read as x20 (as C++)


# ------------------------------------------------------------------ library names
def test_cpp_library_names_map_to_builtins() -> None:
    assert (
        builtin_library("/home/toby/dccl/build/lib/libdccl_ccl_compat.so").name == "dccl_ccl_compat"
    )
    assert builtin_library("libdccl_arithmetic.so.31").name == "dccl_arithmetic"
    assert builtin_library("libdccl_native_protobuf.so.4.2.0").name == "dccl_native_protobuf"
    with pytest.raises(DcclLoadError, match="load_proto_file"):
        builtin_library("/usr/lib/libgobyexample_protobuf.so")
    libraries, others = split_libraries(["libdccl_ccl_compat.so", "my_messages_pb2"])
    assert [lib.name for lib in libraries] == ["dccl_ccl_compat"] and others == ["my_messages_pb2"]
    codec = Codec()
    loaded = builtin_library("libdccl_ccl_compat.so").apply(codec)
    assert [cls.DESCRIPTOR.full_name for cls in loaded] == list(CCL_MESSAGES)
    assert codec.id_codec == "dccl.ccl.id"


# ------------------------------------------------------------------ arithmetic
def test_arithmetic_needs_its_model_before_loading() -> None:
    codec = Codec(loader=loader())
    with pytest.raises(DcclLoadError, match="no arithmetic model called 'ints'"):
        codec.load_proto(TEST_PROTOS / "arith.proto", "arith.Ints")


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ('name: "m" value_bound: [0, 1] frequency: [0]', "nonzero"),
        ('name: "m" value_bound: [0, 1, 2] frequency: [1]', "one more entry"),
        ('name: "m" value_bound: [0, 2, 1] frequency: [1, 1]', "increasing"),
        ('name: "m" value_bound: [0, 1] frequency: [1073741823]', "must not exceed"),
    ],
)
def test_invalid_arithmetic_models_are_refused(text: str, reason: str) -> None:
    with pytest.raises(DcclLoadError, match=reason):
        Codec().set_arithmetic_model(text_format.Parse(text, model_class()()))


def test_arithmetic_top_bound_value_codes_the_last_symbol() -> None:
    codec = arith_codec()
    cls = codec.load_proto(TEST_PROTOS / "arith.proto", "arith.Ints")
    decoded = codec.decode(codec.encode(cls(v=[4, 3, 1], tail=2)))  # bounds 0..4: 4 is the top
    assert list(decoded.v) == [3, 3, 1] and decoded.tail == 2
    doubles = codec.load_proto(TEST_PROTOS / "arith.proto", "arith.Doubles")
    assert list(codec.decode(codec.encode(doubles(d=[10.5, 7.0]))).d) == [2.0, 2.0]


def test_arithmetic_without_eof_frequency_fills_the_list() -> None:
    codec = arith_codec()
    cls = codec.load_proto(TEST_PROTOS / "arith.proto", "arith.NoEof")
    assert list(codec.decode(codec.encode(cls(v=[0, 2]))).v) == [0, 2, 1, 1]  # most probable: 1


def test_arithmetic_out_of_range_value_ends_the_list_without_shifting_later_fields() -> None:
    codec = arith_codec()
    cls = codec.load_proto(TEST_PROTOS / "arith.proto", "arith.Doubles")
    decoded = codec.decode(codec.encode(cls(d=[0.0, 99.0, 0.75], f=[2.0])))  # no OOR frequency
    assert list(decoded.d) == [0.0] and list(decoded.f) == [2.0]


def test_arithmetic_out_of_range_value_with_a_frequency_decodes_as_nan() -> None:
    codec = arith_codec()
    cls = codec.load_proto(TEST_PROTOS / "arith.proto", "arith.Ints")
    decoded = codec.decode(codec.encode(cls(v=[1, 99], tail=0)))
    assert decoded.v[0] == 1 and decoded.v[1] == -(2**31)  # NaN as int32, as on x86-64 C++


def test_adaptive_models_are_per_codec_and_per_direction() -> None:
    sender, receiver = arith_codec(), arith_codec()
    cls = sender.load_proto(TEST_PROTOS / "arith.proto", "arith.Adaptive")
    receiver.load(cls)
    first = sender.encode(cls(v=[1, 1, 1]))
    second = sender.encode(cls(v=[1, 1, 1]))
    assert len(second) < len(first)  # symbol 1 has become more probable
    assert list(receiver.decode(first).v) == [1, 1, 1]
    assert list(receiver.decode(second).v) == [1, 1, 1]
    fresh = arith_codec()
    fresh.load(cls)
    assert fresh.encode(cls(v=[1, 1, 1])) == first  # another Codec starts afresh


def test_cli_arithmetic_model_and_ccl_without_include(tmp_path: Path) -> None:
    def run(*args: str, stdin: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "pygoby.cli", "dccl", *args],
            input=stdin,
            capture_output=True,
            text=True,
            timeout=60,
        )

    result = run(
        "encode",
        "--proto",
        str(TEST_PROTOS / "arith.proto"),
        "--message",
        "arith.Ints",
        "--arithmetic-model",
        str(MODELS / "ints.txt"),
        stdin="v: 1 v: 2 tail: 3\n",
    )
    assert result.returncode == 0, result.stderr
    data = result.stdout.strip()
    result = run(
        "decode",
        "--proto",
        str(TEST_PROTOS / "arith.proto"),
        "--message",
        "arith.Ints",
        "--arithmetic-model",
        str(MODELS / "ints.txt"),
        stdin=data + "\n",
    )
    assert result.stdout.strip() == "v: 1 v: 2 tail: 3"
    result = run(
        "encode",
        "--proto",
        "dccl/ccl/protobuf/ccl.proto",
        "--message",
        "dccl.legacyccl.protobuf.CCLMDATError",
        stdin='message: "hello"\n',
    )
    assert result.returncode == 0 and result.stdout.startswith("0f68656c6c6f"), result


# ------------------------------------------------------------------ native_protobuf
def test_native_protobuf_is_protobufs_own_encoding(tmp_path: Path) -> None:
    codec, cls = load(
        tmp_path,
        """
        message N {
          option (dccl.msg) = { id: 3 max_bytes: 40 codec_version: 4 };
          required int32 a = 1 [(dccl.field).codec = "dccl.native_protobuf"];
          required sint64 b = 2 [(dccl.field).codec = "dccl.native_protobuf"];
          required double c = 3 [(dccl.field).codec = "dccl.native_protobuf"];
        }""",
        "N",
    )
    msg = cls(a=-1, b=-2, c=0.5)
    data = codec.encode(msg)
    # int32 -1: a 10-byte varint; sint64 -2: zigzag 3; double: 8 bytes (no tags, no presence bits)
    assert data[1:] == b"\xff" * 9 + b"\x01" + b"\x03" + struct.pack("<d", 0.5)
    assert codec.decode(data) == msg


# ------------------------------------------------------------------ dynamic conditions
def test_dynamic_conditions_without_lupa_are_a_clear_load_error(
    tmp_path: Path, monkeypatch
) -> None:
    real_import = builtins.__import__

    def no_lupa(name, *args, **kwargs):
        if name.startswith("lupa"):
            raise ImportError("No module named 'lupa'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_lupa)
    with pytest.raises(DcclLoadError, match="lupa"):
        Codec(loader=loader()).load_proto(TEST_PROTOS / "dyncond.proto", "dyn.Basic")


def test_dynamic_condition_that_is_not_lua_is_a_load_error(tmp_path: Path) -> None:
    with pytest.raises(DcclLoadError, match="not valid Lua"):
        load(
            tmp_path,
            """
            message D {
              option (dccl.msg) = { id: 3 max_bytes: 8 codec_version: 4 };
              optional int32 a = 1 [(dccl.field) = { min: 0 max: 3
                dynamic_conditions { omit_if: "this.b ==" } }];
            }""",
            "D",
        )


def test_dynamic_conditions_omit_require_and_bound(tmp_path: Path) -> None:
    codec = Codec(loader=loader())
    cls = codec.load_proto(TEST_PROTOS / "dyncond.proto", "dyn.Basic")
    kind_a, kind_b = 1, 2
    a = codec.encode(cls(kind=kind_a, a=50, b=7, center=150, c=120))
    assert codec.decode(a) == cls(kind=kind_a, a=50, b=7, center=150, c=120, flag=False)
    b = codec.encode(cls(kind=kind_b, a=50, b=7, center=150, c=120))
    # a, center and c are omitted for KIND_B; flag is required (required_if "true")
    assert codec.decode(b) == cls(kind=kind_b, b=7, flag=False)
    assert len(b) < len(a)


def test_lua_error_at_encode_is_an_encode_error(tmp_path: Path) -> None:
    codec, cls = load(
        tmp_path,
        """
        message E {
          option (dccl.msg) = { id: 3 max_bytes: 8 codec_version: 4 };
          optional int32 a = 1 [(dccl.field) = { min: 0 max: 3
            dynamic_conditions { omit_if: "this.missing.x > 1" } }];
        }""",
        "E",
    )
    with pytest.raises(DcclError, match="dynamic_conditions omit_if"):
        codec.encode(cls(a=1))


# ------------------------------------------------------------------ hash
def test_hash_field_sends_the_definition_hash_and_refuses_another(tmp_path: Path) -> None:
    body = """
        message H {
          option (dccl.msg) = { id: 3 max_bytes: 8 codec_version: 4 };
          required uint32 hash = 1 [(dccl.field) = { codec: "dccl.hash" max: 65535 }];
          required int32 a = 2 [(dccl.field) = { min: 0 max: %d }];
        }"""
    codec, cls = load(tmp_path, body % 10, "H")
    data = codec.encode(cls(hash=0, a=3))
    assert codec.decode(data).hash == codec.definition_hash(cls) & 0xFFFF
    other_dir = tmp_path / "other"
    other_dir.mkdir()
    other, other_cls = load(other_dir, body % 11, "H")  # a changed bound: another definition
    with pytest.raises(DcclDecodeError, match="hash mismatch"):
        other.decode(data, other_cls)


# ------------------------------------------------------------------ fuzz every new decoder
NEW_TYPES = [("dccl/ccl/protobuf/ccl.proto", name) for name in CCL_MESSAGES] + [
    (TEST_PROTOS / proto, f"{package}.{name}")
    for proto, package, names in [
        (
            "arith.proto",
            "arith",
            [
                "Ints",
                "Doubles",
                "EnumBool",
                "Singles",
                "Adaptive",
                "NoEof",
                "Long",
                "V2",
                "V3",
                "Nested",
            ],
        ),
        ("native.proto", "native", ["AllTypes", "Lists", "Mixed4", "Mixed3", "Mixed2", "Head"]),
        ("dyncond.proto", "dyn", ["Basic", "Lists", "V3", "Choice", "InHead"]),
        ("hash.proto", "hashing", ["Plain", "Rich", "Head", "V3", "V2", "Arith", "Group"]),
        ("agree.proto", "agree", ["Rep4", "Rep3", "Empty2", "Text", "Text3", "Text2"]),
        ("cclmix.proto", "cclmix", ["Status", "LongId"]),
    ]
    for name in names
]


@pytest.fixture(scope="module")
def fuzz_codecs() -> dict:
    codecs: dict = {}
    for proto, name in NEW_TYPES:
        codec = codecs.setdefault(str(proto), arith_codec())
        codec.load_proto(proto, name)
    return codecs


@settings(max_examples=examples(300), deadline=None)
@given(st.sampled_from(NEW_TYPES), st.binary(max_size=80), st.integers(0, 255))
def test_new_decoders_never_fail_otherwise(fuzz_codecs, kind, data, first) -> None:
    """Any bytes: a message or a DcclError, never another exception or an endless loop."""
    codec = fuzz_codecs[str(kind[0])]
    for candidate in (data, bytes([first]) + data):
        try:
            msg = codec.decode(candidate)
        except DcclError:
            continue
        assert math.isfinite(len(msg.SerializePartialToString()))
