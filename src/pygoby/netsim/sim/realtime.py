"""The same simulation on the wall clock, over TCP, as a vehicle simulator sees netsim.

`RealTimeRun(scenario)` serves a `Simulation`'s pieces on real sockets: the `NetSimManager` on
`real_time.manager_tcp_port` (61999) for NavUpdates from vehicle simulators (iNetSimManager,
netsim_tool), and one Micro-Modem emulator per node on its modem port (62000 + i, plus
`real_time.port_offset`) for drivers such as pAcommsHandler's. Nodes with `in_process_stack`
get the real driver (over TCP to their emulator), MAC and status queue in this process; the
others wait for an external driver. Scripted tracks are posted to the manager every
`position_period`. The clock is the wall clock times the scenario's speed factor (external
programs must run with the same MOOS time warp), or a clock given by the caller.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem import MMDriver
from pygoby.acomms.mmsim.server import MMSimServer
from pygoby.netsim.manager.server import ManagerServer
from pygoby.netsim.sim.scenario import speed_factor
from pygoby.netsim.sim.simulation import EventSink, RunSummary, Simulation, driver_config
from pygoby.protobuf.pygoby.netsim.scenario_pb2 import Scenario
from pygoby.util.clock import Clock, WallClock

log = logging.getLogger(__name__)

WORK_PERIOD = 0.005  # wall seconds between rounds of do_work (drivers set clocks to ~50 ms)
STARTUP_TIMEOUT = 30.0  # wall seconds for the in-process drivers to start


class RealTimeRun:
    def __init__(
        self, scenario: Scenario, on_event: EventSink | None = None, clock: Clock | None = None
    ) -> None:
        """`clock`: share another program's clock (e.g. a MOOS time-warp clock) instead of
        the wall clock times the scenario's speed."""
        if clock is None:
            factor = speed_factor(scenario)
            if factor is None:
                raise ValueError('speed "max" runs on the virtual clock (Simulation.run_virtual)')
            clock = WallClock(factor)
        self.clock = clock
        self.sim = Simulation(scenario, clock=self.clock, on_event=on_event)
        self.sim.start = self.clock.now()
        rt = scenario.real_time
        self.host = rt.listen_address
        self.manager_server = ManagerServer(
            self.sim.manager, self.host, 0 if rt.ephemeral_ports else rt.manager_tcp_port
        )
        self.emulators: dict[int, MMSimServer] = {}  # by modem_id
        self._stop = asyncio.Event()

    @property
    def manager_port(self) -> int:
        return self.manager_server.bound_port

    def emulator_port(self, modem_id: int) -> int:
        port = self.emulators[modem_id].port
        assert port is not None  # (emulators are started with the simulation)
        return port

    async def start(self) -> None:
        """Listen (manager, emulators) and start the in-process stacks' drivers."""
        rt = self.sim.scenario.real_time
        await self.manager_server.start()
        for node, cfg in zip(self.sim.nodes, self.sim.scenario.node, strict=True):
            port = 0 if rt.ephemeral_ports else node.port + rt.port_offset
            server = MMSimServer(node.model, self.sim.physics, self.host, port)
            await server.start()
            self.emulators[node.modem_id] = server
            if cfg.in_process_stack:
                driver = MMDriver(self.clock)
                self.sim.attach_stack(node, driver)
                driver.startup(
                    driver_config(
                        node.modem_id,
                        connection_type=acomms_pb.DriverConfig.CONNECTION_TCP_AS_CLIENT,
                        tcp_server=self.host,
                        tcp_port=server.port,
                        reconnect_interval=1,
                    )
                )
        self.sim.post_positions()
        deadline = time.monotonic() + STARTUP_TIMEOUT
        drivers = [n.driver for n in self.sim.nodes if n.driver is not None]
        while not all(d.startup_complete for d in drivers):
            if time.monotonic() > deadline:
                raise TimeoutError("in-process Micro-Modem drivers did not start")
            for driver in drivers:
                driver.do_work()
            await asyncio.sleep(WORK_PERIOD)
        self.sim.start_macs()

    def request_stop(self) -> None:
        self._stop.set()

    async def run(self, progress: Callable[[], None] | None = None) -> RunSummary:
        """Run for the scenario's duration (simulated seconds) or until `request_stop`;
        `progress()` is called at every round (a few hundred a second)."""
        sim = self.sim
        sim._wall_start = time.perf_counter()
        end = sim.start + sim.scenario.duration
        next_position = self.clock.now() + sim.scenario.position_period
        next_housekeeping = self.clock.now() + sim.scenario.housekeeping_period
        while not self._stop.is_set() and self.clock.now() < end:
            now = self.clock.now()
            if now >= next_position:
                sim.post_positions()
                next_position += sim.scenario.position_period
            sim.physics.do_work()
            housekeeping = now >= next_housekeeping
            if housekeeping:
                next_housekeeping += sim.scenario.housekeeping_period
            for node in sim.nodes:
                if node.driver is None:
                    continue
                node.driver.do_work()
                if node.mac is not None:
                    node.mac.do_work()
                if housekeeping and node.queue is not None:
                    node.queue.do_work()
            if progress is not None:
                progress()
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(WORK_PERIOD):
                    await self._stop.wait()
        summary = sim.summary()
        summary.interrupted = self._stop.is_set()
        return summary

    async def close(self) -> None:
        for node in self.sim.nodes:
            if node.driver is not None:
                node.driver.shutdown()
        for server in self.emulators.values():
            await server.close()
        await self.manager_server.close()

    async def __aenter__(self) -> RealTimeRun:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()
