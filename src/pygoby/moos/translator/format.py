"""TECHNIQUE_FORMAT: printf/scanf-like strings whose directives name field numbers.

`%N%` field N (repeated: all elements joined), `%N.K%` element K of repeated field N,
`%N:M%` field M of sub-message N (nestable, `%N.K:M%` for repeated sub-messages), `%V%` the
output of publish algorithms with output_virtual_field V, plus Boost.Format positional
specs such as `%1$05d`.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Sequence
from dataclasses import dataclass

from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.moos.translator import boostformat
from pygoby.moos.translator.algorithms import AlgorithmRegistry, run_publish_algorithms
from pygoby.moos.translator.conversions import hex_decode
from pygoby.moos.translator.errors import TranslatorConfigError
from pygoby.moos.translator.fields import (
    INT_KINDS,
    append_from_string,
    default_value,
    is_message,
    parse_message_bytes,
    set_element_from_string,
    set_from_string,
    stream_value,
)
from pygoby.protobuf import class_of, message_type
from pygoby.protobuf.descriptors import AnyDescriptor, AnyFieldDescriptor

_SUBMESSAGE_DIRECTIVE = re.compile(r"%([0-9.]+:)+[0-9.]+%")
_INDEXED_DIRECTIVE = re.compile(r"%[0-9]+\.[0-9]+%")

# What an index past the end of a repeated field renders as.
_PAST_END = {
    FieldDescriptor.CPPTYPE_INT32: 2**31 - 1,
    FieldDescriptor.CPPTYPE_INT64: 2**63 - 1,
    FieldDescriptor.CPPTYPE_UINT32: 2**32 - 1,
    FieldDescriptor.CPPTYPE_UINT64: 2**64 - 1,
    FieldDescriptor.CPPTYPE_FLOAT: float("nan"),
    FieldDescriptor.CPPTYPE_DOUBLE: float("nan"),
}


def _int_or_none(text: str) -> int | None:
    return int(text) if re.fullmatch(r"[+-]?[0-9]+", text) else None


def _walk_path(message: Message, parts: list[str], spec: str, create: bool) -> Message:
    """Follow `N`, `N.K` sub-message steps; `create` adds missing repeated elements."""
    for step in parts:
        field_and_index = step.split(".")
        number = _int_or_none(field_and_index[0])
        field = message.DESCRIPTOR.fields_by_number.get(number) if number is not None else None
        if field is None or not is_message(field):
            raise TranslatorConfigError(
                f"Invalid ':' syntax given for format: {spec}. All field indices except the last "
                "must be embedded messages"
            )
        if not field.is_repeated:
            message = getattr(message, field.name)
            if create:
                message.SetInParent()
            continue
        index = _int_or_none(field_and_index[1]) if len(field_and_index) == 2 else None
        if index is None or index < 0:
            raise TranslatorConfigError(
                f"Invalid '.' syntax given for format: {spec}. Repeated message, but no valid "
                "index given. E.g., use '3.4' for index 4 of field 3."
            )
        container = getattr(message, field.name)
        if create:
            while len(container) <= index:
                container.add()
        # Reading past the end (publish side) sees an empty element.
        message = container[index] if index < len(container) else class_of(message_type(field))()
    return message


def _repeated_text(
    msg: Message,
    field: AnyFieldDescriptor,
    start: int,
    end: int,
    indexed: bool,
    delimiter: str,
    short: bool,
) -> str:
    values = getattr(msg, field.name)
    parts = []
    for j in range(start, end):
        if j < len(values):
            parts.append(stream_value(field, values[j], short))
        elif is_message(field):
            parts.append("")
        else:
            parts.append(
                stream_value(field, _PAST_END.get(field.cpp_type, default_value(field)), short)
            )
    return (parts[0] if parts else "") if indexed else delimiter.join(parts)


def _scalar_arg(msg: Message, field: AnyFieldDescriptor, short: bool) -> boostformat.Arg:
    value = getattr(msg, field.name)
    cpp = field.cpp_type
    if cpp in INT_KINDS:
        return boostformat.IntArg(value, 64 if "64" in INT_KINDS[cpp] else 32)
    if cpp == FieldDescriptor.CPPTYPE_DOUBLE:
        return boostformat.FloatArg(value, 15)
    if cpp == FieldDescriptor.CPPTYPE_FLOAT:
        return boostformat.FloatArg(value, 6)
    return stream_value(field, value, short)


def serialize(
    msg: Message,
    fmt: str,
    repeated_delimiter: str = ",",
    algorithms: Sequence = (),
    use_short_enum: bool = False,
    registry: AlgorithmRegistry | None = None,
) -> str:
    descriptor = msg.DESCRIPTOR
    # Every field counts (goby3 skips the first-declared one, so a directive for it renders
    # empty when its number is the largest; fixed: QUIRKS.md Q-APPS-9).
    max_field = max([1, *(f.number for f in descriptor.fields)])
    virtual = (
        run_publish_algorithms(msg, algorithms, registry or AlgorithmRegistry())
        if algorithms
        else {}
    )
    max_field = max([max_field, *virtual])

    working = fmt
    for match in _SUBMESSAGE_DIRECTIVE.finditer(fmt):
        spec = match.group(0).strip("%")
        *path, last = spec.split(":")
        max_field += 1
        sub = _walk_path(msg, path, spec, create=False)
        virtual[max_field] = serialize(sub, f"%{last}%", repeated_delimiter, (), use_short_enum)
        working = working.replace(match.group(0), f"%{max_field}%")

    current = working
    indexed: dict[int, tuple[int, int | None]] = {}
    for match in _INDEXED_DIRECTIVE.finditer(current):
        number_text, index_text = match.group(0).strip("%").split(".")
        max_field += 1
        indexed[max_field] = (int(number_text), int(index_text))
        working = working.replace(match.group(0), f"%{max_field}%")

    args: list[boostformat.Arg] = []
    for number in range(1, max_field + 1):
        field_number, index = indexed.get(number, (number, None))
        field = descriptor.fields_by_number.get(field_number)
        if field is not None and field.is_repeated:
            if index is None:
                size = len(getattr(msg, field.name))
                args.append(
                    _repeated_text(msg, field, 0, size, False, repeated_delimiter, use_short_enum)
                )
            else:
                args.append(_repeated_text(msg, field, index, index + 1, True, "", use_short_enum))
        elif field is not None:
            args.append(_scalar_arg(msg, field, use_short_enum))
        elif number in virtual:
            args.append(virtual[number])
        else:
            args.append("unknown")
    return boostformat.boost_format(boostformat.parse_format(working), args)


def _scan(fmt: str):
    """Yield ('literal', position, char) and ('directive', position, spec, separator) for a
    parse format. The separator is the format character after the directive's closing '%'
    (itself scanned next, as a literal or the next directive's '%': adjacent directives read
    the same text, QUIRKS.md Q-APPS-28), or NUL when the directive ends the format: goby3
    reads the string's terminator there."""
    i = 0
    while i < len(fmt):
        if fmt[i] != "%":
            yield "literal", i, fmt[i]
            i += 1
            continue
        close = fmt.find("%", i + 1)
        if close < 0:
            # goby3 reads past the end of the format looking for the '%' (Q-APPS-29).
            raise TranslatorConfigError(f"format {fmt!r}: unterminated directive")
        spec = fmt[i + 1 : close]
        if not spec:
            # goby3 throws "Bad specifier" at every creation, uncaught: pTranslator ends
            # (QUIRKS.md Q-APPS-29).
            raise TranslatorConfigError(
                f"format {fmt!r}: empty directive '%%' at position {i} (a literal '%' cannot "
                "be parsed)"
            )
        yield "directive", i, spec, fmt[close + 1] if close + 1 < len(fmt) else "\0"
        i = close + 1


def _field_spec(descriptor: AnyDescriptor, spec: str) -> tuple[AnyFieldDescriptor, int | None]:
    parts = spec.split(".")
    number = _int_or_none(parts[0])
    index = _int_or_none(parts[1]) if len(parts) == 2 else None
    if number is None or len(parts) > 2 or (len(parts) == 2 and (index is None or index < 0)):
        raise TranslatorConfigError(
            f"Bad specifier: {spec}, must be an integer. For message: {descriptor.full_name}"
        )
    field = descriptor.fields_by_number.get(number)
    if field is None:
        raise TranslatorConfigError(f"Bad field: {spec} not in message {descriptor.full_name}")
    return field, index


def check_parse_format(descriptor: AnyDescriptor, fmt: str) -> None:
    """Reject create formats that cannot work, before any mail arrives."""
    for kind, _position, spec, *_separator in _scan(fmt.lower()):
        if kind != "directive":
            continue
        current = descriptor
        *path, last = spec.split(":")
        for step in path:
            field, index = _field_spec(current, step)
            if not is_message(field):
                raise TranslatorConfigError(
                    f"Invalid ':' syntax given for format: {spec}. All field indices except the "
                    "last must be singular embedded messages"
                )
            if field.is_repeated and index is None:
                raise TranslatorConfigError(
                    f"Invalid '.' syntax given for format: {spec}. Repeated message, but no "
                    "valid index given. E.g., use '3.4' for index 4 of field 3."
                )
            current = message_type(field)
        _field_spec(current, last)


def parsed_fields(descriptor: AnyDescriptor, fmt: str) -> set[int]:
    """The numbers of the top-level fields a create format sets (for tools that show where a
    field's value comes from)."""
    return {
        _field_spec(descriptor, spec.split(":")[0])[0].number
        for kind, _position, spec, *_separator in _scan(fmt.lower())
        if kind == "directive"
    }


def check_serialize_format(
    descriptor: AnyDescriptor, fmt: str, virtual_fields: Collection[int] = ()
) -> list[str]:
    """Reject publish formats that cannot render (bad sub-message paths, where goby3 throws
    at every publication; bad directives). Return what renders, as in goby3, but is likely a
    mistake: a directive naming a field the message does not have (rendered "unknown", or
    nothing past the highest field number) and an element index on a field that is not
    repeated (the whole field is rendered): QUIRKS.md Q-APPS-27. `virtual_fields`: the publish
    algorithms' output_virtual_field numbers."""
    probe = class_of(descriptor)()
    for match in _SUBMESSAGE_DIRECTIVE.finditer(fmt):
        spec = match.group(0).strip("%")
        _walk_path(probe, spec.split(":")[:-1], spec, create=False)
    notes = []
    for match in _INDEXED_DIRECTIVE.finditer(_SUBMESSAGE_DIRECTIVE.sub("%%", fmt)):
        number = int(match.group(0).strip("%").split(".")[0])
        field = descriptor.fields_by_number.get(number)
        if field is None:
            notes.append(
                f"{match.group(0)} names no field of {descriptor.full_name}: it prints "
                "'unknown', as in goby3"
            )
        elif not field.is_repeated:
            notes.append(
                f"{match.group(0)}: field {number} ({field.name}) is not repeated: the whole "
                "field prints, as in goby3"
            )
    plain = _SUBMESSAGE_DIRECTIVE.sub("%%", _INDEXED_DIRECTIVE.sub("%%", fmt))
    for item in boostformat.parse_format(plain):
        argument: int | None = getattr(item, "argument", None)
        if (
            argument is not None
            and argument not in descriptor.fields_by_number
            and (argument not in virtual_fields)
        ):
            notes.append(
                f"%{argument}% names no field of {descriptor.full_name} (nor an algorithm's "
                "output_virtual_field): it prints 'unknown' or nothing, as in goby3"
            )
    return notes


@dataclass(frozen=True)
class FormatMismatch:
    """Where a create input stopped matching its format: the first format literal that does
    not occur in what remains of the input."""

    literal: str
    format_position: int  # of the literal in the format
    input_position: int  # characters of the input consumed when the literal was looked for

    def __str__(self) -> str:
        return (
            f"no {self.literal!r} (format character {self.format_position}) in the input "
            f"after character {self.input_position}"
        )


def parse(
    text: str,
    msg: Message,
    fmt: str,
    repeated_delimiter: str = ",",
    algorithms: Sequence = (),
    use_short_enum: bool = False,
    registry: AlgorithmRegistry | None = None,
) -> FormatMismatch | None:
    """Scan `text` with `fmt`, setting the fields it names, as goby3 does. A literal format
    character skips the input to just past its next occurrence (case-insensitive); a literal
    that does not occur skips nothing and the scan goes on, so every directive is still
    parsed (from whatever input remains; an empty value gives NaN or the integer maximum).
    Returns the first such literal, None when the whole format matched (QUIRKS.md
    Q-APPS-25)."""
    remaining = text
    lower = text.lower()
    consumed = 0
    mismatch: FormatMismatch | None = None
    for kind, position, spec, *separator in _scan(fmt.lower()):
        if kind == "literal":
            found = lower.find(spec)
            if found < 0:
                if mismatch is None:
                    mismatch = FormatMismatch(spec, position, consumed)
                continue
            lower = lower[found + 1 :]
            remaining = remaining[found + 1 :]
            consumed += found + 1
            continue
        end = lower.find(separator[0])
        extract = remaining if end < 0 else remaining[:end]
        _parse_directive(
            extract, msg, spec, repeated_delimiter, algorithms, use_short_enum, registry
        )
    return mismatch


def _parse_directive(extract, msg: Message, spec, delimiter, algorithms, short, registry) -> None:
    if ":" in spec:
        *path, last = spec.split(":")
        sub = _walk_path(msg, path, spec, create=True)
        _parse_directive(extract, sub, last, delimiter, algorithms, short, registry)
        return
    field, index = _field_spec(msg.DESCRIPTOR, spec)
    for algorithm in algorithms:
        if algorithm.primary_field == field.number:
            extract = (registry or AlgorithmRegistry()).run(algorithm.name, extract)
    # A bytes field takes the text itself, not hex (goby3: QUIRKS.md Q-APPS-31); enums are
    # appended and indexed like every other type (goby3 aborts on a repeated enum: Q-APPS-10).
    if index is not None and field.is_repeated:
        set_element_from_string(msg, field, index, extract, short, bytes_in_hex=False)
    elif field.is_repeated:
        parts = re.split("[" + re.escape(delimiter) + "]", extract) if delimiter else [extract]
        for part in parts:
            append_from_string(msg, field, part, short, bytes_in_hex=False)
    elif is_message(field):
        parse_message_bytes(getattr(msg, field.name), hex_decode(extract), field.name)
    else:
        set_from_string(msg, field, extract, short, bytes_in_hex=False)
