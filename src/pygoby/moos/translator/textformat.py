"""Protobuf TextFormat as Goby's C++ single-line printer writes it, and parsing.

Python's `text_format.MessageToString(as_one_line=True)` differs from C++ (no trailing space,
shortest-repr doubles), and Goby nodes compare these strings, so the printer is our own.
"""

from __future__ import annotations

from google.protobuf import text_format
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.moos.translator.errors import TranslatorError
from pygoby.protobuf.cpp_text import message_text, scalar_text
from pygoby.protobuf.descriptors import AnyFieldDescriptor


def field_value_text(field: AnyFieldDescriptor, value) -> str:
    """One value as TextFormat prints it (also goby's PrintFieldValueToString)."""
    if field.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE:
        return "{ " + message_text(value) + "}"
    return scalar_text(field, value)


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
