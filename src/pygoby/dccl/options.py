"""Read the (dccl.msg) and (dccl.field) options of any protobuf descriptor."""

from __future__ import annotations

import functools

from google.protobuf.descriptor import Descriptor, FieldDescriptor
from google.protobuf.message import Message

from pygoby.protobuf import builtin_class

_CARRIER_PROTO = "pygoby/dccl/option_carrier.proto"


@functools.cache
def _carriers() -> tuple[type[Message], type[Message]]:
    return (
        builtin_class(_CARRIER_PROTO, "pygoby.dccl.FieldOptionsCarrier"),
        builtin_class(_CARRIER_PROTO, "pygoby.dccl.MessageOptionsCarrier"),
    )


def field_options(field: FieldDescriptor) -> Message:
    """The field's DCCLFieldOptions (an empty one when the field has none)."""
    carrier = _carriers()[0]()
    if field.has_options:
        carrier.ParseFromString(field.GetOptions().SerializeToString())
    return carrier.field


def message_options(descriptor: Descriptor) -> Message:
    """The message type's DCCLMessageOptions (an empty one when it has none)."""
    carrier = _carriers()[1]()
    if descriptor.has_options:
        carrier.ParseFromString(descriptor.GetOptions().SerializeToString())
    return carrier.msg
