"""pAcommsHandler's Goby 1.1 side (spec goby-moos-apps.md §4.10, acomms.md §5.8, seed 003
§2.3.5-2.3.7), kept out of the app's wiring:

* `TransitionalMessages.expand(cfg, loader, find)`: the XML message files of
  `transitional_cfg` (where Goby 1.1's dccl_cfg/queue_cfg `message_file`s land at load) become
  DCCL types in the app's loader, `queue_cfg.message_entry`s and `translator_entry`s, as Goby 2
  did at start-up; `complete(msg)` gives a created message Goby 1.1's header defaults (time =
  now, source = our modem id).
* `Goby11Variables`: the Goby 1.1 MOOS variables that goby3 lacks or spells differently: CCL
  queues (`out_pubsub_var` -> queue, received frames -> `in_pubsub_var`), ACOMMS_INCOMING_DATA /
  ACOMMS_OUTGOING_DATA (ModemDataTransmission text), ACOMMS_RANGE_COMMAND ->
  ping, ACOMMS_RANGE_RESPONSE, ACOMMS_POLLER_UPDATE (a MACUpdate, 1.1 slots allowed).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue import QueueError
from pygoby.acomms.queue.ccl import goby11_time
from pygoby.dccl.xml import MessageSet, load_message_set
from pygoby.errors import ConfigError
from pygoby.moos import goby11_config
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import Technique, serialize_for_moos
from pygoby.protobuf import ProtoLoader

log = logging.getLogger(__name__)

INCOMING_DATA = "ACOMMS_INCOMING_DATA"
OUTGOING_DATA = "ACOMMS_OUTGOING_DATA"
RANGE_COMMAND = "ACOMMS_RANGE_COMMAND"
RANGE_RESPONSE = "ACOMMS_RANGE_RESPONSE"
POLLER_UPDATE = "ACOMMS_POLLER_UPDATE"
# Goby 1.1 posted its acomms messages as plain single-line TextFormat
GOBY11_TECHNIQUE = Technique.TECHNIQUE_PROTOBUF_TEXT_FORMAT
V1_RANGING = acomms_pb.V1ModemRangingRequest.DESCRIPTOR.fields_by_name["type"].enum_type.values_by_name
RANGING_TYPES = {  # Goby 1.1 RangingType -> Micro-Modem transmission type
    V1_RANGING["MODEM_TWO_WAY_PING"].number: acomms_pb.MICROMODEM_TWO_WAY_PING,
    V1_RANGING["REMUS_LBL_RANGING"].number: acomms_pb.MICROMODEM_REMUS_LBL_RANGING,
}
V1_RANGING_OF = {v: k for k, v in RANGING_TYPES.items()}


def parse_goby11(value: str | bytes, out: Message) -> None:
    """A Goby 1.1 (or goby3) TextFormat string, 1.1 spellings (slot types, ...) translated."""
    text = value.decode("latin-1") if isinstance(value, bytes) else value
    text_format.Merge(goby11_config.translate(text, out.DESCRIPTOR).text, out)


V1_UPDATE = acomms_pb.V1MACUpdate.UpdateType


def _slot(v1_slot) -> Message:
    slot = acomms_pb.ModemTransmission()
    parse_goby11(text_format.MessageToString(v1_slot), slot)
    return slot


def _same_slot(a: Message, b: Message) -> bool:
    return all(getattr(a, f) == getattr(b, f) for f in ("src", "dest", "rate", "type", "slot_seconds"))


def mac_update_from_goby11(value: str | bytes, current: list[Message], src: int) -> Message | None:
    """A Goby 1.1 MACUpdate (`dest update_type: ADD|REMOVE|REPLACE slot {...}`) as today's
    MACUpdate against the `current` cycle; None if `value` is not the Goby 1.1 form."""
    text = value.decode("latin-1") if isinstance(value, bytes) else value
    old = acomms_pb.V1MACUpdate()
    try:
        text_format.Merge(text, old)
    except text_format.ParseError:
        return None
    slots = [_slot(s) for s in old.slot]
    update = acomms_pb.MACUpdate(src=src, dest=old.dest)
    U = acomms_pb.MACUpdate.UpdateType
    if old.update_type == V1_UPDATE.Value("ADD"):
        update.update_type = U.Value("PUSH_BACK")
        update.slot.extend(slots)
    else:
        if old.update_type == V1_UPDATE.Value("REMOVE"):
            slots = [s for s in current if not any(_same_slot(s, r) for r in slots)]
        update.update_type = U.Value("ASSIGN")
        update.slot.extend(slots)
    return update


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


class Goby11Variables:
    """The Goby 1.1 MOOS variables of a pAcommsHandler (see the module docstring).

    `app` publishes/subscribes (a GobyMOOSApp); `acomms` is its AcommsHandler."""

    def __init__(self, app, acomms, queue_cfg: Message, enabled: bool) -> None:
        self.app, self.acomms = app, acomms
        self.enabled = enabled  # the 1.1 data variables (only for Goby 1.1 style configurations)
        self.in_vars = {q.key.id: q.in_pubsub_var for q in queue_cfg.queue if q.in_pubsub_var}
        self.out_vars = {q.out_pubsub_var: q.key.id for q in queue_cfg.queue if q.out_pubsub_var}
        # these run inside the queue's and the driver's work: a failure is logged, not raised
        acomms.queue.signal_receive_ccl.connect(self._contained(self._on_ccl_received))
        acomms.signal_modem_receive.connect(self._contained(self._on_modem_receive))

    def _contained(self, slot: Callable[[Message], None]) -> Callable[[Message], None]:
        def run(message: Message) -> None:
            try:
                slot(message)
            except Exception:
                self.app.log.exception("cannot post the Goby 1.1 form of %s",
                                       message.DESCRIPTOR.full_name)  # fmt: skip

        return run

    def subscribe_all(self) -> None:
        for var in self.out_vars:
            self.app.subscribe(var, self._on_ccl_out)
        self.app.subscribe(RANGE_COMMAND, self._on_range_command)
        self.app.subscribe(POLLER_UPDATE, self._on_poller_update)

    def _publish(self, var: str, message: Message) -> None:
        self.app.publish(var, serialize_for_moos(message, GOBY11_TECHNIQUE))

    # ---------------------------------------------------------------- MOOS -> acomms
    def _parse(self, msg: MOOSMessage, out: Message) -> Message | None:
        try:
            parse_goby11(msg.value, out)
        except text_format.ParseError as err:
            self.app.log.warning("%s: not a %s (%s)", msg.key, out.DESCRIPTOR.name, err)
            return None
        return out

    def _on_ccl_out(self, msg: MOOSMessage) -> None:
        ccl_id = self.out_vars[msg.key]
        transmission = self._parse(msg, acomms_pb.V1ModemDataTransmission())
        if transmission is None:
            return
        if not transmission.base.HasField("time"):
            transmission.base.time = goby11_time(self.app.clock.now())
        transmission.queue_key.type, transmission.queue_key.id = acomms_pb.QUEUE_CCL, ccl_id
        try:
            self.acomms.queue.push_ccl(ccl_id, transmission)
        except QueueError as err:
            self.app.log.warning("%s: %s", msg.key, err)
            return
        if self.enabled:
            self._publish(OUTGOING_DATA, transmission)

    def _on_range_command(self, msg: MOOSMessage) -> None:
        request = self._parse(msg, acomms_pb.V1ModemRangingRequest())
        if request is None:
            return
        kind = RANGING_TYPES.get(request.type, acomms_pb.MICROMODEM_TWO_WAY_PING)
        ping = acomms_pb.ModemTransmission(src=self.acomms.modem_id, dest=request.base.dest,
                                   type=acomms_pb.DRIVER_SPECIFIC)  # fmt: skip
        extension = ping.Extensions[acomms_pb.MM_TRANSMISSION]
        extension.type = kind
        if kind == acomms_pb.MICROMODEM_REMUS_LBL_RANGING:
            extension.remus_lbl.enable_beacons = request.enable_beacons
            extension.remus_lbl.lbl_max_range = request.max_range
        self.acomms.initiate_transmission(ping)

    def _on_poller_update(self, msg: MOOSMessage) -> None:
        self.apply_mac_update(msg)

    def apply_mac_update(self, msg: MOOSMessage) -> bool:
        """A MACUpdate in Goby 1.1's form applied to the cycle; False if it is not one."""
        update = mac_update_from_goby11(msg.value, self.acomms.mac.slots, self.acomms.modem_id)
        if update is None:
            return False
        self.acomms.apply_mac_update(update)
        return True

    # ---------------------------------------------------------------- acomms -> MOOS
    def _on_ccl_received(self, transmission: Message) -> None:
        var = self.in_vars.get(transmission.queue_key.id)
        if var:
            self._publish(var, transmission)

    def _on_modem_receive(self, transmission: Message) -> None:
        if transmission.type == acomms_pb.DATA and self.enabled:
            for index, frame in enumerate(transmission.frame):
                data = acomms_pb.V1ModemDataTransmission(data=bytes(frame), frame=transmission.frame_start + index,
                                                 ack_requested=transmission.ack_requested)  # fmt: skip
                base = data.base
                base.src, base.dest, base.rate = transmission.src, transmission.dest, max(transmission.rate, 0)
                base.time = goby11_time(transmission.time / 1e6)
                self._publish(INCOMING_DATA, data)
        elif transmission.type == acomms_pb.DRIVER_SPECIFIC and transmission.HasExtension(acomms_pb.MM_TRANSMISSION):
            extension = transmission.Extensions[acomms_pb.MM_TRANSMISSION]
            if extension.type in V1_RANGING_OF and extension.HasField("ranging_reply"):
                reply = acomms_pb.V1ModemRangingReply(type=V1_RANGING_OF[extension.type])
                reply.one_way_travel_time.extend(extension.ranging_reply.one_way_travel_time)
                reply.base.src, reply.base.dest = transmission.src, transmission.dest
                reply.base.time = goby11_time(transmission.time / 1e6)
                self._publish(RANGE_RESPONSE, reply)
