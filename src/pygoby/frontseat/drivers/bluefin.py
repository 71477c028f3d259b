"""The Bluefin frontseat driver: iFrontSeat on a Bluefin AUV's Huxley computer, over the Bluefin
Standard Payload Interface (SPI 1.8 and newer), as goby3's `libgoby_frontseat_bluefin` does.

Configuration: the `bluefin_config` extension (1000) of the frontseat Config
(goby/middleware/frontseat/bluefin/bluefin_config.proto). Transport: a TCP client to
`huxley_tcp_address:huxley_tcp_port`, reconnecting every `reconnect_interval` s; NMEA sentences
(`pygoby.frontseat.bluefin.sentences`).

Start-up (each new connection): the frontseat becomes IDLE, both queues are emptied and the
driver asks for the sentences it reads, one `$BPLOG,<name>,ON` each: ACK first (unless
`disable_ack`), then NVG MIS MSC NVR SVS RVL SHT TOP MBS MBE CTD DVL BOY TRM, CTL when
`accepting_commands_hook` is BFCTL_TRIGGER, then every `extra_bplog` (upper-cased).

Writing: sentences wait in one queue and go out one at a time; each waits for its `$BFACK`
(none with `disable_ack`). Without an ACK after `nmea_resend_interval` s the sentence is written
again, and after `nmea_resend_attempts` writes it is dropped with a demerit; any received
sentence clears the demerits. More than `allowed_nmea_demerits` -> FRONTSEAT_NOT_CONNECTED and
the interface's FS_ERROR (ERROR_FRONTSEAT_IGNORING_COMMANDS); the next tick starts up again.
`$BPSTS,<t>,<1 ok|0>,<status>` is queued every `heartbeat_interval` s: ok unless the interface
is in an error state or a payload status (IFS_DATA_OUT's `payload_status`, kept until its
`expire_time`) is not all_ok; status "Deploy", or the time followed by "; <msg>" per payload id.

`$BFACK,<t>,<sentence>,<t sent>,<insert id>,<status>,<future>,<description>`: status 2 success,
0 invalid, 1 failed (both NAKs: not resent), 3 pending (the sentence waits in a pending queue
for its final ACK). It must name the front of the write queue or of the pending queue, else
both queues are emptied. A final ACK answers the outstanding request of the command behind
the sentence (RMB: desired course, TRM, BOY, SIL, RCB/RCE: cancel behaviour or mission end,
ABT, SMC) with a CommandResponse (unsuccessful ones carry the status as error_code and the
description as error_string).

Reading: NVG starts a new NodeStatus (position, GPS when quality is 1, altitude, depth,
heading, roll, pitch, time = its computed-at timestamp) and marks data as arriving; NVR adds
speed over ground (from the east/north velocities) and the rates, completes it
(`compute_missing`) and emits it. CTD -> a CTDSample (uS/cm -> S/m, kPa -> Pa; the rest
computed); RVL, DVL, BOY, TRM -> the `bluefin_data` extension. The frontseat state: BFMSC_TRIGGER
-> `$BFMSC` means ACCEPTING_COMMANDS; BFMIS_RUNNING_TRIGGER -> a `$BFMIS` whose status says
"Running"; BFCTL_TRIGGER -> `$BFCTL,<t>,1` (`,0` gives control back: IN_CONTROL). A `$BFMIS`
saying Running gives IN_CONTROL under the other hooks (unless already accepting), any other
`$BFMIS` IDLE. No `$BFNVG` for `allow_missing_nav_interval` s: not providing data.

Commands: a desired course -> `$BPRMB,<t>,<heading>,<depth>,0,<speed>,1,0` (or
`<rpm>,0` interpolated in `rpm_table` with `use_rpm_table_for_speed`); a speed under 0.01 m/s,
or both depth and speed under 1 (goby3 compares them truncated to integers: reproduced,
QUIRKS.md Q-BLUEFIN-1) -> the stop request `$BPRMB,<t>,0,0,2,0,0,1`. The BluefinExtraCommands
extension -> `$BPTRM`, `$BPBOY`, `$BPSIL,<t>,<mode>`, `$BPRCE,<t>,0` (cancel behaviour and
mission end), `$BPABT,<t>,backseat abort,<reason>`, `$BPSMC,<t>,1`; a desired course in the same
request is then ignored. `cancel_request_id` forgets that outstanding request. Data to the
frontseat: a CTD sample -> `$BPCTD` (10 significant digits), `dccl_message` -> `$BPDCL` (base64),
the modem's incoming sentence -> `$BPTMR,<t>,3,<text with , as : and * as />` (if
`send_tmr_messages`). Raw text from other processes is written as a sentence (its checksum
recomputed).

Differences from goby3 (QUIRKS.md Q-BLUEFIN-2 to Q-BLUEFIN-7, Q-BLUEFIN-10, Q-BLUEFIN-12): the heartbeat
really comes every `heartbeat_interval` s; only `$BFNVG` counts as data arriving (not `$BFACK`);
an ACK resets the resend count and a mismatched ACK ends the wait; the ACKs of RCE, ABT and SMC
answer their requests; a sentence that cannot be read (missing or non-numeric field) is logged
and skipped; the write queue holds at most MAX_QUEUE sentences; `$BPSTS` shows each payload's
latest status; lines still buffered from a lost connection are discarded (Q-BLUEFIN-12).
Reproduced: the stop request above (Q-BLUEFIN-1), `dvl_time` (Q-BLUEFIN-8), one
sentence freed per tick (Q-BLUEFIN-9).
"""

from __future__ import annotations

import base64
import bisect
import logging
import math
import time
from collections import deque
from typing import Any

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.bluefin import sentences
from pygoby.frontseat.bluefin.sentences import NMEAError, NMEASentence
from pygoby.frontseat.drivers.linked import CONNECT_TIMEOUT, LinkedFrontSeat
from pygoby.frontseat.errors import BluefinConfigError, FrontSeatDriverError
from pygoby.util.clock import Clock
from pygoby.util.errors import LinkClosedError
from pygoby.util.linebased import LineLink

_log = logging.getLogger(__name__)

MAX_QUEUE = 200  # sentences waiting to be written; beyond, the oldest after the front are dropped

BFCFG = frontseat_pb.BluefinConfig
BFCMD = frontseat_pb.BluefinExtraCommands

# $BPLOG requests after ACK, in goby3's order
LOG_REQUESTS = (
    "NVG",
    "MIS",
    "MSC",
    "NVR",
    "SVS",
    "RVL",
    "SHT",
    "TOP",
    "MBS",
    "MBE",
    "CTD",
    "DVL",
    "BOY",
    "TRM",
)

# $BFACK status
ACK_INVALID, ACK_FAILED, ACK_SUCCESS, ACK_PENDING = 0, 1, 2, 3

# Which command an acknowledged sentence carried (RCE: cancel behaviour, or else mission end).
ACKED_COMMANDS: dict[str, tuple[int, ...]] = {
    "RMB": (BFCMD.DESIRED_COURSE,),
    "BOY": (BFCMD.BUOYANCY_ADJUST,),
    "TRM": (BFCMD.TRIM_ADJUST,),
    "SIL": (BFCMD.SILENT_MODE,),
    "RCB": (BFCMD.CANCEL_CURRENT_BEHAVIOR,),
    "RCE": (BFCMD.CANCEL_CURRENT_BEHAVIOR, BFCMD.MISSION_END_CONFIRM),
    "ABT": (BFCMD.ABORT_MISSION,),
    "SMC": (BFCMD.MISSION_START_CONFIRM,),
}

TRANSPORT_ACOUSTIC_MODEM = 3  # $BPTMR's transport field


def bluefin_config(cfg: Any) -> Any:
    """The `bluefin_config` of a frontseat Config, checked (BluefinConfigError)."""
    if not cfg.HasExtension(frontseat_pb.BLUEFIN_CONFIG):
        raise BluefinConfigError(
            "has no [goby.middleware.frontseat.protobuf.bluefin_config]", field="frontseat_cfg"
        )
    bf = cfg.Extensions[frontseat_pb.BLUEFIN_CONFIG]
    missing = bf.FindInitializationErrors()
    if missing:
        raise BluefinConfigError(f"lacks required {', '.join(missing)}", field="bluefin_config")
    if bf.use_rpm_table_for_speed and len(bf.rpm_table) < 2:
        raise BluefinConfigError(
            "needs at least two rpm_table entries with use_rpm_table_for_speed: true",
            field="rpm_table",
        )
    return bf


def rpm_for_speed(speed: float, table: list[tuple[float, int]]) -> int:
    """The RPM for `speed` in `table` (sorted (speed, rpm) pairs, speeds unique): linear
    between entries, clipped to the first and last, truncated to an integer (as goby3)."""
    speeds = [s for s, _ in table]
    upper = bisect.bisect_right(speeds, speed)
    if upper == len(table):
        return table[-1][1]
    if upper == 0:
        return table[0][1]
    (s0, r0), (s1, r1) = table[upper - 1], table[upper]
    return int((speed - s0) / (s1 - s0) * (r1 - r0) + r0)


def _read_status_and_error(sentence: NMEASentence, report: Any) -> None:
    """Fields 2 and 3 of $BFBOY/$BFTRM into a BuoyancyStatus/TrimStatus's `status` and `error`
    (a number the enum lacks leaves the field unset)."""
    enums = report.DESCRIPTOR.fields_by_name
    for name, index in (("status", 2), ("error", 3)):
        number = sentences.required_int(sentence, index)
        if enums[name].enum_type.values_by_number.get(number) is not None:
            setattr(report, name, number)


class BluefinFrontSeat(LinkedFrontSeat):
    """Frontseat driver for a Bluefin Huxley (Standard Payload Interface)."""

    peer = "Huxley"

    def __init__(
        self,
        cfg: Any,
        clock: Clock | None = None,
        *,
        link: LineLink | None = None,
        connect_timeout: float = CONNECT_TIMEOUT,
    ) -> None:
        super().__init__(cfg, clock, connect_timeout=connect_timeout)
        self.bf = bluefin_config(self.cfg)
        self._attach_link(
            link, self.bf.huxley_tcp_address, self.bf.huxley_tcp_port, self.bf.reconnect_interval
        )
        table: dict[float, int] = {}
        for entry in self.bf.rpm_table:
            table.setdefault(entry.speed, entry.rpm)  # a repeated speed keeps its first rpm
        self.rpm_table = sorted(table.items())

        self._connection: int | None = None  # link.connections at the last start-up
        self._last_heartbeat: float | None = None
        self.out: deque[NMEASentence] = deque()  # to write; the front waits for its ACK
        self.pending: deque[NMEASentence] = deque()  # ACKed as pending, waiting for the final ACK
        self._waiting = False
        self._last_write = 0.0
        self._fail_count = 0
        self._demerits = 0
        self._status: Any = None  # the NodeStatus of the last $BFNVG
        self.outstanding: dict[int, Any] = {}  # BluefinCommand -> CommandRequest
        self.payload_status: list[Any] = []  # BluefinExtraData.PayloadStatus

    # --- InterfaceBase hooks -------------------------------------------------------------------

    def loop(self) -> None:
        if not self.link.is_open:
            if self._frontseat_state != frontseat_pb.FRONTSEAT_NOT_CONNECTED:
                self.log.warning("lost Huxley at %s; reconnecting", self.address)
            self._frontseat_state = frontseat_pb.FRONTSEAT_NOT_CONNECTED
        else:
            connection = getattr(self.link, "connections", None)
            if connection != self._connection:  # a new connection: what is buffered is stale
                self._connection = connection
                self._frontseat_state = frontseat_pb.FRONTSEAT_NOT_CONNECTED
                self.link.read_lines()
            if self._frontseat_state == frontseat_pb.FRONTSEAT_NOT_CONNECTED:
                self.log.info("connected to Huxley at %s", self.address)
                self._frontseat_state = frontseat_pb.FRONTSEAT_IDLE
                self._initialize_huxley()
            self._check_heartbeat()
            self._try_send()
            for line in self.link.read_lines():
                self._receive(line)
        missing_nav = self.bf.allow_missing_nav_interval
        if self._last_nav_time is None or self.clock.now() > self._last_nav_time + missing_nav:
            self._providing_data = False

    def send_command_to_frontseat(self, command: Any) -> None:
        if command.HasField("cancel_request_id"):
            self._cancel(command.cancel_request_id)
            return
        kind = BFCMD.UNKNOWN_COMMAND
        if command.HasExtension(frontseat_pb.BLUEFIN_COMMAND):
            extra = command.Extensions[frontseat_pb.BLUEFIN_COMMAND]
            kind = extra.command
            sentence = self._extra_command(extra)
            if sentence is not None:
                self._queue(sentence)
        if command.HasField("desired_course"):
            if kind not in (BFCMD.UNKNOWN_COMMAND, BFCMD.DESIRED_COURSE):
                self.log.warning(
                    "desired course ignored: the request carries the extra command %s "
                    "(one command per request)",
                    BFCMD.BluefinCommand.Name(kind),
                )
            else:
                kind = BFCMD.DESIRED_COURSE
                self._queue(self._desired_course(command.desired_course))
        if not self.bf.disable_ack and command.response_requested:
            if kind in self.outstanding:
                self.log.warning(
                    "a %s request is already outstanding; the new one replaces it",
                    BFCMD.BluefinCommand.Name(kind),
                )
            request = type(command)()
            request.CopyFrom(command)
            self.outstanding[kind] = request

    def send_data_to_frontseat(self, data: Any) -> None:
        now = sentences.time_of_day(self.clock.now())
        if data.HasField("ctd_sample"):
            self._queue_values("$BPCTD", (now, *_ctd_fields(data.ctd_sample)))
        if data.HasField("dccl_message"):
            self._queue_values("$BPDCL", (now, base64.b64encode(data.dccl_message).decode("ascii")))
        if data.HasExtension(frontseat_pb.BLUEFIN_DATA):
            extra = data.Extensions[frontseat_pb.BLUEFIN_DATA]
            if extra.HasField("micro_modem_raw_in") and self.bf.send_tmr_messages:
                text = extra.micro_modem_raw_in.raw.decode("latin-1")
                for old, new in ((",", ":"), ("*", "/"), ("\r", " "), ("\n", " ")):
                    text = text.replace(old, new)
                self._queue_values("$BPTMR", (now, TRANSPORT_ACOUSTIC_MODEM, text))
            for status in extra.payload_status:
                copy = type(status)()
                copy.CopyFrom(status)
                self.payload_status.append(copy)

    def send_raw_to_frontseat(self, raw: Any) -> None:
        text = raw.raw.decode("latin-1")
        try:
            self._queue(sentences.parse_unchecked(text))
        except NMEAError as exc:
            self.log.warning("not sending this invalid sentence %r: %s", text, exc)

    # --- writing -------------------------------------------------------------------------------

    def _initialize_huxley(self) -> None:
        self._demerits = 0
        self._waiting = False
        self._fail_count = 0
        self.out.clear()
        self.pending.clear()
        self._status = None
        names = [] if self.bf.disable_ack else ["ACK"]  # ACK first: the others are then ACKed
        names += LOG_REQUESTS
        if self.bf.accepting_commands_hook == BFCFG.BFCTL_TRIGGER:
            names.append("CTL")
        names += [name.upper() for name in self.bf.extra_bplog]
        for name in names:
            self._queue_values("$BPLOG", (name, "ON"))

    def _check_heartbeat(self) -> None:
        now = self.clock.now()
        if (
            self._last_heartbeat is not None
            and now < self._last_heartbeat + self.bf.heartbeat_interval
        ):
            return
        self._last_heartbeat = now
        ok = self.state not in frontseat_pb.ERROR_STATES
        now_us = now * 1e6
        self.payload_status = [s for s in self.payload_status if s.expire_time > now_us]
        newest: dict[int, Any] = {}
        for status in self.payload_status:  # the latest given for each id
            newest[status.id] = status
        text = "Deploy"
        if newest:
            ok = ok and all(s.all_ok for s in newest.values())
            text = "; ".join([_utc_text(now), *(newest[i].msg for i in sorted(newest))])
        self._queue_values("$BPSTS", (sentences.time_of_day(now), 1 if ok else 0, text))

    def _queue_values(self, token: str, values: tuple[object, ...]) -> None:
        try:
            self._queue(sentences.build(token, values))
        except NMEAError as exc:
            self.log.warning("cannot write %s %r: %s", token, values, exc)

    def _queue(self, sentence: NMEASentence) -> None:
        if len(self.out) >= MAX_QUEUE:
            dropped = self.out[1] if len(self.out) > 1 else self.out[0]
            self.out.remove(dropped)
            self.log.warning("write queue full (%d): dropped %s", MAX_QUEUE, dropped.message())
        self.out.append(sentence)
        if not self._waiting:  # write it now rather than at the next tick
            self._write_front()

    def _try_send(self) -> None:
        if not self.out:
            return
        if not self._waiting:
            self._write_front()
            return
        if self.clock.now() < self._last_write + self.bf.nmea_resend_interval:
            return
        self._fail_count += 1
        if self._fail_count < self.bf.nmea_resend_attempts:
            self.log.info(
                "no $BFACK in %d s: writing %s again",
                self.bf.nmea_resend_interval,
                self.out[0].message(),
            )
            self._write_front()
            return
        self.log.warning(
            "Huxley did not acknowledge %s after %d writes: dropped",
            self.out[0].message(),
            self.bf.nmea_resend_attempts,
        )
        self._pop_front()
        self._demerits += 1
        if self._demerits > self.bf.allowed_nmea_demerits:
            self._frontseat_state = frontseat_pb.FRONTSEAT_NOT_CONNECTED
            raise FrontSeatDriverError(
                frontseat_error=frontseat_pb.ERROR_FRONTSEAT_IGNORING_COMMANDS,
                message=f"Huxley is connected but acknowledged none of {self._demerits} sentences",
            )

    def _pop_front(self) -> None:
        self._waiting = False
        self._fail_count = 0
        if self.out:
            self.out.popleft()

    def _write_front(self) -> None:
        if not self.out or not self.link.is_open:
            return
        sentence = self.out[0]
        text = sentence.message()
        self.signal_raw_to_frontseat(
            frontseat_pb.Raw(raw=text.encode("latin-1"), description=_description(sentence))
        )
        try:
            self.link.write(text + "\r\n")
        except LinkClosedError as exc:
            self.log.warning("not written (%s): %s", exc, text)
            return
        if self.bf.disable_ack:
            self._pop_front()
            if self.out:
                self._write_front()
        else:
            self._waiting = True
            self._last_write = self.clock.now()

    # --- commands ------------------------------------------------------------------------------

    def _cancel(self, request_id: int) -> None:
        for kind, request in self.outstanding.items():
            if request.request_id == request_id:
                del self.outstanding[kind]
                self.log.debug("cancelled request %d", request_id)
                return
        self.log.warning("cannot cancel request %d: no such request outstanding", request_id)

    def _extra_command(self, extra: Any) -> NMEASentence | None:
        now = sentences.time_of_day(self.clock.now())
        kind = extra.command
        if kind == BFCMD.TRIM_ADJUST:
            return sentences.build("$BPTRM", (now,))
        if kind == BFCMD.BUOYANCY_ADJUST:
            return sentences.build("$BPBOY", (now,))
        if kind == BFCMD.SILENT_MODE:
            return sentences.build("$BPSIL", (now, int(extra.silent_mode)))
        if kind in (BFCMD.CANCEL_CURRENT_BEHAVIOR, BFCMD.MISSION_END_CONFIRM):
            return sentences.build("$BPRCE", (now, 0))
        if kind == BFCMD.ABORT_MISSION:
            return sentences.build("$BPABT", (now, "backseat abort", int(extra.abort_reason)))
        if kind == BFCMD.MISSION_START_CONFIRM:
            return sentences.build("$BPSMC", (now, 1))  # goby3 always confirms success
        return None  # UNKNOWN_COMMAND, DESIRED_COURSE: nothing of their own to send

    def _desired_course(self, course: Any) -> NMEASentence:
        now = sentences.time_of_day(self.clock.now())
        stop = (now, 0, 0, 2, 0, 0, 1)  # rudder 0, pitch 0 (2: pitch), rpm 0 (0: rpm), 1: rudder
        if _truncates_to_zero(course.depth) and _truncates_to_zero(course.speed):
            if course.speed >= 0.01:
                self.log.warning(
                    "depth %g and speed %g are both under 1: the stop request is sent (as goby3)",
                    course.depth,
                    course.speed,
                )
            return sentences.build("$BPRMB", stop)
        if not course.speed >= 0.01:
            return sentences.build("$BPRMB", stop)
        if self.bf.use_rpm_table_for_speed:
            thrust: tuple[object, ...] = (rpm_for_speed(course.speed, self.rpm_table), 0)
        else:
            thrust = (float(course.speed), 1)  # 1: speed, not rpm
        # 0 after depth: a depth (not altitude 1 or pitch 2); last 0: a heading (not rudder)
        values = (now, float(course.heading), float(course.depth), 0, *thrust, 0)
        return sentences.build("$BPRMB", values)

    # --- reading -------------------------------------------------------------------------------

    def _receive(self, line: str) -> None:
        line = line.strip()
        if not line:
            return
        try:
            sentence = sentences.parse(line)
        except NMEAError as exc:
            self.log.warning("skipping a bad line from Huxley %r: %s", line, exc)
            return
        self.signal_raw_from_frontseat(
            frontseat_pb.Raw(
                raw=sentence.message().encode("latin-1"), description=_description(sentence)
            )
        )
        self._demerits = 0
        handler = _HANDLERS.get(sentence.sentence_id)
        if handler is None:
            return
        try:
            handler(self, sentence)
        except NMEAError as exc:
            self.log.warning("skipping %s: %s", sentence.fields[0], exc)

    def _bfack(self, sentence: NMEASentence) -> None:
        acked = sentences.field(sentence, 2).upper()
        status = sentences.required_int(sentence, 5)
        description = sentence[7] if len(sentence) > 7 else ""
        if status == ACK_INVALID:
            self.log.warning("Huxley says our %s request was invalid", acked)
        elif status == ACK_FAILED:
            self.log.warning("Huxley could not process our %s request: %r", acked, description)
        elif status == ACK_PENDING:
            self.log.info("Huxley says our %s request is pending", acked)
            if self.out:
                self.pending.append(self.out[0])
        self._waiting = False
        self._fail_count = 0
        if self.out and self.out[0].sentence_id.upper() == acked:
            self.out.popleft()
        elif self.pending and self.pending[0].sentence_id.upper() == acked:
            self.pending.popleft()
        else:
            self.log.warning(
                "$BFACK for %s, which heads neither the write nor the pending queue: both emptied",
                acked,
            )
            self.out.clear()
            self.pending.clear()
            return
        if status != ACK_PENDING:
            self._answer_request(acked, status, description)

    def _answer_request(self, acked: str, status: int, description: str) -> None:
        for kind in ACKED_COMMANDS.get(acked, ()):
            request = self.outstanding.pop(kind, None)
            if request is None:
                continue
            response = frontseat_pb.CommandResponse(
                request_successful=status == ACK_SUCCESS, request_id=request.request_id
            )
            if status != ACK_SUCCESS:
                response.error_code = status
                response.error_string = description
            self.signal_command_response(response)
            return

    def _bfnvg(self, sentence: NMEASentence) -> None:
        field = sentences.field
        status = frontseat_pb.NodeStatus()
        lat = sentences.parse_angle(field(sentence, 2), field(sentence, 3), 2, "S")
        lon = sentences.parse_angle(field(sentence, 4), field(sentence, 5), 3, "W")
        if math.isnan(lat) or math.isnan(lon):
            raise sentences.NMEAError(f"no position in {sentence.message()!r}")
        status.global_fix.lat, status.global_fix.lon = lat, lon
        quality = sentences.optional_float(sentence, 6)
        if quality == 1:
            status.source.position = frontseat_pb.Source.GPS
        for index, message, name in (
            (7, status.global_fix, "altitude"),
            (8, status.global_fix, "depth"),
            (9, status.pose, "heading"),
            (10, status.pose, "roll"),
            (11, status.pose, "pitch"),
        ):
            value = sentences.optional_float(sentence, index)
            if value is not None:
                setattr(message, name, value)
        computed = sentences.parse_time_of_day(field(sentence, 12), self.clock.now())
        if computed is not None:
            status.time = computed
        self._status = status
        self._providing_data = True
        self._last_nav_time = self.clock.now()

    def _bfnvr(self, sentence: NMEASentence) -> None:
        east = sentences.required_float(sentence, 2)
        north = sentences.required_float(sentence, 3)
        rates = [sentences.optional_float(sentence, i) for i in (5, 6, 7)]
        if self._status is None:
            self.log.debug("$BFNVR before any $BFNVG: no position to send yet")
            return
        data = frontseat_pb.InterfaceData()
        status = data.node_status
        status.CopyFrom(self._status)
        for name, value in zip(("pitch_rate", "roll_rate", "heading_rate"), rates, strict=True):
            if value is not None:
                setattr(status.pose, name, value)
        status.speed.over_ground = math.hypot(east, north)
        self.compute_missing(status)
        self.signal_data_from_frontseat(data)

    def _bfctd(self, sentence: NMEASentence) -> None:
        data = frontseat_pb.InterfaceData()
        ctd = data.ctd_sample
        conductivity = sentences.optional_float(sentence, 2)
        temperature = sentences.optional_float(sentence, 3)
        pressure = sentences.optional_float(sentence, 4)
        if conductivity is not None:
            ctd.conductivity = conductivity / 1e4  # uS/cm -> S/m
        if temperature is not None:
            ctd.temperature = temperature
        if pressure is not None:
            ctd.pressure = pressure * 1e3  # kPa -> Pa
        self.compute_missing_ctd(ctd)
        self.signal_data_from_frontseat(data)

    def _bfrvl(self, sentence: NMEASentence) -> None:
        data = frontseat_pb.InterfaceData()
        thruster = data.Extensions[frontseat_pb.BLUEFIN_DATA].thruster
        thruster.rotation = sentences.required_float(sentence, 2)
        speed = sentences.optional_float(sentence, 3)
        if speed is not None:
            thruster.speed_from_lookup_table = speed
        self.signal_data_from_frontseat(data)

    def _bfdvl(self, sentence: NMEASentence) -> None:
        data = frontseat_pb.InterfaceData()
        dvl = data.Extensions[frontseat_pb.BLUEFIN_DATA].dvl
        names = ("u", "v", "w", "beam1_range", "beam2_range", "beam3_range", "beam4_range")
        for index, name in enumerate((*names, "temperature", "dvl_time"), start=2):
            # dvl_time: the hhmmss.ss text read as a number, as goby3 does
            value = sentences.optional_float(sentence, index)
            if value is not None:
                setattr(dvl, name, value)
        self.signal_data_from_frontseat(data)

    def _bfboy(self, sentence: NMEASentence) -> None:
        data = frontseat_pb.InterfaceData()
        boy = data.Extensions[frontseat_pb.BLUEFIN_DATA].buoyancy_status
        _read_status_and_error(sentence, boy)
        boy.debug_string = sentences.field(sentence, 4)
        boy.buoyancy_newtons = sentences.required_float(sentence, 5)
        self.signal_data_from_frontseat(data)

    def _bftrm(self, sentence: NMEASentence) -> None:
        data = frontseat_pb.InterfaceData()
        trim = data.Extensions[frontseat_pb.BLUEFIN_DATA].trim_status
        _read_status_and_error(sentence, trim)
        trim.debug_string = sentences.field(sentence, 4)
        trim.pitch_trim_degrees = sentences.required_float(sentence, 5)
        trim.roll_trim_degrees = sentences.required_float(sentence, 6)
        self.signal_data_from_frontseat(data)

    def _bfmsc(self, sentence: NMEASentence) -> None:
        if self.bf.accepting_commands_hook == BFCFG.BFMSC_TRIGGER:
            self._frontseat_state = frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS

    def _bfmis(self, sentence: NMEASentence) -> None:
        if "Running" not in sentences.field(sentence, 3):
            self._frontseat_state = frontseat_pb.FRONTSEAT_IDLE
        elif self.bf.accepting_commands_hook == BFCFG.BFMIS_RUNNING_TRIGGER:
            self._frontseat_state = frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS
        elif self._frontseat_state != frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS:
            self._frontseat_state = frontseat_pb.FRONTSEAT_IN_CONTROL

    def _bfctl(self, sentence: NMEASentence) -> None:
        if self.bf.accepting_commands_hook != BFCFG.BFCTL_TRIGGER:
            return
        if sentences.field(sentence, 2).strip().lower() in ("1", "true"):
            self._frontseat_state = frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS
        elif self._frontseat_state == frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS:
            self._frontseat_state = frontseat_pb.FRONTSEAT_IN_CONTROL

    def _bfsht(self, sentence: NMEASentence) -> None:
        self.log.warning("Huxley sent $BFSHT: the vehicle is shutting the payload down")

    def _bfmbs(self, sentence: NMEASentence) -> None:
        self.log.info("Huxley began behavior %s", sentence[5] if len(sentence) > 5 else "?")

    def _bfmbe(self, sentence: NMEASentence) -> None:
        self.log.info("Huxley ended behavior %s", sentence[5] if len(sentence) > 5 else "?")


# Sentence id -> handler. Read but not used: SVS (sound speed is computed from the CTD) and TOP.
_HANDLERS = {
    "ACK": BluefinFrontSeat._bfack,
    "NVG": BluefinFrontSeat._bfnvg,
    "NVR": BluefinFrontSeat._bfnvr,
    "RVL": BluefinFrontSeat._bfrvl,
    "DVL": BluefinFrontSeat._bfdvl,
    "CTD": BluefinFrontSeat._bfctd,
    "MSC": BluefinFrontSeat._bfmsc,
    "SHT": BluefinFrontSeat._bfsht,
    "MBS": BluefinFrontSeat._bfmbs,
    "MIS": BluefinFrontSeat._bfmis,
    "MBE": BluefinFrontSeat._bfmbe,
    "CTL": BluefinFrontSeat._bfctl,
    "BOY": BluefinFrontSeat._bfboy,
    "TRM": BluefinFrontSeat._bftrm,
}


def _truncates_to_zero(value: float) -> bool:
    return math.isfinite(value) and abs(value) < 1.0


def _ctd_fields(ctd: Any) -> tuple[str, str, str, str]:
    """$BPCTD's conductivity (S/m), temperature (C), pressure (kPa), sample time; an absent
    or NaN value is an empty field."""

    def text(value: float) -> str:
        return "" if math.isnan(value) else f"{value:.10g}"

    conductivity = text(ctd.conductivity) if ctd.HasField("conductivity") else ""
    return (
        conductivity,
        text(ctd.temperature),
        text(ctd.pressure / 1e3),
        sentences.time_of_day(ctd.time),
    )


def _description(sentence: NMEASentence) -> str:
    return sentences.DESCRIPTIONS.get(sentence.fields[0], "")


def _utc_text(t: float) -> str:
    return time.strftime("%Y-%b-%d %H:%M:%S", time.gmtime(t))


def frontseat_driver_load(cfg: Any, clock: Clock | None = None) -> BluefinFrontSeat:
    """The plug-in factory (entry point `bluefin`, goby3's `libgoby_frontseat_bluefin.so.30`)."""
    return BluefinFrontSeat(cfg, clock)
