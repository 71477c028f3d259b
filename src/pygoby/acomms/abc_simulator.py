"""ABC modem simulator (spec acomms.md §9.3): each TCP client is one modem; no delay, no loss."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Hashable

from pygoby.acomms.abc_protocol import format_abc, parse_abc
from pygoby.acomms.errors import ABCParseError

log = logging.getLogger(__name__)


class ABCSimulator:
    """Sans-I/O: `handle(endpoint, line)` returns the (endpoint, text) pairs to send."""

    def __init__(self) -> None:
        self.modems: dict[int, Hashable] = {}

    def forget(self, endpoint: Hashable) -> None:
        self.modems = {k: v for k, v in self.modems.items() if v != endpoint}

    def handle(self, endpoint: Hashable, line: str) -> list[tuple[Hashable, str]]:
        try:
            key, fields = parse_abc(line)
        except ABCParseError as exc:
            log.error("%s", exc)
            return []
        if key == "CONF" and "MAC" in fields:
            self.modems[int(fields["MAC"])] = endpoint
            return []
        if key != "SEND":
            return []
        missing = [f for f in ("HEX", "FROM", "BITRATE", "TO") if f not in fields]
        if missing:
            log.error("SEND without %s: %r", ", ".join(missing), line)
            return []
        src, dest = int(fields["FROM"]), int(fields["TO"])
        recv = format_abc("RECV", FROM=src, TO=dest, HEX=fields["HEX"], BITRATE=fields["BITRATE"])
        if dest == 0:
            return [(e, recv) for mid, e in self.modems.items() if mid != src]
        if dest not in self.modems:
            log.error("SEND to unknown modem %d", dest)
            return []
        out = [(self.modems[dest], recv)]
        if fields.get("ACK", "").lower() in ("true", "1"):
            out.append((endpoint, format_abc("ACKN", FROM=dest, TO=src)))
        return out


async def serve_abc(sim: ABCSimulator, host: str = "127.0.0.1", port: int = 0) -> asyncio.Server:
    async def client(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            while line := await reader.readline():
                for target, text in sim.handle(writer, line.decode("latin-1")):
                    target.write(text.encode("latin-1"))
        except ConnectionError:
            pass
        finally:
            sim.forget(writer)
            writer.close()

    return await asyncio.start_server(client, host, port)
