"""uField simulation driver (DRIVER_UFIELD_SIM_DRIVER), MOOS-agnostic core.

The driver tunnels hex-encoded ModemTransmissions through MOOS-IvP's uField toolbox. This core
takes either a `publish(variable, text)` callable for outgoing MOOS mail (then it is fed
incoming mail with `handle_mail(variable, text)`), or a `MailLink` set as `driver.mail` before
`startup`: the driver opens it to `moos_server:moos_port` for its variables, publishes through
it and reads its mail in `do_work`, as goby3's driver does with its own MOOS client.
pAcommsHandler gives it one (acomms does not import moos: the link is the app's).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Protocol

from google.protobuf.message import DecodeError

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverBase
from pygoby.acomms.errors import ModemDriverError
from pygoby.util.clock import Clock
from pygoby.util.modem_id import ModemIdLookup

log = logging.getLogger(__name__)

DEFAULT_FRAME_BYTES = 64
SOUND_SPEED = 1500.0
POLL = acomms_pb.UFldTransmission.UFIELD_DRIVER_POLL


def parse_moos_pairs(text: str) -> dict[str, str]:
    pairs = {}
    for part in text.split(","):
        key, sep, value = part.partition("=")
        if sep:
            pairs[key.strip().lower()] = value.strip()
    return pairs


class MailLink(Protocol):
    """The driver's own MOOS connection (goby3: a MOOS client named goby.moos.UFldDriver)."""

    def open(self, host: str, port: int, variables: list[str]) -> None: ...

    def publish(self, variable: str, text: str) -> None: ...

    def fetch(self) -> list[tuple[str, str]]: ...

    def close(self) -> None: ...


class UFldDriver(ModemDriverBase):
    def __init__(
        self, clock: Clock | None = None, publish: Callable[[str, str], None] | None = None
    ) -> None:
        super().__init__(clock)
        self._injected_publish = publish
        self.publish = publish if publish is not None else (lambda var, text: None)
        self.mail: MailLink | None = None
        self.ufld = acomms_pb.UFldConfig()
        self.lookup = ModemIdLookup()
        self._ping_target: str | None = None

    def startup(self, cfg: acomms_pb.DriverConfig) -> None:
        self.cfg = cfg
        self.ufld = cfg.Extensions[acomms_pb.UFLD_CONFIG]
        if self.ufld.modem_id_lookup_path:
            self.lookup = ModemIdLookup.from_file(self.ufld.modem_id_lookup_path)
        if self.mail is not None:
            self.mail.open(self.ufld.moos_server, self.ufld.moos_port, self.subscriptions)
            self.publish = self.mail.publish
        elif self._injected_publish is None:
            raise ModemDriverError(
                "the uField driver needs a MOOS connection (pAcommsHandler gives it one)",
                acomms_pb.ModemDriverStatus.INVALID_CONFIGURATION,
            )

    def shutdown(self) -> None:
        if self.mail is not None:
            self.mail.close()

    def do_work(self) -> None:
        if self.mail is not None:
            for variable, text in self.mail.fetch():
                self.handle_mail(variable, text)

    @property
    def subscriptions(self) -> list[str]:
        """MOOS variables the client must register for."""
        return [self.ufld.incoming_moos_var, self.ufld.micromodem_mimic.range_report_var]

    def _name(self, modem_id: int) -> str:
        return "all" if modem_id == acomms_pb.BROADCAST_ID else self.lookup.name(modem_id)

    # ------------------------------------------------------------------ sending
    def handle_initiate_transmission(self, transmission: acomms_pb.ModemTransmission) -> None:
        msg = acomms_pb.ModemTransmission()
        msg.CopyFrom(transmission)
        self.signal_modify_transmission.emit(msg)
        mm_type = msg.Extensions[acomms_pb.MM_TRANSMISSION].type
        if msg.type == acomms_pb.DATA and msg.src in (self.modem_id, acomms_pb.QUERY_SOURCE_ID):
            msg.src = self.modem_id
            sizes = self.ufld.rate_to_bytes
            msg.max_frame_bytes = (
                sizes[msg.rate] if 0 <= msg.rate < len(sizes) else DEFAULT_FRAME_BYTES
            )
            if not msg.frame:
                self.signal_data_request.emit(msg)
            if msg.frame and msg.frame[0]:
                self._send(msg)
        elif msg.type == acomms_pb.DATA:  # third party: ask that node to send
            poll = acomms_pb.ModemTransmission(
                type=acomms_pb.DRIVER_SPECIFIC, src=self.modem_id, dest=msg.src
            )
            ext = poll.Extensions[acomms_pb.UFLD_TRANSMISSION]
            ext.type, ext.poll_src, ext.poll_dest = POLL, msg.src, msg.dest
            self._send(poll)
        elif msg.type == acomms_pb.DRIVER_SPECIFIC and mm_type == acomms_pb.MICROMODEM_TWO_WAY_PING:
            self.publish(
                self.ufld.micromodem_mimic.range_request_var, f"name={self._name(self.modem_id)}"
            )
            self._ping_target = self._name(msg.dest)
        else:
            log.warning("uField driver ignores transmission type %d", msg.type)

    def _send(self, msg: acomms_pb.ModemTransmission) -> None:
        text = msg.SerializeToString().hex()
        self.publish(self.ufld.outgoing_moos_var, text)
        node_message = (
            f"src_node={self._name(msg.src)},dest_node={self._name(msg.dest)},"
            f"var_name={self.ufld.incoming_moos_var},string_val={text}"
        )
        self.publish(self.ufld.ufield_outgoing_moos_var, node_message)
        self.emit_raw(False, node_message)

    # ------------------------------------------------------------------ receiving
    def handle_mail(self, variable: str, text: str) -> None:
        if variable == self.ufld.incoming_moos_var:
            self._handle_incoming(text)
        elif variable == self.ufld.micromodem_mimic.range_report_var:
            self._handle_range_report(text)

    def _handle_incoming(self, text: str) -> None:
        self.emit_raw(True, text)
        try:
            msg = acomms_pb.ModemTransmission.FromString(bytes.fromhex(text.strip()))
        except (ValueError, DecodeError) as exc:
            log.warning("ignoring bad %s: %s", self.ufld.incoming_moos_var, exc)
            return
        ext = msg.Extensions[acomms_pb.UFLD_TRANSMISSION]
        if msg.type == acomms_pb.DRIVER_SPECIFIC and ext.type == POLL:
            request = acomms_pb.ModemTransmission(
                type=acomms_pb.DATA, src=ext.poll_src, dest=ext.poll_dest
            )
            self.handle_initiate_transmission(request)
            return
        if msg.type == acomms_pb.DATA and msg.ack_requested and msg.dest != acomms_pb.BROADCAST_ID:
            ack = acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=msg.dest, dest=msg.src)
            ack.acked_frame.extend(range(len(msg.frame)))
            self._send(ack)
        self.signal_receive.emit(msg)

    def _handle_range_report(self, text: str) -> None:
        pairs = parse_moos_pairs(text)
        if self._ping_target is None or pairs.get("target") != self._ping_target:
            return
        try:
            owtt = float(pairs["range"]) / SOUND_SPEED
            when = math.floor(float(pairs["time"]))  # whole seconds, as goby3 (Q-ACOMMS-13)
        except (KeyError, ValueError) as exc:
            log.warning("ignoring bad range report %r: %s", text, exc)
            return
        msg = acomms_pb.ModemTransmission(
            type=acomms_pb.DRIVER_SPECIFIC,
            src=self.modem_id,
            dest=self.lookup.modem_id(self._ping_target),
            time=when * 1_000_000,
        )
        ext = msg.Extensions[acomms_pb.MM_TRANSMISSION]
        ext.type = acomms_pb.MICROMODEM_TWO_WAY_PING
        ext.ranging_reply.one_way_travel_time.append(owtt)
        self._ping_target = None
        self.signal_receive.emit(msg)
