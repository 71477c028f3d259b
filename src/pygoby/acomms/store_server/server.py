"""asyncio TCP front end of the store: one RUDICS-framed request per CR-terminated packet."""

from __future__ import annotations

import asyncio
import logging

from google.protobuf.message import DecodeError

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.errors import RudicsPacketError
from pygoby.acomms.rudics import parse_rudics_packet, serialize_rudics_packet
from pygoby.acomms.store_server.store import TransmissionStore
from pygoby.util.clock import Clock, WallClock

log = logging.getLogger(__name__)

DEFAULT_PORT = 11244
PACKET_LIMIT = 1 << 20


class StoreServer:
    """Sans-I/O request handling: packet bytes in, packet bytes out (or None if invalid)."""

    def __init__(self, store: TransmissionStore, clock: Clock | None = None) -> None:
        self.store = store
        self.clock = clock if clock is not None else WallClock()

    def handle_packet(self, packet: bytes) -> bytes | None:
        try:
            request = acomms_pb.StoreServerRequest.FromString(parse_rudics_packet(packet))
        except (RudicsPacketError, DecodeError) as exc:
            log.warning("ignoring a bad store-server request: %s", exc)
            return None
        if not request.IsInitialized():
            log.warning("ignoring a store-server request without modem_id")
            return None
        response = self.store.exchange(request, self.clock.now())
        return serialize_rudics_packet(response.SerializeToString())


async def serve_store(server: StoreServer, host: str = "127.0.0.1", port: int = DEFAULT_PORT):
    """Start serving; returns the asyncio.Server (its port via .sockets[0])."""

    async def client(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            while True:
                try:
                    packet = await reader.readuntil(b"\r")
                except asyncio.LimitOverrunError:
                    await reader.read(PACKET_LIMIT)  # drop an over-long packet
                    continue
                reply = server.handle_packet(packet)
                if reply is not None:
                    writer.write(reply)
        except (asyncio.IncompleteReadError, ConnectionError):
            pass
        finally:
            writer.close()

    return await asyncio.start_server(client, host, port, limit=PACKET_LIMIT)
