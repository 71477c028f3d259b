"""ABC example modem driver (DRIVER_ABC_EXAMPLE_MODEM). A teaching toy."""

from __future__ import annotations

import logging

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.abc_protocol import format_abc, parse_abc
from pygoby.acomms.driver_base import ModemDriverBase
from pygoby.acomms.errors import ABCParseError
from pygoby.util.clock import Clock

log = logging.getLogger(__name__)

MAX_FRAME_BYTES = 500
BITRATE = (100, 1000, 10000, 10000, 10000, 10000)


class ABCDriver(ModemDriverBase):
    DEFAULT_SERIAL_BAUD = 4800

    def __init__(self, clock: Clock | None = None, link=None) -> None:
        super().__init__(clock, link)
        self._last_sent_frames: list[int] = []
        self._running = False
        self._configured = False  # CONF lines sent on the current connection

    def startup(self, cfg: acomms_pb.DriverConfig) -> None:
        self.modem_start(cfg)
        self._running = True
        self._configured = False

    def _configure(self) -> None:
        # on every (re)connection: the simulator registers modems per connection
        abc = self.cfg.Extensions[acomms_pb.ABC_CONFIG]
        self._write(format_abc("CONF", MAC=self.cfg.modem_id))
        self._write(format_abc("CONF", FOO=int(abc.enable_foo)))
        self._write(format_abc("CONF", BAR=int(abc.enable_bar)))
        self._configured = True

    def shutdown(self) -> None:
        self._running = False
        self.modem_close()

    def _write(self, text: str) -> None:
        self.modem_write(text)
        self.emit_raw(False, text.rstrip("\r\n"))

    def handle_initiate_transmission(self, transmission: acomms_pb.ModemTransmission) -> None:
        msg = acomms_pb.ModemTransmission()
        msg.CopyFrom(transmission)
        self.signal_modify_transmission.emit(msg)
        msg.max_frame_bytes = MAX_FRAME_BYTES
        if not msg.frame:
            self.signal_data_request.emit(msg)
        if not msg.frame or not msg.frame[0]:  # nothing to send (QUIRKS.md Q-ACOMMS-8)
            return
        rate = msg.rate if 0 <= msg.rate < len(BITRATE) else len(BITRATE) - 1
        self._last_sent_frames = [msg.frame_start]  # only frame 0 is sent
        self._write(
            format_abc(
                "SEND",
                TO=msg.dest,
                FROM=msg.src,
                HEX=bytes(msg.frame[0]).hex(),
                BITRATE=BITRATE[rate],
                ACK="TRUE",
            )
        )

    def do_work(self) -> None:
        if not self._running or self.link is None:
            return
        if not self.link.is_open:
            self._configured = False
            return
        if not self._configured:
            self._configure()
        for line in self.modem_read():
            if not line.strip():
                continue
            self.emit_raw(True, line.strip())
            try:
                self._handle_line(line)
            except (ABCParseError, ValueError, KeyError) as exc:
                log.warning("ignoring bad ABC line %r: %s", line, exc)

    def _handle_line(self, line: str) -> None:
        key, fields = parse_abc(line)
        now = acomms_pb.now_us(self.clock.now())
        if key == "RECV":
            msg = acomms_pb.ModemTransmission(
                type=acomms_pb.DATA, src=int(fields["FROM"]), dest=int(fields["TO"]), time=now
            )
            msg.frame.append(bytes.fromhex(fields["HEX"]))
        elif key == "ACKN":
            msg = acomms_pb.ModemTransmission(
                type=acomms_pb.ACK, src=int(fields["FROM"]), dest=int(fields["TO"]), time=now
            )
            # goby3's ACK names no frame, which the queue cannot match (QUIRKS.md Q-ACOMMS-9)
            msg.acked_frame.extend(self._last_sent_frames)
        else:
            msg = acomms_pb.ModemTransmission(type=acomms_pb.DATA, time=now)
        self.signal_receive.emit(msg)
