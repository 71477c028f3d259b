"""What the frontseat simulators' TCP servers share: the listening link and the CLI runner.

A simulator server owns one `TCPServerLink` (the payload connects as a client) and writes
"\\r\\n"-terminated lines to whoever is connected; with nobody connected a line is for no one,
as upstream. `run_server_main` is the tail of each simulator's console script.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
from collections.abc import Coroutine
from typing import Any

from pygoby.util.aiorun import run_until_signal
from pygoby.util.errors import LinkClosedError
from pygoby.util.linebased import TCPServerLink

DEFAULT_POLL_INTERVAL = 0.01  # s between looks at the connection


class SimulatorTCPServer:
    """The listening side of a simulator on `port` (0 = ephemeral; see `port` once listening)."""

    def __init__(self, port: int, host: str, poll_interval: float) -> None:
        self.link = TCPServerLink(port, host=host)
        self.poll_interval = poll_interval

    @property
    def port(self) -> int:
        return self.link.port

    async def start(self) -> int:
        """Listen; returns the port."""
        self.link.open()
        return await self.link.wait_listening()

    def close(self) -> None:
        self.link.close()

    def write_line(self, line: str) -> None:
        with contextlib.suppress(LinkClosedError):  # nobody connected: for no one
            self.link.write(line + "\r\n")


def run_server_main(
    parser: argparse.ArgumentParser, verbose: int, serve: Coroutine[Any, Any, None]
) -> int:
    """Log at DEBUG with -v, run `serve` until a signal; 1 if the port cannot be opened."""
    logging.basicConfig(
        level=logging.DEBUG if verbose else logging.INFO,
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    try:
        run_until_signal(serve)
    except OSError as exc:
        print(f"{parser.prog}: {exc}", file=sys.stderr)
        return 1
    return 0
