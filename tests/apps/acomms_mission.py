"""Two pAcommsHandler communities for end-to-end tests: embedded MOOSDBs, Micro-Modem emulators
on real loopback TCP (one perfect acoustic channel), and a MOOS client per community that
records everything it sees.

The missions run at MOOSTimeWarp WARP: the apps, the DBs, the recorders and the emulated modems
share MOOS time (UNIX time x WARP), so the TDMA slots and the modem's timing (the packets on the
water, the sentences on the serial line) pass WARP times faster than real time; the mission is
the same one, only its clock runs fast."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from pathlib import Path

from pygoby.acomms.mmsim import LoopbackChannel, MicroModemModel
from pygoby.acomms.mmsim.server import MMSimServer
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.timewarp import clock_warp, moos_clock
from pygoby.util.clock import Clock

PROTO = Path(__file__).resolve().parents[2] / "examples" / "two_vehicles" / "two_vehicles.proto"
STATUS = "pygoby.examples.SimpleStatus"
COMMAND = "pygoby.examples.Command"
# TDMA slots a packet and its acknowledgement fit in with the emulated modem's timing: a rate-1
# packet of one frame is ~1.3 s on the water (with the host's sentences on the serial line) and
# the acknowledgement 1 s more. Shorter slots are not a mission a real modem could run: the
# modem's transmissions would queue behind each other, later every cycle (a rate-0 packet alone,
# cycle-init and data, is ~4.3 s), and the sender's next cycle would come before the ack.
SLOT_SECONDS = 3
# (a TDMA cycle is then 0.6 s of real time: slack enough for the host's own delays between the
# sentences, which the warp does not shorten)
WARP = 10
SLOTS = "".join(
    f"    slot {{ src: {src} dest: -1 rate: 1 type: DATA slot_seconds: {SLOT_SECONDS} }}\n"
    for src in (1, 2)
)

QUEUE_ENTRIES = f"""\
  queue_cfg {{
    message_entry {{
      protobuf_name: "{STATUS}"  ack: false  max_queue: 1  ttl: 120
      role {{ type: SOURCE_ID field: "src" }}
      role {{ type: DESTINATION_ID field: "dest" }}
      role {{ type: TIMESTAMP field: "time" }}
    }}
    message_entry {{
      protobuf_name: "{COMMAND}"  ack: true  value_base: 5  ttl: 600
      role {{ type: SOURCE_ID field: "src" }}
      role {{ type: DESTINATION_ID field: "dest" }}
      role {{ type: TIMESTAMP field: "time" }}
    }}
  }}
"""

TRANSLATOR_ENTRIES = f"""\
  translator_entry {{
    protobuf_name: "{STATUS}"
    trigger {{ type: TRIGGER_PUBLISH moos_var: "SEND_STATUS" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "DB_TIME" format: "%1%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "MODEM_ID" format: "%2%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_X" format: "%10%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_Y" format: "%11%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_SPEED" format: "%12%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_HEADING" format: "%13%"
             algorithm {{ name: "angle_0_360" primary_field: 13 }} }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_DEPTH" format: "%14%" }}
    publish {{ technique: TECHNIQUE_FORMAT moos_var: "STATUS_REPORT_IN"
              format: "src=%2%,x=%10%,y=%11%,speed=%12%,heading=%13%,depth=%14%" }}
  }}
  translator_entry {{
    protobuf_name: "{COMMAND}"
    trigger {{ type: TRIGGER_PUBLISH moos_var: "COMMAND_OUT" }}
    create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "COMMAND_OUT" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "DB_TIME" format: "%1%" }}
    create {{ technique: TECHNIQUE_FORMAT moos_var: "MODEM_ID" format: "%2%" }}
    publish {{ technique: TECHNIQUE_FORMAT moos_var: "DESIRED_HEADING" format: "%10%" }}
    publish {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "COMMAND_IN" }}
  }}
"""


def micromodem_driver(modem_port: int) -> str:
    return f"""\
  driver_cfg {{
    driver_type: DRIVER_WHOI_MICROMODEM
    connection_type: CONNECTION_TCP_AS_CLIENT
    tcp_server: "127.0.0.1"
    tcp_port: {modem_port}
    reconnect_interval: 1
    [goby.acomms.micromodem.protobuf.config] {{ query_cfg_on_startup: false }}
  }}
"""


def mission_text(
    modem_id: int,
    db_port: int,
    modem_port: int,
    extra: str = "",
    slots: str | None = None,
    driver: str | None = None,
    common: str = "log: false  app_tick: 20  verbosity: WARN",
    warp: float = WARP,
) -> str:
    """vehicle<modem_id>'s mission: `driver` (a driver_cfg block; default: a Micro-Modem on
    `modem_port`), TDMA slots for 1 and 2, the status and command queues and translators."""
    if driver is None:
        driver = micromodem_driver(modem_port)
    if slots is None:
        slots = SLOTS
    return f"""\
ServerHost = localhost
ServerPort = {db_port}
Community  = vehicle{modem_id}
MOOSTimeWarp = {warp:g}

ProcessConfig = pAcommsHandler
{{
  common {{ {common} }}
  modem_id: {modem_id}
{driver}  mac_cfg {{
    type: MAC_FIXED_DECENTRALIZED
{slots}  }}
  load_proto_file: "{PROTO}"
{QUEUE_ENTRIES}{TRANSLATOR_ENTRIES}{extra}
}}
"""


class Recorder:
    """A MOOS client that keeps every notification it receives, by variable (`clock`: MOOS time,
    the DB's)."""

    def __init__(self, name: str, port: int, clock: Clock | None = None) -> None:
        self.client = MOOSClient(name, port=port, clock=clock)
        self.seen: dict[str, list[MOOSMessage]] = {}
        self._task: asyncio.Task | None = None

    async def start(self, variables: list[str]) -> None:
        await self.client.connect()
        for var in variables:
            self.client.subscribe(var)
        await self.client.flush()
        self._task = asyncio.create_task(self._collect())

    async def _collect(self) -> None:
        async for msg in self.client:
            self.seen.setdefault(msg.key, []).append(msg)

    def values(self, var: str) -> list:
        return [msg.value for msg in self.seen.get(var, [])]

    async def wait_for(
        self,
        var: str,
        predicate: Callable[[object], bool] = lambda v: True,
        timeout: float = 20,
        start: int = 0,
    ) -> object:
        """The first value (from the `start`-th on) that satisfies `predicate`."""
        async with asyncio.timeout(timeout):
            while True:
                for value in self.values(var)[start:]:
                    if predicate(value):
                        return value
                await asyncio.sleep(0.02)

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        await self.client.close()


WATCHED = [
    "STATUS_REPORT_IN",
    "DESIRED_HEADING",
    "COMMAND_IN",
    "MODEM_ID",
    "VEHICLE_ID",
    "ACOMMS_NMEA_IN",
    "ACOMMS_NMEA_OUT",
    "ACOMMS_RAW_INCOMING",
    "ACOMMS_RAW_OUTGOING",
    "ACOMMS_MODEM_RECEIVE",
    "ACOMMS_MODEM_TRANSMIT",
    "ACOMMS_QUEUE_RECEIVE",
    "ACOMMS_ACK",
    "ACOMMS_ACK_ORIGINAL",
    "ACOMMS_EXPIRE",
    "ACOMMS_QSIZE",
    "ACOMMS_MAC_INITIATE_TRANSMISSION",
    "ACOMMS_MAC_SLOT_START",
    "ACOMMS_CONFIG",
]


async def start_modem(
    stack: contextlib.AsyncExitStack, modem_id: int, channel, clock
) -> MMSimServer:
    """An emulated Micro-Modem served on loopback TCP, closed with `stack`."""
    sim = MMSimServer(MicroModemModel(modem_id, clock, channel), channel)
    await sim.start()
    stack.push_async_callback(sim.close)
    return sim


def mission_clock(warp: float = WARP) -> Clock:
    """MOOS time at the missions' warp."""
    return moos_clock(warp)


async def start_db(stack: contextlib.AsyncExitStack, modem_id: int, warp: float = WARP) -> MOOSDB:
    """The MOOSDB of community `vehicle<modem_id>` at the missions' warp, closed with `stack`."""
    db = MOOSDB(port=0, community=f"vehicle{modem_id}", clock=mission_clock(warp))
    return await stack.enter_async_context(db)


async def modem_and_db(
    stack: contextlib.AsyncExitStack, modem_id: int, channel, clock
) -> tuple[MMSimServer, MOOSDB]:
    """An emulated Micro-Modem and the MOOSDB of community `vehicle<modem_id>`, both on `clock`
    (MOOS time, at its warp)."""
    modem = await start_modem(stack, modem_id, channel, clock)
    return modem, await start_db(stack, modem_id, clock_warp(clock))


@contextlib.asynccontextmanager
async def two_vehicle_missions(tmp_path: Path, mission, watched: list[str], channel, clock):
    """Vehicles 1 and 2, each an emulated Micro-Modem on `channel`, a MOOSDB, the pAcommsHandler
    of the mission file `mission(modem_id, db_port, modem_port)` writes and a recorder of
    `watched`, all on `clock` (the missions' MOOS time): yields ([app1, app2], [recorder1,
    recorder2])."""
    async with contextlib.AsyncExitStack() as stack:
        apps, recorders = [], []
        for modem_id in (1, 2):
            sim, db = await modem_and_db(stack, modem_id, channel, clock)
            path = tmp_path / f"mm{modem_id}.moos"
            path.write_text(mission(modem_id, db.port, sim.port))
            app = pAcommsHandler.from_mission(path, "pAcommsHandler")
            recorder = Recorder(f"recorder{modem_id}", db.port, clock)
            await recorder.start(watched)
            stack.push_async_callback(recorder.close)
            await stack.enter_async_context(app)
            apps.append(app)
            recorders.append(recorder)
        yield apps, recorders


class MicroModemLink:
    """Micro-Modem emulators on loopback TCP sharing one perfect acoustic channel."""

    def __init__(self, warp: float = WARP) -> None:
        self.sims: list[MMSimServer] = []
        self.clock = mission_clock(warp)
        self.channel = LoopbackChannel(self.clock)

    async def start(self, stack: contextlib.AsyncExitStack, dbs: list[MOOSDB]) -> None:
        for modem_id in (1, 2):
            self.sims.append(await start_modem(stack, modem_id, self.channel, self.clock))

    def driver_cfg(self, modem_id: int) -> str:
        return micromodem_driver(self.sims[modem_id - 1].port)

    def modem_port(self, modem_id: int) -> int:
        return self.sims[modem_id - 1].port


class TwoCommunities:
    """Link (default: emulated Micro-Modems) + DBs + pAcommsHandlers + recorders; `extra` adds
    config to both apps. A link has `start(stack, dbs)` and `driver_cfg(modem_id)` (the
    driver_cfg block of that vehicle's mission); `warp` the missions' MOOSTimeWarp."""

    def __init__(
        self,
        tmp_path: Path,
        extra: str = "",
        slots: str | None = None,
        link=None,
        common: str | None = None,
        warp: float = WARP,
    ) -> None:
        self.tmp_path, self.extra, self.slots, self.warp = tmp_path, extra, slots, warp
        self.link = link if link is not None else MicroModemLink(warp)
        self.common = common
        self.stack = contextlib.AsyncExitStack()

    @property
    def sims(self) -> list[MMSimServer]:
        return self.link.sims

    async def __aenter__(self) -> TwoCommunities:
        self.dbs, self.apps, self.recorders = [], [], []
        for modem_id in (1, 2):
            self.dbs.append(await start_db(self.stack, modem_id, self.warp))
        await self.link.start(self.stack, self.dbs)
        for modem_id, db in zip((1, 2), self.dbs, strict=True):
            path = self.tmp_path / f"vehicle{modem_id}.moos"
            options = {} if self.common is None else {"common": self.common}
            path.write_text(
                mission_text(
                    modem_id,
                    db.port,
                    0,
                    self.extra,
                    self.slots,
                    self.link.driver_cfg(modem_id),
                    **options,
                    warp=self.warp,
                )
            )
            app = pAcommsHandler.from_mission(path, "pAcommsHandler")
            recorder = Recorder(f"recorder{modem_id}", db.port, mission_clock(self.warp))
            await recorder.start(WATCHED)
            self.stack.push_async_callback(recorder.close)
            await self.stack.enter_async_context(app)
            self.apps.append(app)
            self.recorders.append(recorder)
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stack.aclose()

    async def ready(self, timeout: float = 20) -> None:
        """Both drivers started (and linked) and both apps have DB_TIME (the messages' time
        source)."""

        def started(app) -> bool:
            primary = app.acomms.primary
            driver = primary.driver
            link_open = driver.link is None or driver.link.is_open
            return primary.running and link_open and getattr(driver, "startup_complete", True)

        async with asyncio.timeout(timeout):
            while not all(started(app) and "DB_TIME" in app.dynamic_vars for app in self.apps):
                await asyncio.sleep(0.05)
