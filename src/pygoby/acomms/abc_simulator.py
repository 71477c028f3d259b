"""ABC modem simulator: each TCP client is one modem; no delay, no loss.

Bad lines are logged and skipped, one line per client per turn of the event loop, and a modem
that does not read what is sent to it loses packets (as an acoustic modem out of range would)
instead of growing the simulator's memory.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Hashable
from typing import cast

from pygoby.acomms.abc_protocol import format_abc, parse_abc
from pygoby.util.linebased import LineSplitter

log = logging.getLogger(__name__)

READ_SIZE = 4096
MAX_UNREAD_BYTES = 1 << 20  # a modem this far behind in reading loses what is sent to it


class ABCSimulator:
    """Sans-I/O: `handle(endpoint, line)` returns the (endpoint, text) pairs to send."""

    def __init__(self) -> None:
        self.modems: dict[int, Hashable] = {}

    def forget(self, endpoint: Hashable) -> None:
        self.modems = {k: v for k, v in self.modems.items() if v != endpoint}

    def handle(self, endpoint: Hashable, line: str) -> list[tuple[Hashable, str]]:
        try:
            return self._handle(endpoint, line)
        except ValueError as exc:  # ABCParseError, or a number field that is not a number
            log.error("ignoring %r: %s", line[:80], exc)
            return []

    def _handle(self, endpoint: Hashable, line: str) -> list[tuple[Hashable, str]]:
        key, fields = parse_abc(line)
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
        splitter = LineSplitter("\n")
        try:
            while data := await reader.read(READ_SIZE):
                for line in splitter.feed(data):
                    for endpoint, text in sim.handle(writer, line + "\n"):
                        target = cast(asyncio.StreamWriter, endpoint)  # (the endpoints we gave)
                        if target.transport.get_write_buffer_size() > MAX_UNREAD_BYTES:
                            log.warning("dropping a packet for a modem that does not read")
                            continue
                        target.write(text.encode("latin-1"))
                    await asyncio.sleep(0)  # every other client's line comes next
        except ConnectionError:
            pass
        except asyncio.CancelledError:  # shutting down: end quietly (asyncio 3.11 would log
            pass  # the cancellation of a client task as an unhandled exception)
        finally:
            sim.forget(writer)
            writer.close()

    return await asyncio.start_server(client, host, port)
