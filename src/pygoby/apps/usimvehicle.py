"""uSimVehicle: a minimal simulated vehicle for missions and demos (pygoby's own app).

It moves a kinematic vehicle (heading 0 = north = +y, 90 = east = +x), steering toward the
doubles DESIRED_HEADING, DESIRED_SPEED and DESIRED_DEPTH at bounded rates, posts NAV_X, NAV_Y,
NAV_DEPTH, NAV_HEADING and NAV_SPEED every `nav_period` seconds, and posts scripted `event`s
(like uTimerScript) at given times after start, optionally repeating.

    uSimVehicle mission.moos [AppName]
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.protocol import MOOSMessage
from pygoby.protobuf.pygoby.apps.usimvehicle_config_pb2 import uSimVehicleConfig
from pygoby.util.kinematics import advance, slew, turn_toward, wrap_heading

DESIRED = {"DESIRED_HEADING": "heading", "DESIRED_SPEED": "speed", "DESIRED_DEPTH": "depth"}


@dataclass
class VehicleModel:
    """Kinematics, sans I/O: `step(dt)` moves toward the desired heading, speed and depth."""

    x: float = 0.0
    y: float = 0.0
    depth: float = 0.0
    heading: float = 0.0
    speed: float = 0.0
    turn_rate: float = 10.0
    acceleration: float = 0.5
    dive_rate: float = 0.5
    desired_heading: float | None = None
    desired_speed: float | None = None
    desired_depth: float | None = None

    def step(self, dt: float) -> None:
        if dt <= 0:
            return
        if self.desired_heading is not None:
            self.heading = turn_toward(
                self.heading, wrap_heading(self.desired_heading), self.turn_rate * dt
            )
        if self.desired_speed is not None:
            self.speed = slew(self.speed, self.desired_speed, self.acceleration * dt)
        if self.desired_depth is not None:
            self.depth = max(0.0, slew(self.depth, self.desired_depth, self.dive_rate * dt))
        self.x, self.y = advance(self.x, self.y, self.speed, self.heading, dt)


class uSimVehicle(GobyMOOSApp):  # noqa: N801 - the program's name
    config_class = uSimVehicleConfig
    cfg: uSimVehicleConfig
    default_name = "uSimVehicle"

    def __init__(self, cfg: uSimVehicleConfig, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        self.vehicle = VehicleModel(
            x=cfg.start_x,
            y=cfg.start_y,
            depth=cfg.start_depth,
            heading=cfg.start_heading % 360,
            speed=cfg.start_speed,
            turn_rate=cfg.turn_rate,
            acceleration=cfg.acceleration,
            dive_rate=cfg.dive_rate,
        )
        self._last_step: float | None = None
        self._last_nav = -math.inf
        self._script_start = 0.0
        self._next_event = 0
        for var in DESIRED:
            self.subscribe(var, self._on_desired)

    def on_start(self) -> None:
        self._script_start = self.start_time

    def _on_desired(self, msg: MOOSMessage) -> None:
        if not msg.is_double or not math.isfinite(msg.dval):
            self.log.warning("%s must be a finite double; ignored", msg.key)
            return
        setattr(self.vehicle, "desired_" + DESIRED[msg.key], msg.dval)

    def loop(self) -> None:
        now = self.clock.now()
        if self._last_step is not None:
            self.vehicle.step(now - self._last_step)
        self._last_step = now
        if now - self._last_nav >= self.cfg.nav_period:
            self._last_nav = now
            v = self.vehicle
            for var, value in (
                ("NAV_X", v.x),
                ("NAV_Y", v.y),
                ("NAV_DEPTH", v.depth),
                ("NAV_HEADING", v.heading),
                ("NAV_SPEED", v.speed),
            ):
                self.publish(var, round(value, 3))
        self._run_script(now)

    def _run_script(self, now: float) -> None:
        events = self.cfg.event
        while (
            self._next_event < len(events)
            and now >= self._script_start + events[self._next_event].time
        ):
            event = events[self._next_event]
            self.publish(event.var, event.sval if event.HasField("sval") else event.dval)
            self._next_event += 1
        period = self.cfg.script_period
        if period > 0 and self._next_event == len(events) and now >= self._script_start + period:
            self._script_start += period
            self._next_event = 0


def main(argv: Sequence[str] | None = None) -> int:
    return uSimVehicle.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
