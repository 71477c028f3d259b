"""Basic frontseat simulator, sans-I/O (`make bench`): the cost of one control tick (dynamics,
UTM inverse, NAV text) and of handling the lines a backseat sends. ops/s of the tick benchmark
= simulator ticks per second one core can sustain (FREQ*WARP above that cannot keep time)."""

from __future__ import annotations

import pytest

from pygoby.frontseat.simulator.core import BasicFrontSeatSimulator
from pygoby.frontseat.simulator.protocol import Nav, parse_line


def running_simulator() -> BasicFrontSeatSimulator:
    sim = BasicFrontSeatSimulator()
    sim.handle_line("START,LAT:42.35,LON:-70.95,DURATION:0,FREQ:10")
    sim.handle_line("CMD,HEADING:135,SPEED:1.5,DEPTH:20")
    return sim


@pytest.mark.benchmark(group="frontseat-sim")
def test_simulator_tick(benchmark):
    sim = running_simulator()
    (nav,) = benchmark(sim.tick)
    assert nav.startswith("NAV,")


@pytest.mark.benchmark(group="frontseat-sim")
def test_dynamics_step_only(benchmark):
    sim = running_simulator()
    benchmark(sim.step, 0.1)


@pytest.mark.benchmark(group="frontseat-sim")
def test_handle_cmd_line(benchmark):
    sim = running_simulator()
    assert benchmark(sim.handle_line, "CMD,HEADING:260,SPEED:1.5,DEPTH:100") == ["CMD,RESULT:OK"]


@pytest.mark.benchmark(group="frontseat-sim")
def test_parse_nav_line(benchmark):
    line = "NAV,LAT:42.3489125,LON:-70.94874621,DEPTH:20,HEADING:135,SPEED:1.5"
    benchmark(lambda: Nav.from_message(parse_line(line)))
