"""Time codec: the time within a window of num_days days; the receiver's clock
supplies the rest."""

from __future__ import annotations

import math

from pygoby.dccl.codecs.base import FieldInfo, FixedWidthCodec
from pygoby.dccl.codecs.numeric import NumericCodec, c_remainder, c_round


class TimeCodec(FixedWidthCodec):
    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        opts = info.options
        is_double = info.category == "double"
        scale = 1 if is_double else 1_000_000  # double: seconds; 64-bit integers: microseconds
        window = opts.num_days * 86400
        if opts.HasField("precision"):
            res = math.pow(10.0, -(opts.precision + math.log10(scale)))
        else:
            res = opts.resolution
        self.window = window
        self.inner = NumericCodec(
            info, bounds=(0.0, float(window)), resolution=res, category="double"
        )
        self.bits = self.inner.bits
        inner_to_raw, inner_from_raw = self.inner.to_raw, self.inner.from_raw
        now = info.now
        half = window // 2

        def to_raw(value, strict: bool) -> int:
            if value is None:
                return 0
            return inner_to_raw(math.fmod(value / scale, window), strict)

        if is_double:
            digits = opts.precision if opts.HasField("precision") else 0
            power = math.pow(10.0, digits)

            def finish(t: float):
                return c_round(t * power) / power

        else:
            digits = opts.precision if opts.HasField("precision") else -6
            step = 10 ** (-digits) if digits < 0 else 1

            def finish(t: float):
                v = int(t)
                if step == 1:
                    return v
                r = c_remainder(v, step)
                return v - r + (step if r >= step // 2 else 0)

        def from_raw(raw: int):
            e = inner_from_raw(raw)
            if e is None:
                return None
            current = int(now())
            daystart = current - current % window
            today = current - daystart
            if e - today > half:
                daystart -= window
            elif today - e > half:
                daystart += window
            return finish((daystart + e) * scale)

        self.to_raw, self.from_raw = to_raw, from_raw

    def describe(self) -> str:
        return f"time window {self.window} s, res {self.inner.res:g}"
