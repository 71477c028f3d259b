"""Helpers shared by the netsim tests: load the reference vectors and compare messages to them."""

from __future__ import annotations

import json
import math
from functools import cache

from google.protobuf import json_format
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from tests.conftest import VECTORS

NETSIM = VECTORS / "netsim"


@cache
def protocol_vectors() -> tuple[dict, ...]:
    lines = (NETSIM / "netsim_protocol.jsonl").read_text().splitlines()
    return tuple(json.loads(line) for line in lines if line.strip())


def of_kind(kind: str) -> list[dict]:
    return [v for v in protocol_vectors() if v["kind"] == kind]


def by_id(vector_id: str) -> dict:
    (found,) = [v for v in protocol_vectors() if v["id"] == vector_id]
    return found


@cache
def physics() -> dict:
    return json.loads((NETSIM / "physics_checks.json").read_text())


def _value(field: FieldDescriptor, value):
    if field.type == FieldDescriptor.TYPE_MESSAGE:
        return to_vector_dict(value)
    if field.type == FieldDescriptor.TYPE_ENUM:
        return field.enum_type.values_by_number[value].name
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    return value


def to_vector_dict(message: Message) -> dict:
    """A message in the vectors' `decoded` form: set fields only, enums by name."""
    out = {}
    for field, value in message.ListFields():
        if field.is_repeated:
            out[field.name] = [_value(field, v) for v in value]
        else:
            out[field.name] = _value(field, value)
    return out


def from_vector_dict(cls: type[Message], decoded: dict) -> Message:
    message = cls()
    json_format.ParseDict(decoded, message)
    return message
