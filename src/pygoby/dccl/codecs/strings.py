"""String and bytes codecs: v2/v3 strings, var_bytes (v4) and fixed-length bytes."""

from __future__ import annotations

from typing import Any

from pygoby.dccl.codecs.base import FieldCodec, FieldInfo, ceil_log2
from pygoby.dccl.errors import DcclEncodeError, DcclLoadError


class _ByteStringCodec(FieldCodec):
    """Shared by all string/bytes codecs: max_length, value <-> bytes, truncation."""

    max_length_limit: int | None = None

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        self.max_length = int(info.require("max_length"))
        if self.max_length_limit is not None and self.max_length > self.max_length_limit:
            raise DcclLoadError(
                f"{info.name}: max_length {self.max_length} exceeds {self.max_length_limit}"
                f" for {info.codec_name} strings"
            )
        self.is_text = info.category == "string"

    def to_bytes(self, value: Any, strict: bool) -> bytes:
        data = value.encode("utf-8") if isinstance(value, str) else bytes(value)
        if len(data) > self.max_length:
            if strict:
                raise DcclEncodeError(
                    f"{self.info.name}: {len(data)} bytes exceed max_length {self.max_length}"
                )
            data = data[: self.max_length]
        return data

    def from_bytes(self, data: bytes) -> Any:
        # Strings travel as raw bytes and are decoded as such: protobuf checks UTF-8 when the
        # bytes are put into the message (see pygoby.dccl.rawtext for bytes that are not UTF-8).
        return data

    def read_bytes(self, bits: int, pos: int, end: int, n: int) -> bytes:
        raw = self.take(bits, pos, end, 8 * n, self.info.name)
        return raw.to_bytes(n, "little")

    def describe(self) -> str:
        return f"max_length {self.max_length}"


class LengthPrefixedStringCodec(_ByteStringCodec):
    """v2 (8-bit length, max 255) and v3 (ceil_log2(L+1)-bit length) strings: empty = unset."""

    def __init__(self, info: FieldInfo, prefix_bits: int | None = None) -> None:
        super().__init__(info)
        self.prefix = ceil_log2(self.max_length + 1) if prefix_bits is None else prefix_bits

    def encode(self, value: Any, strict: bool) -> tuple[int, int]:
        if value is None:
            return 0, self.prefix
        data = self.to_bytes(value, strict)
        return len(data) | int.from_bytes(data, "little") << self.prefix, self.prefix + 8 * len(
            data
        )

    def decode(self, bits: int, pos: int, end: int) -> tuple[Any, int]:
        n = self.take(bits, pos, end, self.prefix, self.info.name)
        pos += self.prefix
        if n == 0:
            return None, pos
        return self.from_bytes(self.read_bytes(bits, pos, end, n)), pos + 8 * n

    def min_size(self) -> int:
        return self.prefix

    def max_size(self) -> int:
        return self.prefix + 8 * self.max_length


class StringCodecV2(LengthPrefixedStringCodec):
    max_length_limit = 255

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info, prefix_bits=8)


class StringCodecV3(LengthPrefixedStringCodec):
    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)


class VarBytesCodec(_ByteStringCodec):
    """var_bytes: [presence bit if optional][ceil_log2(L+1)-bit length][bytes]; "" != unset."""

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        self.prefix = ceil_log2(self.max_length + 1)
        self.presence = 0 if info.required else 1

    def encode(self, value: Any, strict: bool) -> tuple[int, int]:
        if value is None:
            return 0, self.min_size()
        data = self.to_bytes(value, strict)
        raw = len(data) | int.from_bytes(data, "little") << self.prefix
        if self.presence:
            return 1 | raw << 1, 1 + self.prefix + 8 * len(data)
        return raw, self.prefix + 8 * len(data)

    def decode(self, bits: int, pos: int, end: int) -> tuple[Any, int]:
        if self.presence:
            if not self.take(bits, pos, end, 1, self.info.name):
                return None, pos + 1
            pos += 1
        n = self.take(bits, pos, end, self.prefix, self.info.name)
        pos += self.prefix
        return self.from_bytes(self.read_bytes(bits, pos, end, n)), pos + 8 * n

    def min_size(self) -> int:
        return 1 if self.presence else self.prefix

    def max_size(self) -> int:
        return self.presence + self.prefix + 8 * self.max_length


class FixedBytesCodec(_ByteStringCodec):
    """v2/v3 bytes: exactly max_length bytes (zero padded), after a presence bit if optional."""

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        self.presence = 0 if info.required else 1

    def encode(self, value: Any, strict: bool) -> tuple[int, int]:
        if value is None:
            return 0, self.min_size()
        raw = int.from_bytes(self.to_bytes(value, strict), "little")
        if self.presence:
            return 1 | raw << 1, self.max_size()
        return raw, self.max_size()

    def decode(self, bits: int, pos: int, end: int) -> tuple[Any, int]:
        if self.presence:
            if not self.take(bits, pos, end, 1, self.info.name):
                return None, pos + 1
            pos += 1
        data = self.read_bytes(bits, pos, end, self.max_length)
        return self.from_bytes(data), pos + 8 * self.max_length

    def min_size(self) -> int:
        return 1 if self.presence else 8 * self.max_length

    def max_size(self) -> int:
        return self.presence + 8 * self.max_length
