"""Goby 1.1 XML message files in a pAcommsHandler configuration (spec goby-moos-apps.md §4.10):
the files of `transitional_cfg` (where Goby 1.1's dccl_cfg/queue_cfg `message_file`s land when
the configuration is read) become DCCL types in a loader, `queue_cfg.message_entry`s and
`translator_entry`s, as Goby 2's transitional layer did at start-up. No MOOS needed (e.g. for
tools that show a pAcommsHandler's message set).

    messages = TransitionalMessages.expand(cfg, loader, find=str)   # ConfigError file:line
    messages.complete(created, now, modem_id)   # Goby 1.1's header defaults
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

from google.protobuf.message import Message

from pygoby.dccl.xml import MessageSet, load_message_set
from pygoby.errors import ConfigError
from pygoby.protobuf import ProtoLoader

log = logging.getLogger(__name__)


class TransitionalMessages:
    """The XML message sets of a pAcommsHandler configuration."""

    def __init__(self, sets: list[MessageSet], header_fields: dict[str, tuple[str, str]]) -> None:
        self.sets = sets
        self._header = header_fields  # message name -> (time field, source field)

    @classmethod
    def expand(
        cls, cfg: Message, loader: ProtoLoader, find: Callable[[str], str] = str
    ) -> TransitionalMessages:
        """Load `cfg.transitional_cfg.message_file` (paths through `find`), register the types
        in `loader` and append their queue and translator entries to `cfg`."""
        sets: list[MessageSet] = []
        header: dict[str, tuple[str, str]] = {}
        seen: dict[str, Path] = {}
        transitional = cfg.transitional_cfg
        for message_file in transitional.message_file:
            message_set = load_message_set(find(message_file.path), message_file.manipulator)
            for name in message_set.names:
                if name in seen:
                    raise ConfigError(f"message {name} is defined in {seen[name]} too",
                                      file=message_set.path)  # fmt: skip
                seen[name] = message_set.path
            message_set.register(loader)
            cfg.queue_cfg.message_entry.extend(message_set.queue_entries())
            cfg.translator_entry.extend(message_set.translator_entries())
            if transitional.generated_proto_dir:
                written = message_set.write_proto(transitional.generated_proto_dir)
                log.info("wrote %s (converted from %s)", written, message_set.path)
            for msg in message_set.messages:
                header[msg.name] = (msg.header["time"].name, msg.header["src_id"].name)
            sets.append(message_set)
        return cls(sets, header)

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
