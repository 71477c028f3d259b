"""Values as Goby 1.1's libdccl converts them (its DCCLMessageVal): a field value arrives as a
string, double, long or bool and is read as whatever the field needs, with 1.1's rules.

pAcommsHandler 1.1 hands the codec strings; callers may also pass Python numbers and bools.
A conversion that 1.1 cannot make gives None (1.1: "no value"), which every field encodes as
unset.
"""

from __future__ import annotations

import math
import re

Value = str | float | int | bool | None

# What boost::lexical_cast<double> accepts: a whole C floating literal, no surrounding blanks.
_DOUBLE = re.compile(r"[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf|infinity)", re.I)
# Doubles handed in by callers are formatted with 1.1's default precision of 15 digits.
DEFAULT_PRECISION = 15
_LONG_MIN, _LONG_MAX = -(2**63), 2**63 - 1


def unbiased_round(value: float, decimals: float) -> float:
    """1.1's rounding to `decimals` places: a remainder of exactly one half goes to the even
    neighbour, anything else to the nearest (computed on the scaled double, as 1.1 does)."""
    if not math.isfinite(value):
        return value
    scale = math.pow(10.0, decimals)
    scaled = value * scale
    if not math.isfinite(scaled):
        # a huge value overflows when scaled: C++'s floor keeps the infinity, and so does 1.1
        return scaled / scale
    floor = float(math.floor(scaled))
    remainder = scaled - floor
    if remainder < 0.5 or (remainder == 0.5 and not int(floor) & 1):
        return floor / scale
    return (floor + 1) / scale


def as_double(value: Value) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool):
        return 1.0 if value else 0.0
    if isinstance(value, int | float):
        try:
            return float(value)
        except OverflowError:
            return None
    if _DOUBLE.fullmatch(value):
        return float(value)
    return {"true": 1.0, "false": 0.0}.get(value.lower())


def _rounded_long(number: float) -> int | None:
    rounded = unbiased_round(number, 0)
    if not math.isfinite(rounded) or not _LONG_MIN <= rounded <= _LONG_MAX:
        return None
    return int(rounded)


def as_long(value: Value) -> int | None:
    """A string or double is rounded (half to even); true/false read as 1/0."""
    if value is None:
        return None
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, int):
        return value if _LONG_MIN <= value <= _LONG_MAX else None
    if isinstance(value, float):
        return _rounded_long(value)
    number = as_double(value) if _DOUBLE.fullmatch(value) else None
    if number is not None and (converted := _rounded_long(number)) is not None:
        return converted
    return {"true": 1, "false": 0}.get(value.lower())


def as_bool(value: Value) -> bool | None:
    """Strings true/1/false/0 (any case); numbers must lie in bool's range, as 1.1's checked
    cast requires (a double strictly between -1 and 2, a long 0 or 1)."""
    if value is None or isinstance(value, bool):
        return value
    if isinstance(value, int):
        return bool(value) if value in (0, 1) else None
    if isinstance(value, float):
        return None if value <= -1 or value >= 2 else value != 0
    return {"true": True, "1": True, "false": False, "0": False}.get(value.lower())


def as_string(value: Value) -> str:
    """1.1's text of a value ("" when there is none): doubles in fixed notation with 15
    decimals when that fits in 15 significant digits, else with 15 significant digits."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        magnitude = math.log10(abs(value)) if value else -math.inf
        if magnitude + DEFAULT_PRECISION <= DEFAULT_PRECISION:
            return f"{value:.{DEFAULT_PRECISION}f}"
        return f"{value:.{DEFAULT_PRECISION}g}"
    return value


def to_unsigned_long(number: float) -> int:
    """C++'s (unsigned long) cast of a double as x86-64 computes it (NaN gives 2^63)."""
    if math.isnan(number) or number >= 2.0**64:
        return 1 << 63 if math.isnan(number) else 0
    return int(number) & (2**64 - 1)
