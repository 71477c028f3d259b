"""The ABC / basic simulator frontseat driver.

Talks to `basic_frontseat_simulator` (pygoby.frontseat.simulator) over TCP. Configuration:
the `basic_simulator_config` extension (1001) of the frontseat Config:
`tcp_address`, `tcp_port` (54321) and `start {lat lon duration control_freq vehicle {accel
hdg_rate z_rate}}`; WARP is the Config's `sim_warp_factor` (MOOSTimeWarp).

* `start()` opens the link and waits up to 10 s for the connection; if none comes the driver
  stays FRONTSEAT_NOT_CONNECTED (iFrontSeat's NOT_CONNECTED timeout then applies) while the
  link keeps trying.
* `loop()` (non-blocking): once connected, moves NOT_CONNECTED -> IDLE and sends `START` with
  all eight fields; then handles every received line; after 10 s (interface clock) without
  NAV, `frontseat_providing_data()` becomes false.
* `CTRL,STATE:PAYLOAD` -> ACCEPTING_COMMANDS, `STATE:AUV` -> IN_CONTROL, any other -> IDLE.
  `NAV` -> a NodeStatus (pose.heading, speed.over_ground, global_fix lat/lon/depth) completed
  by `compute_missing` (name, type, time, local_fix) and emitted as InterfaceData. `CMD,RESULT`
  -> a CommandResponse (successful when RESULT is OK, with the last request's id) if the last
  request asked for one. Every received line (trimmed) is emitted raw, every sent line too.
* `send_command_to_frontseat` sends `CMD,HEADING:h,SPEED:v,DEPTH:d` (C++ default formatting, 6
  significant digits) for a desired course; other commands are logged and ignored.
  `send_data_to_frontseat` does nothing; `send_raw_to_frontseat` writes the raw text.

Deviations from upstream:

* Improvement: when the connection is lost the driver goes back to FRONTSEAT_NOT_CONNECTED
  and the link reconnects every `reconnect_interval` seconds; each new connection gets a new
  START (upstream only warns and never reconnects).
* A malformed line, or a NAV lacking a field or carrying a non-numeric value, is logged and
  skipped (upstream emits a NodeStatus with NaN in it).
* START prints its doubles with round-trip precision rather than 6 significant digits (see
  pygoby.frontseat.simulator.protocol), so the simulated vehicle starts where configured.
"""

from __future__ import annotations

from typing import Any

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.drivers.linked import CONNECT_TIMEOUT, LinkedFrontSeat
from pygoby.frontseat.errors import AbcConfigError, SimulatorProtocolError
from pygoby.frontseat.simulator.protocol import (
    KEY_CMD,
    KEY_CTRL,
    KEY_NAV,
    WHITESPACE,
    Command,
    Nav,
    Start,
    parse_line,
)
from pygoby.protobuf import initialization_errors
from pygoby.util.clock import Clock
from pygoby.util.errors import LinkClosedError
from pygoby.util.linebased import LineLink

NAV_TIMEOUT = 10.0  # s without NAV before the frontseat counts as not providing data
RECONNECT_INTERVAL = 1.0  # s between connection attempts

_CTRL_STATES = {
    "PAYLOAD": frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS,
    "AUV": frontseat_pb.FRONTSEAT_IN_CONTROL,
}


def start_params(cfg: Any) -> Start:
    """The START message a frontseat Config asks for."""
    if not cfg.HasExtension(frontseat_pb.BASIC_SIMULATOR_CONFIG):
        raise AbcConfigError(
            "has no [goby.middleware.frontseat.protobuf.basic_simulator_config]",
            field="frontseat_cfg",
        )
    sim = cfg.Extensions[frontseat_pb.BASIC_SIMULATOR_CONFIG]
    missing = initialization_errors(sim)
    if missing:
        raise AbcConfigError(f"lacks required {', '.join(missing)}", field="basic_simulator_config")
    start = sim.start
    try:
        return Start(
            lat=start.lat,
            lon=start.lon,
            duration=start.duration,
            freq=start.control_freq,
            accel=start.vehicle.accel,
            hdg_rate=start.vehicle.hdg_rate,
            z_rate=start.vehicle.z_rate,
            warp=cfg.sim_warp_factor,
        )
    except SimulatorProtocolError as exc:
        raise AbcConfigError(str(exc), field="basic_simulator_config") from None


class AbcFrontSeat(LinkedFrontSeat):
    """Frontseat driver for the basic (ABC) frontseat simulator."""

    peer = "the frontseat simulator"

    def __init__(
        self,
        cfg: Any,
        clock: Clock | None = None,
        *,
        link: LineLink | None = None,
        connect_timeout: float = CONNECT_TIMEOUT,
        reconnect_interval: float = RECONNECT_INTERVAL,
    ) -> None:
        super().__init__(cfg, clock, connect_timeout=connect_timeout)
        self.start_message = start_params(self.cfg)
        sim = self.cfg.Extensions[frontseat_pb.BASIC_SIMULATOR_CONFIG]
        self._attach_link(link, sim.tcp_address, sim.tcp_port, reconnect_interval)
        self._started_connection: int | None = None  # link.connections when START was sent
        self._last_request: Any = None

    # --- InterfaceBase hooks -------------------------------------------------------------------

    def loop(self) -> None:
        self._check_connection()
        for line in self.link.read_lines():
            self._receive(line)
        if not self.link.is_open:  # a CTRL just read came from the lost connection: stale
            self._frontseat_state = frontseat_pb.FRONTSEAT_NOT_CONNECTED
        if self._last_nav_time is None or self.clock.now() > self._last_nav_time + NAV_TIMEOUT:
            self._providing_data = False

    def send_command_to_frontseat(self, command: Any) -> None:
        if not command.HasField("desired_course"):
            self.log.info("unhandled command (only desired_course is supported): %s", command)
            return
        course = command.desired_course
        self._write(Command(course.heading, course.speed, course.depth).to_line())
        self._last_request = type(command)()
        self._last_request.CopyFrom(command)

    def send_data_to_frontseat(self, data: Any) -> None:
        """The simulator takes no data from the backseat."""

    def send_raw_to_frontseat(self, raw: Any) -> None:
        self._write(raw.raw.decode("latin-1"))

    # --- internals -----------------------------------------------------------------------------

    def _check_connection(self) -> None:
        if self.link.is_open:
            if self._started_connection != self.link.connections:
                self._started_connection = self.link.connections
                self.log.info("connected to the frontseat simulator at %s", self.address)
                self._frontseat_state = frontseat_pb.FRONTSEAT_IDLE
                self._write(self.start_message.to_line())
        elif self._frontseat_state != frontseat_pb.FRONTSEAT_NOT_CONNECTED:
            self.log.warning("lost the frontseat simulator at %s; reconnecting", self.address)
            self._frontseat_state = frontseat_pb.FRONTSEAT_NOT_CONNECTED

    def _write(self, line: str) -> None:
        self.signal_raw_to_frontseat(frontseat_pb.Raw(raw=line.encode("latin-1")))
        try:
            self.link.write(line + "\r\n")
        except LinkClosedError as exc:
            self.log.warning("not sent (%s): %s", exc, line)

    def _receive(self, line: str) -> None:
        line = line.strip(WHITESPACE)
        self.signal_raw_from_frontseat(frontseat_pb.Raw(raw=line.encode("latin-1")))
        try:
            msg = parse_line(line)
            if msg.key == KEY_CTRL:
                state = msg.fields.get("STATE", "")
                self._frontseat_state = _CTRL_STATES.get(state, frontseat_pb.FRONTSEAT_IDLE)
            elif msg.key == KEY_NAV:
                self._navigation(Nav.from_message(msg))
            elif msg.key == KEY_CMD:
                self._command_result(msg.fields.get("RESULT", ""))
            else:
                self.log.info("unknown message from the frontseat: %r", line)
        except SimulatorProtocolError as exc:
            self.log.warning("skipping bad line from the frontseat %r: %s", line, exc)

    def _navigation(self, nav: Nav) -> None:
        data = frontseat_pb.InterfaceData()
        status = data.node_status
        status.pose.heading = nav.heading
        status.speed.over_ground = nav.speed
        status.global_fix.lat = nav.lat
        status.global_fix.lon = nav.lon
        status.global_fix.depth = nav.depth
        self.compute_missing(status)
        self.signal_data_from_frontseat(data)
        self._providing_data = True
        self._last_nav_time = self.clock.now()

    def _command_result(self, result: str) -> None:
        request = self._last_request
        if request is None or not request.response_requested:
            return
        self.signal_command_response(
            frontseat_pb.CommandResponse(
                request_successful=result == "OK", request_id=request.request_id
            )
        )


def frontseat_driver_load(cfg: Any, clock: Clock | None = None) -> AbcFrontSeat:
    """The plug-in factory (entry points `abc` and `basic_simulator`)."""
    return AbcFrontSeat(cfg, clock)
