"""iFrontSeat demo in one process: the ABC frontseat simulator, the embedded MOOSDB, iFrontSeat
(configured by abc_auv.moos next to this file, with the `abc` driver) and a scripted helm,
time-warped. The helm drives a few legs; every couple of (warped) seconds a line shows the
interface state, the helm's desired course and the vehicle's NAV_* as it converges on it.

    python examples/frontseat/run_demo.py [--warp 5] [--duration 90]

Ports are picked free, so it runs beside anything else (including `pygoby antler abc_auv.moos`).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
from pathlib import Path

from pygoby.apps.ifrontseat import iFrontSeat
from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.simulator.server import SimulatorServer
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.timewarp import moos_clock

MISSION = Path(__file__).with_name("abc_auv.moos")
SIMULATOR_CONFIG = "goby.middleware.frontseat.protobuf.basic_simulator_config"

# The helm's legs: (from warped second, heading deg, speed m/s, depth m).
LEGS = [(0, 90.0, 1.5, 10.0), (30, 200.0, 2.0, 25.0), (60, 320.0, 1.0, 5.0)]
SETTLE_S = 12.0  # the vehicle settles on a new leg within about 10 warped seconds
NAV = ("NAV_HEADING", "NAV_SPEED", "NAV_DEPTH", "NAV_X", "NAV_Y")


def leg_at(elapsed: float) -> tuple[float, float, float, float]:
    """(start, heading, speed, depth) of the leg the helm steers at `elapsed`."""
    current = LEGS[0]
    for leg in LEGS:
        if elapsed >= leg[0]:
            current = leg
    return current


async def helm(client: MOOSClient, clock, start: float, period: float) -> None:
    """pHelmIvP as iFrontSeat sees it: DRIVE and the leg's DESIRED_* every warped second."""
    while True:
        _, heading, speed, depth = leg_at(clock.now() - start)
        client.publish("IVPHELM_STATE", "DRIVE")
        client.publish("DESIRED_HEADING", heading)
        client.publish("DESIRED_DEPTH", depth)
        client.publish("DESIRED_SPEED", speed)  # last: it makes the command request
        await asyncio.sleep(period)


async def demo(warp: float, duration: float) -> bool:
    """Runs the demo; True when the interface ends in COMMAND with the vehicle on the helm's
    current course (what `make demo` checks)."""
    clock = moos_clock(warp)
    async with contextlib.AsyncExitStack() as stack:
        simulator = SimulatorServer(0, host="127.0.0.1")
        sim_port = await simulator.start()
        serving = asyncio.create_task(simulator.serve())
        stack.callback(serving.cancel)
        db = await stack.enter_async_context(MOOSDB(port=0, clock=clock))
        overrides = [
            ("common", f"time_warp_multiplier: {warp:g}  verbosity: WARN"),
            (
                "frontseat_cfg",
                f'[{SIMULATOR_CONFIG}] {{ tcp_address: "127.0.0.1"  tcp_port: {sim_port} }}',
            ),
        ]
        app = iFrontSeat.from_mission(MISSION, overrides=overrides, port=db.port)
        await stack.enter_async_context(app)

        latest: dict[str, float] = {}

        def seen(msg: MOOSMessage) -> None:
            if msg.is_double:
                latest[msg.key] = msg.dval

        watcher = MOOSClient("demo_watch", port=db.port, clock=clock, on_message=seen)
        await watcher.connect()
        stack.push_async_callback(watcher.close)
        for var in NAV:
            watcher.subscribe(var)
        pilot = MOOSClient("pHelmIvP", port=db.port, clock=clock)
        await pilot.connect()
        stack.push_async_callback(pilot.close)
        start = clock.now()
        steering = asyncio.create_task(helm(pilot, clock, start, 1.0 / warp))
        stack.callback(steering.cancel)

        print(f"ABC simulator on port {sim_port}, MOOSDB on port {db.port}, warp {warp:g}")
        print("    t  interface   desired hdg/spd/dep   NAV hdg/spd/dep            x        y")
        settled = False  # at the last sample where the leg had run SETTLE_S: on course?
        while (elapsed := clock.now() - start) < duration:
            leg_start, heading, speed, depth = leg_at(elapsed)
            state = frontseat_pb.InterfaceState.Name(app.interface.state).removeprefix("INTERFACE_")
            nav = [latest.get(var, float("nan")) for var in NAV]
            print(
                f"{elapsed:5.0f}s {state:10s} {heading:5.0f} {speed:4.1f} {depth:5.1f}    "
                f"{nav[0]:7.1f} {nav[1]:4.2f} {nav[2]:5.1f}   {nav[3]:8.1f} {nav[4]:8.1f}"
            )
            if elapsed - leg_start >= SETTLE_S:
                settled = (
                    state == "COMMAND"
                    and abs(nav[0] - heading) < 1.0
                    and abs(nav[1] - speed) < 0.05
                    and abs(nav[2] - depth) < 0.5
                )
            await asyncio.sleep(3.0 / warp)

        print(
            "iFrontSeat demo: "
            + (
                "OK, the vehicle follows the helm in COMMAND"
                if settled
                else "FAILED: the vehicle is not on the helm's course in COMMAND"
            )
        )
        return settled


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--warp", type=float, default=5.0, help="MOOS time warp (default 5)")
    parser.add_argument("--duration", type=float, default=90.0, help="warped seconds (default 90)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)  # the simulator's and links' chatter
    return 0 if asyncio.run(demo(args.warp, args.duration)) else 1


if __name__ == "__main__":
    raise SystemExit(main())
