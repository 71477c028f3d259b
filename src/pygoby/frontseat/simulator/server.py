"""`basic_frontseat_simulator PORT` (alias `abc_frontseat_simulator`): the simulator on TCP.

A TCP server (any number of clients; lines from all of them are handled in arrival order,
every reply and NAV goes to every client, "\\r\\n" line endings) around the sans-I/O
`BasicFrontSeatSimulator`. The simulator ticks every 1/(FREQ*WARP) wall seconds on a steady
schedule; received lines are handled within `poll_interval` of their arrival, between ticks.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys

from pygoby.frontseat.simserver import DEFAULT_POLL_INTERVAL, SimulatorTCPServer, run_server_main
from pygoby.frontseat.simulator.core import BasicFrontSeatSimulator

log = logging.getLogger(__name__)


class SimulatorServer(SimulatorTCPServer):
    """Serves one `BasicFrontSeatSimulator` on `port` (0 = ephemeral; see `port` once listening)."""

    def __init__(
        self,
        port: int,
        host: str = "127.0.0.1",
        simulator: BasicFrontSeatSimulator | None = None,
        poll_interval: float = DEFAULT_POLL_INTERVAL,
    ) -> None:
        super().__init__(port, host, poll_interval)
        self.simulator = simulator if simulator is not None else BasicFrontSeatSimulator()

    async def serve(self) -> None:
        """Listen (if not yet) and run the simulator until cancelled."""
        try:
            await self.start()
            log.info("basic frontseat simulator listening on %s:%d", self.link.host, self.port)
            loop = asyncio.get_running_loop()
            last_tick = loop.time()
            while True:
                self._handle_input()
                now = loop.time()
                due = last_tick + self.simulator.period  # the period changes with START
                if now >= due:
                    self._send(self.simulator.tick())
                    # keep a steady schedule, but never burst to catch up a long stall
                    last_tick = due if now - due < self.simulator.period else now
                    due = last_tick + self.simulator.period
                await asyncio.sleep(max(0.0, min(due - now, self.poll_interval)))
        finally:
            self.close()

    def _handle_input(self) -> None:
        for line in self.link.read_lines():
            self._send(self.simulator.handle_line(line))

    def _send(self, lines: list[str]) -> None:
        for line in lines:
            log.debug("> %s", line)
            self.write_line(line)


def build_parser(prog: str | None = None) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=prog,
        description="Basic (ABC) frontseat simulator: a TCP server speaking START/CTRL/NAV/CMD "
        "lines (goby3 basic_frontseat_simulator).",
    )
    parser.add_argument("port", type=int, help="TCP port to listen on (0 = any free port)")
    parser.add_argument(
        "--host",
        "--bind",
        dest="host",
        default="127.0.0.1",
        help="address to listen on (default %(default)s; 0.0.0.0: every interface)",
    )
    parser.add_argument(
        "-v", "--verbose", action="count", default=0, help="more log output (-v: every line sent)"
    )
    return parser


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    parser = build_parser(prog)
    args = parser.parse_args(argv)
    server = SimulatorServer(args.port, host=args.host)
    return run_server_main(parser, args.verbose, server.serve())


if __name__ == "__main__":
    sys.exit(main())
