"""The basic (ABC) frontseat simulator, sans-I/O.

`BasicFrontSeatSimulator` is fed the lines a backseat sends (`handle_line`) and is ticked once
per control period (`tick`); both return the lines to send back to every client. The caller
owns the clock: a live server ticks every `period` wall seconds (1/(FREQ*WARP)), a test ticks
as fast as it likes.

Behaviour, as upstream goby3 basic_frontseat_simulator:

* `START` resets FREQ 10, ACCEL 0.5, HDG_RATE 45, Z_RATE 2, WARP 1 and DURATION 0 (no limit) to
  those it carries, sets the UTM datum to (LAT, LON), restarts the mission tick count and
  answers `CTRL,STATE:PAYLOAD`. The Goby 2 ABC `START,LAT:..,LON:..,DURATION:..` is a valid
  START too. The vehicle state (position, depth, speed, heading and the desired course) is NOT
  reset: x/y continue on the grid of the new datum (upstream's behaviour,
  reproduced: QUIRKS.md Q-APPS-16).
* `CMD,HEADING:h,SPEED:v,DEPTH:d` during a mission sets the desired course and answers
  `CMD,RESULT:OK`; a CMD lacking one of the three answers `CMD,RESULT:ERROR`. A CMD before any
  START or after the mission ended is not answered (logged). Unknown keys and malformed lines
  are logged and skipped.
* Each tick: count it; when a mission has a DURATION and ticks // FREQ > DURATION, answer
  `CTRL,STATE:IDLE` and end the mission (no NAV any more); otherwise advance the dynamics by
  dt = 1/FREQ and send `NAV` (all five numbers with C++ precision 10; DEPTH = -z).
* Dynamics per tick: depth z slews toward -DEPTH at Z_RATE, heading toward the desired heading
  at HDG_RATE by the shorter way, speed toward the desired speed at ACCEL (each snapping to the
  target when within one step), then x += v cos(theta) dt, y += v sin(theta) dt with
  theta = (90 - heading) deg, on the local UTM grid of the START datum.

Deviations from upstream (listed in QUIRKS.md, and bad-input handling):

* The heading is kept in [0, 360) (Q-APPS-17). Upstream lets it run past 360 (or below 0) after
  turns through north, prints e.g. HEADING:370 and, once it is more than 540 deg away from a
  new desired heading, turns the long way round. Here the desired heading is wrapped when it is
  received and the heading after every step, so the vehicle always turns the shorter way and
  NAV never shows a heading outside [0, 360).
* A CMD whose numbers are not finite decimals answers `CMD,RESULT:ERROR` and leaves the course
  unchanged (upstream reads them as NaN and the vehicle state becomes NaN for good).
* A START with a bad or out-of-range value (non-numeric, FREQ or WARP <= 0, negative rates,
  |LAT| > 90) is logged and ignored, with no reply (upstream sends PAYLOAD and runs with NaN or
  INT_MAX values).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from pygoby.frontseat.errors import SimulatorProtocolError
from pygoby.frontseat.simulator.protocol import (
    CMD_ERROR,
    CMD_OK,
    CTRL_IDLE,
    CTRL_PAYLOAD,
    KEY_CMD,
    KEY_START,
    Command,
    Message,
    Nav,
    Start,
    parse_line,
)
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.kinematics import advance, slew, turn_toward, wrap_heading

log = logging.getLogger(__name__)


@dataclass
class VehicleState:
    """Local UTM grid position (m), z (m, up; depth = -z), speed (m/s), heading (deg)."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    speed: float = 0.0
    heading: float = 0.0


@dataclass
class DesiredCourse:
    """The last commanded course; z = -DEPTH."""

    z: float = 0.0
    speed: float = 0.0
    heading: float = 0.0


class BasicFrontSeatSimulator:
    """START/CMD in, CTRL/NAV/CMD-result out, one `tick()` per control period."""

    def __init__(self) -> None:
        self.vehicle = VehicleState()
        self.desired = DesiredCourse()
        self.params = Start(lat=0.0, lon=0.0)  # the last accepted START (FREQ/WARP persist)
        self.datum: UTMGeodesy | None = None  # set while a mission runs
        self.ticks_in_mission = 0

    @property
    def running(self) -> bool:
        return self.datum is not None

    @property
    def period(self) -> float:
        """Wall-clock seconds between ticks: 1 / (FREQ * WARP)."""
        return 1.0 / (self.params.freq * self.params.warp)

    def handle_line(self, line: str) -> list[str]:
        """Process one received line (no terminator); returns the replies."""
        try:
            msg = parse_line(line)
            if msg.key == KEY_START:
                return self._start(Start.from_message(msg), line)
            if msg.key == KEY_CMD and self.running:
                return [self._command(msg)]
        except SimulatorProtocolError as exc:
            log.warning("invalid line from payload %r: %s", line, exc)
            return []
        if msg.key == KEY_CMD:
            log.warning("no mission running (send START first); ignoring %r", line)
        else:
            log.warning("unknown key from payload: %r", line)
        return []

    def _start(self, params: Start, line: str) -> list[str]:
        log.info("initialized using: %s", line.strip())
        self.params = params
        self.datum = UTMGeodesy(params.lat, params.lon)
        self.ticks_in_mission = 0
        return [CTRL_PAYLOAD]

    def _command(self, msg: Message) -> str:
        try:
            command = Command.from_message(msg)
        except SimulatorProtocolError as exc:
            log.warning("rejected command: %s", exc)
            return CMD_ERROR
        self.desired = DesiredCourse(
            z=-command.depth, speed=command.speed, heading=wrap_heading(command.heading)
        )
        return CMD_OK

    def tick(self) -> list[str]:
        """One control period; returns `CTRL,STATE:IDLE` at mission end, else NAV if running."""
        self.ticks_in_mission += 1
        params = self.params
        if (
            self.running
            and params.duration != 0
            and self.ticks_in_mission // params.freq > params.duration
        ):
            self.datum = None
            log.info("mission duration (%d s) elapsed", params.duration)
            return [CTRL_IDLE]
        if self.datum is None:
            return []
        self.step(1.0 / params.freq)
        return [self.nav().to_line()]

    def step(self, dt: float) -> None:
        """Advance the vehicle dynamics by `dt` seconds."""
        vehicle, desired, params = self.vehicle, self.desired, self.params
        vehicle.z = slew(vehicle.z, desired.z, params.z_rate * dt)

        vehicle.heading = turn_toward(vehicle.heading, desired.heading, params.hdg_rate * dt)
        vehicle.speed = slew(vehicle.speed, desired.speed, params.accel * dt)
        vehicle.x, vehicle.y = advance(vehicle.x, vehicle.y, vehicle.speed, vehicle.heading, dt)

    def nav(self) -> Nav:
        """The vehicle's navigation in the current datum (a mission must be running)."""
        if self.datum is None:
            raise RuntimeError("no datum: the simulator has no mission running")
        v = self.vehicle
        lat, lon = self.datum.to_geo(v.x, v.y)
        return Nav(lat=lat, lon=lon, depth=-v.z, heading=v.heading, speed=v.speed)
