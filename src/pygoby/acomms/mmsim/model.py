"""A sans-I/O model of a WHOI Micro-Modem: its NMEA interface and its timing (what a host sees).

Feed host sentences with `handle_sentence` (or text with `handle_line`); the modem's sentences go
to `on_output` (or wait in `take_output()`). Acoustic traffic goes through a `ModemChannel`; packets
heard from it arrive in `detect` (start of the signal: `$CARXP`) and `receive` (end of the
signal: `$CACYC`, `$CARXD`, `$CACST`, ...). Everything that takes time is put on a `Timeline`:
whoever runs the model calls `do_work()` (or runs the shared timeline) and, in a discrete-event
simulation, moves the clock to `next_event_time()`.

Timing (pygoby.acomms.mmsim.timing, with the confidence of each figure): a transmission is on the
water for its rate's time and frame count (`$CATXP` at its start, `$CATXF` and `$CAXST` at its
end); a rate-0 cycle goes out as two packets, the FSK cycle-init mini-packet and then the data the
modem asks for with `$CADRQ` once the cycle-init is sent; a PSK packet carries its cycle-init in
its header. A new transmission waits until the current one has left the transducer. A ping reply
leaves TAT (NVRAM) after the ping has been heard; `$CAMPR` reports the one-way travel time from
the measured round trip. `$CATMQ` comes 0.5 s after `$CCTMQ`; a clock set ($CCCLK, $CCTMS mode 0)
takes effect, and is answered, at the modem's next whole second.

Commands answered (those goby3's driver sends, and WHOI's pyacomms): CFG/CFQ (NVRAM: the real
modem's keys only), MSC, CLK/CLQ, TMS/TMQ/ALQ (Micro-Modem 2), CYC/TXD (local and third-party
cycles), MPC, MUC, TDP (FDP, Micro-Modem 2), MEC, PDT/PNT/PGT (navigation pings: there are no
transponders, so $SNTTA reports no travel times at the timeout), SWP/MSQ/RSP (signals). Anything
else gets `$CAERR,<time>,NMEA,2,...`; a bad field `$CAERR,<time>,NMEA,3,...` (the emulator's
wording: the real modem's error texts are not documented here).
"""

from __future__ import annotations

import base64
import datetime as dt
import functools
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem.statistics import (
    CST_FIELD_INDEX,
    DOPPLER_INDEX,
    CycleStatistics,
    format_xst,
)
from pygoby.acomms.mmsim.channel import (
    AcousticPacket,
    ModemChannel,
    ModemPacketKind,
    ModemReception,
)
from pygoby.acomms.mmsim.timing import DEFAULT_TIMING, FDP_RATES, ModemTiming
from pygoby.util.clock import Clock
from pygoby.util.errors import NMEAError
from pygoby.util.nmea import NMEASentence
from pygoby.util.timeline import Timeline

log = logging.getLogger(__name__)

DEFAULT_FIRMWARE = "2.0.40000"  # a Micro-Modem 2 (firmware 2.0) without the old firmware quirks
NMEA_API_LEVEL = 11  # what pyacomms assumes for a Micro-Modem 2 (time queries need 11)
APPLICATION_NAME = "pygoby-mmsim"
MAX_ADDRESS = 127
INT32 = (-(2**31), 2**31 - 1)
# clock settings the emulator accepts: up to year 9998, since a MOOSTimeWarp clock (MOOS time =
# epoch x warp) is centuries ahead (year 3108 at warp 20) and iModemSim's host sets it; 9999 is
# refused so that the modem's time plus any offset stays a date
YEARS = (1970, 9998)
TMS_EXTPPS_TIMEOUT = 3.0  # s: $CCTMS mode 1 waits for an external PPS edge (pyacomms: "up to 3 s")
CST_VERSION_MM2 = 6  # $CACST / $CAXST with a version field and dated times (Micro-Modem 2)

# NVRAM keys of the Micro-Modem Software Interface Guide (the list goby3 carries, v3.04), with
# their defaults where the guide's descriptions give them (CRL, CST, CTO, DBG, DGM, ...) or the
# pygoby emulator's choice otherwise (placeholders, not values read from a modem).
LEGACY_NVRAM = {
    "AGC": 0,
    "AGN": 250,
    "ASD": 0,
    "BBD": 0,
    "BND": 3,
    "BR1": 3,
    "BR2": 3,
    "BRN": 0,
    "BSP": 1,
    "BW0": 4000,
    "CPR": 1,
    "CRL": 50,
    "CST": 1,
    "CTO": 10,
    "DBG": 0,
    "DGM": 0,
    "DOP": 0,
    "DQF": 0,
    "DTH": 108,
    "DTO": 2,
    "DTP": 90,
    "ECD": 50,
    "EFB": 10,
    "EFF": 20,
    "FC0": 25000,
    "FMD": 0,
    "FML": 200,
    "GPS": 0,
    "HFC": 0,
    "IRE": 0,
    "MCM": 0,
    "MFC": 0,
    "MFD": 1,
    "MOD": 0,
    "MPR": 0,
    "MSE": 0,
    "MVM": 0,
    "NDT": 150,
    "NPT": 50,
    "NRL": 25,
    "NRV": 150,
    "PAD": 2,
    "PCM": 0,
    "POW": -100,
    "PRL": 50,
    "PTH": 180,
    "PTO": 6,
    "REV": 1,
    "RXA": 0,
    "RXD": 1,
    "RXP": 1,
    "SCG": 0,
    "SGP": 0,
    "SHF": 0,
    "SNR": 0,
    "SNV": 0,
    "SRC": 1,
    "TAT": 50,
    "TOA": 0,
    "TXD": 400,
    "TXF": 1,
    "TXP": 1,
    "XST": 1,
}
# Micro-Modem 2 dotted keys known from goby3 and pyacomms (info.* are read-only)
MM2_NVRAM: dict[str, int | str] = {
    "psk.packet.mod_hdr_version": 1,
    "recv.base64data": 0,
    "uart1.bitrate": 19200,
}
READ_ONLY = ("info.firmware_version",)


def firmware_major(firmware: str) -> int:
    """`a.b.c[.d]` -> a (ValueError if it is not such a version)."""
    parts = firmware.split(".")
    if len(parts) not in (3, 4) or not all(p.isdigit() for p in parts):
        raise ValueError(f"firmware version must be a.b.c or a.b.c.d, not {firmware!r}")
    return int(parts[0])


@dataclass
class _Transmit:
    src: int
    dest: int
    rate: int
    ack: bool
    num_frames: int
    frames: list[bytes] = field(default_factory=list)
    requested: int = 0  # frame number of the outstanding $CADRQ (0: none)


class MicroModemModel:
    def __init__(
        self,
        modem_id: int,
        clock: Clock,
        channel: ModemChannel | None = None,
        *,
        name: str | None = None,
        firmware: str = DEFAULT_FIRMWARE,
        timing: ModemTiming = DEFAULT_TIMING,
        timeline: Timeline | None = None,
        on_output: Callable[[object], None] | None = None,
    ) -> None:
        self.clock = clock
        self.timeline = timeline if timeline is not None else Timeline(clock)
        self.name = name or f"modem{modem_id}"
        self.firmware = firmware
        self.mm2 = firmware_major(firmware) >= 2
        self.timing = timing
        self.statistics_version = CST_VERSION_MM2 if self.mm2 else 0
        self.nvram = self._factory_nvram(modem_id)
        self._outbox: list = []
        self.on_output = on_output
        self._clock_offset = 0.0
        self._clock_source = "RTC"  # the modem's own clock until the host sets it
        self._tx: _Transmit | None = None
        self._air_free_at = -math.inf  # the transducer is busy until then
        self._line_done = -math.inf  # host sentences have crossed the serial line by then
        self._pings: dict[int, float] = {}  # start of our last ping to each modem
        self._lines: dict[int, int] = {}  # hardware control lines
        self.channel = channel
        if channel is not None:
            channel.attach(self)

    def _factory_nvram(self, modem_id: int) -> dict[str, int | str]:
        nvram: dict[str, int | str] = dict(LEGACY_NVRAM, SRC=modem_id)
        if self.mm2:
            nvram.update(MM2_NVRAM)
            nvram["info.firmware_version"] = self.firmware
        return nvram

    @property
    def modem_id(self) -> int:
        return int(self.nvram["SRC"])

    def modem_time(self) -> float:
        return self.clock.now() + self._clock_offset

    def do_work(self) -> None:
        self.timeline.run_due()

    def next_event_time(self) -> float | None:
        return self.timeline.next_time()

    # ------------------------------------------------------------------ output
    def _say(self, token: str, *values: object) -> None:
        self._emit(NMEASentence.build(token, values))

    @property
    def on_output(self) -> Callable[[object], None] | None:
        """Called with each sentence the modem says (None: they wait in `take_output`)."""
        return self._on_output

    @on_output.setter
    def on_output(self, on_output: Callable[[object], None] | None) -> None:
        self._on_output = on_output
        # (every sentence goes through _emit: one call, straight to where it goes)
        self._emit = on_output if on_output is not None else self._outbox.append

    def take_output(self) -> list:
        """The sentences said since the last call (when there is no `on_output`)."""
        out = self._outbox[:]
        self._outbox.clear()
        return out

    def _hhmmss(self) -> str:
        t = dt.datetime.fromtimestamp(self.modem_time(), dt.UTC)
        return f"{t:%H%M%S}"

    def _iso(self, modem_time: float) -> str:
        t = dt.datetime.fromtimestamp(modem_time, dt.UTC)
        return f"{t:%Y-%m-%dT%H:%M:%S}.{t.microsecond // 100000}Z"

    def _serial_time(self, sentence: NMEASentence) -> float:
        """Seconds a sentence takes on the modem's serial line (start, 8 data, stop bit per
        character; with its checksum and CR LF)."""
        baud = self.timing.baud
        return (len(",".join(sentence.fields)) + 5) * 10 / baud if baud else 0.0

    def _error(self, module: str, code: int, text: str) -> None:
        self._say("$CAERR", self._hhmmss(), module, code, text)

    def _on(self, key: str) -> bool:
        return bool(self.nvram.get(key, 0))

    # ------------------------------------------------------------------ host sentences
    def handle_line(self, line: str) -> None:
        text = line.strip()
        if not text:
            return
        try:
            sentence = NMEASentence.parse(text)
        except NMEAError as exc:
            log.warning("%s: bad sentence from host: %s", self.name, exc)
            self._error("NMEA", 1, "Bad NMEA sentence")
            return
        self.handle_sentence(sentence)

    def handle_sentence(self, s: NMEASentence) -> None:
        sentence_id = s.sentence_id
        command = COMMAND_HANDLERS.get(sentence_id) if s.talker_id == "CC" else None
        if command is None or (sentence_id in _MM2_COMMANDS and not self.mm2):
            self._error("NMEA", 2, f"Unknown command {s.fields[0][1:]}")
            return
        # (the sentence has crossed the serial line when the modem acts on it)
        self._line_done = max(self.clock.now(), self._line_done) + self._serial_time(s)
        try:
            command(self, s)
        except (NMEAError, ValueError, IndexError) as exc:
            log.warning("%s: cannot handle %s: %s", self.name, s.message(), exc)
            self._error("NMEA", 3, "Bad field")

    def _cmd_cfg(self, s: NMEASentence) -> None:
        key = self._nvram_key(s[1])
        if key == "ALL" and s[2] == "0":
            self.nvram = self._factory_nvram(self.modem_id)
            self._say("$CACFG", "ALL", 0)
            return
        if key not in self.nvram or key in READ_ONLY:
            self._error("NMEA", 4, f"Unknown or read-only parameter {s[1]}")
            return
        low, high = (0, MAX_ADDRESS) if key == "SRC" else INT32
        value = s.as_int(2, low, high)
        self.nvram[key] = value
        self._say("$CACFG", key, value)

    def _cmd_cfq(self, s: NMEASentence) -> None:
        query = self._nvram_key(s[1])
        if query in ("ALL", "TOP"):
            keys = sorted(self.nvram)
        elif query in self.nvram:
            keys = [query]
        else:
            keys = sorted(k for k in self.nvram if k.startswith(query + "."))
        if not keys:
            self._error("NMEA", 4, f"Unknown parameter {s[1]}")
        for key in keys:
            self._say("$CACFG", key, self.nvram[key])

    @staticmethod
    def _nvram_key(text: str) -> str:
        return text.upper() if len(text) == 3 else text  # (the three-letter keys in any case)

    def _cmd_msc(self, s: NMEASentence) -> None:
        if self._on("REV"):
            self._say("$CAREV", self._hhmmss(), "AUV", self.firmware)
        self._say("$CAMSC", *s.fields[1:])

    def _cmd_clk(self, s: NMEASentence) -> None:
        year, month, day, hour, minute, second = (
            s.as_int(1, *YEARS),
            s.as_int(2, 1, 12),
            s.as_int(3, 1, 31),
            s.as_int(4, 0, 23),
            s.as_int(5, 0, 59),
            s.as_int(6, 0, 59),
        )
        given = dt.datetime(year, month, day, hour, minute, second, tzinfo=dt.UTC).timestamp()
        self._set_clock_at_next_second(given, self._reply_clk)

    def _reply_clk(self) -> None:
        t = dt.datetime.fromtimestamp(self.modem_time(), dt.UTC)
        self._say("$CACLK", t.year, t.month, t.day, t.hour, t.minute, t.second)

    def _cmd_clq(self, s: NMEASentence) -> None:
        t = dt.datetime.fromtimestamp(self.modem_time(), dt.UTC)
        self._say("$CACLQ", t.year, t.month, t.day, t.hour, t.minute, t.second)

    def _cmd_tms(self, s: NMEASentence) -> None:
        given = _iso_time(s[1])
        if s.as_int(2, 0, 1) == 1:  # at an external PPS edge: there is none here
            self.timeline.at(self.clock.now() + TMS_EXTPPS_TIMEOUT, self._reply_tms, 1)
            return
        self._set_clock_at_next_second(given, self._reply_tms, 0)

    def _reply_tms(self, timed_out: int) -> None:
        self._say("$CATMS", timed_out, self._iso(self.modem_time()))

    def _set_clock_at_next_second(self, given: float, reply: Callable, *args: object) -> None:
        """The modem's clock becomes `given` at its next whole second; `reply` then."""
        edge = self.clock.now() + (math.floor(self.modem_time()) + 1 - self.modem_time())

        def apply() -> None:
            self._clock_offset = given - edge
            self._clock_source = "USER"
            reply(*args)

        self.timeline.at(edge, apply)

    def _cmd_tmq(self, s: NMEASentence) -> None:
        asked = self.modem_time()
        self.timeline.at(
            self.clock.now() + self.timing.tmq_reply,
            self._say,
            "$CATMQ",
            self._iso(asked),
            self._clock_source,
            "RTC",
        )

    def _cmd_alq(self, s: NMEASentence) -> None:
        self._say("$CAALQ", APPLICATION_NAME, NMEA_API_LEVEL)

    # ------------------------------------------------------------------ transmissions
    def _cmd_cyc(self, s: NMEASentence) -> None:
        adr1, adr2 = s.as_int(2, 0, MAX_ADDRESS), s.as_int(3, 0, MAX_ADDRESS)
        rate, ack, nframes = s.as_int(4), s.as_int(5, 0, 1), s.as_int(6, 0, 255)
        if rate not in self.timing.rates:
            self._error("CYC", 5, "Bad rate")
            return
        nframes = max(1, min(nframes, self.timing.rates[rate].frames))
        self._say("$CACYC", 0, adr1, adr2, rate, ack, nframes)
        if adr1 == self.modem_id:
            self._start_transmit(_Transmit(adr1, adr2, rate, bool(ack), nframes))
        else:  # a third-party cycle-init: an acoustic poll asking adr1 to send
            cycle = AcousticPacket(
                ModemPacketKind.CYCLE, adr1, adr2, rate, bool(ack), num_frames=nframes
            )
            self._send(cycle, self.timing.mini_packet, at=self._line_done)

    def _start_transmit(self, tx: _Transmit) -> None:
        self._tx = tx
        if tx.rate == 0:  # the FSK cycle-init goes first, on its own; then the data is asked for
            cycle = AcousticPacket(
                ModemPacketKind.CYCLE, tx.src, tx.dest, 0, tx.ack, num_frames=tx.num_frames
            )
            # (polled acoustically before the host said anything, the line has no time yet: now)
            start = max(self._line_done, self.clock.now())
            self._send(cycle, self.timing.mini_packet, lambda: self._request_frame(tx), start)
        else:
            self._request_frame(tx)

    def _request_frame(self, tx: _Transmit) -> None:
        if self._tx is not tx:
            return  # a newer cycle replaced it
        tx.requested = len(tx.frames) + 1
        nbytes = self.timing.rates[tx.rate].frame_bytes
        drq = NMEASentence.build(
            "$CADRQ", (self._hhmmss(), tx.src, tx.dest, int(tx.ack), nbytes, tx.requested)
        )
        self._emit(drq)
        self._line_done = max(self.clock.now(), self._line_done) + self._serial_time(drq)
        timeout = self.clock.now() + max(1, int(self.nvram["DTO"]))
        self.timeline.at(timeout, self._data_timeout, tx, tx.requested)

    def _data_timeout(self, tx: _Transmit, frame_no: int) -> None:
        if self._tx is tx and tx.requested == frame_no:
            self._error("DATA_TIMEOUT", frame_no, "No data from the host")
            self._finish_transmit(tx)

    def _cmd_txd(self, s: NMEASentence) -> None:
        tx = self._tx
        if tx is None or not tx.requested:
            self._error("TXD", 6, "No data requested")
            return
        hex_data = s[4] if len(s) > 4 else ""
        data = bytes.fromhex(hex_data)
        self._say("$CATXD", s[1], s[2], s[3], hex_data)
        if data:
            tx.frames.append(data[: self.timing.rates[tx.rate].frame_bytes])
        # An empty $CCTXD ends the requests: the packet goes out with the frames given so far.
        # goby3's driver relies on this (it asks for the rate's every frame and answers the first
        # request it has nothing for with an empty $CCTXD), and a modem that kept asking would
        # instead hit DATA_TIMEOUT on every such packet (QUIRKS.md Q-ACOMMS-16).
        if data and len(tx.frames) < tx.num_frames:
            self._request_frame(tx)
        else:
            self._finish_transmit(tx)

    def _finish_transmit(self, tx: _Transmit) -> None:
        self._tx = None
        tx.requested = 0
        if tx.frames:  # (nothing to send: nothing goes out)
            packet = AcousticPacket(
                ModemPacketKind.DATA, tx.src, tx.dest, tx.rate, tx.ack, tx.frames
            )
            self._send(packet, self.timing.data(tx.rate, len(tx.frames)), at=self._line_done)

    def _cmd_mpc(self, s: NMEASentence) -> None:
        src, dest = s.as_int(1, 0, MAX_ADDRESS), s.as_int(2, 0, MAX_ADDRESS)
        self._say("$CAMPC", src, dest)
        ping = AcousticPacket(ModemPacketKind.PING, src, dest)
        self._send(ping, self.timing.ping, at=self._line_done)
        self._pings[dest] = ping.tx_time

    def _cmd_muc(self, s: NMEASentence) -> None:
        src, dest, data = (
            s.as_int(1, 0, MAX_ADDRESS),
            s.as_int(2, 0, MAX_ADDRESS),
            bytes.fromhex(s[3]),
        )
        if len(data) != 2 or data[0] & 0xE0:
            self._error("MUC", 7, "Mini-packet data must be 13 bits")
            return
        self._say("$CAMUC", src, dest, s[3])
        mini = AcousticPacket(ModemPacketKind.MINI, src, dest, frames=[data])
        self._send(mini, self.timing.mini_packet, at=self._line_done)

    def _cmd_tdp(self, s: NMEASentence) -> None:
        dest, rate = s.as_int(1, 0, MAX_ADDRESS), s.as_int(2)
        ack = _c_int(s[3])  # (pyacomms prints Python's False and True here: atoi gives 0)
        data = bytes.fromhex(s[5])
        if rate not in FDP_RATES or not data or len(data) > self.timing.rates[rate].max_bytes:
            self._error("TDP", 8, "Bad rate or data size for the flexible data protocol")
            return
        self._say("$CATDP", *s.fields[1:])
        size = self.timing.rates[rate].frame_bytes  # (the payload goes in its rate's frames)
        frames = [data[i : i + size] for i in range(0, len(data), size)]
        packet = AcousticPacket(ModemPacketKind.FDP, self.modem_id, dest, rate, bool(ack), frames)
        self._send(packet, self.timing.data(rate, len(frames)), at=self._line_done)

    def _cmd_mec(self, s: NMEASentence) -> None:
        src, dest = s.as_int(1, 0, MAX_ADDRESS), s.as_int(2, 0, MAX_ADDRESS)
        line, mode, arg = s.as_int(3, 0, 255), s.as_int(4, 0, 3), s.as_int(5, 0, 7)
        if dest in (self.modem_id, src):  # this modem's own line: the echo carries its value
            self._say("$CAMEC", src, dest, line, mode, self._control_line(line, mode, arg))
            return
        self._say("$CAMEC", src, dest, line, mode, arg)
        command = AcousticPacket(
            ModemPacketKind.HW_CONTROL, src, dest, hw_control=(line, mode, arg)
        )
        self._send(command, self.timing.mini_packet, at=self._line_done)

    def _control_line(self, line: int, mode: int, arg: int) -> int:
        """Set or read a hardware line (modes: 0 read, 1 set, 2/3 toggle); its value after."""
        if mode == 1:
            self._lines[line] = arg
        elif mode in (2, 3):  # a timed toggle: the line ends where it started
            pass
        return self._lines.get(line, 0)

    def _cmd_pdt(self, s: NMEASentence) -> None:
        self._navigation_ping(s, "$SNPDT", timeout_field=5, length=self.timing.nav_ping)

    def _cmd_pnt(self, s: NMEASentence) -> None:
        length = s.as_int(2, 0, 1000) / 1000
        self._navigation_ping(s, "$SNPNT", timeout_field=4, length=length)

    def _cmd_pgt(self, s: NMEASentence) -> None:
        # goby3 sends 11 fields (timeout 4th); pyacomms 14, with a mode first (timeout 5th)
        timeout_field = 5 if len(s) > 12 else 4
        self._navigation_ping(s, "$SNPGT", timeout_field, length=self.timing.nav_ping)

    def _navigation_ping(self, s: NMEASentence, echo: str, timeout_field: int, length: float):
        timeout_ms = s.as_int(timeout_field, 0, 60_000)
        self._say(echo, *s.fields[1:])
        start = max(self._line_done, self._air_free_at)
        self._send(AcousticPacket(ModemPacketKind.SIGNAL, self.modem_id, 0), length, at=start)
        # no transponders answer: the travel times stay empty
        when = dt.datetime.fromtimestamp(start + self._clock_offset, dt.UTC)
        stamp = f"{when:%H%M%S}.{when.microsecond // 10000:02d}"
        self.timeline.at(start + timeout_ms / 1000, self._say, "$SNTTA", "", "", "", "", stamp)

    def _cmd_swp(self, s: NMEASentence) -> None:
        duration_ms = s.as_int(4, 0, 10**6) / 10
        repetitions, period_ms = s.as_int(5, 1, 1000), s.as_int(6, 0, 10**7) / 10
        self._signal(s, "$CASWP", ((repetitions - 1) * period_ms + duration_ms) / 1000)

    def _cmd_msq(self, s: NMEASentence) -> None:
        bits, repetitions = s.as_int(1, 1, 2**16), s.as_int(2, 1, 1000)
        cycles, carrier = s.as_int(3, 1, 1000), s.as_int(4, 1, 10**6)
        self._signal(s, "$CAMSQ", bits * cycles / carrier * repetitions)

    def _cmd_rsp(self, s: NMEASentence) -> None:
        self._signal(s, "$CARSP", self.timing.ping)

    def _signal(self, s: NMEASentence, echo: str, length: float) -> None:
        self._say(echo, *s.fields[1:])
        self._send(
            AcousticPacket(ModemPacketKind.SIGNAL, self.modem_id, 0), length, at=self._line_done
        )

    # ------------------------------------------------------------------ on the water
    def _send(
        self,
        packet: AcousticPacket,
        duration: float,
        then: Callable | None = None,
        at: float | None = None,
    ) -> None:
        """Transmit `packet` for `duration` s as soon as the transducer is free (from `at`, a
        time the modem has kept: a timed event run late still starts on time)."""
        now = self.clock.now()
        start = max(now if at is None else at, self._air_free_at)
        packet.tx_time, packet.duration = start, duration
        self._air_free_at = start + duration
        if start > now:
            self.timeline.at(start, self._on_air, packet, then)
        else:
            self._on_air(packet, then)

    def _on_air(self, packet: AcousticPacket, then: Callable | None) -> None:
        nbytes = sum(map(len, packet.frames))
        if self._on("TXP"):
            self._say("$CATXP", nbytes)
        if self.channel is not None:
            self.channel.transmit(self, packet)
        self.timeline.at(packet.tx_time + packet.duration, self._off_air, packet, nbytes, then)

    def _off_air(self, packet: AcousticPacket, nbytes: int, then: Callable | None) -> None:
        if self._on("TXF"):
            self._say("$CATXF", nbytes)
        if self._on("XST") and packet.kind in _XST_KINDS:
            frames = len(packet.frames)
            values = {
                "clock_mode": self._clock_mode_field(),
                "mode": 0,
                "probe_length": 0,
                "bandwidth": 5000,
                "carrier_freq": 25000,
                "rate": packet.rate,
                "source": packet.src,
                "dest": packet.dest,
                "ack_requested": packet.ack_requested,
                "number_frames_expected": frames if packet.kind is ModemPacketKind.DATA else 0,
                "number_frames_sent": frames,
                "packet_type": _packet_type(packet),
                "number_bytes": nbytes,
            }
            when = packet.tx_time + self._clock_offset
            self._emit(format_xst(when, values, self.statistics_version))
        if then is not None:
            then()

    def _clock_mode_field(self) -> int:
        """$CACST/$CAXST clock mode: Micro-Modem 2's bit field (RTC source: 1 onboard RTC,
        2 user command; PPS source 1, the RTC), or the legacy ClockMode number."""
        user_set = self._clock_source == "USER"
        if self.mm2:
            return (2 if user_set else 1) | 1 << 2
        return 1 if user_set else 0  # NO_SYNC_TO_PPS_AND_CCCLK_GOOD / _BAD

    # ------------------------------------------------------------------ acoustic receptions
    def detect(self, packet: AcousticPacket, arrival: float) -> None:
        if packet.kind is not ModemPacketKind.SIGNAL and self._on("RXP"):
            self._emit(_RXP)

    def receive(self, packet: AcousticPacket, reception: ModemReception) -> None:
        _HEARD[packet.kind](self, packet, reception)

    def _heard_data(self, p: AcousticPacket, r: ModemReception) -> None:
        if p.rate != 0:  # (a PSK packet's header is its cycle-init)
            self._emit(_heard_cycle_sentence(p, len(p.frames)))
        good: list[int] = []
        rxd = self._on("RXD")
        for i, frame in enumerate(p.frames):
            if r.frame_good(i):
                if rxd:
                    sentence = p.heard.get(i)
                    if sentence is None:
                        sentence = p.heard[i] = NMEASentence.build(
                            "$CARXD", (p.src, p.dest, int(p.ack_requested), i + 1, frame.hex())
                        )
                    self._emit(sentence)
                good.append(i + 1)
            else:
                self._say("$CAMSG", "BAD_CRC", i + 1)
        self._cst(p, r, frames=len(p.frames), bad=len(p.frames) - len(good))
        if p.ack_requested and p.dest == self.modem_id and p.dest != 0 and good:
            ack = AcousticPacket(
                ModemPacketKind.ACK, self.modem_id, p.src, p.rate, acked_frames=good
            )
            self._send(ack, self.timing.mini_packet)

    def _heard_cycle(self, p: AcousticPacket, r: ModemReception) -> None:
        self._emit(_heard_cycle_sentence(p, p.num_frames))
        self._cst(p, r, frames=0, bad=0)
        if p.src == self.modem_id and self._tx is None:  # polled: send our data
            self._start_transmit(_Transmit(p.src, p.dest, p.rate, p.ack_requested, p.num_frames))

    def _heard_ack(self, p: AcousticPacket, r: ModemReception) -> None:
        if p.dest != self.modem_id:
            return
        for frame_no in p.acked_frames:
            self._say("$CAACK", p.src, p.dest, frame_no, 1)
        self._cst(p, r, frames=0, bad=0)

    def _heard_ping(self, p: AcousticPacket, r: ModemReception) -> None:
        if p.dest != self.modem_id:
            return
        self._say("$CAMPA", p.src, p.dest)
        # the reply leaves the turnaround time after the ping has been heard
        reply_at = r.arrival_time + p.duration + self._turnaround()
        reply = AcousticPacket(ModemPacketKind.PING_REPLY, self.modem_id, p.src)
        self.timeline.at(reply_at, self._send, reply, self.timing.ping, None, reply_at)

    def _heard_ping_reply(self, p: AcousticPacket, r: ModemReception) -> None:
        sent = self._pings.pop(p.src, None) if p.dest == self.modem_id else None
        if sent is not None:
            round_trip = r.arrival_time - sent - self.timing.ping - self._turnaround()
            self._say("$CAMPR", p.src, p.dest, f"{round_trip / 2:.4f}")

    def _turnaround(self) -> float:
        return max(0, int(self.nvram["TAT"])) / 1000

    def _heard_mini(self, p: AcousticPacket, r: ModemReception) -> None:
        self._say("$CAMUA", p.src, p.dest, p.frames[0].hex().upper())

    def _heard_fdp(self, p: AcousticPacket, r: ModemReception) -> None:
        payload = b"".join(p.frames)
        bad = sum(not r.frame_good(i) for i in range(len(p.frames)))
        good = not bad
        if not good:
            text = ""
        elif self._on("recv.base64data"):
            text = base64.b64encode(payload).decode()
        else:
            text = payload.hex()
        triple = f"{int(good)};{len(payload)};{text}"
        # the whole payload in one frame field (what goby3's driver and pyacomms both read)
        self._say("$CARDP", p.src, p.dest, p.rate, int(p.ack_requested), 0, triple, "")
        self._cst(p, r, frames=len(p.frames), bad=bad)

    def _heard_signal(self, p: AcousticPacket, r: ModemReception) -> None:
        pass  # (sweeps, sequences and navigation pings carry nothing for a modem)

    def _heard_hw_control(self, p: AcousticPacket, r: ModemReception) -> None:
        if p.dest != self.modem_id or p.hw_control is None:
            return
        line, mode, arg = p.hw_control
        if p.reply:
            self._say("$CAMER", p.src, p.dest, line, mode, arg)
            return
        self._say("$CAMEA", p.src, p.dest, line, mode, arg)
        value = self._control_line(line, mode, arg)
        reply = AcousticPacket(
            ModemPacketKind.HW_CONTROL,
            self.modem_id,
            p.src,
            hw_control=(line, mode, value),
            reply=True,
        )
        self._send(reply, self.timing.mini_packet)

    def _cst(self, p: AcousticPacket, r: ModemReception, frames: int, bad: int) -> None:
        if not self._on("CST"):
            return
        stats = tuple(r.stats.items())
        doppler = r.stats.get("doppler")
        if doppler == 0 and math.copysign(1, doppler) < 0:  # (-0.0 would share 0.0's memo)
            base = _cst_values.__wrapped__(stats)
        else:
            base = _cst_values(stats)
        values = (
            *base[:_RATE],
            p.rate,
            p.src,
            p.dest,
            3 if bad else 0,
            _packet_type(p),
            frames,
            bad,
            *base[_BAD_FRAMES + 1 :],
        )
        self._emit(
            CycleStatistics(
                self.statistics_version,
                1 if bad else 0,
                acomms_pb.now_us(r.arrival_time + self._clock_offset),
                self._clock_mode_field(),
                values,
            )
        )


@functools.lru_cache(maxsize=1 << 14)  # (a link's statistics recur: fixed nodes, steady noise)
def _cst_values(stats: tuple[tuple[str, float], ...]) -> tuple:
    """$CACST values with the channel's statistics in place of the defaults (the packet's own
    fields, rate .. number_bad_frames, are set by the caller)."""
    values = list(_CST_DEFAULTS)
    for name, value in stats:
        i = CST_FIELD_INDEX.get(name)
        if i is None:
            log.warning("unknown $CACST statistic %r from the channel", name)
        elif i == DOPPLER_INDEX:
            values[i] = round(value, 1)
        else:
            values[i] = value if type(value) is int else round(value)
    return tuple(values)


def _heard_cycle_sentence(p: AcousticPacket, frames: int) -> NMEASentence:
    """The $CACYC a receiver prints for `p` (made once per packet)."""
    sentence = p.heard.get("CYC")
    if sentence is None:
        sentence = p.heard["CYC"] = NMEASentence.build(
            "$CACYC", (0, p.src, p.dest, p.rate, int(p.ack_requested), frames)
        )
    return sentence


def _packet_type(p: AcousticPacket) -> int:
    """ReceiveStatistics.PacketType: FSK 1, FSK_MINI 2, PSK 3, FLEXIBLE_DATA_PACKET 5."""
    if p.kind is ModemPacketKind.FDP:
        return 5
    if p.kind is ModemPacketKind.DATA:
        return 1 if p.rate == 0 else 3
    return 2


def _iso_time(text: str) -> float:
    """`YYYY-MM-DDThh:mm:ss[.f]Z` (pyacomms adds a second Z) -> seconds since the epoch."""
    if not text.endswith("Z"):
        raise ValueError(f"time must end with Z: {text!r}")
    t = dt.datetime.fromisoformat(text.rstrip("Z")[:32])
    if t.tzinfo is not None or not YEARS[0] <= t.year <= YEARS[1]:
        raise ValueError(f"time out of range or not UTC: {text!r}")
    return t.replace(tzinfo=dt.UTC).timestamp()


def _c_int(text: str) -> int:
    """What C's atoi makes of a field: the leading digits, or 0."""
    digits = ""
    for ch in text.strip()[:10]:
        if not ch.isdigit():
            break
        digits += ch
    return int(digits) if digits else 0


# $CACST values from mfd_peak to bandwidth of a reception the channel says nothing about
_CST_DEFAULTS = (
    1000,
    20,
    150,
    150,
    250,
    0,
    0,
    0,
    0,  # mfd_peak .. shf_p2bshift
    0,
    0,
    0,
    0,
    1,
    0,
    0,  # rate .. number_bad_frames (set per packet)
    100,
    15,
    15,
    20,
    -15,
    200,
    0.0,
    50,
    25000,
    5000,  # snr_rss .. bandwidth
)
_RATE, _BAD_FRAMES = CST_FIELD_INDEX["rate"], CST_FIELD_INDEX["number_bad_frames"]
_RXP = NMEASentence.build("$CARXP", [0])  # (sentences are immutable: one serves every packet)
_XST_KINDS = (ModemPacketKind.DATA, ModemPacketKind.CYCLE, ModemPacketKind.FDP)
# sentence id -> handler; those only a Micro-Modem 2 knows
COMMAND_HANDLERS = {
    "CFG": MicroModemModel._cmd_cfg,
    "CFQ": MicroModemModel._cmd_cfq,
    "MSC": MicroModemModel._cmd_msc,
    "CLK": MicroModemModel._cmd_clk,
    "CLQ": MicroModemModel._cmd_clq,
    "TMS": MicroModemModel._cmd_tms,
    "TMQ": MicroModemModel._cmd_tmq,
    "ALQ": MicroModemModel._cmd_alq,
    "CYC": MicroModemModel._cmd_cyc,
    "TXD": MicroModemModel._cmd_txd,
    "MPC": MicroModemModel._cmd_mpc,
    "MUC": MicroModemModel._cmd_muc,
    "TDP": MicroModemModel._cmd_tdp,
    "MEC": MicroModemModel._cmd_mec,
    "PDT": MicroModemModel._cmd_pdt,
    "PNT": MicroModemModel._cmd_pnt,
    "PGT": MicroModemModel._cmd_pgt,
    "SWP": MicroModemModel._cmd_swp,
    "MSQ": MicroModemModel._cmd_msq,
    "RSP": MicroModemModel._cmd_rsp,
}
_MM2_COMMANDS = frozenset({"TMS", "TMQ", "ALQ", "TDP"})
_HEARD = {
    ModemPacketKind.DATA: MicroModemModel._heard_data,
    ModemPacketKind.CYCLE: MicroModemModel._heard_cycle,
    ModemPacketKind.ACK: MicroModemModel._heard_ack,
    ModemPacketKind.PING: MicroModemModel._heard_ping,
    ModemPacketKind.PING_REPLY: MicroModemModel._heard_ping_reply,
    ModemPacketKind.MINI: MicroModemModel._heard_mini,
    ModemPacketKind.FDP: MicroModemModel._heard_fdp,
    ModemPacketKind.HW_CONTROL: MicroModemModel._heard_hw_control,
    ModemPacketKind.SIGNAL: MicroModemModel._heard_signal,
}
