"""`pygoby mmsim`: run an emulated WHOI Micro-Modem on a TCP port (and optionally a pty)."""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys

from pygoby.errors import ConfigError
from pygoby.util.aiorun import run_until_signal


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "mmsim",
        help="WHOI Micro-Modem emulator (NMEA over TCP / pty)",
        description="Emulated WHOI Micro-Modem with the modem's timing (packets take their "
        "time on the water, travel at the speed of sound over --range). Emulators in other "
        "processes hear each other through a perfect channel carried by UDP multicast on "
        "127.0.0.1.",
    )
    p.add_argument("--port", type=int, required=True, help="TCP port to serve NMEA on (0: any)")
    p.add_argument("--id", type=int, required=True, help="acoustic address (NVRAM SRC)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument(
        "--pty",
        nargs="?",
        const="",
        metavar="PATH",
        help="also serve on a pseudo-terminal, linked at PATH if given (e.g. "
        "/tmp/ttyLOOPA1, for a mission's serial_port)",
    )
    p.add_argument(
        "--firmware",
        help="version in $CAREV: 2.x a Micro-Modem 2 (the default), 0.x a Micro-Modem 1",
    )
    p.add_argument(
        "--channel-group",
        default="239.255.42.99:45454",
        help="multicast group:port shared by emulators (default %(default)s)",
    )
    p.add_argument(
        "--range",
        type=float,
        default=0.0,
        metavar="METERS",
        help="distance between the emulated modems (travel time at --sound-speed)",
    )
    p.add_argument("--sound-speed", type=float, default=1500.0, help="m/s (default %(default)s)")
    p.set_defaults(func=run)

    s = subparsers.add_parser(
        "store_server",
        help="goby_store_server: ModemTransmission mailbox kept in SQLite",
        description="Store server for DRIVER_STORE_SERVER clients (RUDICS packets over TCP).",
    )
    s.add_argument("--port", type=int, default=11244, help="TCP port (default %(default)s)")
    s.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to bind (default %(default)s; 0.0.0.0: every interface)",
    )
    s.add_argument("--db", default="goby_store_server.db", help="SQLite file (default %(default)s)")
    s.add_argument(
        "--max-lookback",
        type=float,
        default=3600.0,
        help="seconds of history a new client receives (default %(default)s)",
    )
    s.add_argument(
        "--retention",
        type=float,
        default=3600.0,
        help="seconds a delivered transmission is kept (default %(default)s)",
    )
    s.add_argument(
        "--lock-timeout",
        type=float,
        default=5.0,
        help="seconds to wait for a database locked by another process before "
        "answering the client with an error (default %(default)s)",
    )
    s.add_argument(
        "--secrets",
        metavar="FILE",
        help="'MODEM_ID SECRET' per line: each modem id's requests must be signed "
        "with its secret, ids not listed are refused (default: no check); the file must "
        "be readable by its owner only",
    )
    s.add_argument(
        "--allow-readable-secrets",
        action="store_true",
        help="accept a --secrets file that its group or others may read",
    )
    s.set_defaults(func=run_store_server)

    lb = subparsers.add_parser(
        "loopbacks",
        help="virtual serial line pairs (/tmp/ttyLOOPA1 <-> /tmp/ttyLOOPA2, ...) for emulated modems",
        description="Pseudo-terminal pairs joined back to back, linked at PREFIX<X>1 and "
        "PREFIX<X>2 for each pair name X (what Goby 1.1 missions made with socat). Runs until "
        "Ctrl-C, then removes the links. Links left by a process that died are replaced.",
    )
    lb.add_argument(
        "--prefix", default="/tmp/ttyLOOP", help="link name prefix (default %(default)s)"
    )
    lb.add_argument("--pairs", default="A,B,C,D", help="pair names (default %(default)s)")
    lb.set_defaults(func=run_loopbacks)

    a = subparsers.add_parser(
        "abc_modem_simulator",
        help="simulator for the ABC example modem (DRIVER_ABC_EXAMPLE_MODEM)",
        description="Each TCP client is one ABC modem; no delay, no loss.",
    )
    a.add_argument("--port", type=int, required=True, help="TCP port to serve on")
    a.add_argument("--host", default="127.0.0.1", help="address to bind (default %(default)s)")
    a.set_defaults(func=run_abc_simulator)


def run(args: argparse.Namespace) -> int:
    from pygoby.util.pty import PtyError

    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    try:
        run_until_signal(_serve(args))
    except (PtyError, ValueError) as exc:
        print(f"mmsim: {exc}", file=sys.stderr)
        return 1
    return 0


async def _serve(args: argparse.Namespace) -> None:
    from pygoby.acomms.mmsim.model import MicroModemModel
    from pygoby.acomms.mmsim.multicast_channel import MulticastChannel
    from pygoby.acomms.mmsim.server import MMSimServer
    from pygoby.util.clock import WallClock

    clock = WallClock()
    group, _, port = args.channel_group.rpartition(":")
    channel = MulticastChannel(group, int(port), clock, args.range, args.sound_speed)
    channel.open()
    firmware = {"firmware": args.firmware} if args.firmware else {}
    model = MicroModemModel(args.id, clock, channel, **firmware)
    server = MMSimServer(model, channel, args.host, args.port, pty_path=args.pty)
    try:
        port_used = await server.start()
        print(f"mmsim id {args.id} listening on {args.host}:{port_used}", flush=True)
        if server.pty_path:
            print(f"mmsim id {args.id} serial pty {server.pty_path}", flush=True)
        await asyncio.Future()
    finally:
        await server.close()
        channel.close()


def run_loopbacks(args: argparse.Namespace) -> int:
    from pygoby.util.pty import PtyError, PtyPair

    names = [n.strip() for n in args.pairs.split(",") if n.strip()]
    pairs: list[PtyPair] = []
    try:
        for name in names:
            pairs.append(PtyPair(f"{args.prefix}{name}1", f"{args.prefix}{name}2").open())
    except (PtyError, OSError) as err:
        for pair in pairs:
            pair.close()
        print(f"loopbacks: {err}", file=sys.stderr)
        return 1
    for pair in pairs:
        print(f"loopback {pair.paths[0]} <-> {pair.paths[1]}", flush=True)

    async def relay() -> None:
        for pair in pairs:
            pair.attach()
        try:
            await asyncio.Future()
        finally:
            for pair in pairs:
                pair.close()

    run_until_signal(relay())
    return 0


def run_store_server(args: argparse.Namespace) -> int:
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    try:
        run_until_signal(_serve_store(args))
    except (ConfigError, OSError) as exc:
        print(f"store_server: {exc}", file=sys.stderr)
        return 1
    return 0


async def _serve_store(args: argparse.Namespace) -> None:
    from pygoby.acomms.store_server import StoreServer, TransmissionStore, serve_store
    from pygoby.acomms.store_server.auth import read_secrets

    secrets = read_secrets(args.secrets, args.allow_readable_secrets) if args.secrets else None
    store = TransmissionStore(args.db, args.max_lookback, args.retention, args.lock_timeout)
    server = await serve_store(StoreServer(store, secrets=secrets), args.host, args.port)
    port = server.sockets[0].getsockname()[1]
    print(f"store_server listening on {args.host}:{port} (database {args.db})", flush=True)
    try:
        await asyncio.Future()
    finally:
        server.close()
        store.close()


def run_abc_simulator(args: argparse.Namespace) -> int:
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    run_until_signal(_serve_abc(args))
    return 0


async def _serve_abc(args: argparse.Namespace) -> None:
    from pygoby.acomms.abc_simulator import ABCSimulator, serve_abc

    server = await serve_abc(ABCSimulator(), args.host, args.port)
    print(
        f"abc_modem_simulator listening on {args.host}:{server.sockets[0].getsockname()[1]}",
        flush=True,
    )
    try:
        await asyncio.Future()
    finally:
        server.close()
