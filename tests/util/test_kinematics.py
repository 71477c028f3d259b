"""The rate-limited motion both simulated vehicles (uSimVehicle, the basic frontseat simulator)
step with."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pygoby.util.kinematics import advance, turn_toward

headings = st.floats(0.0, 360.0, exclude_max=True)


@given(headings, headings, st.floats(0.0, 400.0))
def test_turn_toward_turns_the_shorter_way_by_at_most_the_step(heading, desired, max_turn):
    turned = turn_toward(heading, desired, max_turn)
    assert 0.0 <= turned < 360.0
    gap_before = abs((desired - heading + 180.0) % 360.0 - 180.0)
    moved = abs((turned - heading + 180.0) % 360.0 - 180.0)
    assert moved <= max_turn + 1e-9
    assert moved == pytest.approx(min(max_turn, gap_before), abs=1e-9)


def test_turn_toward_crosses_north_and_snaps_to_the_target():
    assert turn_toward(350.0, 10.0, 5.0) == 355.0
    assert turn_toward(355.0, 10.0, 10.0) == 5.0
    assert turn_toward(5.0, 350.0, 20.0) == 350.0
    assert turn_toward(0.0, 180.0, 10.0) == 10.0  # a half turn either way: clockwise


def test_advance_heading_zero_is_north_and_ninety_is_east():
    x, y = advance(0.0, 0.0, 2.0, 0.0, 3.0)
    assert x == pytest.approx(0.0, abs=1e-12) and y == pytest.approx(6.0)
    x, y = advance(1.0, 1.0, 2.0, 90.0, 0.5)
    assert x == pytest.approx(2.0) and y == pytest.approx(1.0, abs=1e-12)
    x, y = advance(0.0, 0.0, 1.0, 225.0, math.sqrt(2.0))
    assert x == pytest.approx(-1.0) and y == pytest.approx(-1.0)
