"""ModemDriverBase: the interface every modem driver implements.

A driver is advanced by calling `do_work()` regularly (>= 5 Hz); it reads its link, runs its
timers against the Clock, and emits signals synchronously. Line-based drivers talk through a
`LineLink` (pygoby.util.linebased), built from the DriverConfig by `modem_start` or injected
(a MemoryLink makes the driver a pure sans-I/O state machine for tests and simulations).
"""

from __future__ import annotations

import datetime as dt
import logging
from abc import ABC, abstractmethod
from typing import IO

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.errors import ModemDriverError
from pygoby.util.clock import Clock, WallClock
from pygoby.util.errors import LinkClosedError
from pygoby.util.glog import DEBUG1, group_logger
from pygoby.util.linebased import LineLink, SerialLink, TCPClientLink, TCPServerLink
from pygoby.util.signal import Signal

log = logging.getLogger(__name__)

Status = acomms_pb.ModemDriverStatus


def driver_name(cfg: acomms_pb.DriverConfig) -> str:
    """`<DriverType name without DRIVER_>::<modem_id>` (or the plugin name)."""
    if cfg.WhichOneof("driver") == "driver_name":
        kind = cfg.driver_name
    else:
        kind = acomms_pb.DriverType.Name(cfg.driver_type).removeprefix("DRIVER_")
    return f"{kind}::{cfg.modem_id}"


class ModemDriverBase(ABC):
    """Abstract driver with goby's signals; line-based helpers for drivers that need them."""

    DEFAULT_SERIAL_BAUD: int | None = None
    DEFAULT_LINE_DELIMITER: str | None = None  # overrides DriverConfig's default when unset
    RATES: range | None = None  # the transmission rates the modem has (None: any number)

    def __init__(self, clock: Clock | None = None, link: LineLink | None = None) -> None:
        self.clock: Clock = clock if clock is not None else WallClock()
        self.signal_receive: Signal[acomms_pb.ModemTransmission] = Signal()
        self.signal_transmit_result: Signal[acomms_pb.ModemTransmission] = Signal()
        self.signal_data_request: Signal[acomms_pb.ModemTransmission] = Signal()
        self.signal_modify_transmission: Signal[acomms_pb.ModemTransmission] = Signal()
        self.signal_raw_incoming: Signal[acomms_pb.ModemRaw] = Signal()
        self.signal_raw_outgoing: Signal[acomms_pb.ModemRaw] = Signal()
        self.cfg = acomms_pb.DriverConfig()
        self.link: LineLink | None = link
        self._injected_link = link is not None
        self._raw_log: IO[str] | None = None
        self._traffic_logs: tuple[logging.Logger, ...] = (log, log)  # (out, in)
        self._traffic_logs_for: object = None  # the cfg the traffic loggers are named for

    # --- the interface -------------------------------------------------------------------
    @abstractmethod
    def startup(self, cfg: acomms_pb.DriverConfig) -> None: ...

    @abstractmethod
    def shutdown(self) -> None: ...

    @abstractmethod
    def do_work(self) -> None: ...

    @abstractmethod
    def handle_initiate_transmission(self, transmission: acomms_pb.ModemTransmission) -> None: ...

    def update_cfg(self, cfg: acomms_pb.DriverConfig) -> None:
        log.warning("%s: update_cfg is not implemented by this driver", type(self).__name__)

    def report(self):
        report = acomms_pb.ModemReport(
            modem_id=self.cfg.modem_id, time=acomms_pb.now_us(self.clock.now())
        )
        report.link_state = (
            acomms_pb.ModemReport.LINK_AVAILABLE
            if self.link is not None and self.link.is_open
            else acomms_pb.ModemReport.LINK_NOT_AVAILABLE
        )
        return report

    @property
    def modem_id(self) -> int:
        return self.cfg.modem_id

    # --- helpers for line-based modems ---------------------------------------------------
    def modem_start(self, cfg: acomms_pb.DriverConfig) -> None:
        """Validate the link settings, build (or reuse the injected) link and open it."""
        if not cfg.HasField("modem_id"):
            raise ModemDriverError("modem_id is required", Status.INVALID_CONFIGURATION)
        self.cfg = cfg
        delimiter = self.line_delimiter(cfg)
        if not self._injected_link:
            self.link = self._make_link(cfg, delimiter)
        if self.link is None:
            raise ModemDriverError("no link configured", Status.INVALID_CONFIGURATION)
        if cfg.HasField("raw_log"):
            stamp = dt.datetime.fromtimestamp(self.clock.now(), dt.UTC).strftime("%Y%m%dT%H%M%S")
            self._raw_log = open(cfg.raw_log.replace("%1%", stamp), "a", encoding="latin-1")  # noqa: SIM115
        self.link.open()

    def line_delimiter(self, cfg: acomms_pb.DriverConfig) -> str:
        if not cfg.HasField("line_delimiter") and self.DEFAULT_LINE_DELIMITER is not None:
            return self.DEFAULT_LINE_DELIMITER
        return cfg.line_delimiter

    def _make_link(self, cfg: acomms_pb.DriverConfig, delimiter: str) -> LineLink:
        C = acomms_pb.DriverConfig
        # an implicit connection_type is the documented default, SERIAL (QUIRKS.md Q-ACOMMS-1)
        kind = cfg.connection_type
        if kind == C.CONNECTION_SERIAL:
            if not cfg.HasField("serial_port"):
                raise ModemDriverError("serial_port is required", Status.INVALID_CONFIGURATION)
            baud = cfg.serial_baud if cfg.HasField("serial_baud") else self.DEFAULT_SERIAL_BAUD
            if baud is None:
                raise ModemDriverError("serial_baud is required", Status.INVALID_CONFIGURATION)
            return SerialLink(cfg.serial_port, baud, delimiter)
        if kind == C.CONNECTION_TCP_AS_CLIENT:
            if not (cfg.HasField("tcp_server") and cfg.HasField("tcp_port")):
                raise ModemDriverError(
                    "tcp_server and tcp_port are required", Status.INVALID_CONFIGURATION
                )
            return TCPClientLink(cfg.tcp_server, cfg.tcp_port, delimiter, cfg.reconnect_interval)
        if not cfg.HasField("tcp_port"):
            raise ModemDriverError("tcp_port is required", Status.INVALID_CONFIGURATION)
        # A modem (or serial-to-TCP box) elsewhere on the network connects to this server, so,
        # as upstream, every interface unless `tcp_server` names the address to bind.
        host = cfg.tcp_server if cfg.HasField("tcp_server") else "0.0.0.0"
        return TCPServerLink(cfg.tcp_port, host=host, delimiter=delimiter)

    def modem_read(self) -> list[str]:
        if self.link is None:
            return []
        lines = self.link.read_lines()
        if self._raw_log is not None:
            for line in lines:
                self._log_raw("[rx] ", line)
        return lines

    def modem_write(self, text: str) -> None:
        if self.link is None:
            raise ModemDriverError("no link", Status.CONNECTION_TO_MODEM_FAILED)
        try:
            self.link.write(text)
        except LinkClosedError as exc:
            raise ModemDriverError(str(exc), Status.CONNECTION_TO_MODEM_FAILED) from exc
        self._log_raw("[tx] ", text.rstrip("\r\n"))

    def modem_close(self) -> None:
        if self.link is not None:
            self.link.close()
        if self._raw_log is not None:
            self._raw_log.close()
            self._raw_log = None

    def _log_raw(self, prefix: str, line: str) -> None:
        if self._raw_log is not None:
            self._raw_log.write(prefix + line + "\n")
            self._raw_log.flush()

    def emit_raw(self, incoming: bool, raw: bytes | str, description: str = "") -> None:
        """Every driver reports its traffic here (its text edge): the raw signals, and the
        DEBUG1 log `<< line` (from the modem) / `>> line` (to the modem) in the groups
        `goby::acomms::modemdriver::in::<driver name>` / `...::out::<driver name>`."""
        traffic = self._traffic_log(incoming)
        if traffic.isEnabledFor(DEBUG1):
            traffic.log(DEBUG1, "%s %s", "<<" if incoming else ">>", _printable(raw))
        signal = self.signal_raw_incoming if incoming else self.signal_raw_outgoing
        if not signal:
            return  # nobody listens: skip building a ModemRaw for every line
        data = raw.encode("latin-1") if isinstance(raw, str) else raw
        msg = acomms_pb.ModemRaw(raw=data)
        if description:
            msg.description = description
        signal.emit(msg)

    def _traffic_log(self, incoming: bool) -> logging.Logger:
        if self._traffic_logs_for is not self.cfg:  # a new configuration: maybe a new name
            name = driver_name(self.cfg)
            self._traffic_logs = tuple(
                group_logger(f"goby::acomms::modemdriver::{way}::{name}") for way in ("out", "in")
            )
            self._traffic_logs_for = self.cfg
        return self._traffic_logs[incoming]


def _printable(raw: bytes | str) -> str:
    """Text as it is; binary (UDP datagrams, RUDICS packets) as its size and hex."""
    if isinstance(raw, str):
        return raw
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError:
        text = ""
    if text.isprintable() and text:
        return text
    return f"<{len(raw)} B> {raw[:64].hex()}{'...' if len(raw) > 64 else ''}"


class NoDriver(ModemDriverBase):
    """DRIVER_NONE: accepts transmissions and does nothing."""

    def startup(self, cfg: acomms_pb.DriverConfig) -> None:
        self.cfg = cfg

    def shutdown(self) -> None:
        pass

    def do_work(self) -> None:
        pass

    def handle_initiate_transmission(self, transmission: acomms_pb.ModemTransmission) -> None:
        log.debug("DRIVER_NONE: ignoring transmission request")
