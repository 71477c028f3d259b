"""What the UDP and UDP-multicast drivers share: one binary ModemTransmission per datagram, Goby
frame numbering from a running counter, a non-blocking socket read in `do_work()`."""

from __future__ import annotations

import logging
import socket

from google.protobuf.message import DecodeError

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverBase
from pygoby.util.clock import Clock

log = logging.getLogger(__name__)

MAX_DATAGRAM = 65507


class DatagramDriverBase(ModemDriverBase):
    """Subclasses open `self._sock` in startup() and implement `_max_frame_bytes`, `_send` and
    `_handle_transmission`."""

    def __init__(self, clock: Clock | None = None) -> None:
        super().__init__(clock)
        self._sock: socket.socket | None = None
        self._frame_counter = 0

    def shutdown(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def handle_initiate_transmission(self, transmission: acomms_pb.ModemTransmission) -> None:
        msg = acomms_pb.ModemTransmission()
        msg.CopyFrom(transmission)
        self.signal_modify_transmission.emit(msg)
        if not msg.HasField("frame_start"):
            msg.frame_start = self._frame_counter
        if not msg.HasField("max_frame_bytes"):
            msg.max_frame_bytes = self._max_frame_bytes(msg)
        self.signal_data_request.emit(msg)
        self._frame_counter += len(msg.frame)
        if msg.frame and msg.frame[0]:
            self._transmit(msg)

    def _transmit(self, msg: acomms_pb.ModemTransmission) -> None:
        """Send a datagram and report it: every datagram sent, an acknowledgement too, is a
        transmit result (ACOMMS_MODEM_TRANSMIT), as goby3's datagram drivers report theirs."""
        self._send(msg)
        self.signal_transmit_result.emit(msg)

    def do_work(self) -> None:
        if self._sock is None:
            return
        while True:
            try:
                data, _ = self._sock.recvfrom(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:  # e.g. ICMP port unreachable reported on a later call
                log.debug("%s receive error: %s", type(self).__name__, exc)
                continue
            msg = acomms_pb.ModemTransmission()
            try:
                msg.ParseFromString(data)
            except DecodeError as exc:
                self.emit_raw(True, data)
                log.warning("ignoring a datagram that is not a ModemTransmission: %s", exc)
                continue
            self._handle_transmission(msg, data)

    def _max_frame_bytes(self, msg: acomms_pb.ModemTransmission) -> int:
        raise NotImplementedError

    def _send(self, msg: acomms_pb.ModemTransmission) -> None:
        raise NotImplementedError

    def _handle_transmission(self, msg: acomms_pb.ModemTransmission, data: bytes) -> None:
        """A parsed datagram (`data` are its bytes, for the raw log)."""
        raise NotImplementedError
