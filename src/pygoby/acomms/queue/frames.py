"""The DCCL messages packed one after another in a received frame (as the queue packs them).

Shared by the queue's receive path and the tools that read frames back from logs, so that both
split a frame the same way.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

from google.protobuf.message import Message

from pygoby.dccl import Codec, DcclError

CodecFor = Callable[[bytes], Codec]  # the codec for the bytes starting at a message


def unpack_frame(
    data: bytes, codec_for: CodecFor, undecodable: Callable[[int, DcclError], None]
) -> Iterator[tuple[Message, bytes]]:
    """(message, its bytes) for each DCCL message of `data`, in order. A message that does not
    decode ends the frame: the bytes after it cannot be delimited, so `undecodable(offset,
    error)` is told and the messages before it stand."""
    offset = 0
    while offset < len(data):
        rest = data[offset:]
        try:
            msg, used = codec_for(rest).decode_prefix(rest)
        except DcclError as exc:
            undecodable(offset, exc)
            return
        yield msg, rest[:used]
        # a message always takes at least one byte, so a zero-length decode cannot loop forever
        offset += max(used, 1)
