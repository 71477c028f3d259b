"""Goby 1.1 modem frames holding several DCCL1 messages (libqueue 1.1's multi-message frames).

Frame = 0x20, then per message its header bytes 1-5 with the multi-message flag set on all but
the last and the broadcast flag set when that message goes to id 0, then (all but the last) one
byte with its body length, then its body. A frame of one message is that message with the
broadcast flag set when it is broadcast. The receiver clears both flags before decoding each
message (the body was encrypted under the flag-free header).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from pygoby.dccl.dccl1.codec import BROADCAST_ID, DCCL1_FIRST_BYTE, HEADER_BYTES
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError

_MULTIMESSAGE_BIT = 0x08  # in header byte 5: flags and unused bits are its lowest four bits
_BROADCAST_BIT = 0x04
_SIGNED_LENGTH_LIMIT = 0x80


@dataclass
class FramePart:
    data: bytes  # one DCCL1 message, flags cleared, ready for Dccl1Codec.decode
    broadcast: bool  # the sender marked it for id 0


def is_dccl1_frame(frame: bytes) -> bool:
    """1.1 routes a received frame by its first byte: 0x20 is DCCL, anything else is the CCL
    message type of that value."""
    return bool(frame) and frame[0] == DCCL1_FIRST_BYTE


def _with_flags(header: bytes, multimessage: bool, broadcast: bool) -> bytes:
    last = header[HEADER_BYTES - 1] & ~(_MULTIMESSAGE_BIT | _BROADCAST_BIT)
    last |= (_MULTIMESSAGE_BIT if multimessage else 0) | (_BROADCAST_BIT if broadcast else 0)
    return header[: HEADER_BYTES - 1] + bytes([last])


def stitch(messages: Sequence[tuple[bytes, int]]) -> bytes:
    """One frame from (encoded DCCL1 message, its destination id) pairs, in sending order."""
    if not messages:
        raise DcclEncodeError("a frame needs at least one message")
    frame = bytearray([DCCL1_FIRST_BYTE])
    for index, (data, dest) in enumerate(messages):
        if len(data) < HEADER_BYTES or data[0] != DCCL1_FIRST_BYTE:
            raise DcclEncodeError(f"message {index + 1} is not a DCCL1 message")
        last = index == len(messages) - 1
        frame += _with_flags(data[:HEADER_BYTES], not last, dest == BROADCAST_ID)[1:]
        if not last:
            frame.append((len(data) - HEADER_BYTES) & 0xFF)
        frame += data[HEADER_BYTES:]
    return bytes(frame)


def unstitch(frame: bytes) -> list[FramePart]:
    """The messages of a received DCCL1 frame, as 1.1 splits it."""
    if len(frame) < HEADER_BYTES or frame[0] != DCCL1_FIRST_BYTE:
        raise DcclDecodeError("not a DCCL1 frame: it needs 6 bytes starting with 0x20")
    parts: list[FramePart] = []
    rest = frame
    while True:
        if len(rest) < HEADER_BYTES:
            raise DcclDecodeError(f"frame cut short after {len(parts)} message(s)")
        flags = rest[HEADER_BYTES - 1]
        multimessage = bool(flags & _MULTIMESSAGE_BIT)
        broadcast = bool(flags & _BROADCAST_BIT)
        if multimessage and len(rest) > HEADER_BYTES:
            length = rest[HEADER_BYTES]
            rest = rest[:HEADER_BYTES] + rest[HEADER_BYTES + 1 :]
            if length >= _SIGNED_LENGTH_LIMIT:
                # 1.1 reads the length as a signed char: 128 or more takes the whole rest
                multimessage, length = False, len(rest) - HEADER_BYTES
            message = rest[: HEADER_BYTES + length]
            rest = rest[:1] + rest[HEADER_BYTES + length :]
        else:
            message, multimessage = rest, False
        header = _with_flags(message[:HEADER_BYTES], False, False)
        parts.append(FramePart(header + message[HEADER_BYTES:], broadcast))
        if not multimessage:
            return parts
