"""A Bluefin vehicle (Huxley) for a payload to talk to, sans-I/O: `HuxleySimulator`.

Fed the payload's lines (`handle_line(line, now)`) and ticked (`tick(now)`, as often as the
caller likes: it decides itself what is due), it returns the lines to send; `now` is UNIX time
in seconds (the caller's clock, warped or virtual). `connect(now)` starts a new payload
session: nothing is logged until asked for.

How it answers, as a Huxley running a mission with a payload-controlled segment:

* `$BPLOG,<name>,ON|OFF` turns sending `$BF<name>` on or off; only logged sentences are sent.
  Every `$BP...` sentence is acknowledged with `$BFACK` while ACK is logged (ACK,ON is itself
  acknowledged): status 2 (done), 0 for a sentence it does not know, 1 for a set-point
  (`$BPRMB`) outside payload control; `$BPTRM`/`$BPBOY` first get 3 (pending), then on the
  next tick 2 and a `$BFTRM`/`$BFBOY` report.
* Payload control, a state machine: `control_delay` s after the session starts the mission is
  Running (`$BFMIS,<t>,<mission>,Running`) and payload control begins (`$BFMSC,<t>,<text>` and
  `$BFCTL,<t>,1`); after `control_duration` s (0: never) it ends (`$BFCTL,<t>,0`, then
  `$BFMIS,<t>,<mission>,Stopped`). `$BPRCE`/`$BPABT` end it at once.
* `$BPRMB,<t>,<heading|rudder>,<depth|altitude|pitch>,<kind>,<speed|rpm>,<kind>,<kind>` during
  payload control sets the desired heading, depth and speed (rpm / `rpm_per_mps`); the stop form
  (rudder, pitch, rpm 0) stops the vehicle. Out of payload control the vehicle holds its course.
* Every 1/`nav_rate` s: `$BFNVG` (position, depth, heading; quality 0) and `$BFNVR` (east/north
  velocities), and `$BFRVL`, from the vehicle model (`BasicFrontSeatSimulator`'s dynamics:
  rate-limited heading, depth and speed on a local grid round `lat`, `lon`).

Faults (all off by default): `nav_stop_after` s without any more NVG/NVR; `nak` (sentence ids
answered with status 1, e.g. {"RMB"}); `no_ack` (never acknowledge); `drop_after` s into the
first session, `drop_due` asks the server to close the connection (once: the payload's
reconnection then stays up); `clock_skew` s added to every timestamp it writes.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

from pygoby.frontseat.bluefin import sentences
from pygoby.frontseat.bluefin.sentences import NMEAError, NMEASentence
from pygoby.frontseat.simulator.core import BasicFrontSeatSimulator, DesiredCourse
from pygoby.frontseat.simulator.protocol import Start
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.kinematics import wrap_heading

log = logging.getLogger(__name__)

# $BFACK status
ACK_INVALID, ACK_FAILED, ACK_SUCCESS, ACK_PENDING = 0, 1, 2, 3

# the $BP sentences it acts on or simply acknowledges
KNOWN = frozenset(
    {"LOG", "STS", "RMB", "CTD", "TRM", "BOY", "SIL", "RCE", "RCB", "ABT", "SMC", "TMR", "DCL"}
)


@dataclass
class HuxleyOptions:
    lat: float = 44.0888889
    lon: float = 9.84861111
    nav_rate: float = 5.0  # NVG+NVR per second
    control_delay: float = 2.0  # s from session start to payload control
    control_duration: float = 0.0  # s of payload control (0: until the session ends)
    mission: str = "payload_mission"
    rpm_per_mps: float = 500.0
    accel: float = 0.5  # m/s^2, vehicle model
    hdg_rate: float = 45.0  # deg/s
    z_rate: float = 2.0  # m/s
    # faults
    nav_stop_after: float | None = None
    nak: frozenset[str] = field(default_factory=frozenset)
    no_ack: bool = False
    drop_after: float | None = None
    clock_skew: float = 0.0


class HuxleySimulator:
    """A Huxley's side of the Standard Payload Interface for one payload session at a time."""

    def __init__(self, options: HuxleyOptions | None = None) -> None:
        self.options = options if options is not None else HuxleyOptions()
        opts = self.options
        self.model = BasicFrontSeatSimulator()  # its dynamics are the vehicle model
        self.model.params = Start(
            lat=opts.lat, lon=opts.lon, accel=opts.accel, hdg_rate=opts.hdg_rate, z_rate=opts.z_rate
        )
        self.model.datum = UTMGeodesy(opts.lat, opts.lon)
        self.logging: set[str] = set()
        self.session_start: float | None = None
        self.in_control = False
        self.control_done = False
        self.last_model_time: float | None = None
        self.last_nav: float | None = None
        self._dropped = False
        self._reports_due: list[str] = []  # TRM/BOY: the final ACK and report come next tick
        self.received: list[NMEASentence] = []  # every valid sentence from the payload

    # --- session -------------------------------------------------------------------------

    def connect(self, now: float) -> list[str]:
        """A payload connected: a fresh session (no logging, control state machine restarts;
        the vehicle keeps moving)."""
        self.logging.clear()
        self.session_start = now
        self.in_control = False
        self.control_done = False
        self.last_nav = None
        self._reports_due.clear()
        return []

    def disconnect(self) -> None:
        self.session_start = None
        self.in_control = False

    def drop_due(self, now: float) -> bool:
        """True once when the `drop_after` fault wants the connection closed."""
        after = self.options.drop_after
        if after is None or self.session_start is None or self._dropped:
            return False
        if now >= self.session_start + after:
            self._dropped = True
            return True
        return False

    # --- payload -> vehicle --------------------------------------------------------------

    def handle_line(self, line: str, now: float) -> list[str]:
        try:
            sentence = sentences.parse(line)
        except NMEAError as exc:
            log.warning("invalid line from the payload %r: %s", line, exc)
            return []
        if sentence.talker_id != sentences.TALKER_PAYLOAD:
            log.warning("not a payload sentence: %r", line)
            return []
        self.received.append(sentence)
        kind = sentence.sentence_id
        out: list[str] = []
        status, text = ACK_SUCCESS, ""
        if kind not in KNOWN:
            status, text = ACK_INVALID, "unknown sentence"
        elif kind == "LOG":
            status, text = self._log_request(sentence)
        elif kind == "RMB":
            status, text = self._set_point(sentence)
        elif kind in ("TRM", "BOY"):
            status = ACK_PENDING
            self._reports_due.append(kind)
        elif kind in ("RCE", "ABT") and self.in_control:
            out += self._end_control(now)
        if kind in self.options.nak:
            status, text = ACK_FAILED, "simulated failure"
        ack = self._ack(sentence, status, text, now)
        return ack + out

    def _log_request(self, sentence: NMEASentence) -> tuple[int, str]:
        if len(sentence) < 3 or sentence[2] not in ("ON", "OFF"):
            return ACK_INVALID, "expected a sentence name and ON or OFF"
        name = sentence[1].upper()
        if sentence[2] == "ON":
            self.logging.add(name)
        else:
            self.logging.discard(name)
        return ACK_SUCCESS, ""

    def _set_point(self, sentence: NMEASentence) -> tuple[int, str]:
        try:
            values = [float(sentence[i]) for i in range(2, 8)]
        except (IndexError, ValueError):
            return ACK_INVALID, "expected 6 numbers"
        if not self.in_control:
            return ACK_FAILED, "payload is not in control"
        first, second, second_kind, thrust, thrust_kind, first_kind = values
        if not all(math.isfinite(v) for v in values):
            return ACK_INVALID, "not a finite number"
        speed = thrust if thrust_kind == 1 else thrust / self.options.rpm_per_mps
        desired = self.model.desired
        heading = desired.heading if first_kind == 1 else wrap_heading(first)  # 1: rudder
        z = -second if second_kind == 0 else desired.z  # 0: depth; altitude/pitch not modelled
        self.model.desired = DesiredCourse(z=z, speed=max(0.0, speed), heading=heading)
        return ACK_SUCCESS, ""

    def _ack(self, sentence: NMEASentence, status: int, text: str, now: float) -> list[str]:
        acking = "ACK" in self.logging or (
            sentence.sentence_id == "LOG" and len(sentence) > 1 and sentence[1].upper() == "ACK"
        )
        if self.options.no_ack or not acking:
            return []
        sent_at = sentence[1] if sentence.sentence_id != "LOG" and len(sentence) > 1 else ""
        values = (self._t(now), sentence.sentence_id, sent_at, "", status, "", text)
        return [sentences.build("$BFACK", values).message()]

    # --- vehicle -> payload --------------------------------------------------------------

    def tick(self, now: float) -> list[str]:
        out: list[str] = []
        self._advance(now)
        if self.session_start is None:
            return out
        for kind in self._reports_due:
            out += self._report(kind, now)
        self._reports_due.clear()
        out += self._control_state(now)
        out += self._navigation(now)
        return out

    def _advance(self, now: float) -> None:
        if self.last_model_time is not None and now > self.last_model_time:
            self.model.step(now - self.last_model_time)
        self.last_model_time = now

    def _report(self, kind: str, now: float) -> list[str]:
        out: list[str] = []
        if "ACK" in self.logging and not self.options.no_ack:
            values = (self._t(now), kind, "", "", ACK_SUCCESS, "", "")
            out.append(sentences.build("$BFACK", values).message())
        if kind in self.logging:
            if kind == "TRM":  # completed successfully, no error, pitch/roll trim
                values2: tuple[object, ...] = (self._t(now), 2, 0, "trim done", 0.5, 0.0)
            else:  # BOY: completed successfully, no error, buoyancy estimate (N)
                values2 = (self._t(now), 2, 0, "buoyancy done", 1.5)
            out.append(sentences.build(f"$BF{kind}", values2).message())
        return out

    def _control_state(self, now: float) -> list[str]:
        assert self.session_start is not None
        opts = self.options
        start = self.session_start + opts.control_delay
        if not self.in_control and not self.control_done and now >= start:
            self.in_control = True
            log.info("payload control on")
            return [
                *self._send("MIS", (self._t(now), opts.mission, "Running")),
                *self._send("MSC", (self._t(now), "payload control")),
                *self._send("CTL", (self._t(now), 1)),
            ]
        if self.in_control and opts.control_duration > 0 and now >= start + opts.control_duration:
            return self._end_control(now)
        return []

    def _end_control(self, now: float) -> list[str]:
        self.in_control = False
        self.control_done = True
        log.info("payload control off: the vehicle holds its course")
        return [
            *self._send("CTL", (self._t(now), 0)),
            *self._send("MIS", (self._t(now), self.options.mission, "Stopped")),
        ]

    def _navigation(self, now: float) -> list[str]:
        opts = self.options
        assert self.session_start is not None
        if opts.nav_stop_after is not None and now >= self.session_start + opts.nav_stop_after:
            return []
        if self.last_nav is not None and now < self.last_nav + 1.0 / opts.nav_rate:
            return []
        self.last_nav = now
        nav = self.model.nav()
        lat, ns = sentences.latitude(nav.lat)
        lon, ew = sentences.longitude(nav.lon)
        t = self._t(now)
        theta = math.radians(90.0 - nav.heading)
        east, north = nav.speed * math.cos(theta), nav.speed * math.sin(theta)
        nvg = (t, lat, ns, lon, ew, 0, "-1.000", _fixed(nav.depth), _fixed(nav.heading), 0, 0, t)
        nvr = (t, _fixed(east), _fixed(north), 0, 0, 0, 0)
        rvl = (t, _fixed(nav.speed * opts.rpm_per_mps), _fixed(nav.speed))
        return [*self._send("NVG", nvg), *self._send("NVR", nvr), *self._send("RVL", rvl)]

    def _send(self, kind: str, values: tuple[object, ...]) -> list[str]:
        if kind not in self.logging:
            return []
        return [sentences.build(f"$BF{kind}", values).message()]

    def _t(self, now: float) -> str:
        return sentences.time_of_day(now + self.options.clock_skew)


def _fixed(value: float) -> str:
    """A navigation number as Huxley prints it: three decimals (never "-0.000")."""
    text = f"{value:.3f}"
    return "0.000" if text == "-0.000" else text
