"""Goby 1.1 DCCL XML message sets, usable without MOOS.

    from pygoby.dccl import Codec
    from pygoby.dccl.xml import load_message_set

    message_set = load_message_set("simple_status.xml")   # ConfigError: "file:line: ..."
    codec = Codec()
    Status, = message_set.load_into(codec)                # protobuf classes, DCCL-checked
    data = codec.encode(Status(nav_x=100, Speed=1.5))
    message_set.proto_text()          # the same messages as a DCCL .proto (to migrate)
    message_set.queue_entries()       # goby.acomms.protobuf.QueuedMessageEntry per message
    message_set.translator_entries()  # goby.moos.protobuf.TranslatorEntry per message

The messages are converted in memory as Goby 2's transitional layer did and then go through pygoby's
DCCL codec, queue and MOOS translator.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from google.protobuf import descriptor_pb2
from google.protobuf.message import Message

from pygoby.dccl.errors import DcclError
from pygoby.dccl.xml import convert
from pygoby.dccl.xml.model import Publish, PublishVar, Queuing, Var, XmlMessage
from pygoby.dccl.xml.parser import ALGORITHMS, read_message_file, read_message_set
from pygoby.errors import ConfigError
from pygoby.protobuf import ProtoError, ProtoLoader
from pygoby.protobuf.goby.acomms.protobuf.manipulator_pb2 import Manipulator
from pygoby.protobuf.goby.acomms.protobuf.queue_pb2 import QueuedMessageEntry
from pygoby.protobuf.goby.moos.protobuf.translator_pb2 import TranslatorEntry


@dataclass
class MessageSet:
    """The messages of one XML file, with what the conversion needs."""

    path: Path
    messages: list[XmlMessage]
    warnings: list[str] = field(default_factory=list)
    manipulators: tuple[Manipulator.ValueType, ...] = ()

    @property
    def proto_file_name(self) -> str:
        """The name of the converted file in a descriptor pool (and on disk)."""
        return f"{self.path.stem}.proto"

    @property
    def names(self) -> list[str]:
        return [m.name for m in self.messages]

    def file_descriptor(self) -> descriptor_pb2.FileDescriptorProto:
        return convert.file_descriptor(self.messages, self.proto_file_name)

    def proto_text(self) -> str:
        return convert.proto_text(self.messages, self.path.name)

    def write_proto(self, directory: str | os.PathLike[str]) -> Path:
        """Write the converted .proto file into `directory` (created if needed)."""
        out = Path(directory) / self.proto_file_name
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(self.proto_text())
        return out

    def queue_entries(self) -> list[QueuedMessageEntry]:
        return [convert.queue_entry(m, self.manipulators) for m in self.messages]

    def translator_entries(self) -> list[TranslatorEntry]:
        return [convert.translator_entry(m) for m in self.messages]

    def register(self, loader: ProtoLoader) -> list[type[Message]]:
        """Add the converted file to `loader`'s pool; the message classes in XML order."""
        try:
            loader.add_file_proto(self.file_descriptor())
        except ProtoError as err:
            raise ConfigError(str(err), file=self.path) from None
        return [loader.message_class(name) for name in self.names]

    def load_into(self, codec) -> list[type[Message]]:
        """Register the messages in the codec's loader and load them into the DCCL codec (which
        checks that every message fits its <size>); errors name the message's line."""
        classes = self.register(codec.loader)
        for msg, cls in zip(self.messages, classes, strict=True):
            try:
                codec.load(cls)
            except DcclError as err:
                raise ConfigError(
                    f"message {msg.name}: {err}", file=self.path, line=msg.line
                ) from None
        return classes


def load_message_set(
    path: str | os.PathLike[str], manipulators: Iterable[Manipulator.ValueType] = ()
) -> MessageSet:
    """Read and check an XML message set file."""
    messages, warnings = read_message_file(path)
    return MessageSet(Path(path), messages, warnings, tuple(manipulators))


def parse_message_set(text: str | bytes, path: str | os.PathLike[str] = "<xml>") -> MessageSet:
    """The same from XML text (`path` is only used in error messages and the .proto name)."""
    data = text.encode() if isinstance(text, str) else text
    messages, warnings = read_message_set(data, path)
    return MessageSet(Path(path), messages, warnings)


__all__ = [
    "ALGORITHMS",
    "MessageSet",
    "Publish",
    "PublishVar",
    "Queuing",
    "Var",
    "XmlMessage",
    "load_message_set",
    "parse_message_set",
]
