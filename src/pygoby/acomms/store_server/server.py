"""asyncio TCP front end of the store: one RUDICS-framed request per CR-terminated packet.

Every client is served by its own task, one request per turn of the event loop: a client that
pipelines thousands of requests delays another client's request by one request, not by all of
its own. A packet longer than the RUDICS limit is dropped as it streams in, never buffered or
converted, and answers wait for a client that reads slowly instead of piling up in memory.
"""

from __future__ import annotations

import asyncio
import logging

from google.protobuf.message import DecodeError

from pygoby.acomms import messages as m
from pygoby.acomms.rudics import (
    MAX_PACKET_BYTES,
    RudicsPacketError,
    max_data_bytes,
    parse_rudics_packet,
    serialize_rudics_packet,
)
from pygoby.acomms.store_server.store import TransmissionStore
from pygoby.util.clock import Clock, WallClock
from pygoby.util.linebased import LineSplitter

log = logging.getLogger(__name__)

DEFAULT_PORT = 11244
READ_SIZE = 16384


class StoreServer:
    """Sans-I/O request handling: packet bytes in, packet bytes out (or None if invalid)."""

    def __init__(self, store: TransmissionStore, clock: Clock | None = None) -> None:
        self.store = store
        self.clock = clock if clock is not None else WallClock()
        self.requests_answered = 0
        self.requests_refused = 0  # packets that are not valid requests

    def handle_packet(self, packet: bytes) -> bytes | None:
        try:
            request = m.StoreServerRequest.FromString(parse_rudics_packet(packet))
        except (RudicsPacketError, DecodeError) as exc:
            log.warning("ignoring a bad store-server request: %s", exc)
            self.requests_refused += 1
            return None
        if not request.IsInitialized():
            log.warning("ignoring a store-server request without modem_id")
            self.requests_refused += 1
            return None
        response = self.store.exchange(request, self.clock.now(), max_data_bytes())
        self.requests_answered += 1
        return serialize_rudics_packet(response.SerializeToString())


async def serve_store(server: StoreServer, host: str = "127.0.0.1", port: int = DEFAULT_PORT):
    """Start serving; returns the asyncio.Server (its port via .sockets[0])."""

    async def client(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        splitter = LineSplitter("\r", max_line_bytes=MAX_PACKET_BYTES - 1)
        try:
            while data := await reader.read(READ_SIZE):
                for line in splitter.feed(data):
                    reply = server.handle_packet(line.encode("latin-1") + b"\r")
                    if reply is not None:
                        writer.write(reply)
                        await writer.drain()
                    await asyncio.sleep(0)  # the next request waits for every other client's
                await asyncio.sleep(0)
        except ConnectionError:
            pass
        finally:
            writer.close()

    return await asyncio.start_server(client, host, port)
