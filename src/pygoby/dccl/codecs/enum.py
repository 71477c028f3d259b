"""Enum codecs: an int32 numeric field over the value index (packed) or number."""

from __future__ import annotations

from pygoby.dccl.codecs.base import FieldInfo, FixedWidthCodec, ceil_log2
from pygoby.dccl.errors import DcclLoadError
from pygoby.protobuf import enum_type


class EnumCodec(FixedWidthCodec):
    """v3/v4 enum: packed (index) unless `packed_enum: false`, then the enum number."""

    honour_packed_option = True

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        values = enum_type(info.descriptor).values
        if not values:
            raise DcclLoadError(f"{info.name}: enum has no values")
        null = 0 if info.required else 1
        packed = info.options.packed_enum or not self.honour_packed_option
        self.packed = packed
        if packed:
            numbers = [v.number for v in values]
            index = {n: i for i, n in reversed(list(enumerate(numbers)))}
            self.lo, self.hi = 0, len(numbers) - 1
            self.bits = ceil_log2(len(numbers) + null)

            def to_raw(v: int | None, strict: bool) -> int:
                return 0 if v is None else index[v] + null

            def from_raw(raw: int) -> int | None:
                i = raw - null
                return numbers[i] if 0 <= i < len(numbers) else None

        else:
            known = frozenset(v.number for v in values)
            lo, hi = min(known), max(known)
            self.lo, self.hi = lo, hi
            self.bits = ceil_log2(hi - lo + 1 + null)

            def to_raw(v: int | None, strict: bool) -> int:
                return 0 if v is None else v - lo + null

            def from_raw(raw: int) -> int | None:
                if null:
                    if raw == 0:
                        return None
                    raw -= 1
                n = raw + lo
                return n if n in known else None

        self.to_raw, self.from_raw = to_raw, from_raw
        self.value_names = [f"{v.name}={v.number}" for v in values]

    def describe(self) -> str:
        """The encoding and the values by name (as the .proto lists them; a long enum's first
        and last eight)."""
        names = self.value_names
        shown = names if len(names) <= 16 else [*names[:8], "...", *names[-8:]]
        kind = "index" if self.packed else "number"
        return f"{kind} [{self.lo}, {self.hi}]: {', '.join(shown)}"


class EnumCodecV2(EnumCodec):
    """v2 enum: always packed (`packed_enum` is ignored)."""

    honour_packed_option = False
