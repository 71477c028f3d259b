"""Where a queued message's source, destination and time come from (QueuedMessageEntry.role)."""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass

from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.errors import RoleError
from pygoby.protobuf.descriptors import INTEGER_FIELD_TYPES, AnyDescriptor, AnyFieldDescriptor

Role = acomms_pb.QueuedMessageEntry.Role
_INTEGER_TYPES = INTEGER_FIELD_TYPES | {FieldDescriptor.TYPE_ENUM}  # (an enum id is a number)


@dataclass(frozen=True)
class RoleGetter:
    path: tuple[str, ...] | None  # field path, or None for a static value
    static_value: int = 0
    kind: int = FieldDescriptor.TYPE_INT32

    def get(self, msg: Message):
        if self.path is None:
            return self.static_value
        value = msg
        for name in self.path:
            if not value.HasField(name):
                return None
            value = getattr(value, name)
        return value


def compile_roles(
    entry: acomms_pb.QueuedMessageEntry, descriptor: AnyDescriptor
) -> dict[int, RoleGetter]:
    """Validate the roles of `entry` against `descriptor`."""
    getters: dict[int, RoleGetter] = {}
    for role in entry.role:
        if role.type in getters:
            raise RoleError(f"{entry.protobuf_name}: role {role.type} given twice")
        if role.setting == Role.STATIC:
            if role.type == Role.TIMESTAMP:
                raise RoleError(f"{entry.protobuf_name}: TIMESTAMP cannot be STATIC")
            if not role.HasField("static_value"):
                raise RoleError(f"{entry.protobuf_name}: STATIC role needs static_value")
            getters[role.type] = RoleGetter(None, role.static_value)
            continue
        path = tuple(role.field.split("."))
        current: AnyDescriptor | None = descriptor
        field: AnyFieldDescriptor | None = None
        for name in path:
            if current is None or name not in current.fields_by_name:
                raise RoleError(f"{entry.protobuf_name}: no field {role.field!r}")
            field = current.fields_by_name[name]
            if field.is_repeated:
                raise RoleError(f"{entry.protobuf_name}: role field {role.field!r} is repeated")
            current = field.message_type
        assert field is not None
        if role.type in (Role.SOURCE_ID, Role.DESTINATION_ID) and field.type not in _INTEGER_TYPES:
            raise RoleError(f"{entry.protobuf_name}: {role.field!r} must be an integer")
        if role.type == Role.TIMESTAMP and field.type not in (
            FieldDescriptor.TYPE_UINT64,
            FieldDescriptor.TYPE_DOUBLE,
            FieldDescriptor.TYPE_STRING,
        ):
            raise RoleError(f"{entry.protobuf_name}: {role.field!r} cannot carry a time")
        getters[role.type] = RoleGetter(path, kind=field.type)
    return getters


def timestamp_us(getter: RoleGetter, msg: Message) -> int | None:
    value = getter.get(msg)
    if value is None:
        return None
    if getter.kind == FieldDescriptor.TYPE_UINT64:
        return int(value)
    if getter.kind == FieldDescriptor.TYPE_DOUBLE:
        if not math.isfinite(value):
            raise RoleError(f"TIMESTAMP field {'.'.join(getter.path or ())} is {value}, not a time")
        return round(value * 1e6)  # keep sub-second precision (Q-ACOMMS-10)
    try:
        parsed = dt.datetime.fromisoformat(str(value).replace("Z", "+00:00"))
    except ValueError:
        raise RoleError(
            f"TIMESTAMP field {'.'.join(getter.path or ())} is {value!r}, not an ISO 8601 time"
        ) from None
    if parsed.tzinfo is None:
        parsed = parsed.replace(tzinfo=dt.UTC)
    return round(parsed.timestamp() * 1e6)
