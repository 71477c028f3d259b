"""Protobuf values printed as C++ protobuf's TextFormat prints them (DebugString, Goby's
single-line format): C escapes for strings, %.15g/%.17g doubles, %.6g/%.9g floats. Python's
text_format differs (shortest-repr numbers, UTF-8 strings), and C++ peers compare or hash these
texts."""

from __future__ import annotations

import math
import struct
from typing import Any

from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.protobuf import enum_type, message_type
from pygoby.protobuf.descriptors import AnyFieldDescriptor

_ESCAPES = {0x0A: "\\n", 0x0D: "\\r", 0x09: "\\t", 0x22: '\\"', 0x27: "\\'", 0x5C: "\\\\"}
_F32 = struct.Struct("<f")


def c_escape(data: bytes) -> str:
    """C++ CEscape: named escapes, other bytes outside printable ASCII as 3-digit octal."""
    out = []
    for byte in data:
        if byte in _ESCAPES:
            out.append(_ESCAPES[byte])
        elif 0x20 <= byte < 0x7F:
            out.append(chr(byte))
        else:
            out.append(f"\\{byte:03o}")
    return "".join(out)


def _float32(value: float) -> float:
    try:
        return _F32.unpack(_F32.pack(value))[0]
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def double_text(value: float) -> str:
    """C++ TextFormat's double: %.15g unless it does not round-trip, then %.17g."""
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    short = f"{value:.15g}"
    return short if float(short) == value else f"{value:.17g}"


def float_text(value: float) -> str:
    """C++ TextFormat's float: %.6g unless it does not round-trip as a float, then %.9g."""
    value = _float32(value)
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    short = f"{value:.6g}"
    return short if _float32(float(short)) == value else f"{value:.9g}"


def scalar_text(field: AnyFieldDescriptor, value: Any) -> str:
    """A non-message field value as C++ TextFormat prints it."""
    cpp = field.cpp_type
    if cpp == FieldDescriptor.CPPTYPE_STRING:
        data = value if isinstance(value, bytes) else value.encode("utf-8", "surrogateescape")
        return '"' + c_escape(data) + '"'
    if cpp == FieldDescriptor.CPPTYPE_BOOL:
        return "true" if value else "false"
    if cpp == FieldDescriptor.CPPTYPE_DOUBLE:
        return double_text(value)
    if cpp == FieldDescriptor.CPPTYPE_FLOAT:
        return float_text(value)
    if cpp == FieldDescriptor.CPPTYPE_ENUM:
        enum_value = enum_type(field).values_by_number.get(value)
        return enum_value.name if enum_value is not None else str(value)
    return str(value)


def field_label(field: AnyFieldDescriptor) -> str:
    if field.is_extension:
        return "[" + field.full_name + "]"
    if field.type == FieldDescriptor.TYPE_GROUP:
        return message_type(field).name
    return field.name


def message_text(msg: Message, single_line: bool = True, indent: int = 0) -> str:
    """C++ TextFormat of a message, fields in number order: single-line ("a: 1 b { c: 2 } ",
    Goby's form, each field followed by a space) or multi-line from `indent` spaces (what
    `DebugString()` prints)."""
    pad = "" if single_line else " " * indent
    parts = []
    for field, value in sorted(msg.ListFields(), key=lambda item: item[0].number):
        label = field_label(field)
        for element in value if field.is_repeated else [value]:
            if field.cpp_type != FieldDescriptor.CPPTYPE_MESSAGE:
                end = " " if single_line else "\n"
                parts.append(f"{pad}{label}: {scalar_text(field, element)}{end}")
            elif single_line:
                parts.append(f"{label} {{ {message_text(element)}}} ")
            else:
                inner = message_text(element, False, indent + 2)
                parts.append(f"{pad}{label} {{\n{inner}{pad}}}\n")
    return "".join(parts)
