"""Descriptor types as protobuf's stubs give them.

A message's DESCRIPTOR (and what it leads to: fields, enum types) is typed as the pure-Python class
or the upb (C) class of the same name; code that takes either names these unions.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeAlias, TypeVar

from google.protobuf import descriptor
from google.protobuf.message import Message

if TYPE_CHECKING:
    from google._upb import _message as upb

    AnyDescriptor: TypeAlias = descriptor.Descriptor | upb.Descriptor
    AnyFieldDescriptor: TypeAlias = descriptor.FieldDescriptor | upb.FieldDescriptor
    AnyEnumDescriptor: TypeAlias = descriptor.EnumDescriptor | upb.EnumDescriptor
else:  # the upb module exists only with protobuf's C backend
    AnyDescriptor = descriptor.Descriptor
    AnyFieldDescriptor = descriptor.FieldDescriptor
    AnyEnumDescriptor = descriptor.EnumDescriptor

# a function that makes or parses a message of the class it is given returns that class
MessageT = TypeVar("MessageT", bound=Message)

_FD = descriptor.FieldDescriptor
# the integer field types (every width and encoding; enums not included)
INTEGER_FIELD_TYPES = frozenset(
    {
        _FD.TYPE_INT32,
        _FD.TYPE_INT64,
        _FD.TYPE_UINT32,
        _FD.TYPE_UINT64,
        _FD.TYPE_SINT32,
        _FD.TYPE_SINT64,
        _FD.TYPE_FIXED32,
        _FD.TYPE_FIXED64,
        _FD.TYPE_SFIXED32,
        _FD.TYPE_SFIXED64,
    }
)
