"""`pygoby mmsim`: run an emulated WHOI Micro-Modem on a TCP port (and optionally a pty)."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "mmsim",
        help="WHOI Micro-Modem emulator (NMEA over TCP / pty)",
        description="Emulated WHOI Micro-Modem. Emulators in other processes hear each other "
        "through a perfect channel carried by UDP multicast on 127.0.0.1.",
    )
    p.add_argument("--port", type=int, required=True, help="TCP port to serve NMEA on (0: any)")
    p.add_argument("--id", type=int, required=True, help="acoustic address (NVRAM SRC)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--pty", action="store_true", help="also serve on a pseudo-terminal")
    p.add_argument("--firmware", default="0.94.0.00", help="version in $CAREV (2.x = MM2)")
    p.add_argument("--channel-group", default="239.255.42.99:45454",
                   help="multicast group:port shared by emulators (default %(default)s)")  # fmt: skip
    p.add_argument(
        "--travel-time", type=float, default=0.0, help="one-way travel time for pings (s)"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(_serve(args))
    return 0


async def _serve(args: argparse.Namespace) -> None:
    from pygoby.acomms.mmsim.model import MicroModemModel
    from pygoby.acomms.mmsim.multicast_channel import MulticastChannel
    from pygoby.acomms.mmsim.server import MMSimServer
    from pygoby.util.clock import WallClock

    group, _, port = args.channel_group.rpartition(":")
    channel = MulticastChannel(group, int(port), args.travel_time)
    channel.open()
    model = MicroModemModel(args.id, WallClock(), channel, firmware=args.firmware)
    server = MMSimServer(model, channel, args.host, args.port, use_pty=args.pty)
    port_used = await server.start()
    print(f"mmsim id {args.id} listening on {args.host}:{port_used}", flush=True)
    if server.pty_path:
        print(f"mmsim id {args.id} serial pty {server.pty_path}", flush=True)
    try:
        await asyncio.Future()
    finally:
        await server.close()
        channel.close()
