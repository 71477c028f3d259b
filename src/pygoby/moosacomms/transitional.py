"""Goby 1.1 XML message files in a pAcommsHandler configuration:
the files of `transitional_cfg` (where Goby 1.1's dccl_cfg/queue_cfg `message_file`s land when
the configuration is read) become DCCL types in a loader, `queue_cfg.message_entry`s and
`translator_entry`s, as Goby 2's transitional layer did at start-up. No MOOS needed (e.g. for
tools that show a pAcommsHandler's message set).

    messages = TransitionalMessages.expand(cfg, loader, find=str)   # ConfigError file:line
    messages.complete(created, now, modem_id)   # Goby 1.1's header defaults
    messages.single_field_sources()             # where Goby 1.1's `name=value` rule applies
    if messages.speaks_dccl1(cfg):              # Goby 1.1's own bytes on the wire
        queue.use_dccl1(messages.dccl1_bridge(cfg, loader, clock.now))
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

from google.protobuf.message import Message

from pygoby.dccl.dccl1 import Dccl1Codec
from pygoby.dccl.dccl1.bridge import Dccl1Bridge
from pygoby.dccl.xml import MessageSet, XmlMessage, load_message_set
from pygoby.errors import ConfigError
from pygoby.protobuf import ProtoLoader
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import pAcommsHandlerConfig
from pygoby.protobuf.goby.moos.protobuf.transitional_pb2 import MessageFile, WireFormat

log = logging.getLogger(__name__)


class TransitionalMessages:
    """The XML message sets of a pAcommsHandler configuration."""

    def __init__(self) -> None:
        self.sets: list[MessageSet] = []
        self._header: dict[str, tuple[str, str]] = {}  # message name -> (time field, source field)
        self._defined_in: dict[str, Path] = {}

    @classmethod
    def expand(
        cls, cfg: pAcommsHandlerConfig, loader: ProtoLoader, find: Callable[[str], str] = str
    ) -> TransitionalMessages:
        """Load `cfg.transitional_cfg.message_file` (paths through `find`), register the types
        in `loader` and append their queue and translator entries to `cfg`."""
        out = cls()
        for message_file in cfg.transitional_cfg.message_file:
            out.add_file(cfg, message_file, loader, find)
        return out

    def add_file(
        self,
        cfg: pAcommsHandlerConfig,
        message_file: MessageFile,
        loader: ProtoLoader,
        find: Callable[[str], str] = str,
    ) -> MessageSet:
        """One `message_file { path manipulator }`: its types into `loader`, its queue and
        translator entries appended to `cfg` (also how a tool imports one more file)."""
        message_set = load_message_set(find(message_file.path), message_file.manipulator)
        for name in message_set.names:
            if name in self._defined_in:
                raise ConfigError(
                    f"message {name} is defined in {self._defined_in[name]} too",
                    file=message_set.path,
                )
        message_set.register(loader)
        for name in message_set.names:
            self._defined_in[name] = message_set.path
        cfg.queue_cfg.message_entry.extend(message_set.queue_entries())
        cfg.translator_entry.extend(message_set.translator_entries())
        proto_dir = cfg.transitional_cfg.generated_proto_dir
        if proto_dir:
            written = message_set.write_proto(proto_dir)
            log.info("wrote %s (converted from %s)", written, message_set.path)
        for msg in message_set.messages:
            self._header[msg.name] = (msg.header["time"].name, msg.header["src_id"].name)
        self.sets.append(message_set)
        return message_set

    @property
    def messages(self) -> dict[str, XmlMessage]:
        """Every XML message by name."""
        return {msg.name: msg for message_set in self.sets for msg in message_set.messages}

    def single_field_sources(self) -> dict[str, dict[str, str]]:
        """{message: {source variable: field name}} for the source variables that feed one field
        (the translator reads them with a FORMAT create; the shared ones are key=value pairs
        already). Goby 1.1 read such a variable's string as `name=value` when it holds the
        field's name, else whole: Translator.read_named_values."""
        return {name: msg.single_field_sources() for name, msg in self.messages.items()}

    def speaks_dccl1(self, cfg: pAcommsHandlerConfig) -> bool:
        """Whether the XML messages travel as Goby 1.1's DCCL1 (transitional_cfg.wire_format;
        a Goby 1.1 configuration gets DCCL1 when it does not set it)."""
        transitional = cfg.transitional_cfg
        return bool(self.sets) and transitional.wire_format == WireFormat.DCCL1

    def dccl1_bridge(
        self, cfg: pAcommsHandlerConfig, loader: ProtoLoader, clock: Callable[[], float]
    ) -> Dccl1Bridge:
        """A DCCL1 codec for the XML messages (dccl_cfg.crypto_passphrase; Goby 1.1 encrypts
        with an empty passphrase when none is set), for the queue (QueueManager.use_dccl1)."""
        codec = Dccl1Codec(cfg.dccl_cfg.crypto_passphrase or None, cfg.modem_id, clock)
        bridge = Dccl1Bridge(codec, loader.message_class)
        for message_set in self.sets:
            bridge.add(message_set)  # ConfigError file:line: a message too big for DCCL1
        return bridge

    @property
    def warnings(self) -> list[str]:
        return [w for s in self.sets for w in s.warnings]

    def complete(self, message: Message, now: float, modem_id: int) -> Message:
        """Goby 1.1's header defaults: an unset time is now, an unset source our modem id."""
        fields = self._header.get(message.DESCRIPTOR.full_name)
        if fields is not None:
            time_field, source_field = fields
            if not message.HasField(time_field):
                setattr(message, time_field, now)
            if not message.HasField(source_field):
                setattr(message, source_field, modem_id)
        return message
