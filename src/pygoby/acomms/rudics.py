""" "RUDICS packet" framing used by the store-server (and Iridium) drivers.

Serialize: append the CRC-32 of the bytes (big-endian), re-express the byte string in base
256 - len(reserved) (little-endian digits: byte 0 is the least significant; zero bytes at the
most significant end are kept as zero digits), move digits that equal a reserved character to
the values just above the reduced base, and end with CR.

The base change is a big-number conversion (the wire format, shared with C++ Goby, makes the
whole packet one number). Digit by digit it costs O(n²) interpreted steps (a 128 KB line took
38 s); here it splits the number in halves by powers of the base, so the work is done by the
interpreter's own big-integer multiplication and division, and the number of interpreted steps
is linear. What bounds the time of one conversion is the packet limit: `MAX_PACKET_BYTES`.
"""

from __future__ import annotations

import math
import zlib

from pygoby.acomms.errors import RudicsPacketError

DEFAULT_RESERVED = b"\r"
CRC_BYTES = 4
# Longest packet, CR included: the longest line a pygoby driver link accepts, so a server never
# answers with a packet its client would discard. The store-server driver and server keep their
# requests and responses within it.
MAX_PACKET_BYTES = 65536
_LEAF_DIGITS = 32  # runs of digits converted with small-integer arithmetic


def max_data_bytes(packet_bytes: int = MAX_PACKET_BYTES, reserved: bytes = DEFAULT_RESERVED) -> int:
    """The most data bytes whose serialized packet (CRC and CR included) fits `packet_bytes`."""
    digits_per_byte = 8 / math.log2(256 - len(reserved))
    # n data bytes + CRC become at most ceil((n + 4) * digits_per_byte) digits; +1 for CR and
    # +1 to stay clear of rounding in the logarithm
    return max(0, math.floor((packet_bytes - 2) / digits_per_byte) - CRC_BYTES)


def embedded_size(message_bytes: int) -> int:
    """Bytes a message of `message_bytes` takes as a field (one-byte key) of another message:
    what one more transmission adds to a store-server request or response."""
    return 1 + max(1, (message_bytes.bit_length() + 6) // 7) + message_bytes


def serialize_rudics_packet(
    data: bytes, reserved: bytes = DEFAULT_RESERVED, include_crc: bool = True
) -> bytes:
    if include_crc:
        data = data + zlib.crc32(data).to_bytes(CRC_BYTES, "big")
    base = 256 - len(reserved)
    digits = _int_to_digits(int.from_bytes(data, "little"), base)
    packet = bytearray(digits + b"\0" * _most_significant_zeros(data))
    for i, char in enumerate(reserved):
        packet = packet.replace(bytes([char]), bytes([base + i]))
    return bytes(packet) + b"\r"


def parse_rudics_packet(
    packet: bytes,
    reserved: bytes = DEFAULT_RESERVED,
    include_crc: bool = True,
    max_bytes: int | None = MAX_PACKET_BYTES,
) -> bytes:
    """Inverse of serialize_rudics_packet; `packet` ends with its CR. A packet longer than
    `max_bytes` (None: no limit) is refused before any conversion."""
    if not packet:
        raise RudicsPacketError("packet too short for <CR>")
    if max_bytes is not None and len(packet) > max_bytes:
        raise RudicsPacketError(f"packet of {len(packet)} bytes exceeds the {max_bytes}-byte limit")
    body = bytes(b for b in packet[:-1] if b not in reserved)
    base = 256 - len(reserved)
    for i, char in enumerate(reserved):
        body = body.replace(bytes([base + i]), bytes([char]))
    value = _digits_to_int(body, base)
    data = value.to_bytes((value.bit_length() + 7) // 8, "little")
    data += b"\0" * _most_significant_zeros(body)
    if not include_crc:
        return data
    if len(data) < CRC_BYTES:
        raise RudicsPacketError("packet too short for its CRC-32")
    data, given = data[:-CRC_BYTES], int.from_bytes(data[-CRC_BYTES:], "big")
    if zlib.crc32(data) != given:
        raise RudicsPacketError("bad CRC-32")
    return data


def _most_significant_zeros(digits: bytes) -> int:
    return len(digits) - len(digits.rstrip(b"\0"))


def _powers(base: int, count: int) -> list[int]:
    """base ** (_LEAF_DIGITS * 2**k) for k < count."""
    powers = [base**_LEAF_DIGITS]
    while len(powers) < count:
        powers.append(powers[-1] * powers[-1])
    return powers


def _digits_to_int(digits: bytes, base: int) -> int:
    """Little-endian digits to their value: leaves of _LEAF_DIGITS, then pairs joined level by
    level (low + high * base**width), so every big multiplication has balanced halves."""
    values = [
        _leaf_value(digits[start : start + _LEAF_DIGITS], base)
        for start in range(0, len(digits), _LEAF_DIGITS)
    ]
    level = 0
    powers = _powers(base, max(1, len(values).bit_length()))
    while len(values) > 1:
        if len(values) % 2:
            values.append(0)
        width = powers[level]
        values = [low + high * width for low, high in zip(values[::2], values[1::2], strict=True)]
        level += 1
    return values[0] if values else 0


def _leaf_value(digits: bytes, base: int) -> int:
    value = 0
    for digit in reversed(digits):
        value = value * base + digit
    return value


def _int_to_digits(value: int, base: int) -> bytes:
    """Little-endian digits of `value` without zero digits at the most significant end."""
    if not value:
        return b""
    powers = [base**_LEAF_DIGITS]
    while powers[-1] <= value:
        powers.append(powers[-1] * powers[-1])
    out = bytearray()
    # depth-first, low half first: (value, level) gives _LEAF_DIGITS * 2**level digits
    stack = [(value, len(powers) - 1)]
    while stack:
        number, level = stack.pop()
        if level == 0:
            for _ in range(_LEAF_DIGITS):
                number, digit = divmod(number, base)
                out.append(digit)
            continue
        high, low = divmod(number, powers[level - 1])
        stack.append((high, level - 1))
        stack.append((low, level - 1))
    return bytes(out).rstrip(b"\0")
