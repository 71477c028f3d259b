"""UDP multicast driver (DRIVER_UDP_MULTICAST, spec acomms.md §8.3).

Every transmission goes to `multicast_address:multicast_port` as one binary ModemTransmission;
our own datagrams heard back are ignored; DATA addressed to us with an ack request is
acknowledged at once.
"""

from __future__ import annotations

import logging
import socket
import struct

from google.protobuf.message import DecodeError

from pygoby.acomms import messages as m
from pygoby.acomms.driver_base import ModemDriverBase, ModemDriverException
from pygoby.protobuf import default_loader

log = logging.getLogger(__name__)

MAX_DATAGRAM = 65507
Status = m.ModemDriverStatus
_CONFIG = default_loader().pool.FindExtensionByName("goby.acomms.udp_multicast.protobuf.config")


class UDPMulticastDriver(ModemDriverBase):
    def __init__(self, clock=None) -> None:
        super().__init__(clock)
        self.mc_cfg = None
        self._sock: socket.socket | None = None
        self._frame_counter = 0

    def startup(self, cfg) -> None:
        if not cfg.HasField("modem_id"):
            raise ModemDriverException("modem_id is required", Status.INVALID_CONFIGURATION)
        self.cfg = cfg
        self.mc_cfg = c = cfg.Extensions[_CONFIG]
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        # SO_REUSEADDR only: with SO_REUSEPORT Linux hands each group datagram to just one
        # socket of the group instead of to every listener
        try:
            # A socket bound to a unicast address never sees group traffic (Linux), so bind the
            # port on every address and use listen_address as the multicast interface.
            sock.bind(("", c.multicast_port))
            interface = socket.inet_aton(c.listen_address)
            membership = struct.pack("4s4s", socket.inet_aton(c.multicast_address), interface)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
            if c.listen_address != "0.0.0.0":
                sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, interface)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        except OSError as exc:
            sock.close()
            raise ModemDriverException(str(exc), Status.STARTUP_FAILED) from exc
        sock.setblocking(False)
        self._sock = sock

    def shutdown(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def handle_initiate_transmission(self, transmission) -> None:
        msg = m.ModemTransmission()
        msg.CopyFrom(transmission)
        self.signal_modify_transmission.emit(msg)
        if not msg.HasField("frame_start"):
            msg.frame_start = self._frame_counter
        if not msg.HasField("max_frame_bytes"):
            sizes = {rb.rate: rb.bytes for rb in self.mc_cfg.rate_to_bytes}
            msg.max_frame_bytes = sizes.get(msg.rate, self.mc_cfg.max_frame_size)
        self.signal_data_request.emit(msg)
        self._frame_counter += len(msg.frame)
        if msg.frame and msg.frame[0]:
            self._send(msg)
            self.signal_transmit_result.emit(msg)

    def _send(self, msg) -> None:
        if self._sock is None:
            raise ModemDriverException("driver is not started", Status.CONNECTION_TO_MODEM_FAILED)
        data = msg.SerializeToString()
        try:
            self._sock.sendto(data, (self.mc_cfg.multicast_address, self.mc_cfg.multicast_port))
        except OSError as exc:
            log.warning("multicast send failed: %s", exc)
        self.emit_raw(False, data)

    def do_work(self) -> None:
        if self._sock is None:
            return
        while True:
            try:
                data, _ = self._sock.recvfrom(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                log.debug("multicast receive error: %s", exc)
                continue
            msg = m.ModemTransmission()
            try:
                msg.ParseFromString(data)
            except DecodeError as exc:
                log.warning("ignoring a datagram that is not a ModemTransmission: %s", exc)
                continue
            if msg.src == self.modem_id:
                continue  # our own transmission looped back
            self.emit_raw(True, data)
            if msg.type == m.DATA and msg.ack_requested and msg.dest == self.modem_id:
                ack = m.ModemTransmission(type=m.ACK, src=self.modem_id, dest=msg.src)
                ack.acked_frame.extend(range(msg.frame_start, msg.frame_start + len(msg.frame)))
                self._send(ack)
            self.signal_receive.emit(msg)
