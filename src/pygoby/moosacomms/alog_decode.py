"""Decoding a mission's acomms and translator variables in a .alog (`pygoby log convert
--mission`).

pAcommsHandler posts protobuf messages as text (TECHNIQUE_PROTOBUF_TEXT_FORMAT unless its
block says otherwise): ModemTransmission on ACOMMS_MODEM_RECEIVE/TRANSMIT and MAC_SLOT_START,
ModemRaw on RAW_INCOMING/OUTGOING, QueueSize on QSIZE, and the DCCL messages themselves with an
`@PB[type]` prefix on QUEUE_RECEIVE, ACK_ORIGINAL and EXPIRE (their types are the mission's).
The DCCL bytes in a ModemTransmission's frames are decoded through the mission's message set
(the DCCL id picks each type, a frame holds several messages as the queue packs them; Goby 1.1
frames of the XML messages through their DCCL1 codec). The variables of the translator_entry
blocks of pAcommsHandler and pTranslator (their create and publish variables) are read back by
their techniques (moos.translator.Translator.read_back).

A decoded value becomes `{"<Type>.<field path>": text}`: nested messages joined with `.`,
repeated fields indexed `name[i]`, extensions as `[full.name]`, enums by name, bytes as hex, the
rest as protobuf's text format writes them. The second and later messages of one type in a
frame (or read back from one value) are `<Type>[1].<field path>`, `<Type>[2]...`. A value that
does not decode keeps its row's raw `value`, gets no columns, and is counted in `undecodable`.
"""

from __future__ import annotations

import contextlib
import time
from collections import Counter
from collections.abc import Iterable, Iterator
from pathlib import Path

from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.handler import make_codec
from pygoby.acomms.queue.frames import unpack_frame
from pygoby.dccl import Codec, DcclError
from pygoby.dccl.dccl1 import is_dccl1_frame, unstitch
from pygoby.dccl.dccl1.bridge import Dccl1Bridge
from pygoby.moos.alog.format import AlogEntry
from pygoby.moos.appconfig import prefixed_var_names, read_configuration
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import (
    ModemIdLookup,
    Technique,
    Translator,
    TranslatorError,
    dynamic_parse,
    parse_for_moos,
)
from pygoby.moosacomms.acomms_config import AcommsMessageSet, acomms_config_or_defaults
from pygoby.moosacomms.translator_binding import MessageTypes
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import (
    pAcommsHandlerConfig,
)
from pygoby.protobuf.goby.apps.moos.protobuf.pTranslator_config_pb2 import pTranslatorConfig
from pygoby.protobuf.goby.moos.protobuf.translator_pb2 import TranslatorEntry

# moos_var fields (pAcommsHandler's names without the prefix) whose values are of fixed types
# (the first that parses; with a Goby 1.1 configuration QSIZE is Goby 1.1's QueueSize)
FIXED_TYPE_VARIABLES: dict[str, tuple[type[Message], ...]] = {
    "driver_receive": (acomms_pb.ModemTransmission,),
    "driver_transmit": (acomms_pb.ModemTransmission,),
    "mac_slot_start": (acomms_pb.ModemTransmission,),
    "driver_raw_msg_in": (acomms_pb.ModemRaw,),
    "driver_raw_msg_out": (acomms_pb.ModemRaw,),
    "queue_size": (acomms_pb.QueueSize, acomms_pb.V1QueueSize),
}
# the moos_var fields whose ModemTransmission frames carry the DCCL bytes sent and received
FRAME_VARIABLES = ("driver_receive", "driver_transmit")
# moos_var fields whose values are `@PB[type] ...` messages of the mission's DCCL types
PREFIXED_VARIABLES = ("queue_receive", "queue_ack_original_msg", "queue_expire")
# how the prefixed values are written (the body after `@PB[type] `: protobuf text format)
_PREFIXED_TECHNIQUE = Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
TRANSLATOR_BLOCK = "pTranslator"


class FrameClock:
    """The time DCCL decodes a frame at: the frame's own, which goes back and forth between
    the files of a log (the wall clock until a frame gives one)."""

    def __init__(self) -> None:
        self.time = time.time()

    def now(self) -> float:
        return self.time


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


def columns_of(messages: list[Message]) -> dict[str, str]:
    """`<Type>.<path>` columns of `messages`; the n-th (from 0) of a type is `<Type>[n]`."""
    out: dict[str, str] = {}
    seen: Counter[str] = Counter()
    for msg in messages:
        type_name = msg.DESCRIPTOR.name
        nth = seen[type_name]
        seen[type_name] += 1
        prefix = type_name if nth == 0 else f"{type_name}[{nth}]"
        out.update((f"{prefix}.{path}", text) for path, text in flatten(msg))
    return out


class MissionDecoder:
    """`decoder(entry)`: the fields of an acomms or translator variable's value, by its
    mission's names. `undecodable`: per variable, the values that did not decode (each frame
    message that did not is one more)."""

    def __init__(self, mission_path: str | Path, block: str = "pAcommsHandler") -> None:
        mission = MissionFile.read(mission_path)
        # a mission with pTranslator only still has pAcommsHandler's default variable names
        cfg = acomms_config_or_defaults(mission, block)
        names = prefixed_var_names(cfg.moos_var)
        self.fixed = {names[field]: cls for field, cls in FIXED_TYPE_VARIABLES.items()}
        self.frames = {names[field] for field in FRAME_VARIABLES}
        self.prefixed = {names[field] for field in PREFIXED_VARIABLES}
        message_set = AcommsMessageSet.load(cfg, mission.find_file, mission.search_dirs())
        self.types = message_set.types
        self.undecodable: Counter[str] = Counter()
        # the DCCL time codec resolves times near "now": a frame's own time when it has one
        self.clock = FrameClock()
        self.codec = self._frame_codec(cfg, message_set, self.clock)
        self.dccl1: Dccl1Bridge | None = None
        if message_set.transitional.speaks_dccl1(cfg):
            self.dccl1 = message_set.transitional.dccl1_bridge(
                cfg, message_set.loader, self.clock.now
            )
        self.ccl_ids = {queue.key.id for queue in cfg.queue_cfg.queue}  # Goby 1.1 CCL frames
        lat = mission.get_float("LatOrigin", outside_blocks=True) or 0.0
        lon = mission.get_float("LongOrigin", outside_blocks=True) or 0.0
        self.translators = [
            self._translator(cfg.translator_entry, self.types, cfg.modem_id_lookup_path, mission)
        ]
        if mission.goby_block(TRANSLATOR_BLOCK) is not None:
            translator_cfg = read_configuration(pTranslatorConfig, mission, TRANSLATOR_BLOCK)
            types = MessageTypes.of_translator_app(
                [mission.find_file(path) for path in translator_cfg.load_proto_file],
                translator_cfg.load_shared_library,
                mission.search_dirs(),
            )
            self.translators.append(
                self._translator(
                    translator_cfg.translator_entry,
                    types,
                    translator_cfg.modem_id_lookup_path,
                    mission,
                )
            )
        for translator in self.translators:
            translator.set_datum(lat, lon)
        self.translated = set().union(*(t.read_back_variables() for t in self.translators))

    @staticmethod
    def _frame_codec(
        cfg: pAcommsHandlerConfig, message_set: AcommsMessageSet, clock: FrameClock
    ) -> Codec:
        """The handler's codec with its queue's types, then every other loaded type that is a
        DCCL message (a peer may send types this vehicle does not queue)."""
        codec = make_codec(cfg.dccl_cfg, clock, message_set.loader)
        message_set.apply_libraries(codec)
        queued = [entry.protobuf_name for entry in cfg.queue_cfg.message_entry]
        for name in [*queued, *message_set.types.loaded]:
            # not a DCCL type (no dccl.msg id) or not loaded: its frames stay undecoded
            with contextlib.suppress(DcclError, KeyError, TypeError, ValueError):
                codec.load(message_set.types(name))
        return codec

    @staticmethod
    def _translator(
        entries: Iterable[TranslatorEntry],
        types: MessageTypes,
        lookup_path: str,
        mission: MissionFile,
    ) -> Translator:
        """The block's entries (TranslatorConfigError as the app would give at start-up); the
        modem id lookup for the name2modem_id algorithms of create rules."""
        modem_ids = ModemIdLookup.from_file(mission.find_file(lookup_path)) if lookup_path else None
        return Translator(entries, types, modem_ids=modem_ids)

    def __call__(self, entry: AlogEntry) -> dict[str, str]:
        """The value's fields as `{"<Type>.<path>": text}`; {} for other variables and for
        values that do not parse (the row keeps its `value`)."""
        messages: list[Message] = []
        classes = self.fixed.get(entry.name)
        try:
            if classes is not None:
                msg = _parse_first(_text_of(entry.value), classes)
                messages.append(msg)
                if entry.name in self.frames:
                    assert isinstance(msg, acomms_pb.ModemTransmission)
                    messages += self._frame_messages(entry.name, msg)
            elif entry.name in self.prefixed:
                found = dynamic_parse(_text_of(entry.value), self.types, _PREFIXED_TECHNIQUE)
                if found is None:
                    raise TranslatorError("not a message of the mission's types")
                messages.append(found)
            elif entry.name in self.translated:
                messages += self._read_back(entry)
            else:
                return {}
        except (TranslatorError, KeyError, ValueError):
            self.undecodable[entry.name] += 1
            return {}
        return columns_of(messages)

    def _read_back(self, entry: AlogEntry) -> list[Message]:
        messages: list[Message] = []
        failed: TranslatorError | None = None
        for translator in self.translators:
            if entry.name not in translator.read_back_variables():
                continue
            try:
                messages += translator.read_back(entry.name, entry.value)
            except TranslatorError as exc:
                failed = exc
        if not messages and failed is not None:
            raise failed
        return messages

    def _frame_messages(
        self, name: str, transmission: acomms_pb.ModemTransmission
    ) -> list[Message]:
        """The DCCL messages in the frames, as the queue unpacks them."""
        if transmission.type != acomms_pb.DATA:
            return []
        if transmission.HasField("time"):
            self.clock.time = transmission.time / 1e6
        out: list[Message] = []

        def undecodable(_offset: int, _error: DcclError) -> None:
            self.undecodable[name] += 1

        for frame in transmission.frame:
            data = bytes(frame)
            if not data or (data[0] in self.ccl_ids and len(data) == 32):
                continue  # nothing sent in this frame, or a Goby 1.1 CCL frame (not DCCL)
            if self.dccl1 is not None and is_dccl1_frame(data):
                out += self._dccl1_messages(name, data)
                continue
            out += [msg for msg, _ in unpack_frame(data, lambda _: self.codec, undecodable)]
        return out

    def _dccl1_messages(self, name: str, data: bytes) -> list[Message]:
        assert self.dccl1 is not None
        out: list[Message] = []
        try:
            parts = unstitch(data)
        except DcclError:
            self.undecodable[name] += 1
            return out
        for part in parts:
            try:
                out.append(self.dccl1.decode(part.data, self.clock.now()))
            except DcclError:
                self.undecodable[name] += 1
        return out


def _parse_first(value: str | bytes, classes: tuple[type[Message], ...]) -> Message:
    """`value` as the first of `classes` it parses as; the last one's error if none."""
    for cls in classes[:-1]:
        msg = cls()
        with contextlib.suppress(TranslatorError):
            parse_for_moos(value, msg)
            return msg
    msg = classes[-1]()
    parse_for_moos(value, msg)
    return msg


def _text_of(value: str | float | bytes) -> str | bytes:
    if isinstance(value, float):
        raise TranslatorError("a double, not a message")
    return value
