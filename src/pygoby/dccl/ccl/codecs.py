"""Legacy CCL as DCCL field codecs (the `_ccl_*` names of C++ DCCL's libdccl_ccl_compat).

Each codec is a fixed-width wrapper around a function of `pygoby.dccl.ccl.fields`. Like the
reference, they have no "not set" state: an absent value is sent as the encoding of 0 (which
for temperature or sound speed is not all zeros) and every value decodes as set.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from google.protobuf.descriptor import FieldDescriptor

from pygoby.dccl.ccl import fields
from pygoby.dccl.codecs.base import FieldInfo, FixedWidthCodec
from pygoby.dccl.codecs.numeric import NumericCodec, f32
from pygoby.dccl.errors import DcclLoadError
from pygoby.dccl.options import field_extension
from pygoby.protobuf import class_of, message_type
from pygoby.protobuf.dccl.ccl.protobuf.ccl_extensions_pb2 import LegacyCCLFieldOptions


def ccl_options(info: FieldInfo):
    """The field's `(dccl.field).(ccl)` options (LegacyCCLFieldOptions)."""
    return field_extension(info.options, LegacyCCLFieldOptions, 1000)


class _FunctionCodec(FixedWidthCodec):
    """`bits` bits made by `encode(value)` / read by `decode(raw)`."""

    def __init__(
        self, info: FieldInfo, bits: int, encode: Callable[[Any], int], decode: Callable[[int], Any]
    ) -> None:
        super().__init__(info)
        self.bits = bits
        mask = (1 << bits) - 1
        self.null_raw = encode(0) & mask
        self.to_raw = lambda v, strict: self.null_raw if v is None else encode(v) & mask
        self.from_raw = decode

    def describe(self) -> str:
        return "legacy CCL"


def _function_codec(bits: int, encode, decode) -> Callable[[FieldInfo], FixedWidthCodec]:
    return lambda info: _FunctionCodec(info, bits, encode, decode)


class DepthCodec(_FunctionCodec):
    """Depth in the width given by `(dccl.field).(ccl).bit_size` (13 in MDAT_STATE, where the
    mission mode fills the top 3 bits of the CCL word)."""

    def __init__(self, info: FieldInfo) -> None:
        opts = ccl_options(info)
        if not opts.HasField("bit_size"):
            raise DcclLoadError(f"{info.name}: missing (dccl.field).ccl.bit_size")
        super().__init__(info, opts.bit_size, fields.encode_depth, fields.decode_depth)


class SpeedCodec(FixedWidthCodec):
    """Speed scaled by the ThrustMode enum of the root message field numbered
    `(dccl.field).(ccl).thrust_mode_tag` (RPM unless it says METERS_PER_SECOND)."""

    bits = 8
    reads_root = True

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        opts = ccl_options(info)
        if not opts.HasField("thrust_mode_tag"):
            raise DcclLoadError(f"{info.name}: missing (dccl.field).ccl.thrust_mode_tag")
        tag = opts.thrust_mode_tag

        def mode(root) -> int:
            field = root.DESCRIPTOR.fields_by_number.get(tag)
            if field is None or field.cpp_type != FieldDescriptor.CPPTYPE_ENUM:
                raise DcclLoadError(f"{info.name}: thrust_mode_tag {tag} is not an enum field")
            number = getattr(root, field.name)
            return (
                fields.SPEED_MODE_MSEC
                if number == fields.SPEED_MODE_MSEC
                else fields.SPEED_MODE_RPM
            )

        self.to_raw = lambda root, v, strict: fields.encode_speed(
            0.0 if v is None else v, mode(root)
        )
        self.from_raw = lambda root, raw: fields.decode_speed(raw, mode(root))
        self.null_raw = 0


class TimeDateCodec(_FunctionCodec):
    """Microseconds since 1970 as month/day/time; decoded into the receiver's current UTC year."""

    def __init__(self, info: FieldInfo) -> None:
        now = info.now

        def decode(raw: int) -> int:
            return fields.decode_time_date(raw, fields.utc_year(now()))

        super().__init__(info, 24, fields.encode_time_date, decode)


class FixAgeCodec(FixedWidthCodec):
    """Fix age in 4 s steps: the default numeric codec over [0, 255] steps (so an optional
    field gets a "not set" value), fed with the step count; no value is sent as 255 s."""

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        inner = NumericCodec(info, bounds=(0.0, 255.0), resolution=1.0, category="uint32")
        self.bits = inner.bits
        inner_to_raw, inner_from_raw = inner.to_raw, inner.from_raw

        def to_raw(v, strict: bool) -> int:
            return inner_to_raw(fields.encode_fix_age(255 if v is None else v), strict)

        def from_raw(raw: int):
            steps = inner_from_raw(raw)
            return None if steps is None else fields.decode_fix_age(steps)

        self.to_raw, self.from_raw = to_raw, from_raw
        self.null_raw = to_raw(None, False)


class GFIPitchOilCodec(FixedWidthCodec):
    """The GFIPitchOil sub-message (gfi, pitch, oil) in 16 bits."""

    bits = 16

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        cls = class_of(message_type(info.descriptor))
        names = {f.name for f in message_type(info.descriptor).fields}
        if not {"gfi", "pitch", "oil"} <= names:
            raise DcclLoadError(f"{info.name}: _ccl_gfi_pitch_oil needs gfi, pitch and oil fields")

        def to_raw(v, strict: bool) -> int:
            if v is None:
                return fields.encode_gfi_pitch_oil(0.0, 0.0, 0.0)
            return fields.encode_gfi_pitch_oil(v.gfi, v.pitch, v.oil)

        def from_raw(raw: int):
            gfi, pitch, oil = fields.decode_gfi_pitch_oil(raw)
            return cls(gfi=gfi, pitch=pitch, oil=oil)

        self.to_raw, self.from_raw = to_raw, from_raw
        self.null_raw = to_raw(None, False)


CCL_FIELD_CODECS: dict[str, tuple[tuple[str, ...], Callable[[FieldInfo], FixedWidthCodec]]] = {
    "_ccl_latloncompressed": (
        ("double",),
        _function_codec(24, fields.encode_latlon, fields.decode_latlon),
    ),
    "_ccl_fix_age": (("uint32",), FixAgeCodec),
    "_ccl_time_date": (("uint64",), TimeDateCodec),
    "_ccl_heading": (
        ("float",),
        _function_codec(8, fields.encode_heading, lambda raw: f32(fields.decode_heading(raw))),
    ),
    "_ccl_depth": (("float",), DepthCodec),
    "_ccl_velocity": (
        ("float",),
        _function_codec(8, fields.encode_velocity, fields.decode_velocity),
    ),
    "_ccl_watts": (("float",), _function_codec(8, fields.encode_watts, fields.decode_watts)),
    "_ccl_gfi_pitch_oil": (("message",), GFIPitchOilCodec),
    "_ccl_speed": (("float",), SpeedCodec),
    "_ccl_hires_altitude": (
        ("float",),
        _function_codec(16, fields.encode_hires_altitude, fields.decode_hires_altitude),
    ),
    "_ccl_temperature": (
        ("float",),
        _function_codec(8, fields.encode_temperature, fields.decode_temperature),
    ),
    "_ccl_salinity": (
        ("float",),
        _function_codec(8, fields.encode_salinity, fields.decode_salinity),
    ),
    "_ccl_sound_speed": (
        ("float",),
        _function_codec(8, fields.encode_sound_speed, fields.decode_sound_speed),
    ),
}
