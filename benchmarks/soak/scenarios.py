"""The soak's scenarios (issues 16, 25): hostile clients beside a measured one, kill -9 of servers
and apps, and signals and link cuts that used to leave apps behind or disconnected.

Each entry of SCENARIOS is `name: async (seconds, workdir) -> Figures`; a hostile-client one is
a line `hostile(SERVER_SPEC, probe, [hostile clients])` (kit.hostile).
"""

from __future__ import annotations

import asyncio
import contextlib
import random
import signal
import socket
import struct
import sys
import time
import urllib.parse
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path

from benchmarks.soak.kit import (
    ANSWER_TIMEOUT,
    Figures,
    Garbage,
    Hostile,
    IdleConnections,
    NonReader,
    ServerProcess,
    ServerSpec,
    Trickle,
    hostile,
    paced,
    stop_or_fail,
    venv_command,
)
from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.rudics import parse_rudics_packet, serialize_rudics_packet
from pygoby.moos import protocol as p
from pygoby.moos.alog import AlogFile
from pygoby.moos.client import MAX_REFUSED_BACKOFF, MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.util.aiorun import STOP_GRACE
from pygoby.util.nmea import with_checksum
from tests.apps.acomms_mission import Recorder, mission_text, modem_and_db
from tests.faults import CuttableRelay

Scenario = Callable[[float, Path], Awaitable[Figures]]

# -- servers ---------------------------------------------------------------------------------

MOOSDB_SPEC = ServerSpec(
    "moosdb",
    venv_command("pygoby", "moosdb", "--port", "{port}"),
    r"listening on 127\.0\.0\.1:(\d+)",
)
# the budget of issue 25's synchronous-subscriber attack (it reached 666 MB RSS before)
MOOSDB_BUDGET_32 = ServerSpec(
    "moosdb",
    venv_command("pygoby", "moosdb", "--port", "{port}", "--memory-budget", "32"),
    MOOSDB_SPEC.ready,
)
# a 64 MB budget for partial packets and unsent output, a packet deadline the run reaches
MOOSDB_BUDGET = ServerSpec(
    "moosdb",
    venv_command(
        "pygoby", "moosdb", "--port", "{port}", "--memory-budget", "64", "--packet-timeout", "5"
    ),
    MOOSDB_SPEC.ready,
)
STORE_SERVER = ServerSpec(
    "store_server",
    venv_command(
        "pygoby", "store_server", "--host", "127.0.0.1", "--port", "{port}", "--db", "store.db"
    ),
    r"listening on 127\.0\.0\.1:(\d+)",
)


def mmsim_spec() -> ServerSpec:
    group = f"239.255.42.99:{random.randint(40000, 49999)}"  # a channel of its own
    return ServerSpec(
        "mmsim",
        venv_command("pygoby", "mmsim", "--port", "{port}", "--id", "1", "--channel-group", group),
        r"listening on [\d.]+:(\d+)",
    )


# -- probes: a well-behaved client, measured ---------------------------------------------------


class StoreClient:
    """A store-server client as the driver is: one request, then its response."""

    def __init__(self, port: int, modem_id: int) -> None:
        self.port, self.modem_id = port, modem_id
        self.reader: asyncio.StreamReader | None = None
        self.writer: asyncio.StreamWriter | None = None
        self.request_id = 0

    async def exchange(self, outbox=()) -> acomms_pb.StoreServerResponse:
        if self.writer is None:
            self.reader, self.writer = await asyncio.open_connection(
                "127.0.0.1", self.port, limit=1 << 22
            )
        assert self.reader is not None
        self.request_id += 1
        request = acomms_pb.StoreServerRequest(modem_id=self.modem_id, request_id=self.request_id)
        request.outbox.extend(outbox)
        try:
            self.writer.write(serialize_rudics_packet(request.SerializeToString()))
            async with asyncio.timeout(ANSWER_TIMEOUT):
                packet = await self.reader.readuntil(b"\r")
        except BaseException:
            self.close()
            raise
        return acomms_pb.StoreServerResponse.FromString(parse_rudics_packet(packet))

    def close(self) -> None:
        if self.writer is not None:
            self.writer.transport.abort()
        self.reader = self.writer = None


def numbered(k: int) -> acomms_pb.ModemTransmission:
    return acomms_pb.ModemTransmission(
        src=1, dest=2, type=acomms_pb.DATA, frame=[k.to_bytes(4, "big")]
    )


@dataclass
class Mailbox:
    """Transmissions posted (the store answered the request carrying them) and read."""

    posted: set[int]
    read: set[int]

    def take(self, response: acomms_pb.StoreServerResponse) -> None:
        self.read.update(int.from_bytes(t.frame[0], "big") for t in response.inbox if t.frame)


async def store_round_trips(
    port: int,
    seconds: float,
    figures: Figures,
    mailbox: Mailbox | None = None,
    on_error: Callable[[], Awaitable[None]] | None = None,
) -> Mailbox:
    """Modem 1 posts a numbered transmission every 0.1 s, modem 2 reads; every exchange is a
    request. A post whose answer did not come is sent again with the next one (as the driver
    does). At the end modem 2 reads until nothing is missing (2 s at most): lost = posted but
    never read."""
    mailbox = mailbox or Mailbox(set(), set())
    poster, reader = StoreClient(port, 1), StoreClient(port, 2)
    unsent: list[int] = []
    next_id = max(mailbox.posted, default=0) + 1

    async def one(client: StoreClient, outbox) -> acomms_pb.StoreServerResponse | None:
        figures.requests += 1
        started = time.perf_counter()
        try:
            response = await client.exchange(outbox)
        except (OSError, TimeoutError, asyncio.IncompleteReadError, ValueError):
            if on_error is not None:
                await on_error()
            return None
        figures.answer(time.perf_counter() - started)
        return response

    async def step(_: int) -> None:
        nonlocal next_id
        unsent.append(next_id)
        next_id += 1
        if await one(poster, [numbered(k) for k in unsent]) is not None:
            mailbox.posted.update(unsent)
            unsent.clear()
        if (response := await one(reader, [])) is not None:
            mailbox.take(response)

    try:
        await paced(seconds, 0.1, step)
        deadline = time.monotonic() + 2
        while not mailbox.posted <= mailbox.read and time.monotonic() < deadline:
            with contextlib.suppress(OSError, TimeoutError, asyncio.IncompleteReadError):
                mailbox.take(await reader.exchange())
    finally:
        poster.close()
        reader.close()
    figures.lost = len(mailbox.posted - mailbox.read)
    return mailbox


async def mmsim_queries(port: int, seconds: float, figures: Figures) -> None:
    """$CCCFQ,SRC and its $CACFG,SRC answer, one at a time, every 0.05 s."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port, limit=1 << 22)
    query = (with_checksum("$CCCFQ,SRC") + "\r\n").encode()

    async def step(_: int) -> None:
        figures.requests += 1
        started = time.perf_counter()
        writer.write(query)
        with contextlib.suppress(TimeoutError, OSError, asyncio.IncompleteReadError):
            async with asyncio.timeout(ANSWER_TIMEOUT):
                while not (await reader.readuntil(b"\n")).startswith(b"$CACFG,SRC,"):
                    pass
                figures.answer(time.perf_counter() - started)

    try:
        await paced(seconds, 0.05, step)
    finally:
        writer.transport.abort()


async def moos_round_trip(port: int, seconds: float, figures: Figures) -> None:
    """A MOOS client's own post coming back to it, every 0.05 s."""
    async with MOOSClient(f"soak_probe_{random.randint(0, 1 << 30)}", port=port) as client:
        client.subscribe("SOAK_PROBE")
        await client.flush()

        async def step(k: int) -> None:
            figures.requests += 1
            started = time.perf_counter()
            client.publish("SOAK_PROBE", float(k))
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(ANSWER_TIMEOUT):
                    while (msg := await client.receive()).key != "SOAK_PROBE" or msg.dval != k:
                        pass
                    figures.answer(time.perf_counter() - started)

        await paced(seconds, 0.05, step)


def moos_handshake(name: str, asynchronous: bool = True) -> bytes:
    return p.PROTOCOL_STRING + p.encode_packet([p.handshake_message(name, 0.0, asynchronous)])


@dataclass
class MoosHostile(Hostile):
    """A MOOS client running `action(client, stop)` once connected."""

    action: Callable[[MOOSClient, asyncio.Event], Awaitable[None]]

    async def run(self, port: int, stop: asyncio.Event) -> None:
        async with MOOSClient(f"soak_hostile_{random.randint(0, 1 << 30)}", port=port) as client:
            await self.action(client, stop)
            await stop.wait()


async def post_bulk(client: MOOSClient, stop: asyncio.Event) -> None:
    """20 MB for the non-readers that subscribed to SOAK_BULK."""
    for _ in range(200):
        client.publish("SOAK_BULK", b"\0" * 100_000)
        await client.flush()


async def wildcard_hog(client: MOOSClient, stop: asyncio.Event) -> None:
    """A pattern a backtracking matcher takes exponential time on, and new 64-character names
    (a pattern is tested when a variable is first written) every 0.1 s."""
    client.subscribe_wildcard("*a*a*a*a*a*a*a*a*a*a*b", "*")
    k = 0
    while not stop.is_set():
        client.publish(f"{k:a>64}".replace("0", "a")[:64], 1.0)
        k += 1
        await asyncio.sleep(0.1)


async def long_names_and_patterns(client: MOOSClient, stop: asyncio.Event) -> None:
    """Issue 25 item 1: a 30 kB name and `*` + 2000 x `?` + `X*` (refused: beyond the caps),
    then the longest name and pattern allowed (256), a new name every 0.05 s, the pattern
    registered again each time (tested against every variable)."""
    k = 0
    while not stop.is_set():
        client.publish(f"{k}" + "A" * 30_000, 1.0)
        client.subscribe_wildcard("*" + "?" * 2000 + "X*")
        client.publish(f"{k:A>256}", 1.0)
        client.subscribe_wildcard("*" + "?" * 253 + "X*")
        await client.flush()
        k += 1
        await asyncio.sleep(0.05)


# Issue 25 item 2: 200,000 distinct variables as fast as they go (3 s before), from a process
# of its own (making them would otherwise hold up the probe in this one); the DB keeps 20,000
# (--max-variables) and refuses the rest. Argument: the DB's port.
MANY_VARIABLES = """
import asyncio, sys
from pygoby.moos.client import MOOSClient

async def main():
    async with MOOSClient("soak_many", port=int(sys.argv[1])) as client:
        for batch in range(40):
            for k in range(5000):
                client.publish(f"SOAK_MANY_{batch}_{k}", 1.0)
            await client.flush()
        await asyncio.sleep(3600)

asyncio.run(main())
"""


@dataclass
class HostileProcess(Hostile):
    """`script` run by this Python in a process of its own (argument: the port) until the end."""

    script: str

    async def run(self, port: int, stop: asyncio.Event) -> None:
        proc = await asyncio.create_subprocess_exec(
            sys.executable, "-c", self.script, str(port), stderr=asyncio.subprocess.DEVNULL
        )
        try:
            await stop.wait()
        finally:
            with contextlib.suppress(ProcessLookupError):
                proc.kill()
            await proc.wait()


async def flood(client: MOOSClient, stop: asyncio.Event) -> None:
    """100 kB notifications of ten variables without a pause, until the run ends."""
    k = 0
    while not stop.is_set():
        client.publish(f"SOAK_FLOOD_{k % 10}", b"\0" * 100_000)
        await client.flush()
        k += 1


@dataclass
class SyncSleeper(Hostile):
    """Issue 25 item 3: a synchronous client subscribed to `*` that never writes again (its
    mail is held for its next packet) nor reads; reconnects when dropped."""

    async def run(self, port: int, stop: asyncio.Event) -> None:
        name = f"soak_sync_{random.randint(0, 1 << 30)}"
        register = p.MOOSMessage(
            p.WILDCARD_REGISTER, p.STRING, "", sval=p.wildcard_sval("*", "*", 0.0), src=name
        )
        while not stop.is_set():
            with contextlib.suppress(OSError):
                _, writer = await asyncio.open_connection("127.0.0.1", port)
                sock = writer.get_extra_info("socket")
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
                try:
                    writer.write(moos_handshake(name, False) + p.encode_packet([register]))
                    while not stop.is_set() and not writer.is_closing():
                        with contextlib.suppress(TimeoutError):
                            async with asyncio.timeout(0.2):
                                await stop.wait()
                        if writer.transport.is_closing():
                            break
                finally:
                    writer.transport.abort()
            await asyncio.sleep(0.2)


def packet_hogs(count: int, sent: int) -> list[Trickle]:
    """MOOS clients announcing a 16 MB packet, sending `sent` bytes of it, then one a while."""
    return [
        Trickle(moos_handshake(f"soak_hog{i}") + struct.pack("<iiB", 16 << 20, 1, 0) + bytes(sent))
        for i in range(count)
    ]


MOOS_REGISTER_BULK = moos_handshake("soak_sleeper") + p.encode_packet(
    [p.MOOSMessage(p.REGISTER, p.DOUBLE, "SOAK_BULK", dval=0, src="soak_sleeper")]
)

# -- kill -9 of servers ----------------------------------------------------------------------


async def store_server_kill9(seconds: float, workdir: Path) -> Figures:
    """The store server killed with SIGKILL every 3 s and restarted on its file: every
    transmission it answered for is read by its destination in the end."""
    figures = Figures()
    server = ServerProcess(STORE_SERVER, workdir)
    await server.start()
    kills = 0

    async def killer() -> None:
        nonlocal kills
        while True:
            await asyncio.sleep(random.uniform(2.0, 4.0))
            await server.kill9()
            kills += 1
            await asyncio.sleep(0.2)
            await server.start()

    task = asyncio.create_task(killer())
    try:
        # a failed exchange waits a little: the killer restarts the server
        await store_round_trips(server.port, seconds, figures, on_error=lambda: asyncio.sleep(0.2))
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
        if not server.alive:
            await server.start()
        await stop_or_fail(server, figures)
    finally:
        task.cancel()
        await server.kill9()
    figures.requests = figures.answered  # a request cut by a kill is sent again, not lost
    figures.notes.append(f"{kills} kills")
    figures.judge()
    return figures


# -- pAcommsHandler: kill -9 with a persistent queue ------------------------------------------


async def pacommshandler_kill9(seconds: float, workdir: Path) -> Figures:
    """Vehicle 1's pAcommsHandler (a process, persistent queue) is sent commands and killed
    with SIGKILL at random moments; vehicle 2 (in this process) receives. lost = commands
    whose queuing vehicle 1 reported (ACOMMS_QSIZE) that never reached vehicle 2."""
    from pygoby.acomms.mmsim import LoopbackChannel
    from pygoby.apps.pacommshandler import pAcommsHandler
    from pygoby.util.clock import WallClock

    figures = Figures()
    channel, clock = LoopbackChannel(), WallClock()
    async with contextlib.AsyncExitStack() as stack:
        sims, dbs = zip(
            *[await modem_and_db(stack, modem_id, channel, clock) for modem_id in (1, 2)],
            strict=True,
        )
        text = mission_text(1, dbs[0].port, sims[0].port).replace(
            "  queue_cfg {\n", '  queue_cfg {\n    persistent_queue_file: "queue.sqlite"\n', 1
        )
        (workdir / "vehicle1.moos").write_text(text)
        (workdir / "vehicle2.moos").write_text(mission_text(2, dbs[1].port, sims[1].port))
        vehicle2 = pAcommsHandler.from_mission(workdir / "vehicle2.moos", "pAcommsHandler")
        await stack.enter_async_context(vehicle2)
        r1, r2 = Recorder("soak1", dbs[0].port), Recorder("soak2", dbs[1].port)
        await r1.start(["ACOMMS_QSIZE", "DB_TIME"])
        await r2.start(["COMMAND_IN"])
        stack.push_async_callback(r1.close)
        stack.push_async_callback(r2.close)
        vehicle1 = AppProcess(
            ["pAcommsHandler", "vehicle1.moos"], workdir, dbs[0], "pAcommsHandler"
        )
        stack.push_async_callback(vehicle1.kill9)
        queued: set[int] = set()
        crossed: set[int] = set()  # still to deliver when vehicle 1 was killed
        kills = 0
        loop = asyncio.get_running_loop()
        end = loop.time() + seconds
        command_id = 0
        while loop.time() < end:
            await vehicle1.start()
            await r1.wait_for("DB_TIME", start=len(r1.values("DB_TIME")), timeout=10)
            for _ in range(random.randint(1, 3)):
                command_id += 1
                seen = len(r1.values("ACOMMS_QSIZE"))
                r1.client.publish(
                    "COMMAND_OUT", f"dest=2,command_id={command_id},heading=1,speed=1,depth=1"
                )
                with contextlib.suppress(TimeoutError):
                    await r1.wait_for(
                        "ACOMMS_QSIZE", lambda v: "dccl_id: 21" in v, timeout=3, start=seen
                    )
                    queued.add(command_id)
            await asyncio.sleep(random.uniform(0.0, 2.0))  # often before its next slot (6 s TDMA)
            await vehicle1.kill9()
            kills += 1
            crossed |= queued - {_command_id(v) for v in r2.values("COMMAND_IN")}
        await vehicle1.start()  # the last run delivers what is left
        delivered = set[int]()
        deadline = loop.time() + 30
        while not queued <= delivered and loop.time() < deadline:
            await asyncio.sleep(0.5)
            delivered = {_command_id(v) for v in r2.values("COMMAND_IN")}
        received = [_command_id(v) for v in r2.values("COMMAND_IN")]
        figures.requests, figures.answered = len(queued), len(queued & delivered)
        figures.lost = len(queued - delivered)
        figures.notes.append(
            f"{kills} kills; {len(crossed)} commands crossed a kill; "
            f"{len(received) - len(set(received))} duplicates (at-least-once)"
        )
    figures.judge()
    return figures


def _command_id(text: str) -> int:
    fields = dict(part.split("=", 1) for part in text.split(",") if "=" in part)
    return int(fields.get("command_id", -1))


class AppProcess:
    """A MOOS app's console script run in `workdir`; `start` returns once it is in the DB."""

    def __init__(self, argv: list[str], workdir: Path, db: MOOSDB | None, name: str) -> None:
        self.argv, self.workdir, self.db, self.name = argv, workdir, db, name
        self.proc: asyncio.subprocess.Process | None = None

    async def start(self) -> None:
        self.proc = await asyncio.create_subprocess_exec(
            *venv_command(*self.argv),
            cwd=self.workdir,
            stdout=asyncio.subprocess.DEVNULL,
            stderr=asyncio.subprocess.DEVNULL,
        )
        if self.db is not None:
            async with asyncio.timeout(30):
                while self.name not in self.db.client_names:
                    await asyncio.sleep(0.05)

    async def kill9(self) -> None:
        if self.proc is not None and self.proc.returncode is None:
            self.proc.send_signal(signal.SIGKILL)
            await self.proc.wait()
            if self.db is not None:
                async with asyncio.timeout(5):
                    while self.name in self.db.client_names:
                        await asyncio.sleep(0.02)


# -- pLogger: kill -9 while logging ------------------------------------------------------------

PLOGGER_MISSION = """\
ServerPort = {port}
Community = soak
ProcessConfig = pLogger
{{
  AppTick = 10
  CommsTick = 10
  File = run{run}
  PATH = {workdir}
  FileTimeStamp = false
  Log = COUNT @ 0
  LoggingDirectorySummaryFile = {workdir}/.LastOpenedMOOSLogDirectory
}}
"""
PLOGGER_RATE = 200.0  # COUNT posts per second


async def plogger_kill9(seconds: float, workdir: Path) -> Figures:
    """pLogger (a process) logging COUNT at 200 Hz, killed with SIGKILL 1 to 3 s after each
    start and started again on a new file. request = one kill; latency = how much was lost:
    from the post time of the first value its .alog lacks to the kill (the promise: at most
    the last second)."""
    figures = Figures(latency_limit=1.0)
    posted: dict[int, float] = {}  # COUNT value -> wall time of its post
    async with (
        MOOSDB(port=0, community="soak") as db,
        MOOSClient("soak_counter", port=db.port) as counter,
    ):

        async def count() -> None:
            n = 0
            while True:
                n += 1
                posted[n] = time.monotonic()
                counter.publish("COUNT", float(n))
                await asyncio.sleep(1 / PLOGGER_RATE)

        counting = asyncio.create_task(count())
        logger = AppProcess(["pLogger", "plogger.moos"], workdir, db, "pLogger")
        loop = asyncio.get_running_loop()
        end = loop.time() + seconds
        run = 0
        try:
            while loop.time() < end:
                run += 1
                (workdir / "plogger.moos").write_text(
                    PLOGGER_MISSION.format(port=db.port, run=run, workdir=workdir)
                )
                await logger.start()
                await asyncio.sleep(0.5)  # its registration for COUNT reaches the DB
                first = max(posted, default=0) + 1
                await asyncio.sleep(random.uniform(1.0, 3.0))
                killed_at = time.monotonic()
                await logger.kill9()
                alog = workdir / f"run{run}" / f"run{run}.alog"
                logged = {int(e.value) for e in AlogFile(alog) if e.name == "COUNT"}
                missing = [n for n in posted if n >= first and posted[n] < killed_at - 0.05]
                missing = [n for n in missing if n not in logged]
                figures.requests += 1
                figures.answer(killed_at - posted[missing[0]] if missing else 0.0)
        finally:
            counting.cancel()
            await logger.kill9()
    figures.notes.append(f"{run} kills at {PLOGGER_RATE:g} posts/s")
    figures.judge()
    return figures


# -- MOOSDB: kill -9 under running apps ---------------------------------------------------------

APPS_MISSION = """\
ServerHost = localhost
ServerPort = {port}
Community = soak
ProcessConfig = uSimVehicle
{{
  common {{ log: false  app_tick: 10  verbosity: QUIET }}
  start_speed: 1  nav_period: 0.2
}}
ProcessConfig = pAcommsHandler
{{
  common {{ log: false  app_tick: 10  verbosity: QUIET }}
  modem_id: 1
  mac_cfg {{ type: MAC_FIXED_DECENTRALIZED
            slot {{ src: 1 slot_seconds: 0.5 }} slot {{ src: 2 slot_seconds: 0.5 }} }}
}}
ProcessConfig = pTranslator
{{
  common {{ log: false  app_tick: 10  verbosity: QUIET }}
}}
"""
APPS = ("uSimVehicle", "pAcommsHandler", "pTranslator")
STALE_TIMEOUT = 2.0  # s: the DB's client timeout in the stale-session scenario


async def moosdb_kill9(seconds: float, workdir: Path) -> Figures:
    """The MOOSDB (a process) killed with SIGKILL every ~4 s and restarted: uSimVehicle,
    pAcommsHandler and pTranslator come back each time (request = one app after one restart;
    latency = until it is in the DB again), and pAcommsHandler's MAC kept its slots meanwhile
    (its slot starts stamped inside the outages reach the restarted DB)."""
    figures = Figures(latency_limit=5.0)  # reconnection: 0.5 s attempts, a busy machine
    server = ServerProcess(MOOSDB_SPEC, workdir)
    port = await server.start()
    (workdir / "apps.moos").write_text(APPS_MISSION.format(port=port))
    apps = [AppProcess([name, "apps.moos"], workdir, None, name) for name in APPS]
    outages: list[tuple[float, float]] = []
    slot_times: list[float] = []
    try:
        for app in apps:
            await app.start()
        async with MOOSClient("soak_watch", port=port, reconnect_interval=0.1) as watch:
            await _all_in(watch, APPS, 30)
            loop = asyncio.get_running_loop()
            end = loop.time() + seconds
            while loop.time() < end:
                await asyncio.sleep(random.uniform(2.0, 4.0))
                await server.kill9()
                down = time.time()
                await asyncio.sleep(random.uniform(0.5, 2.0))
                await server.start()
                up = time.time()
                outages.append((down, up))
                started = time.perf_counter()
                watch.subscribe(
                    "ACOMMS_MAC_SLOT_START"
                )  # on every connection, posts kept meanwhile
                back = await _all_in(watch, APPS, 20)
                figures.requests += len(APPS)
                for name in back:
                    figures.answer(back[name] - started)
                await asyncio.sleep(1.0)
                slot_times += [m.time for m in watch.fetch() if m.key == "ACOMMS_MAC_SLOT_START"]
        alive = [
            app.argv[0] for app in apps if app.proc is not None and app.proc.returncode is None
        ]
        if len(alive) != len(apps):
            figures.failures.append(f"apps died: {sorted(set(APPS) - set(alive))}")
        kept = sum(any(down < t < up for down, up in outages) for t in slot_times)
        figures.notes.append(f"{len(outages)} kills; {kept} MAC slot starts posted during outages")
        if outages and not kept:
            figures.failures.append("pAcommsHandler's MAC stopped during the DB outages")
    finally:
        for app in apps:
            await app.kill9()
        await server.kill9()
    figures.judge()
    return figures


async def _all_in(watch: MOOSClient, names, timeout: float) -> dict[str, float]:
    """perf_counter times at which each of `names` was seen in the DB's client list."""
    seen: dict[str, float] = {}
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while len(seen) < len(names) and loop.time() < deadline:
        with contextlib.suppress(ConnectionError):
            await watch.wait_connected(1)
            for reply in await watch.server_request("PROC_SUMMARY", timeout=0.5):
                for name in names:
                    if name not in seen and reply.string.startswith(f"{name}:"):
                        seen[name] = time.perf_counter()
        await asyncio.sleep(0.05)
    return seen


# -- apps: SIGTERM as the DB drops; a link cut leaving a stale session ------------------------


async def sigterm_on_drop(seconds: float, workdir: Path) -> Figures:
    """An app gets SIGTERM within a few ms of its MOOSDB going away (the DB killed or stopped):
    it must end within the grace (request = one trial; latency = until it ended)."""
    figures = Figures(latency_limit=STOP_GRACE + 0.5)
    loop = asyncio.get_running_loop()
    end = loop.time() + seconds
    trial = 0
    while loop.time() < end:
        name = APPS[trial % len(APPS)]
        trial += 1
        db = MOOSDB(port=0, community="soak")
        await db.start()
        (workdir / "apps.moos").write_text(APPS_MISSION.format(port=db.port))
        app = AppProcess([name, "apps.moos"], workdir, db, name)
        try:
            await app.start()
            await asyncio.sleep(random.uniform(0.5, 1.5))
            offset = random.uniform(-0.02, 0.02)
            if offset > 0:
                await db.stop()
                await asyncio.sleep(offset)
            assert app.proc is not None
            app.proc.send_signal(signal.SIGTERM)
            started = time.perf_counter()
            if offset <= 0:
                await asyncio.sleep(-offset)
                await db.stop()
            figures.requests += 1
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(STOP_GRACE + 2):
                    await app.proc.wait()
                    figures.answer(time.perf_counter() - started)
        finally:
            await app.kill9()
            await db.stop()
    figures.notes.append(f"{trial} trials over {', '.join(APPS)}")
    figures.judge()
    return figures


async def stale_session(seconds: float, workdir: Path) -> Figures:
    """uSimVehicle's link to the DB is cut without the DB noticing (it keeps the stale session
    for its 2 s client timeout and refuses the name meanwhile): the app must come back by
    itself every time (latency = from the cut until it is in the DB again: the DB's timeout,
    then the client's back-off)."""
    figures = Figures(latency_limit=STALE_TIMEOUT + MAX_REFUSED_BACKOFF + 1)
    async with MOOSDB(port=0, community="soak", client_timeout=STALE_TIMEOUT) as db:
        relay = CuttableRelay(db.port)
        await relay.start()
        (workdir / "apps.moos").write_text(APPS_MISSION.format(port=relay.port))
        app = AppProcess(["uSimVehicle", "apps.moos"], workdir, db, "uSimVehicle")
        try:
            await app.start()
            loop = asyncio.get_running_loop()
            end = loop.time() + seconds
            while loop.time() < end:
                await asyncio.sleep(random.uniform(1.0, 3.0))
                relay.cut()
                started = time.perf_counter()
                figures.requests += 1
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(figures.latency_limit + 5):
                        while "uSimVehicle" in db.client_names:  # the stale session
                            await asyncio.sleep(0.02)
                        while "uSimVehicle" not in db.client_names:
                            await asyncio.sleep(0.02)
                        figures.answer(time.perf_counter() - started)
        finally:
            await app.kill9()
            await relay.close()
    figures.judge()
    return figures


# -- netsim_manager (the load benchmark's clients, with garbage clients beside them) -----------


async def netsim_manager_hostile(seconds: float, workdir: Path) -> Figures:
    """64 clients x 10 Hz NavUpdates with garbage clients (benchmarks/test_netsim_bench.py)."""
    from benchmarks.test_netsim_bench import ManagerProcess, _config, _load

    figures = Figures()
    manager = ManagerProcess(_config(workdir))
    try:
        figures.rss_before_mb = _rss(manager.process.pid)
        result = await _load(manager.port, seconds, garbage_clients=4)
        figures.rss_after_mb = _rss(manager.process.pid)
        if not manager.alive():
            figures.failures.append("netsim_manager died")
    finally:
        manager.process.send_signal(signal.SIGTERM)
        try:
            manager.process.wait(10)
        except Exception:
            figures.failures.append("netsim_manager did not end on SIGTERM")
            manager.process.kill()
    figures.requests, figures.answered = result["sent"], result["answered"]
    figures.given_ms = (result["p50_ms"], result["p99_ms"])
    figures.judge()
    return figures


# -- liaison (issue 25.6-7) --------------------------------------------------------------------

LIAISON_VARIABLES = 2000
LIAISON_STREAMS = 100  # asked for; liaison admits max_streams (16) of them
# regexes that froze a regex engine for seconds to minutes per name; liaison's filter is words and
# MOOS globs now, so they are plain text
LIAISON_FILTERS = [r"((\w+)+)+!", r"(a|aa)+$", "*" + "?*" * 90 + "!", "x" * 200]


async def _http_get(port: int, target: str) -> bytes:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        writer.write(
            f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n".encode()
        )
        await writer.drain()
        return await reader.read()
    finally:
        writer.close()


async def _event_stream(port: int, target: str, stop: asyncio.Event) -> None:
    """A live page that reads everything until `stop` (or until refused)."""
    with contextlib.suppress(OSError):
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        try:
            writer.write(f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
            await writer.drain()
            while not stop.is_set():
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(0.5):
                        if not await reader.read(65536):
                            return
        finally:
            writer.close()


async def liaison_streams_and_filters(seconds: float, workdir: Path) -> Figures:
    """`pygoby liaison` on a MOOSDB with 2000 variables, 100 live Scope streams asked for and
    filters that freeze a regex engine, beside a canary GET every 0.1 s."""
    from tests.topside.test_commander import MISSION

    figures = Figures()
    async with MOOSDB(port=0, community="topside") as db:
        mission = workdir / "topside.moos"
        mission.write_text(
            f"ServerPort = {db.port}\nCommunity = topside\n{MISSION}\n"
            "ProcessConfig = liaison\n{\n  common { log: false }\n  liaison { http_port: 0 }\n}\n"
        )
        spec = ServerSpec(
            "liaison",
            venv_command("pygoby", "liaison", str(mission)),
            r"serving http://127\.0\.0\.1:(\d+)/",
        )
        server = ServerProcess(spec, workdir)
        port = await server.start()
        async with MOOSClient("soak_poster", port=db.port) as poster:
            for i in range(LIAISON_VARIABLES):
                poster.publish(f"SOAK_VARIABLE_{i:05d}", float(i))
            await poster.flush()
            await asyncio.sleep(2)  # liaison has them
            figures.rss_before_mb = server.rss_mb()
            stop = asyncio.Event()
            pages = [
                asyncio.create_task(
                    _event_stream(
                        port,
                        "/api/events?page=scope&filter="
                        + urllib.parse.quote(
                            LIAISON_FILTERS[i % len(LIAISON_FILTERS)] if i % 2 else ""
                        ),
                        stop,
                    )
                )
                for i in range(LIAISON_STREAMS)
            ]

            async def canary() -> None:
                started = time.monotonic()
                reply = await _http_get(port, "/api/commander/types")
                if reply.startswith(b"HTTP/1.1 200"):
                    figures.answer(time.monotonic() - started)

            deadline = time.monotonic() + seconds
            while time.monotonic() < deadline:
                figures.requests += 1
                with contextlib.suppress(TimeoutError, OSError):
                    async with asyncio.timeout(ANSWER_TIMEOUT):
                        await canary()
                # the variables keep changing: the streams get deltas
                poster.publish(f"SOAK_VARIABLE_{figures.requests % LIAISON_VARIABLES:05d}", 0.5)
                await asyncio.sleep(0.1)
            figures.rss_after_mb = server.rss_mb()
            stop.set()
            await asyncio.gather(*pages, return_exceptions=True)
        await stop_or_fail(server, figures)
    figures.notes.append(
        f"{LIAISON_VARIABLES} variables, {LIAISON_STREAMS} streams asked for (16 admitted)"
    )
    figures.judge()
    return figures


def _rss(pid: int) -> float | None:
    from benchmarks.soak.kit import rss_mb

    return rss_mb(pid)


# -- the list ----------------------------------------------------------------------------------

GARBAGE = [bytes(random.getrandbits(8) for _ in range(65536)), b"Z" * (128 << 10), b"x\r" * 4096]
MMSIM_HOSTILE_LINES = [
    (with_checksum("$CCCLK," + "9" * 40 + ",1,1,1,1,1") + "\r\n").encode(),
    (with_checksum("$CCTMS,0001-01-01T00:00:00Z,0") + "\r\n").encode(),
    b"".join((with_checksum(f"$CCCFG,K{i},1") + "\r\n").encode() for i in range(2000)),
    (with_checksum("$CCCYC,0,1,2,1,1,40000000") + "\r\n").encode(),
]

SCENARIOS: dict[str, Scenario] = {
    "netsim_manager: 64 clients x 10 Hz, garbage clients beside": netsim_manager_hostile,
    "MOOSDB: garbage, non-reading and idle clients beside a round trip": hostile(
        MOOSDB_SPEC,
        moos_round_trip,
        [
            Garbage(GARBAGE),
            NonReader(MOOS_REGISTER_BULK),
            MoosHostile(post_bulk),
            IdleConnections(200),
        ],
    ),
    "MOOSDB: backtracking wildcard and 64-character names (16.1)": hostile(
        MOOSDB_SPEC, moos_round_trip, [MoosHostile(wildcard_hog)]
    ),
    "MOOSDB: 20 clients trickling 4 MB of 16 MB packets, 64 MB budget (16.5)": hostile(
        MOOSDB_BUDGET, moos_round_trip, packet_hogs(20, 4 << 20)
    ),
    "MOOSDB: 400 idle connections and unread output, 64 MB budget (16.5)": hostile(
        MOOSDB_BUDGET,
        moos_round_trip,
        [
            IdleConnections(400),
            NonReader(MOOS_REGISTER_BULK),
            MoosHostile(post_bulk),
            MoosHostile(post_bulk),
        ],
    ),
    "MOOSDB: 30 kB names, 2000-? patterns and the longest allowed, again and again (25.1)": (
        hostile(MOOSDB_SPEC, moos_round_trip, [MoosHostile(long_names_and_patterns)])
    ),
    "MOOSDB: 200,000 distinct variables in a burst (25.2)": hostile(
        MOOSDB_SPEC, moos_round_trip, [HostileProcess(MANY_VARIABLES)]
    ),
    "MOOSDB: a synchronous * subscriber never reading beside a flood, 32 MB budget (25.3)": (
        hostile(MOOSDB_BUDGET_32, moos_round_trip, [SyncSleeper(), MoosHostile(flood)])
    ),
    "store_server: garbage, trickling and idle clients beside two modems": hostile(
        STORE_SERVER,
        store_round_trips,
        [
            Garbage(GARBAGE),
            Trickle(b"\x01" * 1000),
            IdleConnections(200),
            Garbage(
                [
                    serialize_rudics_packet(
                        acomms_pb.StoreServerRequest(modem_id=9).SerializeToString()
                    )
                    * 3000
                ],
                pause=0.0,
            ),
        ],
    ),
    "mmsim: hostile NMEA and a non-reading client beside a querying one": hostile(
        mmsim_spec(),
        mmsim_queries,
        [
            Garbage(MMSIM_HOSTILE_LINES + GARBAGE),
            NonReader((with_checksum("$CCCFQ,ALL") + "\r\n").encode()),
        ],
    ),
    "store_server: kill -9 every ~3 s under two modems": store_server_kill9,
    "pAcommsHandler: kill -9 at random with a persistent queue": pacommshandler_kill9,
    "pLogger: kill -9 while logging 200 Hz loses at most the last second": plogger_kill9,
    "MOOSDB: kill -9 every ~3 s under uSimVehicle, pAcommsHandler, pTranslator": moosdb_kill9,
    "apps: SIGTERM as the MOOSDB goes away": sigterm_on_drop,
    "apps: link cut, the DB keeps a stale session": stale_session,
    "liaison: 100 live streams over 2000 variables, regex-bomb filters (25.6-7)": (
        liaison_streams_and_filters
    ),
}
