"""Static codec: 0 bits; decodes to `static_value` parsed like C++ `istream >> value`."""

from __future__ import annotations

import re
from typing import Any

from pygoby.dccl.codecs.base import INTEGER_CATEGORIES, FieldInfo, FixedWidthCodec
from pygoby.dccl.codecs.numeric import f32, wrap_to
from pygoby.dccl.errors import DcclLoadError

_INT = re.compile(r"\s*([+-]?\d+)")
_REAL = re.compile(
    r"\s*([+-]?(?:\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?|inf(?:inity)?|nan))", re.I
)


def parse_static(text: str, category: str) -> Any:
    if category in ("string", "bytes"):
        words = text.split()
        if not words:
            raise ValueError("no word")
        return words[0] if category == "string" else words[0].encode()
    pattern = _INT if category in INTEGER_CATEGORIES else _REAL
    match = pattern.match(text)
    if not match:
        raise ValueError("not a number")
    if category in INTEGER_CATEGORIES:
        return wrap_to(category)(int(match.group(1)))
    value = float(match.group(1))
    return f32(value) if category == "float" else value


class StaticCodec(FixedWidthCodec):
    bits = 0

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        text = info.options.static_value
        if not info.options.HasField("static_value"):
            raise DcclLoadError(f"{info.name}: dccl.static needs (dccl.field).static_value")
        try:
            self.value = parse_static(text, info.category)
        except ValueError:
            raise DcclLoadError(
                f"{info.name}: static_value {text!r} is not a valid {info.category}"
            ) from None
        value = self.value
        self.to_raw = lambda v, strict: 0
        self.from_raw = lambda raw: value

    def describe(self) -> str:
        return f"static {self.value!r}"
