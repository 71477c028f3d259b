"""The ABC driver against the real simulator server over loopback TCP.

The I/O runs in real asyncio; the interface clock is a VirtualClock the test advances, so the
10 s NAV timeout is exercised without waiting 10 s."""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from google.protobuf import text_format

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.drivers.abc import AbcFrontSeat
from pygoby.frontseat.simulator.server import SimulatorServer
from pygoby.util.clock import VirtualClock

T0 = 1_700_000_000.0


def make_driver(port: int, warp: int = 10) -> AbcFrontSeat:
    cfg = text_format.Parse(
        f"""
        name: "auv1"
        origin {{ lat: 42.35 lon: -70.95 }}
        require_helm: true
        sim_warp_factor: {warp}
        [goby.middleware.frontseat.protobuf.basic_simulator_config] {{
          tcp_address: "127.0.0.1"
          tcp_port: {port}
          start {{ lat: 42.35 lon: -70.95 duration: 0 control_freq: 10 }}
        }}
        """,
        frontseat_pb.Config(),
    )
    return AbcFrontSeat(cfg, VirtualClock(T0), connect_timeout=5.0, reconnect_interval=0.1)


async def run_until(driver: AbcFrontSeat, done: Callable[[], bool], timeout: float = 5.0) -> None:
    """Tick the driver (do_work) every 10 ms of real time until `done()`."""
    async with asyncio.timeout(timeout):
        while True:
            driver.do_work()
            if done():
                return
            await asyncio.sleep(0.01)


async def serve(port: int = 0) -> tuple[SimulatorServer, asyncio.Task]:
    server = SimulatorServer(port, host="127.0.0.1")
    task = asyncio.create_task(server.serve())
    await server.start()
    return server, task


async def shut(task: asyncio.Task) -> None:
    task.cancel()
    await asyncio.gather(task, return_exceptions=True)


async def test_session_start_nav_command_timeout_and_reconnect():
    server, serving = await serve()
    port = server.port
    driver = make_driver(port)
    data, responses, raw_out = [], [], []
    driver.signal_data_from_frontseat.connect(data.append)
    driver.signal_command_response.connect(responses.append)
    driver.signal_raw_to_frontseat.connect(lambda r: raw_out.append(r.raw.decode()))
    try:
        await driver.start()
        assert driver.link.is_open

        # connect -> START -> CTRL,STATE:PAYLOAD -> ACCEPTING_COMMANDS; NAV -> LISTEN
        await run_until(
            driver, lambda: driver.frontseat_state() == frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS
        )
        assert raw_out[0] == (
            "START,LAT:42.35,LON:-70.95,DURATION:0,FREQ:10,ACCEL:0.5,HDG_RATE:45,Z_RATE:2,WARP:10"
        )
        await run_until(driver, lambda: driver.state == frontseat_pb.INTERFACE_LISTEN)
        status = data[-1].node_status
        assert status.global_fix.lat == 42.35 and status.global_fix.lon == -70.95
        assert abs(status.local_fix.x) < 1e-3 and abs(status.local_fix.y) < 1e-3
        assert status.name == "auv1" and status.time == T0 and status.IsInitialized()

        # helm drives -> COMMAND; a command is answered with its request id
        driver.set_helm_state(frontseat_pb.HELM_DRIVE)
        await run_until(driver, lambda: driver.state == frontseat_pb.INTERFACE_COMMAND)
        driver.send_command_to_frontseat(
            frontseat_pb.CommandRequest(
                desired_course=frontseat_pb.DesiredCourse(time=T0, heading=90, speed=2, depth=5),
                response_requested=True,
                request_id=65536,
            )
        )
        await run_until(driver, lambda: bool(responses))
        assert responses == [
            frontseat_pb.CommandResponse(request_successful=True, request_id=65536)
        ]
        await run_until(driver, lambda: data[-1].node_status.speed.over_ground > 0.5)
        assert data[-1].node_status.local_fix.x > 0  # heading east

        # simulator stopped: NOT_CONNECTED at once; no data 10 s later (interface clock)
        await shut(serving)
        await run_until(
            driver, lambda: driver.frontseat_state() == frontseat_pb.FRONTSEAT_NOT_CONNECTED
        )
        assert driver.frontseat_providing_data()
        driver.clock.advance(10.0)
        driver.do_work()
        assert driver.frontseat_providing_data()
        driver.clock.advance(0.5)
        driver.do_work()
        assert not driver.frontseat_providing_data()
        assert driver.state == frontseat_pb.INTERFACE_FS_ERROR

        # simulator back on the same port: reconnect, START again, data again
        starts_before = sum(line.startswith("START,") for line in raw_out)
        server, serving = await serve(port)
        await run_until(driver, lambda: driver.frontseat_providing_data())
        assert sum(line.startswith("START,") for line in raw_out) == starts_before + 1
        await run_until(driver, lambda: driver.state == frontseat_pb.INTERFACE_COMMAND)
        # Quirk Q16 is the simulator's: a fresh process starts the vehicle at rest again
        assert data[-1].node_status.speed.over_ground < 2.0
    finally:
        await driver.stop()
        await shut(serving)


async def test_start_gives_up_after_the_timeout_but_keeps_trying():
    probe, probe_task = await serve()
    port = probe.port
    await shut(probe_task)  # a port nobody listens on any more
    driver = make_driver(port)
    driver.connect_timeout = 0.3
    try:
        await driver.start()  # no exception
        driver.do_work()
        assert driver.frontseat_state() == frontseat_pb.FRONTSEAT_NOT_CONNECTED
        _, serving = await serve(port)
        try:
            await run_until(
                driver,
                lambda: driver.frontseat_state() == frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS,
            )
        finally:
            await shut(serving)
    finally:
        await driver.stop()
