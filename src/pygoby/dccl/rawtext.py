"""String fields whose bytes are not UTF-8 (the decoder's rule for them).

DCCL sends strings as raw bytes; C++ keeps whatever bytes arrive. Python protobuf refuses to
*assign* such bytes to a string field, but a proto2 message parsed from protobuf's wire format
keeps them (the field then reads as `bytes`) and serializes them back unchanged. So a decoded
string whose bytes are not UTF-8 is put into the message through protobuf's own parser: the
message then holds exactly the bytes a C++ peer would see, and encoding it again gives the same
DCCL bytes. Proto3 string fields must be UTF-8 (protobuf enforces it): there the decode fails
with a DcclDecodeError naming the field.
"""

from __future__ import annotations

from collections.abc import Sequence

from google.protobuf.message import DecodeError, Message

from pygoby.dccl.errors import DcclDecodeError
from pygoby.protobuf.descriptors import AnyFieldDescriptor
from pygoby.protobuf.wire import length_delimited_field


def _wire(field: AnyFieldDescriptor, values: Sequence[str | bytes]) -> bytes:
    return b"".join(
        length_delimited_field(field.number, v.encode() if isinstance(v, str) else bytes(v))
        for v in values
    )


def _merge(msg: Message, field: AnyFieldDescriptor, wire: bytes) -> None:
    try:
        msg.MergeFromString(wire)
    except DecodeError:
        raise DcclDecodeError(
            f"{field.full_name}: the decoded bytes are not UTF-8, which this (proto3) string"
            " field cannot hold"
        ) from None


def set_raw_string(msg: Message, field: AnyFieldDescriptor, data: bytes) -> None:
    """`msg.<field> = data` for bytes that are not UTF-8 (singular or oneof string field)."""
    _merge(msg, field, _wire(field, [data]))


def extend_raw_strings(
    msg: Message, field: AnyFieldDescriptor, values: Sequence[str | bytes], before: int
) -> None:
    """Append `values` to a repeated string field that held `before` elements, in order, when
    some of them are not UTF-8 (a failed `extend` may have appended a part of them)."""
    del getattr(msg, field.name)[before:]
    _merge(msg, field, _wire(field, values))
