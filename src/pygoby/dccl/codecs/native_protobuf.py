"""`dccl.native_protobuf` (C++ DCCL's libdccl_native_protobuf): numbers, bools and enums coded
as protobuf itself codes them, inside a DCCL message.

    [presence bit, optional encoding only][the protobuf value bytes, without a tag]

Varint types (int32/64, uint32/64, sint32/64 zigzag, enum as its index) take as many bytes as
protobuf needs (a negative int32 takes 10); double, float, fixed*, sfixed* and bool take their
fixed size. Used per field (`codec: "dccl.native_protobuf"`) or for a whole message
(`codec_group: "dccl.native_protobuf"`, where embedded messages use the v4 message codec).
Strings and bytes have no native codec (as in C++).

Decoding reads varint bytes while their top bit is set, as C++ does. Where C++ then reads
undefined memory, pygoby decides: a varint longer than protobuf's 10 bytes is a
DcclDecodeError, a bool byte with its top bit set is true (what C++ gives in practice), a
negative enum index is "not set".
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

from google.protobuf.descriptor import EnumValueDescriptor
from google.protobuf.descriptor import FieldDescriptor as FD  # noqa: N817 (the tables read as C++ DCCL's)

from pygoby.dccl.codecs.base import FieldCodec, FieldInfo
from pygoby.dccl.errors import DcclDecodeError, DcclLoadError
from pygoby.protobuf import enum_type
from pygoby.protobuf.wire import encode_varint

_U64 = (1 << 64) - 1
_U32 = (1 << 32) - 1
_FIXED = {
    FD.TYPE_DOUBLE: struct.Struct("<d"),
    FD.TYPE_FLOAT: struct.Struct("<f"),
    FD.TYPE_FIXED32: struct.Struct("<I"),
    FD.TYPE_SFIXED32: struct.Struct("<i"),
    FD.TYPE_FIXED64: struct.Struct("<Q"),
    FD.TYPE_SFIXED64: struct.Struct("<q"),
}
_VARINT = {
    FD.TYPE_INT32,
    FD.TYPE_INT64,
    FD.TYPE_UINT32,
    FD.TYPE_UINT64,
    FD.TYPE_SINT32,
    FD.TYPE_SINT64,
    FD.TYPE_ENUM,
}
_VARINT32 = {FD.TYPE_INT32, FD.TYPE_UINT32, FD.TYPE_SINT32, FD.TYPE_ENUM}
_SIGNED_32 = {FD.TYPE_INT32, FD.TYPE_SINT32, FD.TYPE_ENUM}


def _zigzag(value: int, bits: int) -> int:
    return (value << 1) ^ (value >> (bits - 1))


def _unzigzag(value: int) -> int:
    return (value >> 1) ^ -(value & 1)


class NativeProtobufCodec(FieldCodec):
    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        kind = info.descriptor.type
        if kind not in _VARINT and kind not in _FIXED and kind != FD.TYPE_BOOL:
            raise DcclLoadError(f"{info.name}: dccl.native_protobuf cannot code this type")
        self.kind = kind
        self.presence = 0 if info.required else 1
        self.varint = kind in _VARINT
        self.fixed = _FIXED.get(kind)
        self.width = 8 * (1 if kind == FD.TYPE_BOOL else self.fixed.size if self.fixed else 1)
        if kind == FD.TYPE_ENUM:
            values: Sequence[EnumValueDescriptor] = enum_type(info.descriptor).values  # type: ignore[assignment]
            self.index = {v.number: i for i, v in reversed(list(enumerate(values)))}
            self.numbers = [v.number for v in values]
        self.to_bytes = self._encoder()

    def _encoder(self):
        kind = self.kind
        if self.fixed is not None:
            return self.fixed.pack
        if kind == FD.TYPE_BOOL:
            return lambda v: b"\x01" if v else b"\x00"
        if kind == FD.TYPE_SINT32:
            return lambda v: encode_varint(_zigzag(v, 32) & _U32)
        if kind == FD.TYPE_SINT64:
            return lambda v: encode_varint(_zigzag(v, 64))
        if kind == FD.TYPE_ENUM:
            return lambda v: encode_varint(self.index[v])
        return encode_varint  # int32 (sign-extended to 64 bits), int64, uint32, uint64

    # ------------------------------------------------------------------ sizes
    def min_size(self) -> int:
        return self.width if not self.presence else 1

    def max_size(self) -> int:
        if not self.varint:
            return self.presence + self.width
        widest = {FD.TYPE_UINT32: 5, FD.TYPE_SINT32: 5}.get(self.kind, 10)
        return self.presence + 8 * widest

    def describe(self) -> str:
        return "protobuf encoding"

    # ------------------------------------------------------------------ coding
    def encode(self, value: Any, strict: bool) -> tuple[int, int]:
        if value is None:
            return 0, self.min_size()
        data = self.to_bytes(value)
        raw = int.from_bytes(data, "little")
        if self.presence:
            return 1 | raw << 1, 1 + 8 * len(data)
        return raw, 8 * len(data)

    def decode(self, bits: int, pos: int, end: int) -> tuple[Any, int]:
        name = self.info.name
        if self.presence:
            if not self.take(bits, pos, end, 1, name):
                return None, pos + 1
            pos += 1
        if not self.varint:
            n = self.width
            raw = self.take(bits, pos, end, n, name)
            pos += n
            if self.fixed is not None:
                return self.fixed.unpack(raw.to_bytes(n // 8, "little"))[0], pos
            # a byte with its top bit set is an unfinished varint to protobuf; C++ DCCL then
            # returns an undefined value, in practice true: any nonzero byte is true here
            return raw != 0, pos
        value = shift = count = 0
        while True:
            byte = self.take(bits, pos, end, 8, name)
            pos += 8
            if count < 10:
                value |= (byte & 0x7F) << shift
            shift += 7
            count += 1
            if not byte & 0x80:
                break
        if count > 10:
            raise DcclDecodeError(f"{name}: a varint of {count} bytes (protobuf allows 10)")
        value &= _U64
        return self._from_varint(value), pos

    def _from_varint(self, value: int) -> Any:
        kind = self.kind
        if kind in _VARINT32:
            value &= _U32
            if kind == FD.TYPE_SINT32:
                return _unzigzag(value)
            if kind in _SIGNED_32 and value & 0x80000000:
                value -= 1 << 32
            if kind == FD.TYPE_ENUM:
                return self.numbers[value] if 0 <= value < len(self.numbers) else None
            return value
        if kind == FD.TYPE_SINT64:
            return _unzigzag(value)
        if kind == FD.TYPE_INT64 and value & (1 << 63):
            return value - (1 << 64)
        return value
