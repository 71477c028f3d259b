"""The WHOI Micro-Modem NMEA driver as a state machine.

Everything happens in `do_work()` (read the modem, dispatch, run timers against the Clock) and in
`handle_initiate_transmission()`; nothing blocks. Start-up is a sequence of phases
advanced by `do_work`; `startup_complete` says when it is done. With an injected MemoryLink the
driver is fully sans-I/O: feed lines, advance a VirtualClock, read what it wrote. A link with
`read_sentences` / `write_sentence` (pygoby.acomms.mmsim.link.ModemLink: an emulator in the same
process) carries parsed sentences instead of text.

Every number the modem sends is range-checked against what a Micro-Modem can do (addresses,
rates, frame counts and sizes, travel times) before it is used: a bad one makes the sentence
"malformed" (logged and ignored), never a huge allocation or an overflow.
"""

from __future__ import annotations

import base64
import contextlib
import datetime as dt
import logging
import math
from collections import deque
from collections.abc import Callable, Iterable
from enum import Enum, auto

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverBase
from pygoby.acomms.drivers.micromodem.app_ack import ApplicationAcks
from pygoby.acomms.drivers.micromodem.rates import RATE_FRAME_BYTES, RATE_NUM_FRAMES, check_rate
from pygoby.acomms.drivers.micromodem.sentence_link import SentenceLink, sentence_link
from pygoby.acomms.drivers.micromodem.statistics import (
    CycleStatistics,
    add_cst,
    parse_toa,
    parse_xst,
)
from pygoby.acomms.errors import ModemDriverError
from pygoby.protobuf.goby.acomms.protobuf.mm_driver_pb2 import TransmissionType
from pygoby.util.clock import Clock
from pygoby.util.errors import NMEAError
from pygoby.util.nmea import NMEASentence

log = logging.getLogger(__name__)

MODEM_WAIT = 5.0  # s before a sentence is resent
RETRIES = 3
MAX_FAILS_BEFORE_DEAD = 5
MULTI_REPLY_QUIET = 2.0  # s of silence that ends a CFQ,ALL / CFQ,TOP burst
DEFAULT_BAUD = 19200
REVINIT_PAUSE = 2.0
MM2_BITFIELD_CLOCK_REVISION = (2, 0, 26038)
HYDROID_GPS_REQUEST_INTERVAL = 30.0
FDP_MAX_FRAME_BYTES = 100
# what a Micro-Modem can do: the bounds of the numbers read from it
MAX_ADDRESS = 127
MAX_FRAMES = max(RATE_NUM_FRAMES)
MAX_FRAME_BYTES = max(RATE_FRAME_BYTES)
MAX_FDP_BYTES = 2048  # (the largest flexible data packet: rate 5, 8 x 256 bytes)
MAX_TRAVEL_TIME = 30.0  # s (goby3's RangingReply bound)
MAX_RATE = 6  # (the driver sends rates 0-5; another modem may use 6)
MAX_NVRAM_KEYS = 1024  # NVRAM parameters remembered from $CACFG
INT32 = (-(2**31), 2**31 - 1)
CLOCK_FIELDS = ((1, 9999), (1, 12), (1, 31), (0, 23), (0, 59), (0, 60))  # $CACLK
HW_LINE_BOUNDS = {3: (0, 255), 4: (0, 3), 5: (0, 7)}  # line, mode, arg

Status = acomms_pb.ModemDriverStatus


class Phase(Enum):
    CONFIGURING = auto()
    SETTING_CLOCK = auto()
    QUERYING = auto()
    READY = auto()
    STOPPED = auto()


class MMDriver(ModemDriverBase):
    DEFAULT_SERIAL_BAUD = DEFAULT_BAUD
    DEFAULT_LINE_DELIMITER = "\r"
    RATES = range(len(RATE_NUM_FRAMES))

    def __init__(self, clock: Clock | None = None, link=None) -> None:
        super().__init__(clock, link)
        self.mm_cfg = acomms_pb.MMConfig()
        self.phase = Phase.STOPPED
        self.app_acks: ApplicationAcks | None = None
        self.nvram: dict[str, int] = {}
        self.revision: tuple[int, int, int] = (0, 0, 0)
        self._sentences: SentenceLink | None = None  # the link, read and written as sentences
        self._buoy = 0  # Hydroid gateway buoy id (prefixes)
        self._keep_alive_seconds = 0
        self._reset_state()

    def _reset_state(self) -> None:
        self._out: deque[NMEASentence] = deque()
        self._written_at: float | None = None  # when the front sentence was last written
        self._tries = 0
        self._fails = 0
        self._hold_until = 0.0  # no writes before this time (after $CAREV,INIT)
        self._multi_reply = False
        self._last_cfg_at = 0.0
        # goby3 asks the modem something once keep_alive_seconds have passed without a sentence
        # from it, the first time at once: its first $CCCFQ,SRC follows the start-up $CCMSC in
        # the queue.
        self._last_keep_alive_at = float("-inf")
        self._clock_set = False
        self._link_was_open = False
        self._last_gps_request = float("-inf")
        # transmission state
        self._cached = acomms_pb.ModemTransmission()
        self._frame_counter = 0
        self._expected_acks: set[int] = set()
        self._expected_ack_src = -1
        self._expected_xst = 0
        self._transmit = acomms_pb.ModemTransmission()
        # reception state
        self._receive: acomms_pb.ModemTransmission | None = None
        self._expected_frames: set[int] = set()
        self._expected_cst = 0
        self._ack_msg: acomms_pb.ModemTransmission | None = None
        self._last_lbl_type = acomms_pb.MICROMODEM_REMUS_LBL_RANGING

    # ------------------------------------------------------------------ interface
    @property
    def startup_complete(self) -> bool:
        return self.phase is Phase.READY

    @property
    def is_mm2(self) -> bool:
        return self.revision[0] >= 2

    def startup(self, cfg: acomms_pb.DriverConfig) -> None:
        self._reset_state()
        self.mm_cfg = cfg.Extensions[acomms_pb.MM_CONFIG]
        self._buoy = self.mm_cfg.hydroid_gateway_id
        self._keep_alive_seconds = self.mm_cfg.keep_alive_seconds
        self.modem_start(cfg)
        self._sentences = sentence_link(self, self._buoy)
        self.app_acks = None
        if self.mm_cfg.use_application_acks:
            ids = {cfg.modem_id, *self.mm_cfg.additional_application_ack_modem_id}
            self.app_acks = ApplicationAcks(ids)
        c = self.mm_cfg
        if c.reset_nvram and not c.hydroid_gateway_id:
            self._push("$CCCFG", "ALL", 0)
        self._push("$CCCFG", "CST", 1)
        self._push_nvram_cfg(c.nvram_cfg)
        self._push("$CCCFG", "SRC", cfg.modem_id)
        if c.HasField("revision"):
            self.revision = (c.revision.mm_major, c.revision.mm_minor, c.revision.mm_patch)
            self._push("$CCCFG", "REV", 0)
        else:
            self._push("$CCCFG", "REV", 1)
        self._push("$CCCFG", "RXP", 1)
        if c.use_base64_fdp:
            self._push("$CCCFG", "recv.base64data", 1)
        self._push("$CCMSC", cfg.modem_id, cfg.modem_id, 0)
        self.phase = Phase.CONFIGURING

    def _push_nvram_cfg(self, entries) -> None:
        for entry in entries:
            key, sep, _ = entry.partition(",")
            if sep and len(key) == 3:
                entry = entry.upper()
            self._out.append(NMEASentence.build("$CCCFG", entry.split(",")))

    def update_cfg(self, cfg: acomms_pb.DriverConfig) -> None:
        """ACOMMS_DRIVER_CONFIG_UPDATE: send the update's Micro-Modem `nvram_cfg` entries (as at
        start-up) and keep them in the configuration, so that a restart sends them too."""
        entries = list(cfg.Extensions[acomms_pb.MM_CONFIG].nvram_cfg)
        self._push_nvram_cfg(entries)
        self.mm_cfg.nvram_cfg.extend(entries)

    def shutdown(self) -> None:
        self.phase = Phase.STOPPED
        self.modem_close()

    def do_work(self) -> None:
        if self.phase is Phase.STOPPED:
            return
        assert self.link is not None
        link_open = self.link.is_open
        if link_open and not self._link_was_open:
            self._written_at = None  # (re)connected: rewrite the outstanding sentence now
        self._link_was_open = link_open
        assert self._sentences is not None
        sentences = self._sentences.read_sentences()
        if sentences:  # (a direct link's empty list: the common case in a simulation)
            self._handle_sentences(sentences)
        if not link_open:
            return  # a dead link is the link's business (it reconnects); do not count failures
        now = self.clock.now()
        # (each step's first test made here: do_work runs for every sentence batch and timer)
        if self._buoy:
            self._hydroid_gps_request(now)
        if self._multi_reply:
            self._check_multi_reply(now)
        if self.phase is not Phase.READY or not self._clock_set:
            self._advance_startup(now)
        if self._written_at is not None:
            self._check_timeout(now)
        if now >= self._last_keep_alive_at + self._keep_alive_seconds:
            self._keep_alive(now)
        self._try_write(now)

    def handle_initiate_transmission(self, transmission: acomms_pb.ModemTransmission) -> None:
        if self.link is None or not self.link.is_open:
            # nothing is taken from the queue, so queued messages wait for the link
            log.warning("link to the modem is down: transmission not started")
            return
        msg = acomms_pb.ModemTransmission()
        msg.CopyFrom(transmission)
        self.signal_modify_transmission.emit(msg)
        if msg.type == acomms_pb.DATA:
            self._initiate_data(msg)
        elif msg.type == acomms_pb.DRIVER_SPECIFIC:
            kind = msg.Extensions[acomms_pb.MM_TRANSMISSION].type
            if kind == acomms_pb.MICROMODEM_TWO_WAY_PING:
                self._push("$CCMPC", msg.src if msg.src >= 0 else self.modem_id, msg.dest)
            elif kind == acomms_pb.MICROMODEM_MINI_DATA:
                self._initiate_mini(msg)
            elif kind == acomms_pb.MICROMODEM_FLEXIBLE_DATA:
                self._initiate_fdp(msg)
            elif kind in _SIMPLE_INITIATORS:
                _SIMPLE_INITIATORS[kind](self, msg)
            else:
                log.warning("Micro-Modem transmission type %d is not supported", kind)
        else:
            log.warning("cannot initiate a transmission of type %d", msg.type)

    def set_silent(self, silent: bool) -> None:
        """MACUpdate cycle_state: SRC,0 stops the modem acknowledging; SRC,<id> restores it."""
        self._push("$CCCFG", "SRC", 0 if silent else self.modem_id)

    # ------------------------------------------------------------------ outgoing FIFO
    def _push(self, token: str, *values: object) -> None:
        self._out.append(NMEASentence.build(token, values))

    def _try_write(self, now: float) -> None:
        if not self._out or self._written_at is not None or now < self._hold_until:
            return
        assert self._sentences is not None
        self._sentences.write_sentence(self._out[0])
        self._written_at = now
        self._tries += 1

    def _pop_front(self) -> None:
        if self._out:
            self._out.popleft()
        self._written_at = None
        self._tries = 0

    def _fail_front(self, reason: str) -> None:
        self._fails += 1
        front = self._out[0].message() if self._out else "?"
        log.warning("no valid answer to %s (%s)", front, reason)
        if self._fails >= MAX_FAILS_BEFORE_DEAD:
            self.shutdown()
            raise ModemDriverError(f"modem did not respond to {front}", Status.MODEM_NOT_RESPONDING)
        if self._tries >= RETRIES:
            log.warning("giving up on %s, continuing onwards anyway", front)
            self._pop_front()
        else:
            self._written_at = None  # resend

    def _hydroid_gps_request(self, now: float) -> None:
        buoy = self.mm_cfg.hydroid_gateway_id
        if buoy and now - self._last_gps_request >= HYDROID_GPS_REQUEST_INTERVAL:
            self.modem_write(f"#G{buoy}\r\n")
            self._last_gps_request = now

    def _check_timeout(self, now: float) -> None:
        if self._written_at is not None and now - self._written_at > MODEM_WAIT:
            self._fail_front("timeout")

    def _keep_alive(self, now: float) -> None:
        """keep_alive_seconds without a sentence from the modem (whatever is queued, as goby3):
        ask the modem its time (Micro-Modem 2, at the start of a second for a precise answer)
        or its source address (before the modem's revision is known, and for Micro-Modem 1)."""
        if self.is_mm2:
            self._push("$CCTMQ", 0)
            self._last_keep_alive_at = float(math.floor(now))
        else:
            self._push("$CCCFQ", "SRC")
            self._last_keep_alive_at = now

    def _check_multi_reply(self, now: float) -> None:
        if self._multi_reply and self._last_cfg_at and now - self._last_cfg_at > MULTI_REPLY_QUIET:
            self._multi_reply = False
            self._last_cfg_at = 0.0
            if self._out and self._out[0].sentence_id == "CFQ":
                self._pop_front()

    def _acknowledge(self, sentence: NMEASentence) -> None:
        """Pop the outstanding sentence if `sentence` answers it."""
        if not self._out:
            return
        front = self._out[0]
        kind, got = front.sentence_id, sentence.sentence_id
        if kind == "CFG":
            if (
                got == "CFG"
                and len(sentence) == 3
                and tuple(sentence.fields[1:]) == tuple(front.fields[1:3])
            ):
                self._pop_front()
        elif kind == "CFQ":
            if got == "CFG" and not self._multi_reply:
                self._pop_front()
        elif kind == "MSC":
            if got in ("REV", "MSC"):
                self._pop_front()
        elif kind == got:
            self._pop_front()

    # ------------------------------------------------------------------ start-up phases
    def _advance_startup(self, now: float) -> None:
        if self.phase is Phase.CONFIGURING and not self._out:
            self.phase = Phase.SETTING_CLOCK
        if self.phase is Phase.SETTING_CLOCK:
            if self._clock_set and not self._out:
                if self.mm_cfg.query_cfg_on_startup:
                    self._multi_reply = True
                    self._push("$CCCFQ", "TOP" if self.is_mm2 else "ALL")
                    self.phase = Phase.QUERYING
                else:
                    self.phase = Phase.READY
        elif self.phase is Phase.QUERYING and not self._out:
            self.phase = Phase.READY
        if self.phase is not Phase.CONFIGURING and not self._clock_set and not self._out:
            self._send_clock(now)

    def _send_clock(self, now: float) -> None:
        # WHOI guidance: set between 50 and 100 ms after a whole second, to the next second.
        if not 0.05 <= now % 1.0 < 0.1:
            return
        t = dt.datetime.fromtimestamp(int(now) + 1, dt.UTC)  # carry properly (Q-ACOMMS-6)
        if self.is_mm2:
            self._push("$CCTMS", f"{t:%Y-%m-%dT%H:%M:%SZ}", 0)
        else:
            self._push("$CCCLK", t.year, t.month, t.day, t.hour, t.minute, t.second)
        self._try_write(now)

    def _check_clock(self, modem_time: float, whole_seconds: bool) -> None:
        now = self.clock.now()
        reference = float(int(now)) if whole_seconds else now
        skew_ms = abs(modem_time - reference) * 1000.0
        if skew_ms < self.mm_cfg.allowed_skew_ms:
            self._clock_set = True
        else:
            log.warning("modem clock is %.0f ms off; setting it again", skew_ms)
            self._clock_set = False

    # ------------------------------------------------------------------ incoming
    def _handle_sentences(self, sentences: Iterable[NMEASentence]) -> None:
        """Handle valid sentences from the modem (received now), in order."""
        for sentence in sentences:
            self._fails = 0
            # a modem that talks is alive: the keep-alive waits keep_alive_seconds from here
            self._last_keep_alive_at = self.clock.now()
            handler = _HANDLERS.get(sentence.sentence_id)
            if handler is not None:
                try:
                    handler(self, sentence)
                except (NMEAError, ValueError, IndexError) as exc:
                    log.warning("ignoring malformed %s: %s", sentence.message(), exc)
            if self._written_at is not None:
                self._acknowledge(sentence)

    def _on_rev(self, s: NMEASentence) -> None:
        if s[2] == "INIT":
            log.warning("modem reported a reboot ($CAREV INIT)")
            self._hold_until = self.clock.now() + REVINIT_PAUSE
            self._clock_set = False
        elif s[2] == "AUV" and not self.mm_cfg.HasField("revision"):
            parts = [int(p) for p in s[3].split(".")]
            patch = parts[2] * 100 + parts[3] if len(parts) > 3 else parts[2]
            self.revision = (parts[0], parts[1], patch)

    def _on_err(self, s: NMEASentence) -> None:
        log.warning("modem error: %s", s.message())
        if len(s) > 2 and s[2] == "NMEA" and self._out and self._written_at is not None:
            self._fail_front("$CAERR NMEA")

    def _on_cfg(self, s: NMEASentence) -> None:
        # integer parameters only (MM2 also has text ones), and a bounded number of them
        if len(s) >= 3 and (s[1] in self.nvram or len(self.nvram) < MAX_NVRAM_KEYS):
            with contextlib.suppress(NMEAError):
                self.nvram[s[1]] = s.as_int(2, *INT32)
        if self._multi_reply:
            self._last_cfg_at = self.clock.now()

    def _on_clk(self, s: NMEASentence) -> None:
        if self._outstanding("CLK"):
            year, month, day, hour, minute, second = (
                s.as_int(i, *bounds) for i, bounds in enumerate(CLOCK_FIELDS, 1)
            )
            t = dt.datetime(year, month, day, hour, minute, second, tzinfo=dt.UTC)
            self._check_clock(t.timestamp(), whole_seconds=True)

    def _on_tms(self, s: NMEASentence) -> None:
        if self._outstanding("TMS"):
            self._check_clock(_iso_time(s[2]), whole_seconds="." not in s[2])

    def _on_tmq(self, s: NMEASentence) -> None:
        if self._outstanding("TMQ"):
            self._check_clock(_iso_time(s[1]) + 0.5, whole_seconds=False)

    def _outstanding(self, kind: str) -> bool:
        return bool(self._out) and self._written_at is not None and self._out[0].sentence_id == kind

    # ------------------------------------------------------------------ data transmission
    def _initiate_data(self, msg: acomms_pb.ModemTransmission) -> None:
        try:
            check_rate(msg.rate)
        except ValueError as exc:
            log.warning("not sending: %s", exc)
            return
        msg.max_num_frames = RATE_NUM_FRAMES[msg.rate]
        msg.max_frame_bytes = RATE_FRAME_BYTES[msg.rate]
        if msg.src < 0:
            msg.src = self.modem_id
        if msg.src != self.modem_id:
            # third-party initiation (polling): the polled node fills the frames
            if msg.dest < 0:  # goby3 sends it unchanged (QUIRKS.md Q-ACOMMS-14)
                log.warning("a poll must name a destination; not sending %s", msg)
                return
            self._push("$CCCYC", 0, msg.src, msg.dest, msg.rate, 1, msg.max_num_frames)
            return
        if not self._request_data(msg):
            log.debug("no data to send; no cycle started")
            return
        c = self._cached
        self._expected_xst = 2 if c.rate == 0 else 1
        self._transmit = acomms_pb.ModemTransmission()
        self._transmit.CopyFrom(c)
        firmware_ack = c.ack_requested and self.app_acks is None
        self._push("$CCCYC", 0, c.src, c.dest, c.rate, firmware_ack, len(c.frame))

    def _request_data(self, msg: acomms_pb.ModemTransmission) -> bool:
        """Fill `msg` from the queue (with the application ack if enabled) and cache it;
        False if there is nothing to send."""
        self._expected_acks.clear()
        self._frame_counter = 0
        placeholder = self.app_acks.prepare(msg) if self.app_acks is not None else 0
        self.signal_data_request.emit(msg)
        if self.app_acks is not None and not self.app_acks.finish(msg, placeholder):
            msg.ClearField("frame")
        if msg.dest < 0:
            msg.dest = acomms_pb.BROADCAST_ID
        self._cached = msg
        return bool(msg.frame) and bool(msg.frame[0])

    def _on_cyc(self, s: NMEASentence) -> None:
        src, dest, rate, ack, nframes = (
            s.as_int(2, 0, MAX_ADDRESS),
            s.as_int(3, 0, MAX_ADDRESS),
            s.as_int(4, 0, MAX_RATE),
            s.as_int(5, 0, 1),
            s.as_int(6, 0, MAX_FRAMES),
        )
        if self._outstanding("CYC") and tuple(self._out[0].fields[2:5]) == tuple(s.fields[2:5]):
            return  # the modem's echo of our own $CCCYC
        if src == self.modem_id:
            check_rate(rate)
            request = acomms_pb.ModemTransmission(
                src=src,
                dest=dest,
                rate=rate,
                type=acomms_pb.DATA,
                time=acomms_pb.now_us(self.clock.now()),
                max_num_frames=nframes,
                max_frame_bytes=RATE_FRAME_BYTES[rate],
                ack_requested=bool(ack),
            )
            self._request_data(request)
            self._expected_xst = 2 if rate == 0 else 1
            self._transmit = acomms_pb.ModemTransmission()
            self._transmit.CopyFrom(self._cached)
            return
        if self._expected_frames:
            log.warning("new cycle before frames %s arrived", sorted(self._expected_frames))
        self._expected_frames = set(range(nframes))
        self._expected_cst = 2 if rate == 0 else 1
        self._receive = None

    def _on_drq(self, s: NMEASentence) -> None:
        src, dest, ack, nbytes, frame_no = (
            s.as_int(2, 0, MAX_ADDRESS),
            s.as_int(3, 0, MAX_ADDRESS),
            s.as_int(4, 0, 1),
            s.as_int(5, 0, MAX_FRAME_BYTES),
            s.as_int(6, 1, MAX_FRAMES),
        )
        index = frame_no - 1
        if 0 <= index < len(self._cached.frame) and self._cached.frame[index]:
            data = bytes(self._cached.frame[index])
            if self.mm_cfg.pad_partial_frames:
                data = data.ljust(nbytes, b"\0")
            self._push("$CCTXD", src, dest, ack, data.hex())
            if ack:
                self._expected_acks.add(self._frame_counter)
                self._frame_counter += 1
                self._expected_ack_src = dest
        else:
            self._push("$CCTXD", src, dest, ack, "")

    def _on_xst(self, s: NMEASentence) -> None:
        self._transmit.Extensions[acomms_pb.MM_TRANSMISSION].transmit_stat.append(parse_xst(s))
        self._expected_xst -= 1
        if self._expected_xst <= 0:
            self.signal_transmit_result.emit(self._transmit)
            self._transmit = acomms_pb.ModemTransmission()

    def _on_ack(self, s: NMEASentence) -> None:
        src, dest = s.as_int(1, 0, MAX_ADDRESS), s.as_int(2, 0, MAX_ADDRESS)
        frame_no = s.as_int(3, 1, MAX_FRAMES)
        if dest != self.modem_id or src != self._expected_ack_src:
            return
        goby_frame = frame_no - 1
        if goby_frame not in self._expected_acks:
            log.warning("unexpected ACK for frame %d", goby_frame)
            return
        self._expected_acks.discard(goby_frame)
        if self._ack_msg is None:
            self._ack_msg = acomms_pb.ModemTransmission(
                type=acomms_pb.ACK, src=src, dest=dest, time=acomms_pb.now_us(self.clock.now())
            )
        self._ack_msg.acked_frame.append(goby_frame)
        if not self._cst_enabled:
            self._flush_ack()

    def _flush_ack(self) -> None:
        if self._ack_msg is not None:
            ack, self._ack_msg = self._ack_msg, None
            self.signal_receive.emit(ack)

    @property
    def _cst_enabled(self) -> bool:
        return self.nvram.get("CST", 1) != 0

    # ------------------------------------------------------------------ reception
    def _receiving(self) -> acomms_pb.ModemTransmission:
        if self._receive is None:
            self._receive = acomms_pb.ModemTransmission(type=acomms_pb.DATA)
        return self._receive

    def _on_rxd(self, s: NMEASentence) -> None:
        src, dest, ack, frame_no = (
            s.as_int(1, 0, MAX_ADDRESS),
            s.as_int(2, 0, MAX_ADDRESS),
            s.as_int(3, 0, 1),
            s.as_int(4, 1, MAX_FRAMES),
        )
        data = _hex(s[5], MAX_FRAME_BYTES) if len(s) > 5 else b""
        rx = self._receiving()
        if frame_no == 1:
            rx.time = acomms_pb.now_us(self.clock.now())
            rx.src, rx.dest, rx.type, rx.ack_requested = src, dest, acomms_pb.DATA, bool(ack)
        if data:
            if frame_no - 1 != len(rx.frame):
                log.warning("frame %d arrived as frame %d", frame_no, len(rx.frame) + 1)
            rx.frame.append(data)
        self._expected_frames.discard(frame_no - 1)
        if not self._cst_enabled and not self._expected_frames:
            self._finish_receive()

    def _on_msg(self, s: NMEASentence) -> None:
        if s[1] in ("BAD_CRC", "Bad CRC") and self._expected_frames:
            rx = self._receiving()
            rx.Extensions[acomms_pb.MM_TRANSMISSION].frame_with_bad_crc.append(len(rx.frame))
            rx.frame.append(b"")
            self._expected_frames.discard(min(self._expected_frames))
            if not self._cst_enabled and not self._expected_frames:
                self._finish_receive()

    def _on_cst(self, s: NMEASentence) -> None:
        if isinstance(s, CycleStatistics) and s.version >= 6:
            today = _EPOCH_DATE  # (a dated time of arrival: the reader's date is not used)
        else:
            today = _utc_date(self.clock.now())
        new_clock = self.revision >= MM2_BITFIELD_CLOCK_REVISION
        if self._ack_msg is not None and self._receive is None and not self._expected_cst:
            ack = self._ack_msg
            ext = ack.Extensions[acomms_pb.MM_TRANSMISSION]
            self._apply_statistics(ack, add_cst(ext.receive_stat, s, today, new_clock))
            self._flush_ack()
            return
        # (what _receiving() gives, kept only once the statistics are in: add_cst appends
        # nothing when the sentence is bad)
        rx = (
            self._receive
            if self._receive is not None
            else acomms_pb.ModemTransmission(type=acomms_pb.DATA)
        )
        ext = rx.Extensions[acomms_pb.MM_TRANSMISSION]
        stat = add_cst(ext.receive_stat, s, today, new_clock)
        self._receive = rx
        if not rx.HasField("src"):
            rx.src, rx.dest = stat.source, stat.dest
        self._apply_statistics(rx, stat)
        self._expected_cst -= 1
        if self._expected_cst <= 0:
            self._finish_receive()
        self._flush_ack()

    @staticmethod
    def _apply_statistics(
        msg: acomms_pb.ModemTransmission, stat: acomms_pb.ReceiveStatistics
    ) -> None:
        """What a $CACST tells of the reception it closes, data or acknowledgement alike (as
        goby3): its time of arrival is the message's time (MODEM_TIME), and with the clock
        synchronised to a PPS it is also a one-way travel time."""
        msg.time, msg.time_source = stat.time, acomms_pb.ModemTransmission.MODEM_TIME
        if stat.clock_mode in (2, 3):
            ranging = msg.Extensions[acomms_pb.MM_TRANSMISSION].ranging_reply
            ranging.one_way_travel_time.append((stat.time % 1_000_000) / 1e6)
            ranging.ambiguity = acomms_pb.RangingReply.OWTT_SECOND_AMBIGUOUS
            ranging.receiver_clk_mode = stat.clock_mode
            ranging.is_one_way_synchronous = True

    def _finish_receive(self) -> None:
        rx, self._receive = self._receive, None
        self._expected_frames.clear()
        self._expected_cst = 0
        if rx is not None:
            self._emit_data(rx)

    def _emit_data(self, rx: acomms_pb.ModemTransmission) -> None:
        """Deliver a data reception (after taking out an application ack, if enabled)."""
        if self.app_acks is not None:
            for ack in self.app_acks.strip(rx):
                ack.time = acomms_pb.now_us(self.clock.now())
                self.signal_receive.emit(ack)
        self.signal_receive.emit(rx)

    # ------------------------------------------------------------------ ranging, mini-packets
    def _on_mpr(self, s: NMEASentence) -> None:
        # src/dest copied as they appear in the sentence, as goby3's code does (its docs say
        # swapped back to the request's order: QUIRKS.md Q-ACOMMS-5)
        owtt = s.as_float(3, 0.0, MAX_TRAVEL_TIME)
        msg = self._ping_result(*_addresses(s))
        msg.Extensions[acomms_pb.MM_TRANSMISSION].ranging_reply.one_way_travel_time.append(owtt)
        self.signal_receive.emit(msg)

    def _on_mpa(self, s: NMEASentence) -> None:
        self.signal_receive.emit(self._ping_result(*_addresses(s)))

    def _ping_result(
        self,
        src: int,
        dest: int,
        kind: TransmissionType.ValueType = acomms_pb.MICROMODEM_TWO_WAY_PING,
    ) -> acomms_pb.ModemTransmission:
        msg = acomms_pb.ModemTransmission(
            type=acomms_pb.DRIVER_SPECIFIC,
            src=src,
            dest=dest,
            time=acomms_pb.now_us(self.clock.now()),
        )
        msg.Extensions[acomms_pb.MM_TRANSMISSION].type = kind
        return msg

    def _initiate_mini(self, msg: acomms_pb.ModemTransmission) -> None:
        msg.max_num_frames, msg.max_frame_bytes = 1, 2
        if msg.src < 0:
            msg.src = self.modem_id
        if not msg.frame:
            self.signal_data_request.emit(msg)
        if not msg.frame or not msg.frame[0]:
            return
        data = bytearray(bytes(msg.frame[0])[:2].ljust(2, b"\0"))
        if data[0] & 0xE0:
            log.warning("mini-packets carry 13 bits; masking the top 3 bits")
            data[0] &= 0x1F
        self._push("$CCMUC", msg.src, msg.dest, data.hex().upper())

    def _initiate_fdp(self, msg: acomms_pb.ModemTransmission) -> None:
        msg.max_num_frames = 1
        if not msg.HasField("max_frame_bytes"):
            msg.max_frame_bytes = FDP_MAX_FRAME_BYTES
        if msg.src < 0:
            msg.src = self.modem_id
        if self.app_acks is not None:
            if not self._request_data(msg):
                return
        elif not msg.frame:
            self.signal_data_request.emit(msg)
        if not msg.frame or not msg.frame[0]:
            return
        if msg.ack_requested and self.app_acks is None:
            log.warning("FDP has no firmware acks; sending without one")
        data = bytes(msg.frame[0])
        major, minor, patch = self.revision
        if (major, minor) == (2, 0) and patch < 35490 and len(data) % 2:
            data += b"\0"  # these firmwares drop an odd final byte
        self._push("$CCTDP", msg.dest, msg.rate, 0, 0, data.hex())

    def _on_rdp(self, s: NMEASentence) -> None:
        msg = self._ping_result(*_addresses(s), acomms_pb.MICROMODEM_FLEXIBLE_DATA)
        msg.rate = s.as_int(3, 0, MAX_RATE)
        frame, good = b"", True
        for part in s.fields[6:8]:
            triple = part.split(";")
            if len(triple) < 3 or not part:
                continue
            crc_ok, payload = triple[0] == "1", triple[2]
            good &= crc_ok
            if len(payload) > 4 * MAX_FDP_BYTES:  # (hex or base64 of more than the packet holds)
                raise ValueError(f"a flexible data packet has at most {MAX_FDP_BYTES} bytes")
            frame += (
                base64.b64decode(payload) if self.mm_cfg.use_base64_fdp else bytes.fromhex(payload)
            )
            if len(frame) > MAX_FDP_BYTES:
                raise ValueError(f"a flexible data packet has at most {MAX_FDP_BYTES} bytes")
        if good:
            msg.frame.append(frame)
        else:
            msg.frame.append(b"")
            msg.Extensions[acomms_pb.MM_TRANSMISSION].frame_with_bad_crc.append(0)
        self._emit_data(msg)

    def _on_mua(self, s: NMEASentence) -> None:
        msg = self._ping_result(*_addresses(s), acomms_pb.MICROMODEM_MINI_DATA)
        msg.frame.append(_hex(s[3], 2))
        self.signal_receive.emit(msg)

    def _lbl_params(self, msg: acomms_pb.ModemTransmission, name: str):
        """Configured LBL parameters merged with the request's own."""
        params = type(getattr(self.mm_cfg, name))()
        params.CopyFrom(getattr(self.mm_cfg, name))
        params.MergeFrom(getattr(msg.Extensions[acomms_pb.MM_TRANSMISSION], name))
        if self.nvram.get("TAT") != params.turnaround_ms:
            self._push("$CCCFG", "TAT", params.turnaround_ms)
        return params, int(params.lbl_max_range * 2 / 1500 * 1000 + params.turnaround_ms)

    def _initiate_remus_lbl(self, msg: acomms_pb.ModemTransmission) -> None:
        params, timeout = self._lbl_params(msg, "remus_lbl")
        bits = params.enable_beacons
        self._last_lbl_type = acomms_pb.MICROMODEM_REMUS_LBL_RANGING
        self._push(
            "$CCPDT", 1, self.modem_id % 4 + 1, 0, 0, timeout, *((bits >> i) & 1 for i in range(4))
        )

    def _initiate_narrowband_lbl(self, msg: acomms_pb.ModemTransmission) -> None:
        p, timeout = self._lbl_params(msg, "narrowband_lbl")
        freqs = [*list(p.receive_freq)[:4], 0, 0, 0, 0][:4]
        self._last_lbl_type = acomms_pb.MICROMODEM_NARROWBAND_LBL_RANGING
        self._push(
            "$CCPNT",
            p.transmit_freq,
            p.transmit_ping_ms,
            p.receive_ping_ms,
            timeout,
            *freqs,
            int(p.transmit_flag),
        )

    def _initiate_generic_lbl(self, msg: acomms_pb.ModemTransmission) -> None:
        p, timeout = self._lbl_params(msg, "generic_lbl")
        codes = [*list(p.receive_seq_code)[:4], 0, 0, 0, 0][:4]
        self._last_lbl_type = acomms_pb.MICROMODEM_GENERIC_LBL_RANGING
        self._push(
            "$CCPGT",
            p.transmit_freq,
            p.n_bits,
            p.transmit_seq_code,
            timeout,
            p.receive_freq,
            *codes,
            p.bandwidth,
            0,
        )

    def _initiate_hardware_control(self, msg: acomms_pb.ModemTransmission) -> None:
        hw = msg.Extensions[acomms_pb.MM_TRANSMISSION].hw_ctl
        src = msg.src if msg.src >= 0 else self.modem_id
        self._push("$CCMEC", src, msg.dest, hw.line, hw.mode, hw.arg)

    def _initiate_fm_sweep(self, msg: acomms_pb.ModemTransmission) -> None:
        p = acomms_pb.MMConfig().fm_sweep
        p.CopyFrom(self.mm_cfg.fm_sweep)
        p.MergeFrom(msg.Extensions[acomms_pb.MM_TRANSMISSION].fm_sweep)
        self._push(
            "$CCSWP",
            int(p.start_freq * 10),
            int(p.stop_freq * 10),
            int(abs(p.start_freq - p.stop_freq)),
            int(p.duration_ms * 10),
            p.number_repetitions,
            int(p.repetition_period_ms * 10),
        )

    def _initiate_m_sequence(self, msg: acomms_pb.ModemTransmission) -> None:
        p = acomms_pb.MMConfig().m_sequence
        p.CopyFrom(self.mm_cfg.m_sequence)
        p.MergeFrom(msg.Extensions[acomms_pb.MM_TRANSMISSION].m_sequence)
        self._push(
            "$CCMSQ", p.seqlen_bits, p.number_repetitions, p.carrier_cycles_per_chip, p.carrier_freq
        )

    def _on_mer(self, s: NMEASentence) -> None:
        src, dest = _addresses(s)
        line, mode, arg = (s.as_int(i, *HW_LINE_BOUNDS[i]) for i in (3, 4, 5))
        major, minor, patch = self.revision
        if major == 2 and minor == 0 and patch < 18307:  # these firmwares swap src and dest
            src, dest = dest, src
        msg = self._ping_result(src, dest, acomms_pb.MICROMODEM_HARDWARE_CONTROL_REPLY)
        hw = msg.Extensions[acomms_pb.MM_TRANSMISSION].hw_ctl
        hw.line, hw.mode, hw.arg = line, mode, arg  # type: ignore[assignment]  # (in range)
        self.signal_receive.emit(msg)

    def _on_tta(self, s: NMEASentence) -> None:
        msg = self._ping_result(self.modem_id, -1, self._last_lbl_type)
        msg.ClearField("dest")
        msg.time_source = acomms_pb.ModemTransmission.MODEM_TIME
        today = _utc_date(self.clock.now())
        msg.time = parse_toa(s[5], today)
        reply = msg.Extensions[acomms_pb.MM_TRANSMISSION].ranging_reply
        for i in range(1, 5):
            reply.one_way_travel_time.append(s.as_float(i, 0.0, MAX_TRAVEL_TIME) if s[i] else 0.0)
        self.signal_receive.emit(msg)


_EPOCH_DATE = dt.date(1970, 1, 1)


def _utc_date(seconds: float) -> dt.date:
    return dt.datetime.fromtimestamp(seconds, dt.UTC).date()


def _iso_time(text: str) -> float:
    return dt.datetime.fromisoformat(text.replace("Z", "+00:00")).timestamp()


def _addresses(s: NMEASentence) -> tuple[int, int]:
    """Fields 1 and 2: source and destination (0 .. 127)."""
    return s.as_int(1, 0, MAX_ADDRESS), s.as_int(2, 0, MAX_ADDRESS)


def _hex(text: str, max_bytes: int) -> bytes:
    """Hex data of at most `max_bytes` bytes (ValueError otherwise)."""
    if len(text) > 2 * max_bytes:
        raise ValueError(f"more than {max_bytes} bytes of data")
    return bytes.fromhex(text)


# sentence id (whatever the talker) -> its handler
_HANDLERS: dict[str, Callable[[MMDriver, NMEASentence], None]] = {
    "REV": MMDriver._on_rev,
    "ERR": MMDriver._on_err,
    "CFG": MMDriver._on_cfg,
    "CLK": MMDriver._on_clk,
    "TMS": MMDriver._on_tms,
    "TMQ": MMDriver._on_tmq,
    "CYC": MMDriver._on_cyc,
    "DRQ": MMDriver._on_drq,
    "XST": MMDriver._on_xst,
    "ACK": MMDriver._on_ack,
    "RXD": MMDriver._on_rxd,
    "MSG": MMDriver._on_msg,
    "CST": MMDriver._on_cst,
    "MPR": MMDriver._on_mpr,
    "MPA": MMDriver._on_mpa,
    "RDP": MMDriver._on_rdp,
    "MUA": MMDriver._on_mua,
    "MER": MMDriver._on_mer,
    "TTA": MMDriver._on_tta,
}


# Micro-Modem transmission type -> the method that starts it by sending its sentences
_SIMPLE_INITIATORS: dict[int, Callable[[MMDriver, acomms_pb.ModemTransmission], None]] = {
    acomms_pb.MICROMODEM_REMUS_LBL_RANGING: MMDriver._initiate_remus_lbl,
    acomms_pb.MICROMODEM_NARROWBAND_LBL_RANGING: MMDriver._initiate_narrowband_lbl,
    acomms_pb.MICROMODEM_GENERIC_LBL_RANGING: MMDriver._initiate_generic_lbl,
    acomms_pb.MICROMODEM_HARDWARE_CONTROL: MMDriver._initiate_hardware_control,
    acomms_pb.MICROMODEM_FM_SWEEP: MMDriver._initiate_fm_sweep,
    acomms_pb.MICROMODEM_M_SEQUENCE: MMDriver._initiate_m_sequence,
}
