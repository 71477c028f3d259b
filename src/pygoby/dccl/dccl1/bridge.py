"""DCCL1 bytes for the protobuf messages `pygoby.dccl.xml` converts XML messages into, so the
queue, translator and apps built on those types can put Goby 1.1's bytes on the wire.

    bridge = Dccl1Bridge(Dccl1Codec(passphrase), loader.message_class)
    bridge.add(message_set)                 # the XML messages, also loaded into the codec
    data = bridge.encode(msg)               # a converted-type message -> DCCL1 bytes
    msgs = bridge.decode(data, now)         # DCCL1 bytes -> the converted-type message

Fields map by XML name: the header time is unix seconds (a received time of day is placed on a
date as Goby 1.1 does), enums by value name, hex as bytes. Goby 1.1 sends array elements
unset one by one; a protobuf repeated field cannot, so an unset element decodes as the type's
zero value. A <repeat/> message's converted type has one copy: it is sent as the first copy.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from google.protobuf.message import Message

from pygoby.dccl.dccl1.codec import Dccl1Codec, Dccl1Decoded
from pygoby.dccl.dccl1.values import Value
from pygoby.dccl.errors import DcclDecodeError
from pygoby.dccl.xml import MessageSet
from pygoby.dccl.xml.convert import enum_value_name
from pygoby.dccl.xml.model import XmlMessage
from pygoby.protobuf import enum_type
from pygoby.protobuf.descriptors import AnyFieldDescriptor


class Dccl1Bridge:
    def __init__(self, codec: Dccl1Codec, message_class: Callable[[str], type[Message]]) -> None:
        self.codec = codec
        self._message_class = message_class
        self._xml: dict[str, XmlMessage] = {}

    def add(self, message_set: MessageSet) -> None:
        self.codec.load(message_set)
        for msg in message_set.messages:
            self._xml[msg.name] = msg

    def handles(self, full_name: str) -> bool:
        return full_name in self._xml

    @property
    def xml_messages(self) -> list[XmlMessage]:
        return list(self._xml.values())

    def dccl_ids(self) -> dict[int, str]:
        return {msg.id or 0: name for name, msg in self._xml.items()}

    def encode(self, msg: Message) -> bytes:
        xml = self._xml[msg.DESCRIPTOR.full_name]
        values: dict[str, Value | list[Value]] = {}
        for var in xml.all_vars():
            if var.kind == "static":
                continue
            field = msg.DESCRIPTOR.fields_by_name[var.name]
            if var.array_length != 1:  # a repeated field in the converted type
                values[var.name] = [_to_value(var, field, v) for v in getattr(msg, var.name)]
            elif msg.HasField(var.name):
                values[var.name] = _to_value(var, field, getattr(msg, var.name))
        return self.codec.encode(xml.name, values)

    def decode(self, data: bytes, now: float | None = None) -> Message:
        return self.to_message(self.codec.decode(data, now))

    def to_message(self, decoded: Dccl1Decoded) -> Message:
        xml = self._xml.get(decoded.message)
        if xml is None:
            raise DcclDecodeError(f"DCCL1 message {decoded.message} has no protobuf type")
        try:
            return self._fill(xml, decoded)
        except (ValueError, TypeError) as err:  # e.g. a delta-decoded int beyond int32
            raise DcclDecodeError(f"{xml.name}: {err}") from None

    def _fill(self, xml: XmlMessage, decoded: Dccl1Decoded) -> Message:
        msg = self._message_class(xml.name)()
        header = decoded.header
        setattr(msg, xml.header["time"].name, decoded.time)
        setattr(msg, xml.header["src_id"].name, header.src)
        setattr(msg, xml.header["dest_id"].name, header.dest)
        for var in xml.layout:
            value = decoded.values.get(var.name)
            field = msg.DESCRIPTOR.fields_by_name[var.name]
            if var.array_length != 1:
                elements = value if isinstance(value, list) else [value]
                getattr(msg, var.name).extend(_from_value(var, field, v) for v in elements)
                continue
            if isinstance(value, list):  # <repeat/> copies: the converted type holds the first
                value = value[0]
            if value is not None:
                setattr(msg, var.name, _from_value(var, field, value))
        return msg


def _to_value(var, field: AnyFieldDescriptor, value: Any) -> Value:
    if var.kind == "enum":
        name = enum_type(field).values_by_number[value].name
        return var.enum_values[[enum_value_name(var, v) for v in var.enum_values].index(name)]
    if var.kind == "hex":
        return bytes(value).hex()
    return value


def _from_value(var, field: AnyFieldDescriptor, value: object) -> object:
    if value is None:  # only inside arrays: the element's zero value
        zero = {"bool": False, "string": "", "hex": b"", "static": var.static_value or ""}
        if var.kind == "enum":
            return 0
        return zero.get(var.kind, 0)
    if var.kind == "enum":
        return field.enum_type.values_by_name[enum_value_name(var, str(value))].number  # type: ignore[union-attr]
    if var.kind == "hex":
        return bytes.fromhex(str(value))
    if var.kind == "int":
        return int(value)  # type: ignore[call-overload]
    return value
