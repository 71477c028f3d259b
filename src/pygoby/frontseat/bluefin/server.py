"""`bluefin_frontseat_simulator PORT`: the Huxley simulator (`HuxleySimulator`) on TCP.

The payload (iFrontSeat with the `bluefin` driver) connects as a TCP client; "\\r\\n" line
endings. Each new connection is a new session; the simulator is ticked every `poll_interval`
s of wall time and reads the time from its clock (`--warp` for MOOSTimeWarp, or a test's
virtual clock).
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys

from pygoby.frontseat.bluefin.simulator import HuxleyOptions, HuxleySimulator
from pygoby.frontseat.simserver import DEFAULT_POLL_INTERVAL, SimulatorTCPServer, run_server_main
from pygoby.util.clock import Clock, WallClock

log = logging.getLogger(__name__)


class HuxleyServer(SimulatorTCPServer):
    """Serves one `HuxleySimulator` on `port` (0 = ephemeral; see `port` once listening)."""

    def __init__(
        self,
        port: int,
        host: str = "127.0.0.1",
        simulator: HuxleySimulator | None = None,
        clock: Clock | None = None,
        poll_interval: float = DEFAULT_POLL_INTERVAL,
    ) -> None:
        super().__init__(port, host, poll_interval)
        self.simulator = simulator if simulator is not None else HuxleySimulator()
        self.clock: Clock = clock if clock is not None else WallClock()
        self.exchange: list[str] = []  # "< line" received, "> line" sent, in order
        self._session: int | None = None  # link.connections of the current session
        self.steps = 0  # step() calls so far (tests on a virtual clock wait for the next one)

    async def serve(self) -> None:
        """Listen (if not yet) and run until cancelled."""
        try:
            await self.start()
            log.info("Bluefin (Huxley) simulator listening on %s:%d", self.link.host, self.port)
            while True:
                self.step()
                await asyncio.sleep(self.poll_interval)
        finally:
            self.close()

    def step(self) -> None:
        """One look: session changes, received lines, the simulator's tick, faults."""
        self.steps += 1
        now = self.clock.now()
        simulator = self.simulator
        if self.link.is_open and self._session != self.link.connections:
            self._session = self.link.connections
            log.info("payload connected")
            self._send(simulator.connect(now))
        elif not self.link.is_open and self._session is not None:
            self._session = None
            log.info("payload disconnected")
            simulator.disconnect()
        for line in self.link.read_lines():
            self.exchange.append(f"< {line}")
            self._send(simulator.handle_line(line, now))
        self._send(simulator.tick(now))
        if simulator.drop_due(now):
            log.warning("fault: dropping the payload's connection")
            self.link.drop_connections()

    def _send(self, lines: list[str]) -> None:
        for line in lines:
            self.exchange.append(f"> {line}")
            self.write_line(line)


def build_parser(prog: str | None = None) -> argparse.ArgumentParser:
    defaults = HuxleyOptions()
    parser = argparse.ArgumentParser(
        prog=prog,
        description="Bluefin vehicle (Huxley) simulator: a TCP server speaking the Bluefin "
        "Standard Payload Interface to iFrontSeat's bluefin driver.",
    )
    parser.add_argument("port", type=int, help="TCP port to listen on (0 = any free port)")
    parser.add_argument("--host", "--bind", dest="host", default="127.0.0.1")
    parser.add_argument("--lat", type=float, default=defaults.lat, help="start latitude (deg)")
    parser.add_argument("--lon", type=float, default=defaults.lon, help="start longitude (deg)")
    parser.add_argument("--nav-rate", type=float, default=defaults.nav_rate, help="NVG per s")
    parser.add_argument(
        "--control-delay",
        type=float,
        default=defaults.control_delay,
        help="s from connection to payload control (default %(default)s)",
    )
    parser.add_argument(
        "--control-duration",
        type=float,
        default=defaults.control_duration,
        help="s of payload control (0: until disconnected)",
    )
    parser.add_argument("--warp", type=float, default=1.0, help="time warp (MOOSTimeWarp)")
    faults = parser.add_argument_group("faults")
    faults.add_argument("--nav-stop-after", type=float, help="stop NVG/NVR after this many s")
    faults.add_argument(
        "--nak",
        action="append",
        default=[],
        metavar="ID",
        help="answer this sentence (e.g. RMB) with a failed $BFACK; repeatable",
    )
    faults.add_argument("--no-ack", action="store_true", help="never send $BFACK")
    faults.add_argument(
        "--drop-after",
        type=float,
        help="close the connection once, this many s after the first connection",
    )
    faults.add_argument("--clock-skew", type=float, default=0.0, help="s added to timestamps")
    parser.add_argument("-v", "--verbose", action="count", default=0)
    return parser


def options_from(args: argparse.Namespace) -> HuxleyOptions:
    return HuxleyOptions(
        lat=args.lat,
        lon=args.lon,
        nav_rate=args.nav_rate,
        control_delay=args.control_delay,
        control_duration=args.control_duration,
        nav_stop_after=args.nav_stop_after,
        nak=frozenset(name.upper() for name in args.nak),
        no_ack=args.no_ack,
        drop_after=args.drop_after,
        clock_skew=args.clock_skew,
    )


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    parser = build_parser(prog)
    args = parser.parse_args(argv)
    if not args.nav_rate > 0 or not args.warp > 0:
        parser.error("--nav-rate and --warp must be positive")
    server = HuxleyServer(
        args.port,
        host=args.host,
        simulator=HuxleySimulator(options_from(args)),
        clock=WallClock(args.warp),
    )
    return run_server_main(parser, args.verbose, server.serve())


if __name__ == "__main__":
    sys.exit(main())
