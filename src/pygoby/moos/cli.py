"""`pygoby moosdb`, `pygoby moos poke|get|watch` and `pygoby antler`."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import logging
import os
import re
import sys
from collections.abc import Coroutine
from typing import Any

from pygoby.errors import ConfigError
from pygoby.moos import protocol as p
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import (
    DEFAULT_CLIENT_TIMEOUT,
    DEFAULT_MAX_CLIENTS,
    DEFAULT_MEMORY_BUDGET,
    DEFAULT_PACKET_TIMEOUT,
    MOOSDB,
)
from pygoby.moos.dbcore import DEFAULT_MAX_VARIABLES
from pygoby.moos.errors import MoosRefusedError
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.timewarp import moos_clock
from pygoby.util.aiorun import StopSignals

_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def register(subparsers: argparse._SubParsersAction) -> None:
    db = subparsers.add_parser("moosdb", help="run an embedded MOOSDB")
    db.add_argument(
        "mission", nargs="?", help=".moos file (ServerPort, Community, MOOSTimeWarp, ClientTimeout)"
    )
    db.add_argument(
        "--port", "--moos_port", type=int, help="TCP port (default: ServerPort, else 9000; 0 = any)"
    )
    db.add_argument(
        "--community", "--moos_community", help="community name (default: Community, else #1)"
    )
    db.add_argument("--time-warp", "--moos_time_warp", type=float, help="MOOS time warp")
    db.add_argument("--timeout", "--moos_timeout", type=float, help="client silence timeout, s")
    db.add_argument("--host", default="127.0.0.1", help="address to bind (0.0.0.0: all interfaces)")
    db.add_argument(
        "--max-packet",
        type=int,
        default=p.DEFAULT_MAX_PACKET_SIZE,
        help="largest packet accepted, bytes",
    )
    db.add_argument(
        "--packet-timeout",
        type=float,
        default=DEFAULT_PACKET_TIMEOUT,
        help="seconds a packet may take from its first byte to its last",
    )
    db.add_argument(
        "--max-clients",
        type=int,
        default=DEFAULT_MAX_CLIENTS,
        help="most connections at once (handshaking ones included)",
    )
    db.add_argument(
        "--memory-budget",
        type=float,
        default=DEFAULT_MEMORY_BUDGET / 2**20,
        help="MB of stored variables, partial packets, held and unsent mail, all clients together",
    )
    db.add_argument(
        "--max-variables",
        type=int,
        default=DEFAULT_MAX_VARIABLES,
        help="most variables the DB holds (new ones beyond are refused)",
    )
    db.add_argument("-v", "--verbose", action="store_true")
    db.set_defaults(func=_run_moosdb)

    moos = subparsers.add_parser("moos", help="talk to a MOOSDB: poke, get, watch")
    sub = moos.add_subparsers(dest="moos_command", required=True, metavar="ACTION")
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--host", default="127.0.0.1")
    common.add_argument("--port", type=int, default=p.DEFAULT_PORT)
    common.add_argument("--name", help="MOOS name of this client (default: pygoby_<action>_<pid>)")
    common.add_argument("--connect-timeout", type=float, default=5.0)

    poke = sub.add_parser(
        "poke",
        parents=[common],
        help="publish values: VAR=3.5 (double), VAR=text or VAR:=3.5 (string)",
    )
    poke.add_argument("assignments", nargs="+", metavar="VAR=value")
    poke.set_defaults(func=_run_poke)

    get = sub.add_parser(
        "get", parents=[common], help="print current values (exit 1 if one was never written)"
    )
    get.add_argument("variables", nargs="+", metavar="VAR")
    get.add_argument("--json", action="store_true", help="one JSON object keyed by variable")
    get.set_defaults(func=_run_get)

    watch = sub.add_parser(
        "watch", parents=[common], help="print notifications of matching variables"
    )
    watch.add_argument(
        "patterns", nargs="+", metavar="PATTERN", help="variable name or MOOS wildcard (* ?)"
    )
    watch.add_argument("--secs", type=float, help="stop after this many seconds")
    watch.add_argument("--json", action="store_true", help="one JSON object per line")
    watch.set_defaults(func=_run_watch)

    antler = subparsers.add_parser("antler", help="launch a mission's ANTLER block (and a MOOSDB)")
    antler.add_argument("mission")
    antler.add_argument(
        "--no-db",
        action="store_true",
        help="do not start the embedded MOOSDB: use the one listening on ServerPort",
    )
    antler.add_argument(
        "--logs",
        metavar="DIR",
        help="write each program's output to DIR/<name>.log instead of the terminal",
    )
    antler.add_argument(
        "--color",
        choices=("auto", "always", "never"),
        default="auto",
        help="coloured name prefixes for NewConsole = true programs (auto: on a terminal)",
    )
    antler.set_defaults(func=_run_antler)


def _run(coro: Coroutine[Any, Any, int]) -> int:
    try:
        return asyncio.run(coro)
    except KeyboardInterrupt:
        return 130


# -- moosdb ------------------------------------------------------------------------------------


def _run_moosdb(args: argparse.Namespace) -> int:
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(asctime)s %(name)s %(levelname)s: %(message)s",
    )
    mission = None
    if args.mission:
        try:
            mission = MissionFile.read(args.mission)
        except OSError as err:
            print(
                f"moosdb: cannot read {args.mission} ({err.strerror}); using defaults",
                file=sys.stderr,
            )
    port = args.port
    if port is None:
        try:
            port = mission.get_port("ServerPort") if mission else None
        except ConfigError as err:
            print(f"moosdb: {err}", file=sys.stderr)
            return 1
        port = p.DEFAULT_PORT if port is None else port
    community = (
        args.community or (mission and mission.get_value("Community")) or p.DEFAULT_COMMUNITY
    )
    warp = args.time_warp or (mission and mission.get_float("MOOSTimeWarp")) or 1.0
    timeout = (
        args.timeout or (mission and mission.get_float("ClientTimeout")) or DEFAULT_CLIENT_TIMEOUT
    )
    db = MOOSDB(
        args.host,
        port,
        community,
        clock=moos_clock(warp),
        client_timeout=timeout,
        max_packet_size=args.max_packet,
        packet_timeout=args.packet_timeout,
        max_clients=args.max_clients,
        memory_budget=int(args.memory_budget * 2**20),
        max_variables=args.max_variables,
    )
    return _run(_serve(db))


async def _serve(db: MOOSDB) -> int:
    try:
        await db.start()
    except OSError as err:
        print(f"moosdb: cannot listen on {db.host}:{db.port}: {err.strerror}", file=sys.stderr)
        return 1
    stop = asyncio.Event()
    with StopSignals(asyncio.get_running_loop(), stop.set, "moosdb"):
        if not logging.getLogger("pygoby.moos.db").isEnabledFor(logging.INFO):  # else it logs it
            print(f"MOOSDB {db.community} listening on {db.host}:{db.port}", flush=True)
        await stop.wait()
        await db.stop()
    return 0


# -- client tools ------------------------------------------------------------------------------


def _client(args: argparse.Namespace, action: str) -> MOOSClient:
    name = args.name or f"pygoby_{action}_{os.getpid()}"
    return MOOSClient(name, args.host, args.port, reconnect_interval=0.2)


async def _connected(client: MOOSClient, args: argparse.Namespace) -> bool:
    try:
        await client.connect(timeout=args.connect_timeout)
        return True
    except (TimeoutError, ConnectionError, MoosRefusedError) as err:
        print(f"cannot connect to a MOOSDB at {args.host}:{args.port}: {err}", file=sys.stderr)
        await client.close()
        return False


def parse_assignment(text: str) -> tuple[str, float | str]:
    """`VAR=3.5` -> double; `VAR=abc` -> string; `VAR:=3.5` -> the string "3.5"."""
    name, sep, value = text.partition("=")
    if not sep or not name or name == ":":
        raise ValueError(f"expected VAR=value or VAR:=text, got {text!r}")
    if name.endswith(":"):
        return name[:-1], value
    return name, float(value) if _NUMBER.fullmatch(value.strip()) else value


def _run_poke(args: argparse.Namespace) -> int:
    try:
        pairs = [parse_assignment(a) for a in args.assignments]
    except ValueError as err:
        print(f"poke: {err}", file=sys.stderr)
        return 2
    return _run(_poke(args, pairs))


async def _poke(args: argparse.Namespace, pairs: list[tuple[str, float | str]]) -> int:
    client = _client(args, "poke")
    if not await _connected(client, args):
        return 1
    for name, value in pairs:
        client.publish(name, value)
    await client.flush()
    await client.server_request("VAR_SUMMARY", timeout=2.0)  # a round trip: all were processed
    await client.close()
    return 0


def _describe(msg: p.MOOSMessage) -> dict[str, Any]:
    kind = {p.DOUBLE: "double", p.STRING: "string", p.BINARY: "binary"}.get(
        msg.data_type, msg.data_type
    )
    value: Any = msg.sval.hex() if msg.is_binary else msg.value
    return {
        "name": msg.key,
        "type": kind,
        "value": value,
        "src": msg.src,
        "src_aux": msg.src_aux,
        "community": msg.community,
        "time": msg.time,
    }


def _format(msg: p.MOOSMessage) -> str:
    if msg.is_double:
        value = f"{msg.dval:.17g}" if msg.dval != int(msg.dval) else f"{msg.dval:g}"
    elif msg.is_binary:
        value = f"<binary {len(msg.sval)} B: {msg.sval[:32].hex()}{'...' if len(msg.sval) > 32 else ''}>"
    else:
        value = json.dumps(msg.string, ensure_ascii=False)
    return f"{msg.key} = {value}  ({msg.src}, t={msg.time:.3f})"


def _run_get(args: argparse.Namespace) -> int:
    return _run(_get(args))


async def _get(args: argparse.Namespace) -> int:
    client = _client(args, "get")
    if not await _connected(client, args):
        return 1
    for name in args.variables:
        client.subscribe(name)
    # R messages and the Q go in one packet; the DB answers the Q after queuing the snapshots,
    # so when its reply is in, every written variable's value has arrived before it.
    await client.server_request("VAR_SUMMARY", timeout=5.0)
    values = {m.key: m for m in client.fetch() if m.msg_type == p.NOTIFY}
    await client.close()
    missing = [n for n in args.variables if n not in values]
    if args.json:
        print(
            json.dumps({n: _describe(values[n]) if n in values else None for n in args.variables})
        )
    else:
        for name in args.variables:
            if name in values:
                print(_format(values[name]))
    for name in missing:
        print(f"get: {name} has never been written", file=sys.stderr)
    return 1 if missing else 0


def _run_watch(args: argparse.Namespace) -> int:
    return _run(_watch(args))


async def _watch(args: argparse.Namespace) -> int:
    client = _client(args, "watch")
    if not await _connected(client, args):
        return 1
    for pattern in args.patterns:
        if "*" in pattern or "?" in pattern:
            client.subscribe_wildcard(pattern, "*")
        else:
            client.subscribe(pattern)
    loop = asyncio.get_running_loop()
    deadline = None if args.secs is None else loop.time() + args.secs
    try:
        while deadline is None or loop.time() < deadline:
            left = None if deadline is None else max(deadline - loop.time(), 0.0)
            try:
                msg = await client.receive(left)
            except TimeoutError:
                break
            line = json.dumps(_describe(msg)) if args.json else _format(msg)
            print(line, flush=True)
    finally:
        with contextlib.suppress(Exception):
            await client.close()
    return 0


def _run_antler(args: argparse.Namespace) -> int:
    from pygoby.moos.antler import run_antler

    colour = {"auto": None, "always": True, "never": False}[args.color]
    return run_antler(args.mission, start_db=not args.no_db, logs=args.logs, colour=colour)
