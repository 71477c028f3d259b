"""The subset of Boost.Format that TECHNIQUE_FORMAT output relies on.

Directives: `%N%`, `%N$<flags><width>.<prec><conv>`, `%|N$...|`, non-positional printf
directives (`%5d`), and `%%`. Missing arguments render as empty (goby disables boost's
too-few/too-many-arguments errors). Floating-point arguments arrive "grouped" with a fixed
precision (15 for doubles, 6 for floats) that overrides the directive's precision while
keeping its flags and conversion (goby3's output, reproduced: QUIRKS.md Q-APPS-21).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from pygoby.moos.translator.errors import TranslatorConfigError


@dataclass(frozen=True)
class IntArg:
    value: int
    bits: int  # 32 or 64: width of the two's complement used for hex/octal of negatives


@dataclass(frozen=True)
class FloatArg:
    value: float
    precision: int


Arg = str | IntArg | FloatArg


@dataclass(frozen=True)
class Directive:
    argument: int | None  # 1-based; None = next sequential argument
    flags: str = ""
    width: int = 0
    precision: int | None = None
    conversion: str = ""


_PRINTF_SPEC = re.compile(
    r"([-+ 0#']*)([0-9]*)(?:\.([0-9]*))?(?:hh|h|ll|l|L|j|z|t|q)?([diuoxXeEfFgGaAcCsS]?)"
)


def parse_format(fmt: str) -> list[str | Directive]:
    """Split a Boost.Format string into literal text and directives."""
    items: list[str | Directive] = []
    literal: list[str] = []
    i = 0
    positional = sequential = False
    while i < len(fmt):
        c = fmt[i]
        if c != "%":
            literal.append(c)
            i += 1
            continue
        if fmt[i + 1 : i + 2] == "%":
            literal.append("%")
            i += 2
            continue
        directive, i = _parse_directive(fmt, i + 1)
        if directive.argument is None:
            sequential = True
        else:
            positional = True
        if literal:
            items.append("".join(literal))
            literal = []
        items.append(directive)
    if positional and sequential:
        raise TranslatorConfigError(f"format {fmt!r} mixes positional and sequential directives")
    if literal:
        items.append("".join(literal))
    return items


def _parse_directive(fmt: str, i: int) -> tuple[Directive, int]:
    if fmt[i : i + 1] == "|":
        close = fmt.find("|", i + 1)
        if close < 0:
            raise TranslatorConfigError(f"format {fmt!r}: unterminated %|...| directive")
        directive = _parse_spec(fmt[i + 1 : close], fmt, require_conversion=False)
        return directive, close + 1
    digits = re.match(r"[0-9]+", fmt[i:])
    if digits:
        end = i + digits.end()
        if fmt[end : end + 1] == "%":
            return Directive(int(digits.group())), end + 1
        if fmt[end : end + 1] == "$":
            match = _PRINTF_SPEC.match(fmt, end + 1)
            if match is None or not match.group(4):
                raise TranslatorConfigError(f"format {fmt!r}: bad directive at position {i - 1}")
            return _directive(int(digits.group()), match, fmt), match.end()
    match = _PRINTF_SPEC.match(fmt, i)
    if match is None or not match.group(4):
        raise TranslatorConfigError(f"format {fmt!r}: bad directive at position {i - 1}")
    return _directive(None, match, fmt), match.end()


def _parse_spec(spec: str, fmt: str, require_conversion: bool) -> Directive:
    argument = None
    digits = re.match(r"([0-9]+)\$", spec)
    if digits:
        argument = int(digits.group(1))
        spec = spec[digits.end() :]
    match = _PRINTF_SPEC.fullmatch(spec)
    if match is None or (require_conversion and not match.group(4)):
        raise TranslatorConfigError(f"format {fmt!r}: bad directive {spec!r}")
    return _directive(argument, match, fmt)


def _directive(argument: int | None, match: re.Match, fmt: str) -> Directive:
    if argument == 0:
        raise TranslatorConfigError(f"format {fmt!r}: argument numbers start at 1")
    flags, width, precision, conversion = match.groups()
    return Directive(
        argument,
        flags,
        int(width) if width else 0,
        int(precision or 0) if precision is not None else None,
        conversion,
    )


def _render_int(arg: IntArg, d: Directive) -> tuple[str, str]:
    conv = d.conversion
    value = arg.value
    if conv in ("x", "X", "o"):
        if value < 0:
            value &= (1 << arg.bits) - 1
        digits = format(value, "x" if conv != "o" else "o")
        prefix = ""
        if "#" in d.flags and value:
            prefix = "0x" if conv == "x" else "0X" if conv == "X" else "0"
        return prefix, digits.upper() if conv == "X" else digits
    sign = "-" if value < 0 else "+" if "+" in d.flags else " " if " " in d.flags else ""
    return sign, str(abs(value))


def _render_float(arg: FloatArg, d: Directive) -> tuple[str, str]:
    value = arg.value
    conv = d.conversion
    if math.isnan(value):
        body = "nan"
        sign = "-" if math.copysign(1.0, value) < 0 else ""
    else:
        alt = "#" if "#" in d.flags else ""
        kind = "f" if conv in "fF" and conv else "e" if conv in "eE" and conv else "g"
        body = ("%" + alt + "." + str(arg.precision) + kind) % abs(value)
        sign = "-" if math.copysign(1.0, value) < 0 else ""
    if not sign:
        sign = "+" if "+" in d.flags else " " if " " in d.flags else ""
    if conv in "EFGX" and conv:
        body = body.upper()
    return sign, body


def _render_text(d: Directive, text: str) -> str:
    """A string argument (an algorithm's output, a string or enum field...) as Boost.Format
    streams it: the conversion character does not convert it; only `s`/`S` with a precision
    (at most that many characters) and `c`/`C` (one character) cut it. Flags: `-` pads on
    the right, `0` (unless `-`) fills with zeros on the left, ` ` (unless `+` or `0`) puts a
    space before text that does not start with a sign."""
    cut = _cut(d)
    text = text if cut is None else text[:cut]
    zero_fill = "0" in d.flags and "-" not in d.flags
    if " " in d.flags and "+" not in d.flags and not zero_fill and text[:1] not in ("+", "-"):
        text = " " + text
    padding = d.width - len(text)
    if padding <= 0:
        return text
    if "-" in d.flags:
        return text + " " * padding
    return ("0" if zero_fill else " ") * padding + text


def _cut(d: Directive) -> int | None:
    """How many characters Boost.Format keeps of an argument's output (None: all)."""
    if d.conversion in ("s", "S"):
        return d.precision
    return 1 if d.conversion in ("c", "C") else None


def render(d: Directive, arg: Arg) -> str:
    if isinstance(arg, str):
        return _render_text(d, arg)
    if isinstance(arg, IntArg):
        prefix, body = _render_int(arg, d)
    else:
        prefix, body = _render_float(arg, d)
    cut = _cut(d)
    if cut is not None:  # a number printed with %s/%c is cut like text
        return _render_text(
            Directive(d.argument, d.flags.replace(" ", ""), d.width), (prefix + body)[:cut]
        )
    padding = d.width - len(prefix) - len(body)
    if padding <= 0:
        return prefix + body
    if "-" in d.flags:
        return prefix + body + " " * padding
    if "0" in d.flags:
        return prefix + "0" * padding + body
    return " " * padding + prefix + body


def boost_format(items: list[str | Directive], args: list[Arg]) -> str:
    out = []
    next_sequential = 0
    for item in items:
        if isinstance(item, str):
            out.append(item)
            continue
        if item.argument is None:
            index = next_sequential
            next_sequential += 1
        else:
            index = item.argument - 1
        if index < len(args):
            out.append(render(item, args[index]))
    return "".join(out)
