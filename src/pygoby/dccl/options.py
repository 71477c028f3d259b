"""Read the (dccl.msg) and (dccl.field) options of any protobuf descriptor."""

from __future__ import annotations

from google.protobuf.message import Message

# add-on extensions of DCCLFieldOptions, imported so that they are known to the carriers' pool and
# parse (and print, for dccl.hash) as the named extensions C++ DCCL sees
from pygoby.protobuf.dccl.arithmetic.protobuf import arithmetic_extensions_pb2  # noqa: F401
from pygoby.protobuf.dccl.ccl.protobuf import ccl_extensions_pb2  # noqa: F401
from pygoby.protobuf.dccl.option_extensions_pb2 import DCCLFieldOptions, DCCLMessageOptions
from pygoby.protobuf.descriptors import AnyDescriptor, AnyFieldDescriptor, MessageT
from pygoby.protobuf.pygoby.dccl.option_carrier_pb2 import (
    FieldOptionsCarrier,
    MessageOptionsCarrier,
)
from pygoby.protobuf.wire import length_delimited


def field_options(field: AnyFieldDescriptor) -> DCCLFieldOptions:
    """The field's DCCLFieldOptions (an empty one when the field has none)."""
    carrier = FieldOptionsCarrier()
    if field.has_options:
        carrier.ParseFromString(field.GetOptions().SerializeToString())
    return carrier.field


def message_options(descriptor: AnyDescriptor) -> DCCLMessageOptions:
    """The message type's DCCLMessageOptions (an empty one when it has none)."""
    carrier = MessageOptionsCarrier()
    if descriptor.has_options:
        carrier.ParseFromString(descriptor.GetOptions().SerializeToString())
    return carrier.msg


def field_extension(options: Message, extension_class: type[MessageT], number: int) -> MessageT:
    """An add-on's extension of DCCLFieldOptions (e.g. `(dccl.field).(arithmetic)`, number
    1001, or `(dccl.field).(ccl)`, 1000) as a message of `extension_class`.

    Read from the serialized options, so it works whichever descriptor pool compiled the user's
    .proto file (there the extension is known or an unknown field)."""
    extension = extension_class()
    extension.ParseFromString(length_delimited(options.SerializeToString(), number))
    return extension
