"""`make demo`: pygoby on its embedded defaults, showing what it does.

1. DCCL: a vehicle status report encoded (clear and encrypted) and decoded: the same bytes the
   C++ DCCL library produces.
2. A two-vehicle acoustic-communications mission, time-warped: the missions next to this file
   (topside.moos and unicorn.moos: a topside and an AUV, each a MOOS community with its own
   embedded MOOSDB, pAcommsHandler and uSimVehicle) run in this process, each pAcommsHandler
   talking to an emulated WHOI Micro-Modem over loopback TCP, with TDMA slots. The emulators
   hear each other through netsim's acoustic physics (`PhysicsChannel`), at the vehicles'
   positions. The vehicles broadcast DCCL status reports; the topside sends acknowledged
   commands that send the AUV away, so travel times grow with range until packets are lost. A
   monitor client on each MOOSDB prints what happens, slot by slot; every acoustic transmission
   and reception goes to an event log (`pygoby netsim report LOG` plots it), and each
   community's pLogger writes its .alog (`pygoby log summary FILE` reads it).

    python examples/two_vehicles/run_demo.py [--warp 25] [--duration 720] [--event-log PATH]
                                             [--log-dir DIR] [--skip-dccl]

`run_mission()` is the reusable part (benchmarks/test_acomms_handler_bench.py uses it).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from google.protobuf import text_format

from pygoby.acomms.messages import MM_CONFIG
from pygoby.dccl import Codec
from pygoby.dccl.analyze import describe

MISSION_DIR = Path(__file__).resolve().parent
EXAMPLES = MISSION_DIR.parent
VEHICLES = (("topside", 1), ("unicorn", 2))
# The missions' emulator ports (their `pygoby mmsim --port` lines): the nodes' identities in the
# acoustic channel and its event log.
MODEM_PORTS = {"topside": 62101, "unicorn": 62102}
NAV = ("NAV_X", "NAV_Y", "NAV_DEPTH", "NAV_SPEED", "NAV_HEADING")
SHORT_NAMES = {"pygoby.examples.SimpleStatus": "status", "pygoby.examples.Command": "command"}
WATCHED = (
    "ACOMMS_MAC_SLOT_START",
    "ACOMMS_MODEM_TRANSMIT",
    "ACOMMS_QUEUE_RECEIVE",
    "ACOMMS_ACK_ORIGINAL",
    "ACOMMS_QSIZE",
    "STATUS_REPORT_IN",
    "COMMAND_IN",
    "COMMAND_OUT",
    *NAV,
)
# The acoustic environment: spherical spreading and a noisy harbour (100 dB re 1 uPa of ambient
# noise in the modem's band), so that rate-0 packets fail beyond 2-3.5 km, within reach of the AUV
# in a demo of minutes (netsim's default channel carries them to about 9.5 km). The channel has no
# fading, so rate 0 (the data and every control packet here) gets a wide frame-error curve in its
# place: losses grow over a kilometre of range instead of all at once.
CHANNEL_SETTINGS = {"spreading": 2.0, "noise_level": 100.0}
RATE0_FRAME_ERRORS = {"snr50_db": 0.0, "width_db": 1.5}  # logistic: 1% at 7 dB, 99% at -7 dB
PHYSICS_SEED = 1


def dccl_demo() -> None:
    codec = Codec()
    status_cls = codec.load_proto(
        EXAMPLES / "dccl" / "status.proto", "pygoby.examples.VehicleStatus"
    )
    print(describe(codec.compiled(status_cls)))
    status = status_cls(
        time=float(int(time.time())),
        src=3,
        nav_x=1234.4,
        nav_y=-567.8,
        nav_depth=42.25,
        nav_heading=271.6,
        nav_speed=1.46,
        mode=status_cls.MODE_SURVEY,
        note="all good",
    )
    plain = codec.encode(status)
    print("\nstatus:    ", text_format.MessageToString(status, as_one_line=True))
    print(
        f"encoded:    {plain.hex()}  ({len(plain)} bytes;"
        f" protobuf would use {len(status.SerializeToString())})"
    )
    print("decoded:   ", text_format.MessageToString(codec.decode(plain), as_one_line=True))
    secret = Codec(passphrase="demo passphrase")
    encrypted = secret.encode(status)
    print(f"encrypted:  {encrypted.hex()}  (header {encrypted[:2].hex()} stays clear)")
    assert secret.decode(encrypted) == codec.decode(plain)


# ---------------------------------------------------------------------------------------------
# The two-vehicle mission


@dataclass
class VehicleStats:
    """What one community's monitor saw (counts of DCCL messages by short type name)."""

    name: str
    modem_id: int
    sent: Counter = field(default_factory=Counter)
    received: Counter = field(default_factory=Counter)
    acked: Counter = field(default_factory=Counter)
    queued: dict[str, int] = field(default_factory=dict)
    last_report: str = ""
    # acoustic packets that reached this vehicle's modem, and those it could not decode
    packets_in: int = 0
    packets_lost: int = 0
    last_range_m: float | None = None  # of the newest packet that reached it
    last_owtt: float | None = None  # its one-way travel time, s


class AcousticTally:
    """An `on_event` sink for `PhysicsChannel`: counts each vehicle's receptions in its
    VehicleStats and passes every event on to `sink` (the event log)."""

    def __init__(self, by_port: dict[int, VehicleStats], sink=None) -> None:
        self.by_port, self.sink = by_port, sink
        self.newest: VehicleStats | None = None  # the receiver of the newest reception

    def __call__(self, event: dict) -> None:
        if self.sink is not None:
            self.sink(event)
        receiver = self.by_port.get(event["port"]) if event["event"] == "rx" else None
        if receiver is None:
            return
        receiver.packets_in += 1
        receiver.packets_lost += event["outcome"] != "good"
        receiver.last_range_m, receiver.last_owtt = event["range_m"], event["owtt"]
        self.newest = receiver


@dataclass
class MissionResult:
    simulated_seconds: float
    real_seconds: float
    vehicles: list[VehicleStats]
    alogs: list[Path] = field(default_factory=list)  # each community's pLogger .alog

    @property
    def delivered(self) -> int:
        """End-to-end messages: accepted by the receiving queue and published to MOOS."""
        return sum(sum(v.received.values()) for v in self.vehicles)

    @property
    def per_simulated_hour(self) -> float:
        return self.delivered * 3600.0 / self.simulated_seconds if self.simulated_seconds else 0.0


_QUIET = 1  # goby.util.protobuf.GLogConfig.QUIET


def _short(value: str) -> str:
    """The short type name of an `@PB[type] ...` post."""
    name = value[4 : value.find("]")] if value.startswith("@PB[") else "?"
    return SHORT_NAMES.get(name, name.rsplit(".", 1)[-1])


def _field(value: str, name: str) -> str:
    _, _, rest = value.partition(f"{name}: ")
    return rest.split(" ", 1)[0] if rest else ""


class Monitor:
    """A MOOS client on one community that turns ACOMMS_* mail into VehicleStats and events."""

    def __init__(self, stats: VehicleStats, codec: Codec, clock, port: int, say, on_nav) -> None:
        """`on_nav(nav, t)`: the vehicle's NAV_* values (by name) at MOOS time t, on every
        NAV_* post once each has been seen."""
        from pygoby.moos.client import MOOSClient

        self.stats, self.codec, self.say, self.on_nav = stats, codec, say, on_nav
        self.nav: dict[str, float] = {}
        self.id_names = {
            codec.compiled(cls).id: SHORT_NAMES[cls.DESCRIPTOR.full_name] for cls in codec.loaded()
        }
        self.client = MOOSClient(
            f"uDemoMonitor_{stats.name}", port=port, clock=clock, on_message=self._on_mail
        )
        self.slot: tuple[int, int] | None = None  # (slot index, slot src) of the newest slot

    async def start(self) -> None:
        await self.client.connect()
        for var in WATCHED:
            self.client.subscribe(var)

    @staticmethod
    def _parse(message_class, value):
        from pygoby.moos.translator import TranslatorError, parse_for_moos

        msg = message_class()
        try:
            parse_for_moos(value, msg)
        except TranslatorError:
            return None
        return msg

    def _on_mail(self, msg) -> None:
        from pygoby.acomms import messages as acomms_pb

        s, value = self.stats, msg.value
        if msg.key in NAV and msg.is_double:
            self.nav[msg.key] = msg.dval
            if len(self.nav) == len(NAV):
                self.on_nav(self.nav, msg.time)
        elif msg.key == "ACOMMS_MAC_SLOT_START" and (
            slot := self._parse(acomms_pb.ModemTransmission, value)
        ):
            self.slot = (slot.slot_index, slot.src)
        elif msg.key == "ACOMMS_MODEM_TRANSMIT" and (
            tx := self._parse(acomms_pb.ModemTransmission, value)
        ):
            for frame in tx.frame:
                s.sent.update(self._types_in(bytes(frame)))
        elif msg.key == "ACOMMS_QUEUE_RECEIVE" and isinstance(value, str):
            s.received[_short(value)] += 1
        elif msg.key == "ACOMMS_ACK_ORIGINAL" and isinstance(value, str):
            s.acked[_short(value)] += 1
            self.say(
                f"{s.name}: {_short(value)} {_field(value, 'command_id')} acknowledged by the receiving modem"
            )
        elif msg.key == "ACOMMS_QSIZE" and (size := self._parse(acomms_pb.QueueSize, value)):
            s.queued[self.id_names.get(size.dccl_id, str(size.dccl_id))] = size.size
        elif msg.key == "STATUS_REPORT_IN":
            s.last_report = str(value)
        elif msg.key == "COMMAND_IN":
            shown = ",".join(
                kv for kv in str(value).split(",") if not kv.startswith(("time=", "src="))
            )
            self.say(f"{s.name}: command received: {shown} -> DESIRED_HEADING/SPEED/DEPTH")
        elif msg.key == "COMMAND_OUT":
            self.say(f"{s.name}: queues a command: {value}")

    def _types_in(self, frame: bytes) -> list[str]:
        """Short type names of the DCCL messages packed in one frame."""
        names, offset = [], 0
        while offset < len(frame):
            try:
                decoded, used = self.codec.decode_prefix(frame[offset:])
            except Exception:
                break
            names.append(SHORT_NAMES.get(decoded.DESCRIPTOR.full_name, decoded.DESCRIPTOR.name))
            offset += max(used, 1)
        return names


def _counts(counter: Counter) -> str:
    return "/".join(str(counter[name]) for name in SHORT_NAMES.values())


def _link(v: VehicleStats | None) -> str:
    if v is None or v.last_range_m is None or v.last_owtt is None:
        return "range    - km  owtt    - s"
    return f"range {v.last_range_m / 1000:4.2f} km  owtt {v.last_owtt:4.2f} s"


def summary_line(
    t: float,
    slot: tuple[int, int] | None,
    vehicles: list[VehicleStats],
    newest: VehicleStats | None = None,
) -> str:
    """One line: time, slot owner, range and one-way travel time of the newest acoustic
    reception (`newest` heard it), then per vehicle its message counts and lost packets."""
    names = {modem_id: name for name, modem_id in VEHICLES}
    owner = f"slot {slot[0]} ({names.get(slot[1], slot[1])})" if slot else "slot -"
    parts = [f"t={t:4.0f} s  {owner:<17} {_link(newest)}"]
    for v in vehicles:
        queued = "/".join(str(v.queued.get(name, 0)) for name in SHORT_NAMES.values())
        parts.append(
            f"{v.name}: sent {_counts(v.sent)} rcvd {_counts(v.received)} "
            f"acked {v.acked['command']} queue {queued} "
            f"lost {v.packets_lost}/{v.packets_in}"
        )
    return " | ".join(parts)


def _channel_config():
    from pygoby.netsim.channel import ChannelConfig, LogisticModel, RateErrorModels
    from pygoby.netsim.channel.frame_errors import DEFAULT_RATE_MODELS

    rate0 = LogisticModel(**RATE0_FRAME_ERRORS)
    errors = RateErrorModels(by_rate={**DEFAULT_RATE_MODELS, 0: rate0})
    return ChannelConfig(**CHANNEL_SETTINGS, error_models=errors)


def _geodesy(mission):
    from pygoby.util.geodesy import UTMGeodesy

    lat, lon = mission.get_float("LatOrigin"), mission.get_float("LongOrigin")
    if lat is None or lon is None:
        raise ValueError(f"{mission.path}: the demo needs LatOrigin and LongOrigin")
    return UTMGeodesy(lat, lon)


async def run_mission(
    warp: int = 25,
    duration: float = 720.0,
    say=print,
    mission_dir: Path = MISSION_DIR,
    event_log: Path | None = None,
    log_dir: Path | None = None,
) -> MissionResult:
    """Run the two missions of `mission_dir` in this process for `duration` simulated seconds at
    MOOS time warp `warp` (embedded MOOSDBs, emulated Micro-Modems on ephemeral loopback ports
    hearing each other through netsim's physics at the vehicles' NAV_* positions), printing a
    summary line at every TDMA slot, and events, through `say`; the channel's events go to
    `event_log` (JSON lines) if given. With `log_dir`, each community's pLogger (from its
    mission's block) writes its logs there instead of the block's PATH."""
    from pygoby.acomms.mmsim import MicroModemModel
    from pygoby.acomms.mmsim.server import MMSimServer
    from pygoby.apps.pacommshandler import pAcommsHandler
    from pygoby.apps.plogger import pLogger
    from pygoby.apps.usimvehicle import uSimVehicle
    from pygoby.moos.db import MOOSDB
    from pygoby.moos.moosfile import MissionFile
    from pygoby.moos.timewarp import moos_clock
    from pygoby.netsim.channel import Channel
    from pygoby.netsim.report.eventlog import EventLogWriter
    from pygoby.netsim.sim.physics_channel import PhysicsChannel

    clock = moos_clock(warp)
    codec = Codec(clock=clock)
    for name in SHORT_NAMES:
        codec.load_proto(mission_dir / "two_vehicles.proto", name)
    stats = [VehicleStats(name, modem_id) for name, modem_id in VEHICLES]
    monitors = []
    loggers: list[pLogger] = []
    real_start = time.monotonic()
    async with contextlib.AsyncExitStack() as stack:
        writer = None
        if event_log is not None:
            writer = stack.enter_context(EventLogWriter(event_log))
        tally = AcousticTally({MODEM_PORTS[v.name]: v for v in stats}, writer)
        channel = PhysicsChannel(
            Channel(_channel_config(), seed=PHYSICS_SEED),
            clock,
            ports=MODEM_PORTS,
            on_event=tally,
        )
        for vehicle_stats in stats:
            name, modem_id = vehicle_stats.name, vehicle_stats.modem_id
            mission = MissionFile.read(mission_dir / f"{name}.moos")
            db = MOOSDB(port=0, community=name, clock=clock)
            await stack.enter_async_context(db)
            # the channel polled every 5 ms (1/8 simulated s at warp 25): deliveries on time
            sim = MMSimServer(
                MicroModemModel(modem_id, clock, channel, name=name), channel, work_period=0.005
            )
            await sim.start()
            stack.push_async_callback(sim.close)
            on_nav = _position_feed(channel, MODEM_PORTS[name], _geodesy(mission))
            monitor = Monitor(vehicle_stats, codec, clock, db.port, say, on_nav)
            await monitor.start()
            stack.push_async_callback(monitor.client.close)
            monitors.append(monitor)
            apps: tuple[type, ...] = (pAcommsHandler, uSimVehicle)
            for app_class in apps + ((pLogger,) if log_dir is not None else ()):
                cfg = app_class.read_config(mission, app_class.default_name)
                cfg.common.time_warp_multiplier = int(warp)
                cfg.common.verbosity = _QUIET  # the monitors report instead
                if app_class is pAcommsHandler:
                    cfg.driver_cfg.tcp_port = sim.port
                    # The modem waits DTO seconds of its (warped) clock for the host's data
                    # after $CADRQ: the emulator's 2 s are 80 ms of real time at warp 25, less
                    # than a busy machine may take to answer the first slots (the modem then
                    # says $CAERR DATA_TIMEOUT and the driver gives up on its $CCTXD). The
                    # longest a Micro-Modem allows, 30 s, is 1.2 s of real time.
                    mm_cfg = cfg.driver_cfg.Extensions[MM_CONFIG]
                    mm_cfg.nvram_cfg.append("DTO,30")
                app = app_class(cfg, name=app_class.default_name, mission=mission, port=db.port)
                if app_class is pLogger:
                    # the block's `PATH = ./logs` would write into the current directory
                    app.settings.path = str(log_dir)
                    app.settings.summary_file = str(log_dir / f".LastOpenedMOOSLogDirectory_{name}")
                    loggers.append(app)
                await stack.enter_async_context(app)
        start = clock.now()
        reported = None
        while (now := clock.now()) < start + duration:
            slot = monitors[0].slot
            if slot is not None and slot != reported:  # one line per TDMA slot
                say(summary_line(now - start, slot, stats, tally.newest))
                reported = slot
            await asyncio.sleep(0.02)
        simulated = clock.now() - start
        say(summary_line(simulated, monitors[0].slot, stats, tally.newest))
        alogs = [app.sink.alog_path for app in loggers if app.sink is not None]
    return MissionResult(simulated, time.monotonic() - real_start, stats, alogs)


def _position_feed(channel, port: int, geodesy):
    """A Monitor's `on_nav`: the vehicle's position (local x/y to lat/lon about the mission's
    origin), with speed and heading for dead reckoning, to the acoustic channel."""
    from pygoby.netsim.channel import NavFix

    def update(nav: dict[str, float], t: float) -> None:
        lat, lon = geodesy.to_geo(nav["NAV_X"], nav["NAV_Y"])
        channel.channel.update_position(
            port,
            NavFix(lat, lon, nav["NAV_DEPTH"], t, nav["NAV_SPEED"], nav["NAV_HEADING"]),
        )

    return update


MISSION_INTRO = """\
topside (modem 1) holds station; unicorn (modem 2) is an AUV the topside's commands send
north-east at 5 m/s. Each runs MOOSDB + pAcommsHandler + uSimVehicle. Their modems hear each
other through netsim's acoustic physics in a noisy harbour (spreading factor {spreading:g}, ambient noise
{noise_level:g} dB re 1 uPa in band, half the packets lost at {snr50_db:g} dB SNR), in 10 s TDMA slots. Per slot:
  range, owtt: distance and one-way travel time of the newest acoustic packet
  sent/rcvd: status/command DCCL messages; queue: messages waiting to be sent
  lost: acoustic packets that reached the vehicle's modem but could not be decoded / all of them
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--warp", type=int, default=25, help="MOOS time warp (default %(default)s)")
    parser.add_argument(
        "--duration",
        type=float,
        default=720.0,
        help="simulated seconds of the mission (default %(default)s)",
    )
    parser.add_argument(
        "--event-log",
        type=Path,
        help="acoustic event log to write (default: in a new temporary folder)",
    )
    parser.add_argument(
        "--log-dir",
        type=Path,
        help="where the pLoggers write (default: beside the event log)",
    )
    parser.add_argument("--skip-dccl", action="store_true", help="skip the DCCL part")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR, format="%(name)s: %(message)s")
    event_log = (
        args.event_log or Path(tempfile.mkdtemp(prefix="pygoby-demo-")) / "netsim_events.jsonl"
    )
    log_dir = args.log_dir or event_log.parent
    if not args.skip_dccl:
        print("== pygoby demo 1/2: DCCL ==\n")
        dccl_demo()
    print(
        f"\n== pygoby demo 2/2: two vehicles, pAcommsHandler + Micro-Modem emulators + TDMA "
        f"(time warp {args.warp:g}) =="
    )
    print(MISSION_INTRO.format(**CHANNEL_SETTINGS, **RATE0_FRAME_ERRORS))
    result = asyncio.run(
        run_mission(args.warp, args.duration, say=_say, event_log=event_log, log_dir=log_dir)
    )
    print(
        f"\n{result.simulated_seconds:.0f} simulated seconds in {result.real_seconds:.1f} s: "
        f"{result.delivered} messages delivered end to end "
        f"({result.per_simulated_hour:.0f} per simulated hour)"
    )
    for v in result.vehicles:
        print(
            f"  {v.name}: decoded {v.packets_in - v.packets_lost} of {v.packets_in} acoustic "
            f"packets; the last one: {_link(v)}"
        )
        print(f"  {'':{len(v.name)}}  last status heard: {v.last_report or '-'}")
    print(
        f"acoustic event log: {event_log}\n"
        f"  plot it (success vs range and SNR, timeline): "
        f"pygoby netsim report {event_log} -o DIR"
    )
    print(f"logs: {log_dir}")
    for alog in result.alogs:
        print(f"  {log_line(alog)}")
    topside, unicorn = result.vehicles
    ok = (
        topside.received["status"] > 0
        and unicorn.received["status"] > 0
        and topside.acked["command"] > 0
    )
    print(
        "demo finished OK"
        if ok
        else "demo FAILED: expected statuses both ways and an acknowledged command"
    )
    return 0 if ok else 1


def log_line(alog: Path) -> str:
    """One line on a pLogger .alog: its lines and variables, and the command that says more."""
    from pygoby.moos.alog.files import AlogFile
    from pygoby.moos.alog.tools import summarize

    table = summarize(AlogFile(alog))
    lines = sum(row.count for row in table.values())
    return f"{alog.name}: {lines} lines, {len(table)} variables; `pygoby log summary {alog}`"


def _say(text: str) -> None:
    print(text if text.startswith("t=") else f"{'':10}{text}", flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
