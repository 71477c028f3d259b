"""Reflection helpers shared by the CSV and FORMAT techniques: render one field value the way
Goby streams it, and convert a string back into a field value (goby `as<T>` rules)."""

from __future__ import annotations

import logging

from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import DecodeError, Message

from pygoby.moos.translator.conversions import (
    MAX_INT_DIGITS,
    as_bool,
    as_double,
    as_float,
    as_int,
    format_double,
    format_float,
    hex_decode,
    hex_encode,
    is_integer_literal,
    significant_digits,
)
from pygoby.moos.translator.errors import TranslatorError, UnconvertibleError
from pygoby.protobuf import enum_type
from pygoby.protobuf.descriptors import AnyFieldDescriptor

log = logging.getLogger("pygoby.moos.translator")

INT_KINDS = {
    FieldDescriptor.CPPTYPE_INT32: "int32",
    FieldDescriptor.CPPTYPE_INT64: "int64",
    FieldDescriptor.CPPTYPE_UINT32: "uint32",
    FieldDescriptor.CPPTYPE_UINT64: "uint64",
}


def is_message(field: AnyFieldDescriptor) -> bool:
    return field.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE


def is_bytes(field: AnyFieldDescriptor) -> bool:
    return field.type == FieldDescriptor.TYPE_BYTES


def strip_name_from_enum(value_name: str, field_name: str) -> str:
    """use_short_enum on output: remove the first case-insensitive occurrence of `<field>_`
    anywhere in the value name (goby3's behaviour, reproduced: not only a
    prefix; QUIRKS.md Q-APPS-8)."""
    needle = field_name.lower() + "_"
    pos = value_name.lower().find(needle)
    return value_name if pos < 0 else value_name[:pos] + value_name[pos + len(needle) :]


def enum_name(field: AnyFieldDescriptor, number: int, use_short_enum: bool) -> str:
    value = enum_type(field).values_by_number.get(number)
    name = value.name if value is not None else str(number)
    return strip_name_from_enum(name, field.name) if use_short_enum else name


def serialize_message(msg: Message) -> bytes:
    return msg.SerializePartialToString(deterministic=True)


def stream_value(field: AnyFieldDescriptor, value, use_short_enum: bool) -> str:
    """One element of `field` as Goby's CSV/FORMAT serializers stream it."""
    cpp = field.cpp_type
    if cpp == FieldDescriptor.CPPTYPE_MESSAGE:
        return hex_encode(serialize_message(value))
    if cpp in INT_KINDS:
        return str(value)
    if cpp == FieldDescriptor.CPPTYPE_BOOL:
        return "true" if value else "false"
    if cpp == FieldDescriptor.CPPTYPE_STRING:
        return hex_encode(value) if is_bytes(field) else value
    if cpp == FieldDescriptor.CPPTYPE_FLOAT:
        return format_float(value)
    if cpp == FieldDescriptor.CPPTYPE_DOUBLE:
        return format_double(value)
    return enum_name(field, value, use_short_enum)


def default_value(field: AnyFieldDescriptor):
    """The value an unset element reads as: the declared default, else the type default."""
    if not field.is_repeated:
        return field.default_value
    if field.cpp_type == FieldDescriptor.CPPTYPE_ENUM:
        return enum_type(field).values[0].number
    if field.cpp_type == FieldDescriptor.CPPTYPE_STRING:
        return b"" if is_bytes(field) else ""
    return _TYPE_DEFAULTS[field.cpp_type]


_TYPE_DEFAULTS = {
    FieldDescriptor.CPPTYPE_INT32: 0,
    FieldDescriptor.CPPTYPE_INT64: 0,
    FieldDescriptor.CPPTYPE_UINT32: 0,
    FieldDescriptor.CPPTYPE_UINT64: 0,
    FieldDescriptor.CPPTYPE_DOUBLE: 0.0,
    FieldDescriptor.CPPTYPE_FLOAT: 0.0,
    FieldDescriptor.CPPTYPE_BOOL: False,
}


def value_from_string(
    field: AnyFieldDescriptor, text: str, use_short_enum: bool, *, bytes_in_hex: bool = True
):
    """Convert `text` to a scalar value for `field` (not for message fields). A bytes field
    reads `text` as hex, or with `bytes_in_hex=False` as the text's own UTF-8 bytes (goby3's
    FORMAT create: QUIRKS.md Q-APPS-31)."""
    cpp = field.cpp_type
    if cpp in INT_KINDS:
        if is_integer_literal(text) and significant_digits(text) > MAX_INT_DIGITS:
            log.warning(
                "field %s: a %d-digit integer is out of range; set to the %s maximum as goby3 does",
                field.name,
                len(text),
                INT_KINDS[cpp],
            )
        return as_int(text, INT_KINDS[cpp])
    if cpp == FieldDescriptor.CPPTYPE_BOOL:
        return as_bool(text)
    if cpp == FieldDescriptor.CPPTYPE_STRING:
        if is_bytes(field):
            return hex_decode(text) if bytes_in_hex else text.encode("utf-8", "surrogateescape")
        try:
            text.encode("utf-8")
        except UnicodeEncodeError:
            raise TranslatorError(
                f"value for string field {field.name} is not valid UTF-8"
            ) from None
        return text
    if cpp == FieldDescriptor.CPPTYPE_FLOAT:
        return as_float(text)
    if cpp == FieldDescriptor.CPPTYPE_DOUBLE:
        return as_double(text)
    wanted = field.name.upper() + "_" + text if use_short_enum else text
    if not wanted.isascii():
        # Enum value names are identifiers; protobuf's lookup fails on undecodable bytes.
        raise UnconvertibleError(f"{text!r} is not a value of enum {enum_type(field).full_name}")
    for candidate in (wanted, wanted.upper(), wanted.lower()):
        value = enum_type(field).values_by_name.get(candidate)
        if value is not None:
            return value.number
    raise UnconvertibleError(f"{text!r} is not a value of enum {enum_type(field).full_name}")


def parse_message_bytes(target: Message, data: bytes, where: str) -> None:
    """Binary-parse into `target` (cleared first, like C++ ParseFromString)."""
    try:
        target.ParseFromString(data)
    except (DecodeError, RuntimeError, ValueError) as exc:
        raise TranslatorError(
            f"{where}: cannot decode embedded {target.DESCRIPTOR.full_name}: {exc}"
        ) from None


def set_from_string(
    msg: Message,
    field: AnyFieldDescriptor,
    text: str,
    use_short_enum: bool,
    *,
    bytes_in_hex: bool = True,
) -> None:
    """Set singular `field` of `msg` from `text` (message fields: hex of the binary encoding)."""
    if is_message(field):
        parse_message_bytes(getattr(msg, field.name), hex_decode(text), field.name)
        return
    try:
        setattr(
            msg,
            field.name,
            value_from_string(field, text, use_short_enum, bytes_in_hex=bytes_in_hex),
        )
    except UnconvertibleError as exc:
        log.warning("field %s: %s; field left unchanged", field.name, exc)


def append_from_string(
    msg: Message,
    field: AnyFieldDescriptor,
    text: str,
    use_short_enum: bool,
    *,
    bytes_in_hex: bool = True,
) -> None:
    """Append one element parsed from `text` to repeated `field`."""
    container = getattr(msg, field.name)
    if is_message(field):
        parse_message_bytes(container.add(), hex_decode(text), field.name)
        return
    try:
        container.append(value_from_string(field, text, use_short_enum, bytes_in_hex=bytes_in_hex))
    except UnconvertibleError as exc:
        log.warning("field %s: %s; element skipped", field.name, exc)


def set_element_from_string(
    msg: Message,
    field: AnyFieldDescriptor,
    index: int,
    text: str,
    use_short_enum: bool,
    *,
    bytes_in_hex: bool = True,
) -> None:
    """Set element `index` of repeated `field`, padding with default values as needed."""
    container = getattr(msg, field.name)
    if is_message(field):
        while len(container) <= index:
            container.add()
        parse_message_bytes(container[index], hex_decode(text), field.name)
        return
    while len(container) <= index:
        container.append(default_value(field))
    try:
        container[index] = value_from_string(field, text, use_short_enum, bytes_in_hex=bytes_in_hex)
    except UnconvertibleError as exc:
        log.warning("field %s[%d]: %s; element left unchanged", field.name, index, exc)
