"""`dccl.hash`'s field codec: a uint32 field that sends the message definition's hash masked to
its `max`; the hash itself is computed from the type's plans by `pygoby.dccl.hashing`."""

from __future__ import annotations

import dataclasses

from pygoby.dccl.codecs.base import FieldInfo, FixedWidthCodec
from pygoby.dccl.codecs.numeric import NumericCodec
from pygoby.dccl.errors import DcclDecodeError, DcclLoadError


class HashCodec(FixedWidthCodec):
    """A uint32 field sending `definition hash & max` (always, in the required encoding); on
    decode a different value is an error. The hash is set when the whole type is planned."""

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        opts = info.options
        lo, hi = opts.min, opts.max
        if lo != 0:
            raise DcclLoadError(f"{info.name}: dccl.hash needs (dccl.field).min = 0")
        if hi > 2**32 - 1 or hi != 2 ** (int(hi).bit_length()) - 1 or hi != int(hi):
            raise DcclLoadError(
                f"{info.name}: dccl.hash needs (dccl.field).max = 2^k - 1 (e.g. 255, 4294967295)"
            )
        required = dataclasses.replace(info, required=True)
        self.inner = NumericCodec(required, bounds=(0.0, hi), resolution=1.0, category="uint32")
        self.bits = self.inner.bits
        self.mask = int(hi)
        self.expected = 0
        inner_to_raw, inner_from_raw = self.inner.to_raw, self.inner.from_raw

        def to_raw(value, strict: bool) -> int:
            return inner_to_raw(self.expected, strict)

        def from_raw(raw: int) -> int:
            received = inner_from_raw(raw)
            if received != self.expected:
                raise DcclDecodeError(
                    f"{info.name}: hash mismatch (expected {self.expected}, received {received}):"
                    " sender and receiver do not use the same DCCL definition"
                )
            return received

        self.to_raw, self.from_raw = to_raw, from_raw

    def set_hash(self, full_hash: int) -> None:
        self.expected = full_hash & self.mask
        self.null_raw = self.inner.to_raw(self.expected, False)

    def describe(self) -> str:
        return f"definition hash & {self.mask:#x}"
