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
