"""The six protobuf techniques (text, native binary, hex, and their `@PB[type] ` prefixed forms)
and the `serialize_for_moos` / `parse_for_moos` helpers built on them."""

from __future__ import annotations

import enum
from collections.abc import Callable

from google.protobuf.message import DecodeError, Message

from pygoby.moos.translator.conversions import hex_decode, hex_encode
from pygoby.moos.translator.errors import TranslatorConfigError, TranslatorError
from pygoby.moos.translator.fields import serialize_message
from pygoby.moos.translator.textformat import message_text, parse_text
from pygoby.protobuf.goby.moos.protobuf.goby_moos_app_pb2 import GobyMOOSAppConfig

MAGIC_PROTOBUF_HEADER = "@PB"


class Technique(enum.IntEnum):
    """TranslatorEntry.ParserSerializerTechnique (same names and numbers)."""

    TECHNIQUE_PROTOBUF_TEXT_FORMAT = 1
    TECHNIQUE_PROTOBUF_NATIVE_ENCODED = 2
    TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS = 3
    TECHNIQUE_FORMAT = 4
    TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT = 5
    TECHNIQUE_PROTOBUF_NATIVE_HEX = 6
    TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_HEX = 7
    TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED = 8


T = Technique
PREFIXED_BASE = {
    T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT: T.TECHNIQUE_PROTOBUF_TEXT_FORMAT,
    T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_HEX: T.TECHNIQUE_PROTOBUF_NATIVE_HEX,
    T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED: T.TECHNIQUE_PROTOBUF_NATIVE_ENCODED,
}
PROTOBUF_TECHNIQUES = frozenset(
    {
        T.TECHNIQUE_PROTOBUF_TEXT_FORMAT,
        T.TECHNIQUE_PROTOBUF_NATIVE_ENCODED,
        T.TECHNIQUE_PROTOBUF_NATIVE_HEX,
    }
    | set(PREFIXED_BASE)
)
BINARY_TECHNIQUES = frozenset(
    {T.TECHNIQUE_PROTOBUF_NATIVE_ENCODED, T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED}
)

MoosValue = str | float | bytes


def as_text(value: MoosValue) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8", "surrogateescape")
    return value if isinstance(value, str) else str(value)


def as_bytes(value: MoosValue) -> bytes:
    if isinstance(value, bytes):
        return value
    return (value if isinstance(value, str) else str(value)).encode("utf-8", "surrogateescape")


def serialize_protobuf(msg: Message, technique: Technique) -> str | bytes:
    """bytes for the two binary techniques, str otherwise."""
    technique = Technique(technique)
    if technique in PREFIXED_BASE:
        header = f"{MAGIC_PROTOBUF_HEADER}[{msg.DESCRIPTOR.full_name}] "
        body = serialize_protobuf(msg, PREFIXED_BASE[technique])
        return header.encode() + body if isinstance(body, bytes) else header + body
    if technique == T.TECHNIQUE_PROTOBUF_TEXT_FORMAT:
        return message_text(msg)
    if technique == T.TECHNIQUE_PROTOBUF_NATIVE_ENCODED:
        return serialize_message(msg)
    if technique == T.TECHNIQUE_PROTOBUF_NATIVE_HEX:
        return hex_encode(serialize_message(msg))
    raise TranslatorConfigError(f"{technique.name} is not a protobuf technique")


def _parse_binary(data: bytes, msg: Message) -> None:
    try:
        parsed = type(msg)()
        parsed.ParseFromString(data)
    except (DecodeError, RuntimeError, ValueError) as exc:
        raise TranslatorError(
            f"cannot decode {msg.DESCRIPTOR.full_name} from {len(data)} bytes: {exc}"
        ) from None
    msg.Clear()
    msg.MergeFrom(parsed)


def _parse_base(value: MoosValue, msg: Message, technique: Technique) -> None:
    if technique == T.TECHNIQUE_PROTOBUF_TEXT_FORMAT:
        parse_text(as_text(value), msg)
    elif technique == T.TECHNIQUE_PROTOBUF_NATIVE_ENCODED:
        _parse_binary(as_bytes(value), msg)
    elif technique == T.TECHNIQUE_PROTOBUF_NATIVE_HEX:
        _parse_binary(hex_decode(as_text(value)), msg)
    else:
        raise TranslatorConfigError(f"{technique.name} is not a protobuf technique")


def split_prefix(value: MoosValue) -> tuple[str, bytes] | None:
    """(type name, body) of an `@PB[type] body` value; None if it has no prefix.

    Exactly one separator character after `]` is skipped (goby3's dynamic parse skips none,
    corrupting binary bodies; fixed: QUIRKS.md Q-APPS-7)."""
    data = as_bytes(value)
    magic = MAGIC_PROTOBUF_HEADER.encode()
    if len(data) <= len(magic) or not data.startswith(magic):
        return None
    end = data.find(b"]")
    if end < 0:
        raise TranslatorError(
            f"Incorrectly formatted protobuf message (no ']' in header): {data[:60]!r}"
        )
    name = data[len(magic) + 1 : end].decode("utf-8", "replace")
    return name, data[end + 2 :]


def _body_value(body: bytes, base: Technique) -> MoosValue:
    return (
        body
        if base == T.TECHNIQUE_PROTOBUF_NATIVE_ENCODED
        else body.decode("utf-8", "surrogateescape")
    )


def parse_protobuf(value: MoosValue, msg: Message, technique: Technique) -> None:
    """Replace `msg` with the parsed value (all or nothing; TranslatorError on failure)."""
    technique = Technique(technique)
    if technique not in PREFIXED_BASE:
        _parse_base(value, msg, technique)
        return
    base = PREFIXED_BASE[technique]
    prefixed = split_prefix(value)
    if prefixed is None:
        _parse_base(value, msg, base)  # prefixed parsers accept bare bodies
        return
    name, body = prefixed
    if name != msg.DESCRIPTOR.full_name:
        raise TranslatorError(
            f"Wrong Protobuf type passed to {technique.name} parse. "
            f"Expected: {msg.DESCRIPTOR.full_name}, received: {name}"
        )
    if body:
        _parse_base(_body_value(body, base), msg, base)
    else:
        msg.Clear()


def dynamic_parse(
    value: MoosValue, resolve: Callable[[str], type[Message]], technique: Technique
) -> Message | None:
    """Parse an `@PB[type] ...` value into a new message of the named type (multiplexing).

    Only the prefixed techniques can do this; an unknown type or a parse failure gives None.
    """
    technique = Technique(technique)
    if technique not in PREFIXED_BASE:
        return None
    try:
        prefixed = split_prefix(value)
        if prefixed is None:
            return None
        name, body = prefixed
        msg = resolve(name)()
        if body:
            _parse_base(_body_value(body, PREFIXED_BASE[technique]), msg, PREFIXED_BASE[technique])
        return msg
    except Exception:  # unknown type (resolver error) or bad body: "no message"
        return None


DEFAULT_MOOS_TECHNIQUE = T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT


def moos_technique_from_config(common: GobyMOOSAppConfig | None) -> Technique:
    """The app-internal technique from a GobyMOOSAppConfig: moos_parser_technique wins, else
    use_binary_protobuf picks prefixed binary or prefixed text, else prefixed text."""
    if common is None:
        return DEFAULT_MOOS_TECHNIQUE
    if common.HasField("moos_parser_technique"):
        technique = Technique(common.moos_parser_technique)
        if technique not in PROTOBUF_TECHNIQUES:
            raise TranslatorConfigError(
                f"Non-PROTOBUF techniques are not supported for 'moos_parser_technique': {technique.name}"
            )
        return technique
    if common.HasField("use_binary_protobuf"):
        return (
            T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED
            if common.use_binary_protobuf
            else DEFAULT_MOOS_TECHNIQUE
        )
    return DEFAULT_MOOS_TECHNIQUE


def serialize_for_moos(msg: Message, technique: Technique = DEFAULT_MOOS_TECHNIQUE) -> str | bytes:
    """An app-internal message as posted on MOOS (bytes = post as a MOOS binary string)."""
    if Technique(technique) not in PROTOBUF_TECHNIQUES:
        raise TranslatorConfigError(
            f"{Technique(technique).name} is not allowed for serialize_for_moos"
        )
    return serialize_protobuf(msg, technique)


def parse_for_moos(
    value: MoosValue, msg: Message, technique: Technique = DEFAULT_MOOS_TECHNIQUE
) -> None:
    """Inverse of serialize_for_moos; raises TranslatorError on bad input (msg unchanged)."""
    if Technique(technique) not in PROTOBUF_TECHNIQUES:
        raise TranslatorConfigError(
            f"{Technique(technique).name} is not allowed for parse_for_moos"
        )
    parse_protobuf(value, msg, technique)
