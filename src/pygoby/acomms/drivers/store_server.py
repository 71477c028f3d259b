"""Store-server driver (DRIVER_STORE_SERVER): polls a goby_store_server.

Every `query_interval_seconds` (when no reply is pending) it sends a StoreServerRequest with the
pending outbox over its line link (TCP client, CR-delimited RUDICS packets); each response's
inbox is delivered, acknowledged and polls are turned into local data requests. No reply within
`reset_interval_seconds` closes and reopens the link.
"""

from __future__ import annotations

import logging

from google.protobuf.message import DecodeError

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverBase
from pygoby.acomms.errors import ModemDriverError, RudicsPacketError
from pygoby.acomms.rudics import (
    embedded_size,
    max_data_bytes,
    parse_rudics_packet,
    serialize_rudics_packet,
)
from pygoby.acomms.store_server.auth import AUTH_BYTES, read_secret_file, sign_request
from pygoby.errors import ConfigError
from pygoby.util.clock import Clock

log = logging.getLogger(__name__)

DEFAULT_PORT = 11244
POLL = acomms_pb.StoreServerTransmission.STORE_SERVER_DRIVER_POLL
# Room in a request for everything but the frames' bytes (ids, times, the transmission's other
# fields, the request around it), so that one full transmission always fits in one packet.
TRANSMISSION_OVERHEAD = 256


class StoreServerDriver(ModemDriverBase):
    DEFAULT_LINE_DELIMITER = "\r"

    def __init__(self, clock: Clock | None = None, link=None) -> None:
        super().__init__(clock, link)
        self.ss_cfg = acomms_pb.StoreServerConfig()
        self._outbox: list = []
        self._request_id = 0
        self._waiting_since: float | None = None
        self._last_query = 0.0
        self._frame_counter = 0
        self._running = False
        self._secret: bytes | None = None
        self._in_flight: list = []  # the outbox of the request awaiting its reply

    def startup(self, cfg: acomms_pb.DriverConfig) -> None:
        cfg_copy = acomms_pb.DriverConfig()
        cfg_copy.CopyFrom(cfg)
        cfg = cfg_copy
        if not cfg.HasField("tcp_port"):
            cfg.tcp_port = DEFAULT_PORT
        if not cfg.HasField("connection_type"):
            cfg.connection_type = acomms_pb.DriverConfig.CONNECTION_TCP_AS_CLIENT
        self.ss_cfg = cfg.Extensions[acomms_pb.STORE_SERVER_CONFIG]
        auth = cfg.Extensions[acomms_pb.STORE_SERVER_AUTH]
        if auth.HasField("secret_file"):
            try:
                self._secret = read_secret_file(auth.secret_file)
            except ConfigError as exc:
                raise ModemDriverError(
                    f"store_server_auth.secret_file: {exc}",
                    acomms_pb.ModemDriverStatus.INVALID_CONFIGURATION,
                ) from None
        self.modem_start(cfg)
        self._running = True

    def shutdown(self) -> None:
        self._running = False
        self.modem_close()

    # ------------------------------------------------------------------ sending
    def handle_initiate_transmission(self, transmission: acomms_pb.ModemTransmission) -> None:
        msg = acomms_pb.ModemTransmission()
        msg.CopyFrom(transmission)
        self.signal_modify_transmission.emit(msg)
        if msg.type != acomms_pb.DATA:
            log.warning("store-server driver only sends DATA transmissions")
            return
        if msg.src < 0:
            msg.src = self.modem_id
        if msg.src != self.modem_id:
            poll = acomms_pb.ModemTransmission(
                src=self.modem_id, dest=msg.src, type=acomms_pb.DRIVER_SPECIFIC
            )
            ext = poll.Extensions[acomms_pb.STORE_SERVER_TRANSMISSION]
            ext.type, ext.poll_src, ext.poll_dest = POLL, msg.src, msg.dest
            self._outbox.append(poll)
            return
        rate = msg.rate
        msg.frame_start = self._frame_counter
        to_bytes, to_frames = self.ss_cfg.rate_to_bytes, self.ss_cfg.rate_to_frames
        if 0 <= rate < len(to_frames):
            msg.max_num_frames = to_frames[rate]
        # whatever the configuration says, a transmission must fit in one RUDICS packet
        frames = max(1, msg.max_num_frames)
        packet_room = (max_data_bytes() - TRANSMISSION_OVERHEAD) // frames
        msg.max_frame_bytes = min(
            to_bytes[rate] if 0 <= rate < len(to_bytes) else self.ss_cfg.max_frame_size,
            packet_room,
        )
        if len(msg.frame) < msg.max_num_frames:
            self.signal_data_request.emit(msg)
        self._frame_counter += len(msg.frame)
        if msg.frame and msg.frame[0]:
            self._outbox.append(msg)
            self.signal_transmit_result.emit(msg)

    # ------------------------------------------------------------------ polling loop
    def do_work(self) -> None:
        if not self._running or self.link is None:
            return
        for line in self.modem_read():
            self._handle_packet(line.encode("latin-1") + b"\r")
        now = self.clock.now()
        if (
            self._waiting_since is not None
            and now - self._waiting_since > self.ss_cfg.reset_interval_seconds
        ):
            log.warning("no reply from the store server: reconnecting")
            self.link.close()
            self.link.open()
            self._waiting_since = None
        if (
            self._waiting_since is None
            and self.link.is_open
            and now - self._last_query >= self.ss_cfg.query_interval_seconds
        ):
            self._send_request(now)

    def _send_request(self, now: float) -> None:
        self._request_id += 1
        request = acomms_pb.StoreServerRequest(modem_id=self.modem_id, request_id=self._request_id)
        # as much of the outbox as fits in one packet, oldest first; the rest goes next time
        room = max_data_bytes() - request.ByteSize() - (AUTH_BYTES if self._secret else 0)
        sent = 0
        for t in self._outbox:
            size = embedded_size(t.ByteSize())
            if size > room:
                if sent == 0:
                    log.error("dropping a transmission of %d bytes: larger than a packet", size)
                    sent = 1
                break
            room -= size
            request.outbox.append(t)
            sent += 1
        payload = request.SerializeToString()
        if self._secret is not None:
            payload = sign_request(payload, self._secret, now)
        packet = serialize_rudics_packet(payload)
        self.modem_write(packet.decode("latin-1"))
        self.emit_raw(False, packet)
        self._in_flight = list(request.outbox)
        self._outbox = self._outbox[sent:]
        self._waiting_since = now
        self._last_query = now

    def _handle_packet(self, packet: bytes) -> None:
        self.emit_raw(True, packet)
        try:
            payload = parse_rudics_packet(packet)
            response = acomms_pb.StoreServerResponse.FromString(payload)
            status = acomms_pb.StoreServerResponseStatus.FromString(payload)
        except (RudicsPacketError, DecodeError) as exc:
            log.warning("ignoring a bad store-server response: %s", exc)
            return
        self._waiting_since = None
        if status.error:  # nothing was stored: that outbox goes with the next request
            log.warning("store server: %s; sending again", status.error)
            self._outbox[:0] = self._in_flight
            self._in_flight = []
            return
        self._in_flight = []
        for t in response.inbox:
            ext = t.Extensions[acomms_pb.STORE_SERVER_TRANSMISSION]
            if t.type == acomms_pb.DRIVER_SPECIFIC and ext.type == POLL:
                if ext.poll_src == self.modem_id:
                    request = acomms_pb.ModemTransmission(
                        src=ext.poll_src, dest=ext.poll_dest, type=acomms_pb.DATA
                    )
                    self.handle_initiate_transmission(request)
                continue
            if t.type == acomms_pb.DATA and t.dest == self.modem_id and t.ack_requested:
                ack = acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=t.dest, dest=t.src)
                ack.acked_frame.extend(range(t.frame_start, t.frame_start + len(t.frame)))
                self._outbox.append(ack)
            self.signal_receive.emit(t)
