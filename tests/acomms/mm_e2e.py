"""Helpers for end-to-end tests: emulated Micro-Modems on real TCP, drivers advanced by a loop."""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem import MMDriver
from pygoby.acomms.mmsim import LoopbackChannel, MicroModemModel
from pygoby.acomms.mmsim.server import MMSimServer
from pygoby.acomms.mmsim.timing import DEFAULT_TIMING, ModemTiming, RateTiming
from pygoby.util.clock import WallClock

DRIVER_WHOI_MICROMODEM = 2
TCP_CLIENT = acomms_pb.DriverConfig.CONNECTION_TCP_AS_CLIENT


def mm_config(modem_id: int, port: int, **mm) -> object:
    cfg = acomms_pb.DriverConfig(
        driver_type=DRIVER_WHOI_MICROMODEM,
        modem_id=modem_id,
        connection_type=TCP_CLIENT,
        tcp_server="127.0.0.1",
        tcp_port=port,
        reconnect_interval=1,
    )
    ext = cfg.Extensions[acomms_pb.MM_CONFIG]
    ext.query_cfg_on_startup = mm.pop("query", False)
    for key, value in mm.items():
        setattr(ext, key, value)
    return cfg


# The modem's durations, ten times shorter: end-to-end tests of the driver and queue, not of
# the timing (tests/acomms/test_mmsim_model.py and the pyacomms tests use the real ones).
FAST = ModemTiming(
    rates={
        rate: RateTiming(t.frames, t.frame_bytes, t.lead / 10, t.per_frame / 10)
        for rate, t in DEFAULT_TIMING.rates.items()
    },
    mini_packet=DEFAULT_TIMING.mini_packet / 10,
    ping=DEFAULT_TIMING.ping / 10,
)


async def start_emulators(ids, range_m=0.0, timing=FAST):
    clock = WallClock()
    channel = LoopbackChannel(clock, range_m)
    servers = []
    for modem_id in ids:
        model = MicroModemModel(modem_id, clock, channel, timing=timing)
        server = MMSimServer(model, channel)
        await server.start()
        servers.append(server)
    return channel, servers


async def run_until(
    condition: Callable[[], bool], workers: list, timeout: float = 10.0, period: float = 0.005
) -> None:
    """Call every worker's do_work() until `condition()` holds (TimeoutError otherwise)."""
    async with asyncio.timeout(timeout):
        while not condition():
            for worker in workers:
                worker.do_work()
            await asyncio.sleep(period)


async def started_driver(modem_id: int, port: int, **mm) -> MMDriver:
    driver = MMDriver(WallClock())
    driver.startup(mm_config(modem_id, port, **mm))
    await run_until(lambda: driver.startup_complete, [driver], timeout=15)
    return driver
