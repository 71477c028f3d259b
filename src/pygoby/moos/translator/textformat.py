"""Protobuf TextFormat as Goby's C++ single-line printer writes it, and parsing.

Python's `text_format.MessageToString(as_one_line=True)` differs from C++ (no trailing space,
shortest-repr doubles), and Goby nodes compare these strings, so the printer is our own.
"""

from __future__ import annotations

from google.protobuf import text_format
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.moos.translator.conversions import text_format_double, text_format_float
from pygoby.moos.translator.errors import TranslatorError

_ESCAPES = {0x0A: "\\n", 0x0D: "\\r", 0x09: "\\t", 0x22: '\\"', 0x27: "\\'", 0x5C: "\\\\"}


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


def field_value_text(field: FieldDescriptor, value) -> str:
    """One value as TextFormat prints it (also goby's PrintFieldValueToString)."""
    cpp = field.cpp_type
    if cpp == FieldDescriptor.CPPTYPE_MESSAGE:
        return "{ " + message_text(value) + "}"
    if cpp == FieldDescriptor.CPPTYPE_STRING:
        data = value if isinstance(value, bytes) else value.encode("utf-8", "surrogateescape")
        return '"' + c_escape(data) + '"'
    if cpp == FieldDescriptor.CPPTYPE_BOOL:
        return "true" if value else "false"
    if cpp == FieldDescriptor.CPPTYPE_DOUBLE:
        return text_format_double(value)
    if cpp == FieldDescriptor.CPPTYPE_FLOAT:
        return text_format_float(value)
    if cpp == FieldDescriptor.CPPTYPE_ENUM:
        enum_value = field.enum_type.values_by_number.get(value)
        return enum_value.name if enum_value is not None else str(value)
    return str(value)


def _field_label(field: FieldDescriptor) -> str:
    if field.is_extension:
        return "[" + field.full_name + "]"
    if field.type == FieldDescriptor.TYPE_GROUP:
        return field.message_type.name
    return field.name


def message_text(msg: Message) -> str:
    """Single-line TextFormat: fields in number order, each followed by one space."""
    parts = []
    for field, value in sorted(msg.ListFields(), key=lambda item: item[0].number):
        label = _field_label(field)
        values = value if field.is_repeated else [value]
        for element in values:
            if field.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE:
                parts.append(f"{label} {{ {message_text(element)}}} ")
            else:
                parts.append(f"{label}: {field_value_text(field, element)} ")
    return "".join(parts)


def parse_text(text: str, msg: Message) -> None:
    """Replace the contents of `msg` with the TextFormat `text` (all or nothing)."""
    try:
        parsed = type(msg)()
        text_format.Parse(text, parsed, allow_unknown_extension=False)
    except (text_format.ParseError, UnicodeError, ValueError) as exc:
        raise TranslatorError(
            f"cannot parse {msg.DESCRIPTOR.full_name} from TextFormat {text!r}: {exc}"
        ) from None
    msg.Clear()
    msg.MergeFrom(parsed)
