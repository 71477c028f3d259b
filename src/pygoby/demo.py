"""`make demo`: pygoby on its embedded defaults, showing what it does.

1. DCCL: a vehicle status report encoded (clear and encrypted) and decoded: the same bytes the
   C++ DCCL library produces.
2. A two-vehicle acoustic-communications mission, time-warped: the missions of
   examples/two_vehicles/ (a topside and an AUV, each a MOOS community with its own embedded
   MOOSDB, pAcommsHandler and uSimVehicle) run in this process, each pAcommsHandler talking to an
   emulated WHOI Micro-Modem over loopback TCP, with TDMA slots. The vehicles broadcast DCCL
   status reports; the topside sends acknowledged commands that steer the AUV. A monitor client
   on each MOOSDB prints what happens, slot by slot.

    python -m pygoby.demo [--warp 25] [--duration 400] [--quiet]

`run_mission()` is the reusable part (benchmarks/test_acomms_handler_bench.py uses it).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from google.protobuf import text_format

from pygoby.dccl import Codec
from pygoby.dccl.analyze import describe

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
MISSION_DIR = EXAMPLES / "two_vehicles"
VEHICLES = (("topside", 1), ("unicorn", 2))
SHORT_NAMES = {"pygoby.examples.SimpleStatus": "status", "pygoby.examples.Command": "command"}
WATCHED = (
    "ACOMMS_MAC_SLOT_START", "ACOMMS_MODEM_TRANSMIT", "ACOMMS_QUEUE_RECEIVE", "ACOMMS_ACK_ORIGINAL",
    "ACOMMS_QSIZE", "STATUS_REPORT_IN", "COMMAND_IN", "COMMAND_OUT",
)  # fmt: skip


def dccl_demo() -> None:
    codec = Codec()
    status_cls = codec.load_proto(
        EXAMPLES / "dccl" / "status.proto", "pygoby.examples.VehicleStatus"
    )
    print(describe(codec.compiled(status_cls)))
    status = status_cls(
        time=float(int(time.time())), src=3, nav_x=1234.4, nav_y=-567.8, nav_depth=42.25,
        nav_heading=271.6, nav_speed=1.46, mode=status_cls.MODE_SURVEY, note="all good",
    )  # fmt: skip
    plain = codec.encode(status)
    print("\nstatus:    ", text_format.MessageToString(status, as_one_line=True))
    print(f"encoded:    {plain.hex()}  ({len(plain)} bytes;"
          f" protobuf would use {len(status.SerializeToString())})")  # fmt: skip
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


@dataclass
class MissionResult:
    simulated_seconds: float
    real_seconds: float
    vehicles: list[VehicleStats]

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
    head, _, rest = value.partition(f"{name}: ")
    return rest.split(" ", 1)[0] if rest else ""


class Monitor:
    """A MOOS client on one community that turns ACOMMS_* mail into VehicleStats and events."""

    def __init__(self, stats: VehicleStats, codec: Codec, clock, port: int, say) -> None:
        from pygoby.moos.client import MOOSClient

        self.stats, self.codec, self.say = stats, codec, say
        self.id_names = {codec.compiled(cls).id: SHORT_NAMES[cls.DESCRIPTOR.full_name]
                         for cls in codec.loaded()}  # fmt: skip
        self.client = MOOSClient(f"uDemoMonitor_{stats.name}", port=port, clock=clock,
                                 on_message=self._on_mail)  # fmt: skip
        self.slot: tuple[int, int] | None = None  # (slot index, slot src) of the newest slot

    async def start(self) -> None:
        await self.client.connect()
        for var in WATCHED:
            self.client.subscribe(var)

    @staticmethod
    def _parse(cls, value):
        from pygoby.moos.translator import TranslatorError, parse_for_moos

        msg = cls()
        try:
            parse_for_moos(value, msg)
        except TranslatorError:
            return None
        return msg

    def _on_mail(self, msg) -> None:
        from pygoby.acomms import messages as m

        s, value = self.stats, msg.value
        if msg.key == "ACOMMS_MAC_SLOT_START" and (slot := self._parse(m.ModemTransmission, value)):
            self.slot = (slot.slot_index, slot.src)
        elif msg.key == "ACOMMS_MODEM_TRANSMIT" and (tx := self._parse(m.ModemTransmission, value)):
            for frame in tx.frame:
                s.sent.update(self._types_in(bytes(frame)))
        elif msg.key == "ACOMMS_QUEUE_RECEIVE" and isinstance(value, str):
            s.received[_short(value)] += 1
        elif msg.key == "ACOMMS_ACK_ORIGINAL" and isinstance(value, str):
            s.acked[_short(value)] += 1
            self.say(
                f"{s.name}: {_short(value)} {_field(value, 'command_id')} acknowledged by the receiving modem"
            )
        elif msg.key == "ACOMMS_QSIZE" and (size := self._parse(m.QueueSize, value)):
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


def summary_line(t: float, slot: tuple[int, int] | None, vehicles: list[VehicleStats]) -> str:
    names = {modem_id: name for name, modem_id in VEHICLES}
    owner = f"slot {slot[0]} ({names.get(slot[1], slot[1])})" if slot else "slot -"
    parts = [f"t={t:6.0f} s  {owner:<17}"]
    for v in vehicles:
        queued = "/".join(str(v.queued.get(name, 0)) for name in SHORT_NAMES.values())
        parts.append(f"{v.name}: sent {_counts(v.sent)} rcvd {_counts(v.received)} "
                     f"acked {v.acked['command']} queue {queued}")  # fmt: skip
    return " | ".join(parts)


async def run_mission(
    warp: int = 25,
    duration: float = 400.0,
    say=print,
    mission_dir: Path = MISSION_DIR,
) -> MissionResult:
    """Run the two missions of `mission_dir` in this process for `duration` simulated seconds at
    MOOS time warp `warp` (embedded MOOSDBs, emulated Micro-Modems on ephemeral loopback ports),
    printing a summary line at every TDMA slot, and events, through `say`."""
    from pygoby.acomms.mmsim import LoopbackChannel, MicroModemModel
    from pygoby.acomms.mmsim.server import MMSimServer
    from pygoby.apps.pacommshandler import pAcommsHandler
    from pygoby.apps.usimvehicle import uSimVehicle
    from pygoby.moos.db import MOOSDB
    from pygoby.moos.moosfile import MissionFile
    from pygoby.moos.timewarp import moos_clock

    clock = moos_clock(warp)
    channel = LoopbackChannel()
    codec = Codec(clock=clock)
    for name in SHORT_NAMES:
        codec.load_proto(mission_dir / "two_vehicles.proto", name)
    stats, monitors = [], []
    real_start = time.monotonic()
    async with contextlib.AsyncExitStack() as stack:
        for name, modem_id in VEHICLES:
            mission = MissionFile.read(mission_dir / f"{name}.moos")
            db = MOOSDB(port=0, community=name, clock=clock)
            await stack.enter_async_context(db)
            sim = MMSimServer(MicroModemModel(modem_id, clock, channel, name=name), channel)
            await sim.start()
            stack.push_async_callback(sim.close)
            vehicle_stats = VehicleStats(name, modem_id)
            monitor = Monitor(vehicle_stats, codec, clock, db.port, say)
            await monitor.start()
            stack.push_async_callback(monitor.client.close)
            stats.append(vehicle_stats)
            monitors.append(monitor)
            for app_class in (pAcommsHandler, uSimVehicle):
                cfg = app_class.read_config(mission, app_class.default_name)
                cfg.common.time_warp_multiplier = int(warp)
                cfg.common.verbosity = _QUIET  # the monitors report instead
                if app_class is pAcommsHandler:
                    cfg.driver_cfg.tcp_port = sim.port
                app = app_class(cfg, name=app_class.default_name, mission=mission, port=db.port)
                await stack.enter_async_context(app)
        start = clock.now()
        reported = None
        while (now := clock.now()) < start + duration:
            slot = monitors[0].slot
            if slot is not None and slot != reported:  # one line per TDMA slot
                say(summary_line(now - start, slot, stats))
                reported = slot
            await asyncio.sleep(0.02)
        simulated = clock.now() - start
        say(summary_line(simulated, monitors[0].slot, stats))
    return MissionResult(simulated, time.monotonic() - real_start, stats)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m pygoby.demo", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--warp", type=int, default=25, help="MOOS time warp (default %(default)s)")
    parser.add_argument("--duration", type=float, default=400.0,
                        help="simulated seconds of the mission (default %(default)s)")  # fmt: skip
    parser.add_argument("--skip-dccl", action="store_true", help="skip the DCCL part")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR, format="%(name)s: %(message)s")
    if not args.skip_dccl:
        print("== pygoby demo 1/2: DCCL ==\n")
        dccl_demo()
    print(f"\n== pygoby demo 2/2: two vehicles, pAcommsHandler + Micro-Modem emulators + TDMA "
          f"(time warp {args.warp:g}) ==")  # fmt: skip
    print("topside (modem 1) and unicorn (modem 2): MOOSDB + pAcommsHandler + uSimVehicle each;")
    print("10 s TDMA slots; counts are status/command DCCL messages; queue = messages waiting\n")
    result = asyncio.run(run_mission(args.warp, args.duration, say=_say))
    print(f"\n{result.simulated_seconds:.0f} simulated seconds in {result.real_seconds:.1f} s: "
          f"{result.delivered} messages delivered end to end "
          f"({result.per_simulated_hour:.0f} per simulated hour)")  # fmt: skip
    for v in result.vehicles:
        print(f"  {v.name}: last status heard: {v.last_report or '-'}")
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


def _say(text: str) -> None:
    print(text if text.startswith("t=") else f"{'':10}{text}", flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
