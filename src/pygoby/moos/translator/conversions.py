"""String <-> value conversions with the exact spellings Goby (C++ streams, boost) produces.

Goby's outputs are read by other Goby nodes and mission scripts, so numbers must print the
way C++ prints them, not the way Python's repr does.
"""

from __future__ import annotations

import math
import re
import struct

_FLOAT_MAX = 3.4028234663852886e38

# boost::lexical_cast<double> grammar (whole string, no whitespace).
_DOUBLE_RE = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|nan|inf|infinity)", re.I | re.A
)
_INT_RE = re.compile(r"[+-]?[0-9]+")

INT_LIMITS: dict[str, tuple[int, int]] = {
    "int32": (-(2**31), 2**31 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint32": (0, 2**32 - 1),
    "uint64": (0, 2**64 - 1),
}


def lexical_double(text: str) -> float | None:
    """`boost::lexical_cast<double>`: the value, or None if the cast would throw."""
    if not _DOUBLE_RE.fullmatch(text):
        return None
    value = float(text)
    if math.isinf(value) and not text.lstrip("+-")[:1].isalpha():
        return None  # numeric overflow (e.g. 1e400) is a cast failure, not infinity
    return value


def as_double(text: str) -> float:
    """goby `as<double>`: NaN when the string is not a number."""
    value = lexical_double(text)
    return math.nan if value is None else value


def as_float(text: str) -> float:
    """goby `as<float>`: NaN when not a number or out of float range; rounded to float."""
    value = lexical_double(text)
    if value is None or (math.isfinite(value) and abs(value) > _FLOAT_MAX):
        return math.nan
    return to_float32(value)


def to_float32(value: float) -> float:
    try:
        return struct.unpack("<f", struct.pack("<f", value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)


# More significant digits than any 64-bit integer has.
MAX_INT_DIGITS = 20


def is_integer_literal(text: str) -> bool:
    """What boost::lexical_cast reads as an integer: an optional sign and decimal digits."""
    return _INT_RE.fullmatch(text) is not None


def significant_digits(integer_text: str) -> int:
    """The number of digits of an integer literal without its sign and leading zeros."""
    return len(integer_text.lstrip("+-").lstrip("0"))


def as_int(text: str, kind: str) -> int:
    """goby `as<intN>`: the type's maximum on failure; '-1' wraps for unsigned types."""
    low, high = INT_LIMITS[kind]
    if not is_integer_literal(text):
        return high
    if significant_digits(text) > MAX_INT_DIGITS:
        return high  # out of every type's range and of Python's int() limit: Q-APPS-30
    value = int(text)
    if kind.startswith("u"):
        if value < 0:
            magnitude = -value
            return high if magnitude > high else (high + 1 - magnitude) & high
        return value if value <= high else high
    return value if low <= value <= high else high


def as_bool(text: str) -> bool:
    return text.lower() in ("true", "1")


def _nan_text(value: float) -> str:
    return "-nan" if math.copysign(1.0, value) < 0 else "nan"


def format_general(value: float, precision: int) -> str:
    """C++ `ostream << setprecision(p) << value` (default float format, i.e. %.<p>g)."""
    if math.isnan(value):
        return _nan_text(value)
    return f"{value:.{precision}g}"


def format_double(value: float) -> str:
    """How Goby streams a double field (precision 15): 550, 1023.5, 1e+20, nan."""
    return format_general(value, 15)


def format_float(value: float) -> str:
    """How Goby streams a float field (precision 6)."""
    return format_general(value, 6)


def double_to_string17(value: float) -> str:
    """`as<std::string>(double)`: 17 significant digits (0.1 -> 0.10000000000000001)."""
    return format_general(value, 17)


def looks_like_double(text: str) -> bool:
    """Would `boost::lexical_cast<double>` accept this? (decides MOOS double vs string posts)"""
    return lexical_double(text) is not None


def hex_encode(data: bytes) -> str:
    return data.hex()


def hex_decode(text: str) -> bytes:
    """goby `hex_decode`: odd length gets a leading 0 nibble; non-hex characters count as 0."""
    if len(text) % 2:
        text = "0" + text
    nibbles = [int(c, 16) if c in "0123456789abcdefABCDEF" else 0 for c in text]
    return bytes(nibbles[i] << 4 | nibbles[i + 1] for i in range(0, len(nibbles), 2))
