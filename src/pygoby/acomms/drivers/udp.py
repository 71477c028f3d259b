"""UDP driver (DRIVER_UDP): one datagram = one binary ModemTransmission.

Wire-compatible with goby3's UDPDriver: no header or checksum, immediate ACK datagrams naming
the Goby frame numbers (`frame_start` from a running counter). The socket is non-blocking and
read in `do_work()`.
"""

from __future__ import annotations

import logging
import socket

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.datagram import DatagramDriverBase
from pygoby.acomms.errors import ModemDriverError
from pygoby.util.clock import Clock

log = logging.getLogger(__name__)

Status = acomms_pb.ModemDriverStatus


class UDPDriver(DatagramDriverBase):
    def __init__(self, clock: Clock | None = None) -> None:
        super().__init__(clock)
        self.udp_cfg = acomms_pb.UDPConfig()
        self._remotes: dict[int, list[tuple[str, int]]] = {}
        self._ack_ids: set[int] = set()
        self._unreachable: set[int] = set()  # destinations already warned about

    @property
    def local_port(self) -> int:
        assert self._sock is not None
        return self._sock.getsockname()[1]

    def startup(self, cfg: acomms_pb.DriverConfig) -> None:
        if not cfg.HasField("modem_id"):
            raise ModemDriverError("modem_id is required", Status.INVALID_CONFIGURATION)
        self.cfg = cfg
        self.udp_cfg = cfg.Extensions[acomms_pb.UDP_CONFIG]
        if not self.udp_cfg.HasField("local"):
            raise ModemDriverError("UDP config needs local", Status.INVALID_CONFIGURATION)
        family = socket.AF_INET6 if self.udp_cfg.ipv6 else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            sock.bind(("::" if self.udp_cfg.ipv6 else "0.0.0.0", self.udp_cfg.local.port))
        except OSError as exc:
            sock.close()
            raise ModemDriverError(str(exc), Status.STARTUP_FAILED) from exc
        sock.setblocking(False)
        self._sock = sock
        self._remotes = {}
        for remote in self.udp_cfg.remote:
            try:
                info = socket.getaddrinfo(remote.ip, remote.port, family, socket.SOCK_DGRAM)
            except OSError as exc:
                raise ModemDriverError(
                    f"cannot resolve {remote.ip}: {exc}", Status.INVALID_CONFIGURATION
                ) from exc
            host, port = info[0][4][:2]
            self._remotes.setdefault(remote.modem_id, []).append((str(host), int(port)))
        self._ack_ids = {cfg.modem_id, *self.udp_cfg.additional_application_ack_modem_id}

    def _max_frame_bytes(self, msg: acomms_pb.ModemTransmission) -> int:
        return self.udp_cfg.max_frame_size

    def _send(self, msg: acomms_pb.ModemTransmission) -> None:
        if self._sock is None:
            raise ModemDriverError("UDP driver is not started", Status.CONNECTION_TO_MODEM_FAILED)
        data = msg.SerializeToString()
        targets = list(self._remotes.get(acomms_pb.BROADCAST_ID, []))
        if msg.HasField("dest") and msg.dest != acomms_pb.BROADCAST_ID:
            targets += self._remotes.get(msg.dest, [])
        if not targets and msg.dest not in self._unreachable:
            self._unreachable.add(msg.dest)  # once per destination: it recurs every slot
            log.warning(
                "UDP driver: no remote for destination %d (remotes configured for modem ids "
                "%s); a broadcast (0) reaches only the remotes whose modem_id is 0",
                msg.dest,
                sorted(self._remotes) or "none",
            )
        for address in targets:
            try:
                self._sock.sendto(data, address)
            except OSError as exc:
                log.warning("UDP send to %s failed: %s", address, exc)
        self.emit_raw(False, data)

    def _handle_transmission(self, msg: acomms_pb.ModemTransmission, data: bytes) -> None:
        self.emit_raw(True, data)
        if msg.type != acomms_pb.ACK and msg.ack_requested and msg.dest in self._ack_ids:
            ack = acomms_pb.ModemTransmission(
                type=acomms_pb.ACK,
                time=acomms_pb.now_us(self.clock.now()),
                src=msg.dest,
                dest=msg.src,
            )
            ack.acked_frame.extend(range(msg.frame_start, msg.frame_start + len(msg.frame)))
            self._transmit(ack)
        self.signal_receive.emit(msg)
