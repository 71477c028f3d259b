"""UDP multicast driver (DRIVER_UDP_MULTICAST).

Every transmission goes to `multicast_address:multicast_port` as one binary ModemTransmission;
our own datagrams heard back are ignored; DATA addressed to us with an ack request is
acknowledged at once.
"""

from __future__ import annotations

import logging
import socket
import struct

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.datagram import DatagramDriverBase
from pygoby.acomms.errors import ModemDriverError
from pygoby.util.clock import Clock

log = logging.getLogger(__name__)

Status = acomms_pb.ModemDriverStatus
_CONFIG = acomms_pb.UDP_MULTICAST_CONFIG


class UDPMulticastDriver(DatagramDriverBase):
    def __init__(self, clock: Clock | None = None) -> None:
        super().__init__(clock)
        self.mc_cfg = acomms_pb.UDPMulticastConfig()

    def startup(self, cfg: acomms_pb.DriverConfig) -> None:
        if not cfg.HasField("modem_id"):
            raise ModemDriverError("modem_id is required", Status.INVALID_CONFIGURATION)
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
            raise ModemDriverError(str(exc), Status.STARTUP_FAILED) from exc
        sock.setblocking(False)
        self._sock = sock

    def _max_frame_bytes(self, msg: acomms_pb.ModemTransmission) -> int:
        sizes = {rb.rate: rb.bytes for rb in self.mc_cfg.rate_to_bytes}
        return sizes.get(msg.rate, self.mc_cfg.max_frame_size)

    def _send(self, msg: acomms_pb.ModemTransmission) -> None:
        if self._sock is None:
            raise ModemDriverError("driver is not started", Status.CONNECTION_TO_MODEM_FAILED)
        data = msg.SerializeToString()
        try:
            self._sock.sendto(data, (self.mc_cfg.multicast_address, self.mc_cfg.multicast_port))
        except OSError as exc:
            log.warning("multicast send failed: %s", exc)
        self.emit_raw(False, data)

    def _handle_transmission(self, msg: acomms_pb.ModemTransmission, data: bytes) -> None:
        if msg.src == self.modem_id:
            return  # our own transmission looped back
        self.emit_raw(True, data)
        if msg.type == acomms_pb.DATA and msg.ack_requested and msg.dest == self.modem_id:
            ack = acomms_pb.ModemTransmission(type=acomms_pb.ACK, src=self.modem_id, dest=msg.src)
            ack.acked_frame.extend(range(msg.frame_start, msg.frame_start + len(msg.frame)))
            self._transmit(ack)
        self.signal_receive.emit(msg)
