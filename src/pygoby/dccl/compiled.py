"""A loaded root message type in compiled form: its plans, sizes and generated functions."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from google.protobuf.message import Message

from pygoby.dccl.plan import MessageNode


@dataclass
class CompiledType:
    """Everything needed to encode/decode one loaded root message type."""

    cls: type[Message]
    name: str
    version: int
    id: int | None
    id_bits: int
    max_bytes: int
    head: MessageNode
    body: MessageNode
    head_bytes: int  # the header is fixed-size: ceil((id_bits + head bits) / 8)
    encode_head: Callable
    encode_body: Callable
    decode_head: Callable
    decode_body: Callable
    # The generated Python of the four functions above, by function name ("encode_head", ...);
    # tracebacks show its lines under `<dccl TYPE FUNCTION>`.
    source: dict[str, str]

    def max_size(self) -> int:
        return self.head_bytes + (self.body.max_size() + 7) // 8

    def min_size(self) -> int:
        return self.head_bytes + (self.body.min_size() + 7) // 8
