"""Bounded numeric codec, used by every codec version for integers, float and double.

The arithmetic reproduces the reference exactly: rounding is floor(x + 0.5), resolutions below 1
multiply by inv = 1.0 / res, float fields round every intermediate to float32, and integer fields
truncate toward zero at each conversion.
"""

from __future__ import annotations

import copy
import math
import struct
from collections.abc import Callable
from typing import Any

from pygoby.dccl.codecs.base import INTEGER_CATEGORIES, FieldInfo, FixedWidthCodec, ceil_log2
from pygoby.dccl.errors import DcclEncodeError, DcclLoadError

_F32 = struct.Struct("<f")
_INF = float("inf")
_EPSILON = 2.220446049250313e-16  # DBL_EPSILON

TYPE_LIMITS: dict[str, tuple[int, int]] = {
    "int32": (-(2**31), 2**31 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint32": (0, 2**32 - 1),
    "uint64": (0, 2**64 - 1),
}
_FLOAT32_MAX = 3.4028234663852886e38


def f32(x: float) -> float:
    """Round a double to the nearest float32 (as a C++ float variable would store it)."""
    try:
        return _F32.unpack(_F32.pack(x))[0]
    except OverflowError:
        return _INF if x > 0 else -_INF


def c_round(x: float) -> int:
    return math.floor(x + 0.5)


def c_remainder(v: int, d: int) -> int:
    """C's % on integers: truncates toward zero, so the result has the sign of v."""
    r = abs(v) % d
    return -r if v < 0 else r


def quantize_real(x: float, res: float, inv: float) -> float:
    if res >= 1:
        return c_round(x / res) * res
    return c_round(x * inv) / inv


def wrap_to(category: str) -> Callable[[int], int]:
    """Conversion of an integer to the field's C++ type (two's complement wrap-around)."""
    lo, hi = TYPE_LIMITS[category]
    span = hi - lo + 1
    return lambda v: v if lo <= v <= hi else (v - lo) % span + lo


def make_quantize_int(res: float, category: str) -> Callable[[int], int]:
    if res - math.trunc(res) >= _EPSILON:  # res has a fractional part: no quantisation at all
        return lambda v: v
    step = int(res)
    half = res / 2
    wrap = wrap_to(category)

    def quantize_int(v: int) -> int:
        r = c_remainder(v, step)
        v -= r
        if r >= half:
            v = wrap(int(float(v) + res))
        return v

    return quantize_int


class NumericCodec(FixedWidthCodec):
    """min/max/precision/resolution numeric codec for int*, uint*, float and double fields."""

    def __init__(
        self,
        info: FieldInfo,
        bounds: tuple[float, float] | None = None,
        resolution: float | None = None,
        category: str | None = None,
    ) -> None:
        super().__init__(info)
        category = category or info.category
        if bounds is None:
            self.min = float(info.require("min"))
            self.max = float(info.require("max"))
        else:
            self.min, self.max = bounds
        self.res = self._resolution(info) if resolution is None else resolution
        self.null = 0 if info.required else 1
        self._validate(category)
        self.category = category
        self.static_bounds = (self.min, self.max)
        self.bits = ceil_log2((self.max - self.min) / self.res + 1 + self.null)
        self.inv = 1.0 / self.res
        self.to_raw, self.from_raw = self._build(category)

    def rebound(self, lo: float, hi: float) -> NumericCodec:
        """This codec with other bounds (dynamic conditions): the width follows them, as in
        C++ DCCL; the bounds are not validated again."""
        other = copy.copy(self)
        other.min, other.max = lo, hi
        other.bits = ceil_log2(max(0.0, (hi - lo) / self.res + 1 + self.null))
        other.to_raw, other.from_raw = other._build(self.category)
        return other

    def _resolution(self, info: FieldInfo) -> float:
        opts = info.options
        if opts.HasField("precision") and opts.HasField("resolution"):
            raise DcclLoadError(f"{info.name}: set precision or resolution, not both")
        if opts.HasField("resolution"):
            res = opts.resolution
            if not res > 0:
                raise DcclLoadError(f"{info.name}: resolution must be > 0 (is {res})")
            return res
        return math.pow(10.0, -opts.precision)

    def _validate(self, category: str) -> None:
        name = self.info.name
        if not (math.isfinite(self.min) and math.isfinite(self.max)):
            raise DcclLoadError(f"{name}: min and max must be finite")
        if self.min > self.max:
            raise DcclLoadError(f"{name}: min {self.min} is greater than max {self.max}")
        if category in TYPE_LIMITS:
            lo, hi = TYPE_LIMITS[category]
            if self.min < lo or self.max > hi:
                raise DcclLoadError(f"{name}: [{self.min}, {self.max}] does not fit a {category}")
        elif category == "float" and max(abs(self.min), abs(self.max)) > _FLOAT32_MAX:
            raise DcclLoadError(f"{name}: [{self.min}, {self.max}] does not fit a float")
        if self.info.options.HasField("resolution"):
            inv = 1.0 / self.res
            for bound in (self.min, self.max):
                if abs(quantize_real(bound, self.res, inv) - bound) > 1e-10:
                    raise DcclLoadError(
                        f"{name}: {bound} is not a multiple of the resolution {self.res}"
                    )
        if self.max > self.min and math.log2(self.max - self.min) - math.log2(self.res) > 53:
            raise DcclLoadError(f"{name}: range/resolution needs more than 53 bits")

    def describe(self) -> str:
        return f"[{self.min:g}, {self.max:g}] res {self.res:g}"

    def _fail(self, value: Any, strict: bool) -> int:
        if strict:
            raise DcclEncodeError(
                f"{self.info.name}: value {value!r} is out of range [{self.min:g}, {self.max:g}]"
            )
        return 0

    def _build(self, category: str) -> tuple[Callable[[Any, bool], int], Callable[[int], Any]]:
        if category in INTEGER_CATEGORIES:
            return self._build_integer(category)
        if category == "float":
            return self._build_float()
        return self._build_double()

    def _build_double(self):
        lo, hi, res, inv, null, fail = self.min, self.max, self.res, self.inv, self.null, self._fail
        floor = math.floor
        qmin = quantize_real(lo, res, inv)
        if res >= 1:

            def to_raw(v: float, strict: bool) -> int:
                if v != v:  # NaN: the reference writes raw 0 (decodes as min)
                    return null
                if not -_INF < v < _INF:
                    return fail(v, strict)
                w = floor(v / res + 0.5) * res
                if w < lo or w > hi:
                    return fail(v, strict)
                return floor((w - qmin) / res + 0.5) + null

            def from_raw(raw: int) -> float | None:
                if null:
                    if raw == 0:
                        return None
                    raw -= 1
                return floor((raw * res + qmin) / res + 0.5) * res

        else:

            def to_raw(v: float, strict: bool) -> int:
                if v != v:
                    return null
                if not -_INF < v < _INF:
                    return fail(v, strict)
                w = floor(v * inv + 0.5) / inv
                if w < lo or w > hi:
                    return fail(v, strict)
                return floor((w - qmin) * inv + 0.5) + null

            def from_raw(raw: int) -> float | None:
                if null:
                    if raw == 0:
                        return None
                    raw -= 1
                return floor((raw / inv + qmin) * inv + 0.5) / inv

        return to_raw, from_raw

    def _build_float(self):
        lo, hi, res, inv, null, fail = self.min, self.max, self.res, self.inv, self.null, self._fail
        floor = math.floor
        m32 = f32(quantize_real(f32(lo), res, inv))

        def to_raw(v: float, strict: bool) -> int:
            if v != v:
                return null
            if not -_INF < v < _INF:
                return fail(v, strict)
            w = f32(quantize_real(v, res, inv))
            if w < lo or w > hi:
                return fail(v, strict)
            w = f32(w - m32)
            w = f32(w / res) if res >= 1 else f32(w * inv)
            return int(f32(floor(w + 0.5))) + null

        def from_raw(raw: int) -> float | None:
            if null:
                if raw == 0:
                    return None
                raw -= 1
            w = f32(float(raw))
            w = f32(w * res) if res >= 1 else f32(w / inv)
            return f32(quantize_real(f32(w + m32), res, inv))

        return to_raw, from_raw

    def _build_integer(self, category: str):
        lo, hi, res, inv, null, fail = self.min, self.max, self.res, self.inv, self.null, self._fail
        quantize = make_quantize_int(res, category)
        wrap = wrap_to(category)
        qmin = quantize(int(lo))
        if res >= 1:

            def to_raw(v: int, strict: bool) -> int:
                w = quantize(v)
                if not lo <= float(w) <= hi:  # compared as doubles, like the reference
                    return fail(v, strict)
                return int((w - qmin) / res) + null

            def from_raw(raw: int) -> int | None:
                if null:
                    if raw == 0:
                        return None
                    raw -= 1
                return wrap(quantize(wrap(int(wrap(raw) * res) + qmin)))

        else:

            def to_raw(v: int, strict: bool) -> int:
                w = quantize(v)
                if not lo <= float(w) <= hi:
                    return fail(v, strict)
                return int((w - qmin) * inv) + null

            def from_raw(raw: int) -> int | None:
                if null:
                    if raw == 0:
                        return None
                    raw -= 1
                return wrap(quantize(wrap(int(wrap(raw) / inv) + qmin)))

        return to_raw, from_raw
