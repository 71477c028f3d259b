"""Per-field trace of encoding and decoding (`Codec(trace=True)`), modelled on C++ DCCL's
DEBUG2 log: one line per field with its path, value, and the bits it occupies.

Lines go to the `pygoby.dccl.trace` logger at DEBUG, e.g.

    encode example.Tiny body: b = 3 (3 bits: 011)

Each record also carries `dccl_field`, `dccl_value` and `dccl_bits` attributes. Only the traced
variant of the generated code calls a tracer; a Codec without `trace` runs code with no hooks.
"""

from __future__ import annotations

import logging
from typing import Any

from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.protobuf.descriptors import AnyFieldDescriptor

log = logging.getLogger("pygoby.dccl.trace")


def show(value: Any, field: AnyFieldDescriptor | None = None) -> str:
    """A field value as the trace prints it (enum values by name)."""
    if value is None:
        return "not set"
    if isinstance(value, Message):
        return "{" + text_format.MessageToString(value, as_one_line=True) + "}"
    if isinstance(value, int) and field is not None and field.enum_type is not None:
        enum_value = field.enum_type.values_by_number.get(value)
        return repr(value) if enum_value is None else enum_value.name
    if isinstance(value, str | bytes | bool | int | float):
        return repr(value)
    return "[" + ", ".join(show(v, field) for v in value) + "]"  # a repeated field


class FieldTracer:
    """Called by traced generated code after each field of one part of one message type."""

    def __init__(self, type_name: str, action: str, part: str) -> None:
        self.where = f"{action} {type_name} {part}"
        self.fields: dict[str, AnyFieldDescriptor] = {}  # by the paths the generated code passes

    def __call__(self, path: str, value: Any, start: int, end: int, bits: int) -> None:
        """`bits` holds the field's bits at positions start..end (LSB first)."""
        if not log.isEnabledFor(logging.DEBUG):
            return
        nbits = end - start
        # most significant bit first, as C++ DCCL prints a Bitset
        pattern = f": {bits >> start & (1 << nbits) - 1:0{nbits}b}" if nbits else ""
        log.debug(
            "%s: %s = %s (%d bit%s%s)",
            self.where,
            path,
            show(value, self.fields.get(path)),
            nbits,
            "" if nbits == 1 else "s",
            pattern,
            extra={"dccl_field": path, "dccl_value": value, "dccl_bits": nbits},
        )
