"""Field codec interface and the context a codec is built with.

A field codec turns one field value into bits and back. Two shapes exist:

* `FixedWidthCodec`: always `bits` bits; implement `to_raw(value, strict) -> int` and
  `from_raw(raw) -> value | None`. The message compiler inlines these (fast path).
* `FieldCodec` (general): implement `encode(value, strict) -> (raw, nbits)` and
  `decode(bits, pos, end) -> (value, new_pos)`, plus `min_size()`/`max_size()`.

`value` is None when the field is unset; `from_raw`/`decode` return None for "not set". A raw value
of `nbits` bits is written least-significant bit first at the current bit position.
User codecs subclass one of these and are registered with `CodecRegistry.register`.

A codec whose encoding depends on other fields of the message (e.g. the legacy CCL speed, scaled
by a thrust mode) sets `reads_root = True`: its `to_raw`/`from_raw` (or `encode`/`decode`) then
take the root message first (the message being encoded, or as far as it is decoded).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from google.protobuf.descriptor import FieldDescriptor

from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError, DcclLoadError
from pygoby.protobuf.dccl.option_extensions_pb2 import DCCLFieldOptions
from pygoby.protobuf.descriptors import AnyFieldDescriptor

_CATEGORY_BY_CPPTYPE = {
    FieldDescriptor.CPPTYPE_INT32: "int32",
    FieldDescriptor.CPPTYPE_INT64: "int64",
    FieldDescriptor.CPPTYPE_UINT32: "uint32",
    FieldDescriptor.CPPTYPE_UINT64: "uint64",
    FieldDescriptor.CPPTYPE_DOUBLE: "double",
    FieldDescriptor.CPPTYPE_FLOAT: "float",
    FieldDescriptor.CPPTYPE_BOOL: "bool",
    FieldDescriptor.CPPTYPE_ENUM: "enum",
    FieldDescriptor.CPPTYPE_MESSAGE: "message",
}
INTEGER_CATEGORIES = frozenset({"int32", "int64", "uint32", "uint64"})
NUMERIC_CATEGORIES = INTEGER_CATEGORIES | {"double", "float"}
SCALAR_CATEGORIES = NUMERIC_CATEGORIES | {"bool", "enum", "string", "bytes"}
ALL_CATEGORIES = SCALAR_CATEGORIES | {"message"}


def field_category(field: AnyFieldDescriptor) -> str:
    """The DCCL type family of a field: int32, int64, uint32, uint64, double, float, bool, enum,
    string, bytes or message (members of a protobuf family are encoded identically)."""
    if field.cpp_type == FieldDescriptor.CPPTYPE_STRING:
        return "bytes" if field.type == FieldDescriptor.TYPE_BYTES else "string"
    return _CATEGORY_BY_CPPTYPE[field.cpp_type]


def ceil_log2(n: float) -> int:
    """Smallest b >= 0 with 2**b >= n (for a double, of its ceiling)."""
    if n != n or n in (float("inf"), float("-inf")):
        raise DcclLoadError(f"field size is not finite ({n})")
    whole = int(n) if float(n).is_integer() else int(n) + (1 if n > 0 else 0)
    return 0 if whole <= 1 else (whole - 1).bit_length()


@dataclass(frozen=True)
class FieldInfo:
    """What a codec knows about the field it encodes."""

    descriptor: AnyFieldDescriptor
    options: DCCLFieldOptions
    category: str
    # required encoding (no "not set" state): v4 `required`, `repeated` elements, oneof members
    # and fields whose dynamic condition makes them required; v3 the same but oneofs; v2
    # `required` only
    required: bool
    version: int  # the root message's codec_version
    codec_name: str  # the resolved registry name, e.g. "dccl.default4"
    now: Callable[[], float]  # receiver clock (UNIX seconds), for time codecs
    registry: Any  # the CodecRegistry, for codecs that wrap another codec

    @property
    def name(self) -> str:
        return self.descriptor.full_name

    def require(self, option: str) -> Any:
        if not self.options.HasField(option):  # type: ignore[arg-type]  # (a field name)
            raise DcclLoadError(f"{self.name}: missing (dccl.field).{option}")
        return getattr(self.options, option)


class FieldCodec:
    """General field codec (variable size). Subclasses override the methods below."""

    reads_root = False  # True: the methods take the root message as their first argument

    def __init__(self, info: FieldInfo) -> None:
        self.info = info

    def encode(self, value: Any, strict: bool) -> tuple[int, int]:
        raise NotImplementedError

    def decode(self, bits: int, pos: int, end: int) -> tuple[Any, int]:
        raise NotImplementedError

    def min_size(self) -> int:
        raise NotImplementedError

    def max_size(self) -> int:
        raise NotImplementedError

    def describe(self) -> str:
        """Extra facts for `analyze` (bounds, lengths...)."""
        return ""

    # helpers for subclasses
    def out_of_range(self, value: Any, why: str, strict: bool) -> None:
        if strict:
            raise DcclEncodeError(f"{self.info.name}: {why} (value {value!r})")

    @staticmethod
    def take(bits: int, pos: int, end: int, n: int, name: str) -> int:
        if pos + n > end:
            raise DcclDecodeError(f"message is truncated: {name} needs bits past the end")
        return (bits >> pos) & ((1 << n) - 1)


class FixedWidthCodec(FieldCodec):
    """A codec whose encoding is always `self.bits` bits."""

    bits: int = 0
    # The raw value written for "no value" (an absent optional field, a padding slot of a
    # repeated field): every default codec writes zeros; some legacy CCL codecs do not.
    null_raw: int = 0

    # value <-> raw integer: each codec sets them in __init__ (a closure per field: the hot path)
    to_raw: Callable[..., int]  # (value, strict); root-aware CCL codecs: (root, value, strict)
    from_raw: Callable[..., Any]  # (raw); root-aware CCL codecs: (root, raw)

    def encode(self, value: Any, strict: bool) -> tuple[int, int]:
        return self.to_raw(value, strict), self.bits

    def decode(self, bits: int, pos: int, end: int) -> tuple[Any, int]:
        raw = self.take(bits, pos, end, self.bits, self.info.name)
        return self.from_raw(raw), pos + self.bits

    def min_size(self) -> int:
        return self.bits

    def max_size(self) -> int:
        return self.bits


class RepeatedFieldCodec(FieldCodec):
    """A codec that codes a whole repeated field itself (no count prefix, no slots), like C++
    DCCL's RepeatedTypedFieldCodec; on a singular field it codes a list of at most one value.

    Implement `encode_list(values, strict) -> (raw, nbits)` and `decode_list(bits, pos, end) ->
    (values, pos)`; `encode`/`decode` serve singular fields."""

    def encode_list(self, values: list, strict: bool) -> tuple[int, int]:
        raise NotImplementedError

    def decode_list(self, bits: int, pos: int, end: int) -> tuple[list, int]:
        raise NotImplementedError
