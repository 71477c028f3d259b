""" "RUDICS packet" framing used by the store-server (and Iridium) drivers (spec acomms.md §11).

Serialize: append the CRC-32 of the bytes (big-endian), re-express the byte string in base
256 - len(reserved) (little-endian digits: byte 0 is the least significant; zero bytes at the
most significant end are kept as zero digits), move digits that equal a reserved character to
the values just above the reduced base, and end with CR.
"""

from __future__ import annotations

import zlib

from pygoby.acomms.errors import RudicsPacketError

DEFAULT_RESERVED = b"\r"


def _convert(data: bytes, source_base: int, sink_base: int) -> bytes:
    value = 0
    for digit in reversed(data):
        value = value * source_base + digit
    trailing_zeros = len(data) - len(data.rstrip(b"\0"))
    out = bytearray()
    while value:
        value, remainder = divmod(value, sink_base)
        out.append(remainder)
    return bytes(out) + b"\0" * trailing_zeros


def serialize_rudics_packet(
    data: bytes, reserved: bytes = DEFAULT_RESERVED, include_crc: bool = True
) -> bytes:
    if include_crc:
        data = data + zlib.crc32(data).to_bytes(4, "big")
    base = 256 - len(reserved)
    packet = bytearray(_convert(data, 256, base))
    for i, char in enumerate(reserved):
        packet = packet.replace(bytes([char]), bytes([base + i]))
    return bytes(packet) + b"\r"


def parse_rudics_packet(
    packet: bytes, reserved: bytes = DEFAULT_RESERVED, include_crc: bool = True
) -> bytes:
    """Inverse of serialize_rudics_packet; `packet` ends with its CR."""
    if not packet:
        raise RudicsPacketError("packet too short for <CR>")
    body = bytes(b for b in packet[:-1] if b not in reserved)
    base = 256 - len(reserved)
    for i, char in enumerate(reserved):
        body = body.replace(bytes([base + i]), bytes([char]))
    data = _convert(body, base, 256)
    if not include_crc:
        return data
    if len(data) < 4:
        raise RudicsPacketError("packet too short for its CRC-32")
    data, given = data[:-4], int.from_bytes(data[-4:], "big")
    if zlib.crc32(data) != given:
        raise RudicsPacketError("bad CRC-32")
    return data
