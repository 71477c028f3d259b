"""Decoding a mission's acomms variables in a .alog (`pygoby log convert --mission`).

pAcommsHandler posts protobuf messages as text (TECHNIQUE_PROTOBUF_TEXT_FORMAT unless its
block says otherwise): ModemTransmission on ACOMMS_MODEM_RECEIVE/TRANSMIT and MAC_SLOT_START,
ModemRaw on RAW_INCOMING/OUTGOING, QueueSize on QSIZE, and the DCCL messages themselves with an
`@PB[type]` prefix on QUEUE_RECEIVE, ACK_ORIGINAL and EXPIRE (their types are the mission's). A
decoded value becomes `{"<Type>.<field path>": text}`: nested messages joined with `.`, repeated
fields indexed `name[i]`, extensions as `[full.name]`, enums by name, bytes as hex, the rest as
protobuf's text format writes them.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.moos.alog.format import AlogEntry
from pygoby.moos.appconfig import prefixed_var_names
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import Technique, TranslatorError, dynamic_parse, parse_for_moos
from pygoby.moosacomms.acomms_config import AcommsMessageSet, read_acomms_config

# moos_var fields (pAcommsHandler's names without the prefix) whose values are one fixed type
FIXED_TYPE_VARIABLES: dict[str, type[Message]] = {
    "driver_receive": acomms_pb.ModemTransmission,
    "driver_transmit": acomms_pb.ModemTransmission,
    "mac_slot_start": acomms_pb.ModemTransmission,
    "driver_raw_msg_in": acomms_pb.ModemRaw,
    "driver_raw_msg_out": acomms_pb.ModemRaw,
    "queue_size": acomms_pb.QueueSize,
}
# moos_var fields whose values are `@PB[type] ...` messages of the mission's DCCL types
PREFIXED_VARIABLES = ("queue_receive", "queue_ack_original_msg", "queue_expire")
# how the prefixed values are written (the body after `@PB[type] `: protobuf text format)
_PREFIXED_TECHNIQUE = Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT


def flatten(msg: Message, prefix: str = "") -> Iterator[tuple[str, str]]:
    """(field path, value text) for every set field of `msg`, depth first."""
    for field, value in msg.ListFields():
        name = f"[{field.full_name}]" if field.is_extension else field.name
        path = f"{prefix}{name}"
        if field.is_repeated:
            for index, item in enumerate(value):
                yield from _flatten_value(field, item, f"{path}[{index}]")
        else:
            yield from _flatten_value(field, value, path)


def _flatten_value(field: FieldDescriptor, value: object, path: str) -> Iterator[tuple[str, str]]:
    if field.type in (FieldDescriptor.TYPE_MESSAGE, FieldDescriptor.TYPE_GROUP):
        assert isinstance(value, Message)
        yield from flatten(value, f"{path}.")
    elif field.type == FieldDescriptor.TYPE_ENUM:
        number = int(value)  # type: ignore[call-overload]
        enum_value = field.enum_type.values_by_number.get(number) if field.enum_type else None
        yield path, enum_value.name if enum_value is not None else str(number)
    elif field.type == FieldDescriptor.TYPE_BYTES:
        assert isinstance(value, bytes)
        yield path, value.hex()
    elif field.type == FieldDescriptor.TYPE_BOOL:
        yield path, "true" if value else "false"
    else:
        yield path, str(value)


class MissionDecoder:
    """`decoder(entry)`: the fields of an acomms variable's value, by its mission's names."""

    def __init__(self, mission_path: str | Path, block: str = "pAcommsHandler") -> None:
        mission = MissionFile.read(mission_path)
        cfg = read_acomms_config(mission, block)
        names = prefixed_var_names(cfg.moos_var)
        self.fixed = {names[field]: cls for field, cls in FIXED_TYPE_VARIABLES.items()}
        self.prefixed = {names[field] for field in PREFIXED_VARIABLES}
        self.types = AcommsMessageSet.load(cfg, mission.find_file, mission.search_dirs()).types

    def __call__(self, entry: AlogEntry) -> dict[str, str]:
        """The value's fields as `{"<Type>.<path>": text}`; {} for other variables and for
        values that do not parse (the row keeps its `value`)."""
        if isinstance(entry.value, float):
            return {}
        cls = self.fixed.get(entry.name)
        msg: Message | None
        try:
            if cls is not None:
                msg = cls()
                parse_for_moos(entry.value, msg)
            elif entry.name in self.prefixed:
                msg = dynamic_parse(entry.value, self.types, _PREFIXED_TECHNIQUE)
            else:
                return {}
        except (TranslatorError, KeyError, ValueError):
            return {}
        if msg is None:
            return {}
        type_name = msg.DESCRIPTOR.name
        return {f"{type_name}.{path}": text for path, text in flatten(msg)}
