"""Rate-limited motion shared by pygoby's simulated vehicles (uSimVehicle, the basic frontseat
simulator)."""

from __future__ import annotations

import math


def wrap_heading(degrees: float) -> float:
    """`degrees` in [0, 360)."""
    wrapped = math.fmod(degrees, 360.0)
    if wrapped < 0.0:
        wrapped += 360.0
    return 0.0 if wrapped >= 360.0 else wrapped  # -1e-20 + 360 rounds to 360


def slew(value: float, target: float, step: float) -> float:
    """`value` moved toward `target` by `step`, or `target` itself when within one step."""
    if abs(value - target) > step:
        return value + step if value < target else value - step
    return target


def turn_toward(heading: float, desired: float, max_turn: float) -> float:
    """`heading` turned toward `desired` (both in [0, 360)) by at most `max_turn` degrees, the
    shorter way round (clockwise when both ways are 180 degrees); the result is in [0, 360)."""
    target = desired  # one correction of +-360 gives the shorter way
    if heading - target >= 180.0:
        target += 360.0
    elif heading - target < -180.0:
        target -= 360.0
    return wrap_heading(slew(heading, target, max_turn))


def advance(x: float, y: float, speed: float, heading: float, dt: float) -> tuple[float, float]:
    """(x, y) after `dt` seconds at `speed` on `heading` (degrees true: 0 = north = +y,
    90 = east = +x)."""
    theta = (90.0 - heading) * math.pi / 180.0
    return x + speed * math.cos(theta) * dt, y + speed * math.sin(theta) * dt
