"""pAcommsHandler's handling of the Goby 1.1 MOOS variables that goby3 lacks or spells
differently (the XML message sets themselves are pygoby.moosacomms.transitional):

* `Goby11Variables`: CCL queues (`out_pubsub_var` -> queue, received frames ->
  `in_pubsub_var`), ACOMMS_INCOMING_DATA / ACOMMS_OUTGOING_DATA (ModemDataTransmission text),
  ACOMMS_RANGE_COMMAND -> ping, ACOMMS_RANGE_RESPONSE, ACOMMS_POLLER_UPDATE. When the XML
  messages travel as Goby 1.1's bytes (DCCL1) also 1.1's ACOMMS_ACK (ModemDataAck),
  ACOMMS_EXPIRE (ModemDataExpire), ACOMMS_QSIZE (QueueSize by queue key, CCL queues too),
  ACOMMS_FLUSH_QUEUE (`key { type: QUEUE_DCCL id: 20 }` or `key_type=QUEUE_DCCL,key_id=20`),
  each DCCL message on ACOMMS_OUTGOING_DATA / ACOMMS_INCOMING_DATA and on its
  `OUT_<NAME>_HEX_<size>B` / `IN_<NAME>_HEX_<size>B` (or `<*_hex_moos_var>`), and a
  ModemDataTransmission another process posts on an IN_ variable is decoded as if received.
* `mac_update_from_goby11`: a Goby 1.1 MACUpdate (ADD/REMOVE/REPLACE, SLOT_* slots) as today's.
"""

from __future__ import annotations

from collections.abc import Callable

from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.handler import AcommsHandler
from pygoby.acomms.queue import QueueError
from pygoby.acomms.queue.ccl import goby11_time
from pygoby.dccl.dccl1 import is_dccl1_frame
from pygoby.moos import goby11_config
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.protocol import Value as MoosValue
from pygoby.moos.translator import Technique, serialize_for_moos
from pygoby.moos.translator.keyvalue import val_from_string
from pygoby.protobuf.descriptors import MessageT
from pygoby.protobuf.goby.moos.protobuf.transitional_pb2 import QueueType as V1QueueType
from pygoby.protobuf.goby.moos.protobuf.transitional_pb2 import Slot as V1Slot
from pygoby.util.signal import Signal

INCOMING_DATA = "ACOMMS_INCOMING_DATA"
OUTGOING_DATA = "ACOMMS_OUTGOING_DATA"
RANGE_COMMAND = "ACOMMS_RANGE_COMMAND"
RANGE_RESPONSE = "ACOMMS_RANGE_RESPONSE"
POLLER_UPDATE = "ACOMMS_POLLER_UPDATE"
# Goby 1.1 posted its acomms messages as plain single-line TextFormat
GOBY11_TECHNIQUE = Technique.TECHNIQUE_PROTOBUF_TEXT_FORMAT
RANGING_TYPES = {  # Goby 1.1 RangingType -> Micro-Modem transmission type
    acomms_pb.V1RangingType.MODEM_TWO_WAY_PING: acomms_pb.MICROMODEM_TWO_WAY_PING,
    acomms_pb.V1RangingType.REMUS_LBL_RANGING: acomms_pb.MICROMODEM_REMUS_LBL_RANGING,
}
V1_RANGING_OF = {v: k for k, v in RANGING_TYPES.items()}


def parse_goby11(value: MoosValue, out: Message) -> None:
    """A Goby 1.1 (or goby3) TextFormat string, 1.1 spellings (slot types, ...) translated."""
    text = value.decode("latin-1") if isinstance(value, bytes) else str(value)
    text_format.Merge(goby11_config.translate(text, out.DESCRIPTOR).text, out)


V1_UPDATE = acomms_pb.V1MACUpdate.UpdateType


def _slot(v1_slot: V1Slot) -> acomms_pb.ModemTransmission:
    slot = acomms_pb.ModemTransmission()
    parse_goby11(text_format.MessageToString(v1_slot), slot)
    return slot


def _same_slot(a: acomms_pb.ModemTransmission, b: acomms_pb.ModemTransmission) -> bool:
    return all(
        getattr(a, f) == getattr(b, f) for f in ("src", "dest", "rate", "type", "slot_seconds")
    )


def mac_update_from_goby11(
    value: MoosValue, current: list[acomms_pb.ModemTransmission], src: int
) -> acomms_pb.MACUpdate | None:
    """A Goby 1.1 MACUpdate (`dest update_type: ADD|REMOVE|REPLACE slot {...}`) as today's
    MACUpdate against the `current` cycle; None if `value` is not the Goby 1.1 form."""
    text = value.decode("latin-1") if isinstance(value, bytes) else str(value)
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


class Goby11Variables:
    """The Goby 1.1 MOOS variables of a pAcommsHandler (see the module docstring).

    `app` publishes/subscribes (a GobyMOOSApp); `acomms` is its AcommsHandler; `dccl1` the
    queue's Dccl1Bridge when the XML messages travel as Goby 1.1's bytes (then the 1.1 forms
    of ACOMMS_ACK/EXPIRE/QSIZE/FLUSH_QUEUE are used on `var`, the app's variable names)."""

    def __init__(
        self,
        app,
        acomms: AcommsHandler,
        queue_cfg: acomms_pb.QueueManagerConfig,
        enabled: bool,
        dccl1=None,
        var=None,
    ) -> None:
        self.app, self.acomms = app, acomms
        self.enabled = enabled  # the 1.1 data variables (only for Goby 1.1 style configurations)
        self.dccl1 = dccl1
        self.var = var or {}
        # DCCL id -> (name, incoming hex variable, outgoing hex variable)
        self.hex_vars = {
            msg.id: (msg.name, *msg.hex_vars()) for msg in (dccl1.xml_messages if dccl1 else [])
        }
        self.by_name = {name: (dccl_id, out) for dccl_id, (name, _, out) in self.hex_vars.items()}
        self.in_vars = {q.key.id: q.in_pubsub_var for q in queue_cfg.queue if q.in_pubsub_var}
        self.out_vars = {q.out_pubsub_var: q.key.id for q in queue_cfg.queue if q.out_pubsub_var}
        # these run inside the queue's and the driver's work: a failure is logged, not raised
        acomms.queue.signal_receive_ccl.connect(
            self._on_ccl_received, contain_errors=True, logger=app.log
        )
        acomms.signal_modem_receive.connect(
            self._on_modem_receive, contain_errors=True, logger=app.log
        )
        if dccl1 is not None:
            queue = acomms.queue
            connections: tuple[tuple[Signal[...], Callable[..., object]], ...] = (
                (queue.signal_queued, self._on_dccl1_queued),
                (queue.signal_receive_dccl1, self._on_dccl1_received),
                (queue.signal_ack, self._on_ack),
                (queue.signal_expire, self._on_expire),
                (queue.signal_queue_size_change, self._on_dccl_size),
                (queue.signal_ccl_queue_size_change, self._on_ccl_size),
            )
            for signal, slot in connections:
                signal.connect(slot, contain_errors=True, logger=app.log)

    @property
    def goby11_forms(self) -> bool:
        """ACOMMS_ACK/EXPIRE/QSIZE/FLUSH_QUEUE take Goby 1.1's forms."""
        return self.dccl1 is not None

    def subscribe_all(self) -> None:
        for var in self.out_vars:
            self.app.subscribe(var, self._on_ccl_out)
        self.app.subscribe(RANGE_COMMAND, self._on_range_command)
        self.app.subscribe(POLLER_UPDATE, self._on_poller_update)
        for incoming, _ in {(v[1], v[0]) for v in self.hex_vars.values()}:
            self.app.subscribe(incoming, self._on_incoming_hex)

    def _publish(self, var: str, message: Message) -> None:
        self.app.publish(var, serialize_for_moos(message, GOBY11_TECHNIQUE))

    # ---------------------------------------------------------------- MOOS -> acomms
    def _parse(self, msg: MOOSMessage, out: MessageT) -> MessageT | None:
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
        ping = acomms_pb.ModemTransmission(
            src=self.acomms.modem_id, dest=request.base.dest, type=acomms_pb.DRIVER_SPECIFIC
        )
        extension = ping.Extensions[acomms_pb.MM_TRANSMISSION]
        extension.type = kind
        if kind == acomms_pb.MICROMODEM_REMUS_LBL_RANGING:
            extension.remus_lbl.enable_beacons = request.enable_beacons
            extension.remus_lbl.lbl_max_range = request.max_range
        self.acomms.initiate_transmission(ping)

    def _on_poller_update(self, msg: MOOSMessage) -> None:
        self.apply_mac_update(msg)

    def apply_flush(self, msg: MOOSMessage) -> bool:
        """A QueueFlush in Goby 1.1's form (TextFormat, or `key_type=...,key_id=N` as 1.1's
        comma-equals form); False if it is not one."""
        text = msg.value.decode("latin-1") if isinstance(msg.value, bytes) else str(msg.value)
        text = text.strip()
        flush = acomms_pb.V1QueueFlush()
        if " " not in text and "=" in text:
            kind, key_id = val_from_string(text, "key_type"), val_from_string(text, "key_id")
            kinds = {"QUEUE_DCCL": acomms_pb.QUEUE_DCCL, "QUEUE_CCL": acomms_pb.QUEUE_CCL}
            if kind is None or key_id is None or not key_id.strip().isdigit():
                return False
            flush.key.type = kinds.get(kind.strip().upper(), acomms_pb.QUEUE_DCCL)
            flush.key.id = int(key_id)
        else:
            try:
                text_format.Merge(text, flush)
            except text_format.ParseError:
                return False
            if not flush.HasField("key"):
                return False
        if flush.key.type == acomms_pb.QUEUE_CCL:
            self.acomms.queue.flush_ccl_queue(flush.key.id)
        else:
            self.acomms.queue.flush_queue(acomms_pb.QueueFlush(dccl_id=flush.key.id))
        return True

    def _on_incoming_hex(self, msg: MOOSMessage) -> None:
        """Another process hands us a received DCCL message (1.1's tcp_share and tools did)."""
        if msg.src == self.app.name or not msg.is_string:
            return
        transmission = self._parse(msg, acomms_pb.V1ModemDataTransmission())
        if transmission is not None:
            self.acomms.queue.receive_dccl1_message(bytes(transmission.data))

    def apply_mac_update(self, msg: MOOSMessage) -> bool:
        """A MACUpdate in Goby 1.1's form applied to the cycle; False if it is not one."""
        update = mac_update_from_goby11(msg.value, self.acomms.mac.slots, self.acomms.modem_id)
        if update is None:
            return False
        self.acomms.apply_mac_update(update)
        return True

    # ---------------------------------------------------------------- acomms -> MOOS
    def _dccl_transmission(self, data: bytes, dccl_id: int, src: int, dest: int, time: float):
        out = acomms_pb.V1ModemDataTransmission(data=data)
        out.base.src, out.base.dest, out.base.time = src, dest, goby11_time(time)
        out.queue_key.type, out.queue_key.id = acomms_pb.QUEUE_DCCL, dccl_id
        return out

    def _original(self, message: Message):
        """The Goby 1.1 ModemDataTransmission of a queued message (acked or expired)."""
        if isinstance(message, acomms_pb.V1ModemDataTransmission):
            return message  # a CCL frame
        name = message.DESCRIPTOR.full_name
        if name not in self.by_name:
            return None
        dccl_id = self.by_name[name][0]
        header_src, header_dest = self.acomms.modem_id, self.acomms.queue.message_dest(message)
        data = self.dccl1.encode(message)  # the bytes it was sent as (same values, same bytes)
        return self._dccl_transmission(data, dccl_id, header_src, header_dest, self._now())

    def _now(self) -> float:
        return self.app.clock.now()

    def _on_dccl1_queued(self, name: str, item) -> None:
        if name not in self.by_name:
            return
        dccl_id, outgoing = self.by_name[name]
        data = self._dccl_transmission(item.encoded, dccl_id, item.src, item.dest, item.time / 1e6)
        data.ack_requested = item.ack_requested
        self._publish(OUTGOING_DATA, data)
        self._publish(outgoing, data)

    def _on_dccl1_received(
        self, transmission: acomms_pb.ModemTransmission, data: bytes, dccl_id: int
    ) -> None:
        out = self._dccl_transmission(
            data, dccl_id, transmission.src, transmission.dest, transmission.time / 1e6
        )
        out.base.rate = max(transmission.rate, 0)
        self._publish(INCOMING_DATA, out)
        if dccl_id in self.hex_vars:
            self._publish(self.hex_vars[dccl_id][1], out)

    def _on_ack(self, ack: acomms_pb.ModemTransmission, original: Message) -> None:
        out = acomms_pb.V1ModemDataAck(frame=ack.acked_frame[0] if ack.acked_frame else 0)
        out.base.src, out.base.dest = ack.src, ack.dest
        out.base.time = goby11_time(ack.time / 1e6 if ack.HasField("time") else self._now())
        orig = self._original(original)
        if orig is not None:
            out.orig_msg.CopyFrom(orig)
        self._publish(self.var["queue_ack_transmission"], out)

    def _on_expire(self, original: Message) -> None:
        out = acomms_pb.V1ModemDataExpire()
        orig = self._original(original)
        if orig is not None:
            out.orig_msg.CopyFrom(orig)
        self._publish(self.var["queue_expire"], out)

    def _on_dccl_size(self, size: acomms_pb.QueueSize) -> None:
        self._publish_size(acomms_pb.QUEUE_DCCL, size.dccl_id, size.size)

    def _on_ccl_size(self, ccl_id: int, size: int) -> None:
        self._publish_size(acomms_pb.QUEUE_CCL, ccl_id, size)

    def _publish_size(self, kind: V1QueueType.ValueType, queue_id: int, size: int) -> None:
        out = acomms_pb.V1QueueSize(size=size)
        out.key.type, out.key.id = kind, queue_id
        self._publish(self.var["queue_size"], out)

    def _on_ccl_received(self, transmission: acomms_pb.V1ModemDataTransmission) -> None:
        var = self.in_vars.get(transmission.queue_key.id)
        if var:
            self._publish(var, transmission)

    def _on_modem_receive(self, transmission: acomms_pb.ModemTransmission) -> None:
        if transmission.type == acomms_pb.DATA and self.enabled:
            for index, frame in enumerate(transmission.frame):
                if self.dccl1 is not None and is_dccl1_frame(bytes(frame)):
                    continue  # posted per message, as Goby 1.1 did (_on_dccl1_received)
                data = acomms_pb.V1ModemDataTransmission(
                    data=bytes(frame),
                    frame=transmission.frame_start + index,
                    ack_requested=transmission.ack_requested,
                )
                base = data.base
                base.src, base.dest, base.rate = (
                    transmission.src,
                    transmission.dest,
                    max(transmission.rate, 0),
                )
                base.time = goby11_time(transmission.time / 1e6)
                self._publish(INCOMING_DATA, data)
        elif transmission.type == acomms_pb.DRIVER_SPECIFIC and transmission.HasExtension(
            acomms_pb.MM_TRANSMISSION
        ):
            extension = transmission.Extensions[acomms_pb.MM_TRANSMISSION]
            if extension.type in V1_RANGING_OF and extension.HasField("ranging_reply"):
                reply = acomms_pb.V1ModemRangingReply(type=V1_RANGING_OF[extension.type])
                reply.one_way_travel_time.extend(extension.ranging_reply.one_way_travel_time)
                reply.base.src, reply.base.dest = transmission.src, transmission.dest
                reply.base.time = goby11_time(transmission.time / 1e6)
                self._publish(RANGE_RESPONSE, reply)
