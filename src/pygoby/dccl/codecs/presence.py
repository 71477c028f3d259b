"""Presence codec: a presence bit before the version's default codec (required form)."""

from __future__ import annotations

import dataclasses
from typing import Any

from pygoby.dccl.codecs.base import FieldCodec, FieldInfo


class PresenceCodec(FieldCodec):
    """[0] when unset, [1][inner codec, required encoding] when set."""

    def __init__(self, info: FieldInfo, inner: FieldCodec) -> None:
        super().__init__(info)
        self.inner = inner

    def encode(self, value: Any, strict: bool) -> tuple[int, int]:
        if value is None:
            return 0, 1
        raw, n = self.inner.encode(value, strict)
        return 1 | raw << 1, n + 1

    def decode(self, bits: int, pos: int, end: int) -> tuple[Any, int]:
        if not self.take(bits, pos, end, 1, self.info.name):
            return None, pos + 1
        return self.inner.decode(bits, pos + 1, end)

    def min_size(self) -> int:
        return 1

    def max_size(self) -> int:
        return 1 + self.inner.max_size()

    def describe(self) -> str:
        return f"presence bit + {self.inner.describe()}"


def make_presence_codec(info: FieldInfo) -> FieldCodec:
    default_name = f"dccl.default{info.version}"
    inner_info = dataclasses.replace(info, required=True, codec_name=default_name)
    inner = info.registry.create(default_name, inner_info)
    # Required, repeated and oneof fields have no "not set" state: exactly the inner codec.
    return inner if info.required else PresenceCodec(info, inner)
