"""The Bluefin driver against the Huxley simulator over loopback TCP: the interface reaches
INTERFACE_COMMAND with the helm driving and the vehicle follows the helm's set-points; each fault
of the simulator has its effect. The I/O is real asyncio; both ends read one VirtualClock that the
test advances 0.1 s per few real milliseconds."""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator, Callable

import pytest

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.bluefin.server import HuxleyServer, build_parser, options_from
from pygoby.frontseat.bluefin.simulator import HuxleyOptions, HuxleySimulator
from pygoby.frontseat.drivers.bluefin import BluefinFrontSeat
from pygoby.util.clock import VirtualClock

from .bluefin_scenario import T0, Helm, config


class Rig:
    def __init__(
        self,
        server: HuxleyServer,
        serving: asyncio.Task,
        driver: BluefinFrontSeat,
        clock: VirtualClock,
    ) -> None:
        self.server, self.serving, self.driver, self.clock = server, serving, driver, clock
        self.helm = Helm(driver)
        self.data: list = []
        self.responses: list = []
        driver.signal_data_from_frontseat.connect(self.data.append)
        driver.signal_command_response.connect(self.responses.append)

    async def run(self, until: Callable[[], bool], limit: float = 120.0) -> float:
        """Advance virtual time 0.1 s per step (the helm acting, the driver ticking, the
        simulator stepping once after the driver, however slow the machine) until `until()`;
        returns the virtual seconds since T0. Fails after `limit` virtual s."""
        while not until():
            assert self.clock.now() - T0 < limit, "condition not reached in virtual time"
            self.clock.advance(0.1)
            self.helm.act(self.clock.now() - T0)
            self.driver.do_work()
            steps = self.server.steps
            while self.server.steps < steps + 2:  # it has read what the driver wrote
                assert not self.serving.done(), self.serving
                await asyncio.sleep(0.001)
        return self.clock.now() - T0

    def last_status(self):
        return [d.node_status for d in self.data if d.HasField("node_status")][-1]


@contextlib.asynccontextmanager
async def rig(options: HuxleyOptions | None = None, extra: str = "") -> AsyncIterator[Rig]:
    clock = VirtualClock(T0)
    server = HuxleyServer(0, simulator=HuxleySimulator(options), clock=clock, poll_interval=0.002)
    port = await server.start()
    serving = asyncio.create_task(server.serve())
    driver = BluefinFrontSeat(
        config(port, "reconnect_interval: 1 " + extra), clock, connect_timeout=5
    )
    await driver.start()
    try:
        yield Rig(server, serving, driver, clock)
    finally:
        await driver.stop()
        serving.cancel()
        await asyncio.gather(serving, return_exceptions=True)


def state(rig_: Rig) -> int:
    return rig_.driver.state


async def test_reaches_command_and_follows_the_helm():
    async with rig() as r:
        await r.run(lambda: state(r) == frontseat_pb.INTERFACE_COMMAND)
        assert r.driver.frontseat_state() == frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS
        await r.run(lambda: r.clock.now() - T0 > 18)  # first leg: 90 deg, 1.5 m/s, 10 m
        status = r.last_status()
        assert status.pose.heading == pytest.approx(90, abs=0.5)
        assert status.speed.over_ground == pytest.approx(1.5, abs=0.01)
        assert status.global_fix.depth == pytest.approx(10, abs=0.1)
        assert status.local_fix.x > 5 and abs(status.local_fix.y) < 1
        await r.run(lambda: r.clock.now() - T0 > 35)  # second leg: 180 deg, 2 m/s, 20 m
        status = r.last_status()
        assert status.pose.heading == pytest.approx(180, abs=0.5)
        assert status.speed.over_ground == pytest.approx(2.0, abs=0.01)
        assert status.global_fix.depth == pytest.approx(20, abs=0.1)
        assert r.responses and all(resp.request_successful for resp in r.responses)
        assert state(r) == frontseat_pb.INTERFACE_COMMAND


async def test_payload_control_ending_returns_to_listen():
    async with rig(HuxleyOptions(control_duration=5.0)) as r:
        await r.run(lambda: state(r) == frontseat_pb.INTERFACE_COMMAND)
        await r.run(lambda: state(r) == frontseat_pb.INTERFACE_LISTEN)
        assert r.driver.frontseat_state() == frontseat_pb.FRONTSEAT_IDLE  # $BFMIS ... Stopped


async def test_missing_navigation_is_not_providing_data():
    async with rig(HuxleyOptions(nav_stop_after=6.0)) as r:
        await r.run(lambda: state(r) == frontseat_pb.INTERFACE_COMMAND)
        t = await r.run(lambda: state(r) == frontseat_pb.INTERFACE_FS_ERROR)
        assert r.driver.status().frontseat_error == frontseat_pb.ERROR_FRONTSEAT_NOT_PROVIDING_DATA
        assert (
            6.0 + 5.0 <= t <= 6.0 + 5.0 + 1.0
        )  # allow_missing_nav_interval 5 s after the last NVG


async def test_naks_answer_the_helm_unsuccessfully():
    async with rig(HuxleyOptions(nak=frozenset({"RMB"}))) as r:
        await r.run(lambda: len(r.responses) >= 2)
        assert not any(resp.request_successful for resp in r.responses)
        assert {(resp.error_code, resp.error_string) for resp in r.responses} == {
            (1, "simulated failure")
        }
        assert state(r) == frontseat_pb.INTERFACE_COMMAND  # a NAK is an answer: no error state


async def test_silence_makes_the_frontseat_ignoring_commands():
    async with rig(HuxleyOptions(no_ack=True, nav_stop_after=0.0), "nmea_resend_interval: 1") as r:
        await r.run(lambda: state(r) == frontseat_pb.INTERFACE_FS_ERROR, limit=60)
        assert r.driver.status().frontseat_error == frontseat_pb.ERROR_FRONTSEAT_IGNORING_COMMANDS


async def test_a_dropped_connection_is_noticed_and_the_driver_starts_over():
    async with rig(HuxleyOptions(drop_after=4.0)) as r:
        await r.run(lambda: state(r) == frontseat_pb.INTERFACE_COMMAND)
        await r.run(lambda: r.driver.frontseat_state() == frontseat_pb.FRONTSEAT_NOT_CONNECTED)
        await r.run(lambda: state(r) == frontseat_pb.INTERFACE_FS_ERROR)
        assert r.driver.status().frontseat_error == frontseat_pb.ERROR_FRONTSEAT_NOT_CONNECTED
        # reconnected (1 s of real time): a new session, logging asked for again, control again
        await r.run(lambda: state(r) == frontseat_pb.INTERFACE_COMMAND, limit=100_000)
        assert sum(line.startswith("< $BPLOG,ACK,ON") for line in r.server.exchange) == 2


async def test_clock_skew_shows_in_the_node_status_time():
    async with rig(HuxleyOptions(clock_skew=-30.0)) as r:
        await r.run(lambda: any(d.HasField("node_status") for d in r.data))
        status = r.last_status()
        assert status.time - r.clock.now() == pytest.approx(-30.0, abs=0.2)


def test_the_command_line_options():
    args = build_parser().parse_args(
        [
            "0",
            "--nak",
            "rmb",
            "--no-ack",
            "--drop-after",
            "3",
            "--clock-skew",
            "2",
            "--nav-stop-after",
            "9",
        ]
    )
    options = options_from(args)
    assert options.nak == frozenset({"RMB"}) and options.no_ack
    assert (options.drop_after, options.clock_skew, options.nav_stop_after) == (3, 2, 9)
    assert math.isclose(options.lat, HuxleyOptions().lat)


@pytest.mark.parametrize("command", ["bluefin_frontseat_simulator", "basic_frontseat_simulator"])
def test_the_pygoby_subcommands_are_the_simulators(command, capsys):
    from pygoby.cli import main

    with pytest.raises(SystemExit) as exit_info:
        main([command, "--help"])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: pygoby {command} [-h]")
    assert ("--nak" in out) == (command == "bluefin_frontseat_simulator")
