"""asyncio TCP server for `NetSimManager`, and the `netsim_manager` console script.

Each connection gets its own `ManagerConnection`; answers are written back on the connection the
request came in on, as soon as the request is processed. One client's bad input only ever
affects that client's own lines.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys

from pygoby.errors import ConfigError
from pygoby.netsim.manager.config import EXAMPLE_CONFIG, load_config
from pygoby.netsim.manager.core import NetSimManager
from pygoby.netsim.manager.gprmc import GpsOutputs
from pygoby.util.aiorun import run_until_signal
from pygoby.util.clock import WallClock

log = logging.getLogger(__name__)

# Small reads plus a yield after each one give every connection its turn: a client flooding
# the manager with garbage can only hold the event loop for one small chunk at a time.
READ_SIZE = 4096
CLOSE_TIMEOUT = 1.0  # s


class ManagerServer:
    """Serves a NetSimManager on TCP. Use `await start()`, then `await close()`."""

    def __init__(self, manager: NetSimManager, host: str | None = None, port: int | None = None):
        self.manager = manager
        self.host = host if host is not None else manager.config.listen_address
        self.port = port if port is not None else manager.config.manager_tcp_port
        self._server: asyncio.Server | None = None
        self._tasks: set[asyncio.Task] = set()

    @property
    def bound_port(self) -> int:
        """The port actually listened on (useful with port 0)."""
        assert self._server is not None, "server not started"
        return self._server.sockets[0].getsockname()[1]

    async def start(self) -> None:
        self._server = await asyncio.start_server(self._serve, self.host, self.port)
        log.info("netsim_manager listening on %s:%d", self.host, self.bound_port)

    async def close(self) -> None:
        if self._server is None:
            return
        self._server.close()
        for task in list(self._tasks):
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        await self._server.wait_closed()

    async def serve_forever(self) -> None:
        assert self._server is not None, "server not started"
        await self._server.serve_forever()

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        peer = writer.get_extra_info("peername")
        connection = self.manager.connection(peer[0] if peer else "")
        log.info("client connected: %s", peer)
        try:
            while data := await reader.read(READ_SIZE):
                replies = connection.receive(data)
                if replies:
                    writer.write(b"".join(replies))
                    await writer.drain()
                await asyncio.sleep(0)
        except (ConnectionError, OSError) as exc:
            log.info("client %s: %s", peer, exc)
        except asyncio.CancelledError:  # closing: end quietly (asyncio 3.11's stream callback
            pass  # would log the cancelled task's CancelledError as an unhandled exception)
        finally:
            self._tasks.discard(task)
            writer.close()
            try:  # a peer that never reads could keep unsent answers pending forever
                await asyncio.wait_for(writer.wait_closed(), CLOSE_TIMEOUT)
            except (TimeoutError, ConnectionError, OSError):
                writer.transport.abort()
            log.info("client disconnected: %s (%d bad lines)", peer, connection.errors)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="netsim_manager",
        description="netsim manager: validates vehicle position updates (NETSIM line protocol).",
    )
    parser.add_argument("config", nargs="?", help="configuration file (protobuf TextFormat)")
    parser.add_argument("--example_config", action="store_true", help="print an example config")
    parser.add_argument("--port", type=int, help="override manager_tcp_port")
    parser.add_argument(
        "--host",
        "--listen",
        dest="host",
        help="address to listen on, overriding listen_address (default 127.0.0.1; "
        "0.0.0.0: every interface)",
    )
    parser.add_argument("-v", "--verbose", action="count", default=0)
    return parser


async def _run(manager: NetSimManager, host: str | None, port: int | None) -> None:
    server = ManagerServer(manager, host, port)
    await server.start()
    try:
        await server.serve_forever()
    finally:
        await server.close()


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.example_config:
        sys.stdout.write(EXAMPLE_CONFIG)
        return 0
    if args.config is None:
        build_parser().print_usage(sys.stderr)
        print("netsim_manager: a configuration file is required", file=sys.stderr)
        return 2
    level = logging.WARNING - 10 * args.verbose
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    try:
        config = load_config(args.config)
        manager = NetSimManager(config)
        if config.gps_out:
            manager.on_nav(GpsOutputs.open_serial(config, WallClock()).on_nav_update)
    except ConfigError as exc:
        print(f"netsim_manager: {exc.located(file=args.config)}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"netsim_manager: {exc}", file=sys.stderr)
        return 1
    run_until_signal(_run(manager, args.host, args.port))
    return 0


if __name__ == "__main__":
    sys.exit(main())
