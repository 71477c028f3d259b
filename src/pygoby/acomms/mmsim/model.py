"""A sans-I/O model of a WHOI Micro-Modem's NMEA behaviour (what the host sees).

Feed host sentences with `handle_line`; read the modem's sentences from `take_output()` (or get
them through `on_output`). Acoustic traffic goes through a `Channel`; packets heard from it arrive
in `receive`. The model answers the sentences the pygoby driver (and pyacomms) use: CFG/CFQ,
MSC→REV, CLK/TMS/TMQ, CYC/DRQ/TXD (local and polled), RXD/MSG/CST/XST, ACK, MPC/MPR/MPA,
MUC/MUA. Anything else gets `$CAERR,…,NMEA,…`. Rates, frame counts and sizes follow §7.6.
"""

from __future__ import annotations

import datetime as dt
import functools
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem.rates import RATE_FRAME_BYTES, RATE_NUM_FRAMES
from pygoby.acomms.drivers.micromodem.statistics import cst_head_fields, cst_tail, format_xst
from pygoby.acomms.mmsim.channel import AcousticPacket, Channel, PacketKind, Reception
from pygoby.util.clock import Clock
from pygoby.util.errors import NMEAError
from pygoby.util.nmea import NMEASentence, checksum, printed

log = logging.getLogger(__name__)

DEFAULT_NVRAM = {
    "AGC": 0, "AGN": 250, "ASD": 0, "BND": 3, "BR1": 3, "CST": 1, "CTO": 10, "DBG": 0,
    "DQF": 0, "DTH": 108, "DTO": 2, "ECD": 50, "MFD": 1, "NRV": 150, "PCM": 0, "POW": -100,
    "PTH": 180, "REV": 1, "RXA": 0, "RXD": 1, "RXP": 1, "SRC": 1, "TAT": 50, "TOA": 0,
    "XST": 1,
}  # fmt: skip


@dataclass
class _Transmit:
    src: int
    dest: int
    rate: int
    ack: bool
    num_frames: int
    frames: list[bytes] = field(default_factory=list)


class MicroModemModel:
    def __init__(
        self,
        modem_id: int,
        clock: Clock,
        channel: Channel | None = None,
        *,
        name: str | None = None,
        firmware: str = "0.94.0.00",
        on_output: Callable[[str], None] | None = None,
    ) -> None:
        self.clock = clock
        self.name = name or f"modem{modem_id}"
        self.firmware = firmware
        self.nvram = dict(DEFAULT_NVRAM, SRC=modem_id)
        self.on_output = on_output
        self._outbox: list[str] = []
        self._clock_offset = 0.0
        self._tx: _Transmit | None = None
        self.channel = channel
        if channel is not None:
            channel.attach(self)

    @property
    def modem_id(self) -> int:
        return self.nvram["SRC"]

    def modem_time(self) -> float:
        return self.clock.now() + self._clock_offset

    # ------------------------------------------------------------------ output
    def _say(self, token: str, *values: object) -> None:
        self._output(_sentence_line(token, *values))

    def _say_sentence(self, sentence: NMEASentence) -> None:
        self._output(printed(sentence) + "\r\n")

    def _output(self, line: str) -> None:
        if self.on_output is not None:
            self.on_output(line)
        else:
            self._outbox.append(line)

    def take_output(self) -> list[str]:
        out, self._outbox = self._outbox, []
        return out

    def _hhmmss(self) -> str:
        t = dt.datetime.fromtimestamp(self.modem_time(), dt.UTC)
        return f"{t.hour:02d}{t.minute:02d}{t.second:02d}"  # %H%M%S, faster than strftime

    def _error(self, module: str, code: int, text: str) -> None:
        self._say("$CAERR", self._hhmmss(), module, code, text)

    # ------------------------------------------------------------------ host sentences
    def handle_line(self, line: str) -> None:
        if not line.strip():
            return
        try:
            s = NMEASentence.parse(line)
        except NMEAError as exc:
            log.warning("%s: bad sentence from host: %s", self.name, exc)
            self._error("NMEA", 1, "Bad NMEA sentence")
            return
        handler = getattr(self, "_cmd_" + s.sentence_id.lower(), None)
        if handler is None or s.talker_id != "CC":
            self._error("NMEA", 2, "Unknown command")
            return
        try:
            handler(s)
        except (NMEAError, ValueError, IndexError) as exc:
            log.warning("%s: cannot handle %s: %s", self.name, s.message(), exc)
            self._error("NMEA", 3, "Bad field")

    def _cmd_cfg(self, s: NMEASentence) -> None:
        key, value = s[1], s[2]
        if key == "ALL" and value == "0":
            self.nvram = dict(DEFAULT_NVRAM, SRC=self.modem_id)
        else:
            self.nvram[key] = int(value)
        self._say("$CACFG", key, value)

    def _cmd_cfq(self, s: NMEASentence) -> None:
        if s[1] in ("ALL", "TOP"):
            for key, value in sorted(self.nvram.items()):
                self._say("$CACFG", key, value)
        elif s[1] in self.nvram:
            self._say("$CACFG", s[1], self.nvram[s[1]])
        else:
            self._error("CFQ", 4, "Unknown parameter")

    def _cmd_msc(self, s: NMEASentence) -> None:
        if self.nvram.get("REV", 1):
            self._say("$CAREV", self._hhmmss(), "AUV", self.firmware)
        self._say("$CAMSC", s[1], s[2], s[3])

    def _cmd_clk(self, s: NMEASentence) -> None:
        given = dt.datetime(*s.as_ints(1, 7), tzinfo=dt.UTC).timestamp()
        self._clock_offset = given - math.ceil(self.clock.now())
        t = dt.datetime.fromtimestamp(self.modem_time(), dt.UTC)
        self._say("$CACLK", t.year, t.month, t.day, t.hour, t.minute, t.second)

    def _cmd_tms(self, s: NMEASentence) -> None:
        given = dt.datetime.fromisoformat(s[1].replace("Z", "+00:00")).timestamp()
        self._clock_offset = given - math.ceil(self.clock.now())
        self._say("$CATMS", 0, self._iso_now())

    def _cmd_tmq(self, s: NMEASentence) -> None:
        self._say("$CATMQ", self._iso_now(), 0)

    def _iso_now(self) -> str:
        t = dt.datetime.fromtimestamp(self.modem_time(), dt.UTC)
        return f"{t:%Y-%m-%dT%H:%M:%S}.{t.microsecond // 100000}Z"

    def _cmd_cyc(self, s: NMEASentence) -> None:
        adr1, adr2, rate, ack, nframes = s.as_ints(2, 7)
        if not 0 <= rate <= 5:
            self._error("CYC", 5, "Bad rate")
            return
        nframes = max(1, min(nframes, RATE_NUM_FRAMES[rate]))
        self._say("$CACYC", 0, adr1, adr2, rate, ack, nframes)
        if adr1 == self.modem_id:
            self._start_transmit(_Transmit(adr1, adr2, rate, bool(ack), nframes))
        else:  # third-party cycle-init: an acoustic poll
            self._transmitted(rate, adr1, adr2, bool(ack), 0, 0)
            self._send(
                AcousticPacket(PacketKind.CYCLE, adr1, adr2, rate, bool(ack), num_frames=nframes)
            )

    def _start_transmit(self, tx: _Transmit) -> None:
        self._tx = tx
        if tx.rate == 0:  # the FSK cycle-init goes out as its own packet
            self._transmitted(0, tx.src, tx.dest, tx.ack, 0, 0)
        self._request_frame()

    def _request_frame(self) -> None:
        tx = self._tx
        assert tx is not None
        self._say(
            "$CADRQ", self._hhmmss(), tx.src, tx.dest, int(tx.ack), RATE_FRAME_BYTES[tx.rate],
            len(tx.frames) + 1,
        )  # fmt: skip

    def _cmd_txd(self, s: NMEASentence) -> None:
        tx = self._tx
        if tx is None:
            self._error("TXD", 6, "No data requested")
            return
        data = bytes.fromhex(s[4]) if len(s) > 4 else b""
        self._say("$CATXD", s[1], s[2], s[3], s[4] if len(s) > 4 else "")
        if data:
            tx.frames.append(data[: RATE_FRAME_BYTES[tx.rate]])
        if data and len(tx.frames) < tx.num_frames:
            self._request_frame()
            return
        self._tx = None
        nbytes = sum(len(f) for f in tx.frames)
        self._transmitted(tx.rate, tx.src, tx.dest, tx.ack, len(tx.frames), nbytes)
        if tx.frames:
            self._send(AcousticPacket(PacketKind.DATA, tx.src, tx.dest, tx.rate, tx.ack, tx.frames))

    def _transmitted(self, rate, src, dest, ack, frames, nbytes) -> None:
        self._say("$CATXP", nbytes)
        self._say("$CATXF", nbytes)
        self._say_sentence(format_xst(self.modem_time(), rate, src, dest, ack, frames, nbytes))

    def _cmd_mpc(self, s: NMEASentence) -> None:
        src, dest = s.as_int(1), s.as_int(2)
        self._say("$CAMPC", src, dest)
        self._send(AcousticPacket(PacketKind.PING, src, dest))

    def _cmd_muc(self, s: NMEASentence) -> None:
        src, dest, data = s.as_int(1), s.as_int(2), bytes.fromhex(s[3])
        if len(data) != 2 or data[0] & 0xE0:
            self._error("MUC", 7, "Mini-packet data must be 13 bits")
            return
        self._say("$CAMUC", src, dest, s[3])
        self._send(AcousticPacket(PacketKind.MINI, src, dest, frames=[data]))

    def _send(self, packet: AcousticPacket) -> None:
        packet.tx_time = self.clock.now()
        if self.channel is not None:
            self.channel.transmit(self, packet)

    # ------------------------------------------------------------------ acoustic receptions
    def receive(self, packet: AcousticPacket, reception: Reception) -> None:
        # (`_value_`: the enum member's value without the `value` property's Python call)
        handler = getattr(self, "_heard_" + packet.kind._value_)
        handler(packet, reception)

    def _heard_data(self, p: AcousticPacket, r: Reception) -> None:
        self._say("$CARXP", 0)
        self._say("$CACYC", 0, p.src, p.dest, p.rate, int(p.ack_requested), len(p.frames))
        if p.rate == 0:
            self._cst(p, r, frames=0, bad=0)
        good: list[int] = []
        for i, frame in enumerate(p.frames):
            if r.frame_good(i):
                self._say("$CARXD", p.src, p.dest, int(p.ack_requested), i + 1, frame.hex())
                good.append(i + 1)
            else:
                self._say("$CAMSG", "BAD_CRC", i + 1)
        self._cst(p, r, frames=len(p.frames), bad=len(p.frames) - len(good))
        if p.ack_requested and p.dest == self.modem_id and p.dest != 0 and good:
            self._send(
                AcousticPacket(PacketKind.ACK, self.modem_id, p.src, p.rate, acked_frames=good)
            )

    def _heard_cycle(self, p: AcousticPacket, r: Reception) -> None:
        self._say("$CARXP", 0)
        self._say("$CACYC", 0, p.src, p.dest, p.rate, int(p.ack_requested), p.num_frames)
        self._cst(p, r, frames=0, bad=0)
        if p.src == self.modem_id and self._tx is None:
            self._start_transmit(_Transmit(p.src, p.dest, p.rate, p.ack_requested, p.num_frames))

    def _heard_ack(self, p: AcousticPacket, r: Reception) -> None:
        if p.dest != self.modem_id:
            return
        for frame_no in p.acked_frames:
            self._say("$CAACK", p.src, p.dest, frame_no, 1)
        self._cst(p, r, frames=0, bad=0)

    def _heard_ping(self, p: AcousticPacket, r: Reception) -> None:
        if p.dest != self.modem_id:
            return
        self._say("$CAMPA", p.src, p.dest)
        self._send(AcousticPacket(PacketKind.PING_REPLY, self.modem_id, p.src))

    def _heard_ping_reply(self, p: AcousticPacket, r: Reception) -> None:
        if p.dest == self.modem_id:
            self._say("$CAMPR", p.src, p.dest, f"{r.travel_time:.4f}")

    def _heard_mini(self, p: AcousticPacket, r: Reception) -> None:
        self._say("$CAMUA", p.src, p.dest, p.frames[0].hex().upper())

    def _cst(self, p: AcousticPacket, r: Reception, frames: int, bad: int) -> None:
        if not self.nvram.get("CST", 1):
            return
        # Everything after the time of arrival is the same for every packet of a link (the
        # same statistics): that text and its checksum are made once.
        key = (p.rate, p.src, p.dest, frames, bad, *r.stats.items())
        tail = _cst_tails.get(key) or self._cst_tail(key, p, r, frames, bad)
        head = cst_head_fields(1 if bad else 0, acomms_pb.now_us(r.arrival_time + self._clock_offset))
        self._output(printed(NMEASentence.of_parts(head, *tail)) + "\r\n")

    def _cst_tail(
        self, key: tuple, p: AcousticPacket, r: Reception, frames: int, bad: int
    ) -> tuple[tuple[str, ...], str, int]:
        """The $CACST fields after the time of arrival, their text and its checksum."""
        values = dict(
            clock_mode=0, mfd_peak=1000, mfd_power=20, mfd_ratio=150, spl=150, shf_agn=250,
            shf_ainpshift=0, shf_ainshift=0, shf_mfdshift=0, shf_p2bshift=0, rate=p.rate,
            source=p.src, dest=p.dest, psk_error_code=3 if bad else 0,
            packet_type=1 if p.rate == 0 else 3, number_frames=frames, number_bad_frames=bad,
            snr_rss=100, snr_in=15, snr_out=15, snr_symbols=20, mse_equalizer=-15,
            data_quality_factor=200, doppler=0.0, stddev_noise=50, carrier_freq=25000,
            bandwidth=5000,
        )  # fmt: skip
        known = True
        for name, value in r.stats.items():
            if name not in _STATISTICS:
                log.warning("%s: unknown $CACST statistic %r from the channel", self.name, name)
                known = False  # (not remembered: warned about every time)
            elif name in _DECIMAL_STATISTICS:
                values[name] = float(value)
            else:  # (an int is already what int(round()) would make of it)
                values[name] = value if type(value) is int else int(round(value))
        text = cst_tail(values)
        tail = (tuple(text.split(",")), text, checksum(text))
        if known:
            if len(_cst_tails) >= _CST_TAILS_LIMIT:
                _cst_tails.clear()
            _cst_tails[key] = tail
        return tail


# $CACST fields after the time of arrival, with their text and its checksum, by link and
# statistics
_cst_tails: dict[tuple, tuple[tuple[str, ...], str, int]] = {}
_CST_TAILS_LIMIT = 4096


# Many of the modem's sentences recur verbatim ($CARXP,0, $CACYC for each source, $CACFG
# answers to keep-alives): their text is built once. `typed`: 1, 1.0 and True print differently.
@functools.lru_cache(maxsize=1024, typed=True)
def _sentence_line(token: str, *values: object) -> str:
    return printed(NMEASentence.build(token, values)) + "\r\n"


_STATISTICS = acomms_pb.ReceiveStatistics.DESCRIPTOR.fields_by_name
_DECIMAL_STATISTICS = {
    name for name, f in _STATISTICS.items() if f.cpp_type == f.CPPTYPE_DOUBLE
}  # fmt: skip
