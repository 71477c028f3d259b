"""Read the (dccl.msg) and (dccl.field) options of any protobuf descriptor."""

from __future__ import annotations

import functools

from google.protobuf.message import Message

from pygoby.protobuf import builtin_class, default_loader
from pygoby.protobuf.descriptors import AnyDescriptor, AnyFieldDescriptor
from pygoby.protobuf.wire import length_delimited

_CARRIER_PROTO = "pygoby/dccl/option_carrier.proto"


# add-on extensions of DCCLFieldOptions, known to the carriers' pool so that they parse (and
# print, for dccl.hash) as the named extensions C++ DCCL sees
_EXTENSION_PROTOS = (
    "dccl/ccl/protobuf/ccl_extensions.proto",
    "dccl/arithmetic/protobuf/arithmetic_extensions.proto",
)


@functools.cache
def _carriers() -> tuple[type[Message], type[Message]]:
    for proto in _EXTENSION_PROTOS:
        default_loader().load_file(proto)
    return (
        builtin_class(_CARRIER_PROTO, "pygoby.dccl.FieldOptionsCarrier"),
        builtin_class(_CARRIER_PROTO, "pygoby.dccl.MessageOptionsCarrier"),
    )


def field_options(field: AnyFieldDescriptor) -> Message:
    """The field's DCCLFieldOptions (an empty one when the field has none)."""
    carrier = _carriers()[0]()
    if field.has_options:
        carrier.ParseFromString(field.GetOptions().SerializeToString())
    return carrier.field


def message_options(descriptor: AnyDescriptor) -> Message:
    """The message type's DCCLMessageOptions (an empty one when it has none)."""
    carrier = _carriers()[1]()
    if descriptor.has_options:
        carrier.ParseFromString(descriptor.GetOptions().SerializeToString())
    return carrier.msg


def field_extension(options: Message, proto_file: str, message_name: str, number: int) -> Message:
    """An add-on's extension of DCCLFieldOptions (e.g. `(dccl.field).(arithmetic)`, number
    1001, or `(dccl.field).(ccl)`, 1000) as a message of `message_name` from our `proto_file`.

    Read from the serialized options, so it works whichever descriptor pool compiled the user's
    .proto file (there the extension is known or an unknown field)."""
    extension = builtin_class(proto_file, message_name)()
    extension.ParseFromString(length_delimited(options.SerializeToString(), number))
    return extension
