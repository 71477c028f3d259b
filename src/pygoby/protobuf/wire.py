"""Bits of protobuf's wire format: varints, and the payloads of one length-delimited field
(options extensions read from serialized options, strings put into a message as protobuf
parses them)."""

from __future__ import annotations

_U64 = (1 << 64) - 1


def encode_varint(value: int) -> bytes:
    """A varint of a 64-bit two's complement value (a negative int32 takes 10 bytes)."""
    value &= _U64
    out = bytearray()
    while value > 0x7F:
        out.append(value & 0x7F | 0x80)
        value >>= 7
    out.append(value)
    return bytes(out)


def read_varint(data: bytes, pos: int) -> tuple[int, int]:
    """(value, position after it)."""
    value = shift = 0
    while True:
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, pos


def length_delimited(data: bytes, number: int) -> bytes:
    """The concatenated payloads of the length-delimited field `number` in serialized `data`
    (several occurrences of a message field merge, as protobuf merges them)."""
    found, pos = [], 0
    while pos < len(data):
        tag, pos = read_varint(data, pos)
        wire = tag & 7
        if wire == 0:
            _, pos = read_varint(data, pos)
        elif wire == 1:
            pos += 8
        elif wire == 5:
            pos += 4
        elif wire == 2:
            size, pos = read_varint(data, pos)
            if tag >> 3 == number:
                found.append(data[pos : pos + size])
            pos += size
        else:  # groups: not used where this is read
            break
    return b"".join(found)


def length_delimited_field(number: int, payload: bytes) -> bytes:
    """One length-delimited field (tag, length, payload)."""
    return encode_varint(number << 3 | 2) + encode_varint(len(payload)) + payload
