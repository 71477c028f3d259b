"""TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS: `key=value,key={v1,v2},...`.

Sub-messages are flattened one level as `<field>_<subfield>`. Parsing lower-cases the whole
input first (goby3 does, so string values arrive in lower case; kept because missions depend on it:
QUIRKS.md Q-APPS-20).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

from google.protobuf.message import Message

from pygoby.moos.translator.algorithms import AlgorithmRegistry, run_publish_algorithms
from pygoby.moos.translator.fields import (
    append_from_string,
    is_message,
    set_from_string,
    stream_value,
)
from pygoby.protobuf import message_type
from pygoby.protobuf.descriptors import AnyFieldDescriptor

log = logging.getLogger("pygoby.moos.translator")


def is_set(msg: Message, field: AnyFieldDescriptor) -> bool:
    """C++ HasField / FieldSize > 0 semantics."""
    if field.is_repeated:
        return len(getattr(msg, field.name)) > 0
    if field.has_presence:
        return msg.HasField(field.name)
    return getattr(msg, field.name) != field.default_value


def val_from_string(text: str, key: str) -> str | None:
    """The value of `key` in `text` (case-insensitive key match at the start or right after a
    comma), or None. `key={a,b}` gives `a,b`; otherwise the value runs to the next comma."""
    needle = (key + "=").lower()
    haystack = text.lower()
    start = haystack.find(needle)
    while start > 0 and text[start - 1] != ",":
        start = haystack.find(needle, start + 1)
    if start < 0:
        return None
    value_start = start + len(needle)
    if text[value_start : value_start + 1] == "{":
        end = text.find("}", value_start)
        return text[value_start + 1 : end if end >= 0 else len(text)]
    end = text.find(",", value_start)
    return text[value_start : end if end >= 0 else len(text)]


def _sub_value(msg: Message, field: AnyFieldDescriptor, use_short_enum: bool) -> str:
    """A field inside a flattened sub-message: repeated ones joined by commas, no braces."""
    value = getattr(msg, field.name)
    if field.is_repeated:
        return ",".join(stream_value(field, v, use_short_enum) for v in value)
    return stream_value(field, value, use_short_enum)


def _entry(msg: Message, field: AnyFieldDescriptor, use_short_enum: bool) -> str:
    name = field.name
    value = getattr(msg, name)
    if is_message(field):
        sub_fields = message_type(field).fields
        if field.is_repeated:
            return ",".join(
                f"{name}_{sub.name}={{"
                + ",".join(_sub_value(e, sub, use_short_enum) for e in value)
                + "}"
                for sub in sub_fields
            )
        return ",".join(
            f"{name}_{sub.name}=" + _sub_value(value, sub, use_short_enum) for sub in sub_fields
        )
    if field.is_repeated:
        return f"{name}={{" + ",".join(stream_value(field, v, use_short_enum) for v in value) + "}"
    return f"{name}=" + stream_value(field, value, use_short_enum)


def serialize(
    msg: Message,
    algorithms: Sequence = (),
    use_short_enum: bool = False,
    registry: AlgorithmRegistry | None = None,
) -> str:
    """Fields in declaration order (unset ones skipped), then the algorithm outputs as
    `,alg1+alg2(primary field name)=value` in ascending virtual-field order."""
    descriptor = msg.DESCRIPTOR
    out = ",".join(
        _entry(msg, field, use_short_enum) for field in descriptor.fields if is_set(msg, field)
    )
    if algorithms:
        outputs = run_publish_algorithms(msg, algorithms, registry or AlgorithmRegistry())
        for virtual_field in sorted(outputs):
            targeting = [a for a in algorithms if a.output_virtual_field == virtual_field]
            primary = descriptor.fields_by_number.get(targeting[-1].primary_field)
            primary_name = primary.name if primary is not None else str(targeting[-1].primary_field)
            key = "+".join(a.name for a in targeting) + f"({primary_name})"
            out += f",{key}={outputs[virtual_field]}"
    return out


def _set_values(
    msg: Message, field: AnyFieldDescriptor, values: list[str], index: int, use_short_enum: bool
) -> None:
    if field.is_repeated:
        for value in values:
            append_from_string(msg, field, value, use_short_enum)
    else:
        set_from_string(msg, field, values[index], use_short_enum)


def parse(
    text: str,
    msg: Message,
    algorithms: Sequence = (),
    use_short_enum: bool = False,
    registry: AlgorithmRegistry | None = None,
    where: str = "",
) -> None:
    """Set the fields found in `text` (others are left as they are)."""
    lower = text.lower()
    for field in msg.DESCRIPTOR.fields:
        if not is_message(field):
            value = val_from_string(lower, field.name)
            if value is None:
                continue
            for algorithm in algorithms:
                if algorithm.primary_field == field.number:
                    value = (registry or AlgorithmRegistry()).run(algorithm.name, value)
            _set_values(msg, field, value.split(","), 0, use_short_enum)
            continue
        for sub in message_type(field).fields:
            value = val_from_string(lower, f"{field.name}_{sub.name}")
            if value is None:
                continue
            values = value.split(",")
            if field.is_repeated:
                container = getattr(msg, field.name)
                for index in range(len(values)):
                    element = container[index] if index < len(container) else container.add()
                    _set_values(element, sub, values, index, use_short_enum)
            else:
                embedded = getattr(msg, field.name)
                embedded.SetInParent()
                _set_values(embedded, sub, values, 0, use_short_enum)
    _warn_unknown_keys(lower, msg, where)


def _top_level_keys(text: str) -> list[str | None]:
    """Keys of the top-level pairs (None for a segment with no '=')."""
    keys: list[str | None] = []
    pos = 0
    while pos < len(text):
        comma = text.find(",", pos)
        equals = text.find("=", pos)
        if equals < 0 or (0 <= comma < equals):
            keys.append(None)
            pos = comma + 1 if comma >= 0 else len(text)
            continue
        keys.append(text[pos:equals])
        if text[equals + 1 : equals + 2] == "{":
            close = text.find("}", equals)
            pos = len(text) if close < 0 else close + 1
            pos = pos + 1 if text[pos : pos + 1] == "," else pos
        else:
            pos = comma + 1 if comma >= 0 else len(text)
    return keys


# Unknown keys are reported once per (variable, type, key): feeds such as MOOS-IvP's
# NODE_REPORT routinely carry keys a mission does not map, and arrive several times a second.
_REPORTED_LIMIT = 10_000
_reported: set[tuple[str, str, str]] = set()


def _warn_unknown_keys(lower: str, msg: Message, where: str) -> None:
    known = set()
    for field in msg.DESCRIPTOR.fields:
        known.add(field.name.lower())
        if is_message(field):
            known.update(f"{field.name}_{sub.name}".lower() for sub in message_type(field).fields)
    keys = _top_level_keys(lower)
    type_name = msg.DESCRIPTOR.full_name
    unknown = [k for k in keys if k is not None and k not in known and "(" not in k]
    new = [k for k in unknown if (where, type_name, k) not in _reported]
    prefix = f"{where}: " if where else ""
    if new:
        if len(_reported) < _REPORTED_LIMIT:
            _reported.update((where, type_name, k) for k in new)
        log.warning(
            "%sunknown key(s) %s ignored for %s (reported once)",
            prefix,
            ", ".join(repr(k) for k in new),
            type_name,
        )
    elif unknown:
        log.debug("%sunknown key(s) ignored for %s", prefix, type_name)
    malformed = keys.count(None)
    if malformed:
        log.warning(
            "%s%d segment(s) without '=' ignored in key=value string %.80r",
            prefix,
            malformed,
            lower,
        )
