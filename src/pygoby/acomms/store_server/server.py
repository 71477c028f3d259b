"""asyncio TCP front end of the store: one RUDICS-framed request per CR-terminated packet.

Every client is served by its own task, one request per turn of the event loop: a client that
pipelines thousands of requests delays another client's request by one request, not by all of
its own. A packet longer than the RUDICS limit is dropped as it streams in, never buffered or
converted, and answers wait for a client that reads slowly instead of piling up in memory.
"""

from __future__ import annotations

import asyncio
import logging
import sqlite3
from collections.abc import Mapping

from google.protobuf.message import DecodeError

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.errors import RudicsPacketError, StoreServerAuthError
from pygoby.acomms.rudics import (
    MAX_PACKET_BYTES,
    max_data_bytes,
    parse_rudics_packet,
    serialize_rudics_packet,
)
from pygoby.acomms.store_server.auth import verify_request
from pygoby.acomms.store_server.store import TransmissionStore
from pygoby.util.clock import Clock, WallClock
from pygoby.util.linebased import LineSplitter

log = logging.getLogger(__name__)

DEFAULT_PORT = 11244
READ_SIZE = 16384
DEFAULT_AUTH_WINDOW = 300.0  # s between a signed request's time and the server's clock
DEFAULT_PRUNE_INTERVAL = 60.0  # s between prunes of the store


class StoreServer:
    """Sans-I/O request handling: packet bytes in, packet bytes out (or None if invalid).

    `secrets`: modem id -> shared secret; when given, only requests signed with their modem
    id's secret (store_server.auth) are carried out, ids without a secret are refused, and
    outbox transmissions whose `src` is not the signing modem are dropped (a modem must not
    post mail as another).
    `auth_window`: how far (s) a signed request's time may be from the server's clock.
    """

    def __init__(
        self,
        store: TransmissionStore,
        clock: Clock | None = None,
        secrets: Mapping[int, bytes] | None = None,
        auth_window: float = DEFAULT_AUTH_WINDOW,
        prune_interval: float = DEFAULT_PRUNE_INTERVAL,
    ) -> None:
        self.store = store
        self.clock = clock if clock is not None else WallClock()
        self.secrets = secrets
        self.auth_window = auth_window
        self.prune_interval = prune_interval
        self._next_prune = 0.0
        self.requests_answered = 0
        self.requests_refused = 0  # packets that are not valid requests, or not authentic
        self.store_errors = 0  # requests answered with an error: the store could not be used

    def handle_packet(self, packet: bytes) -> bytes | None:
        try:
            payload = parse_rudics_packet(packet)
            request = acomms_pb.StoreServerRequest.FromString(payload)
        except (RudicsPacketError, DecodeError) as exc:
            log.warning("ignoring a bad store-server request: %s", exc)
            self.requests_refused += 1
            return None
        if not request.IsInitialized():
            log.warning("ignoring a store-server request without modem_id")
            self.requests_refused += 1
            return None
        now = self.clock.now()
        try:
            auth_time = self._authenticate(request.modem_id, payload, now)
            if auth_time is not None:
                _drop_forged(request)
            response = self.store.exchange(request, now, max_data_bytes(), auth_time)
        except StoreServerAuthError as exc:
            log.warning("refusing a request for modem id %d: %s", request.modem_id, exc)
            self.requests_refused += 1
            return _error_reply(request, "not authenticated for this modem id")
        except sqlite3.Error as exc:  # e.g. locked by another process: the client tries again
            log.warning("store unavailable for modem id %d: %s", request.modem_id, exc)
            self.store_errors += 1
            return _error_reply(request, f"store unavailable: {exc}")
        self.requests_answered += 1
        self._prune(now)
        return serialize_rudics_packet(response.SerializeToString())

    def _authenticate(self, modem_id: int, payload: bytes, now: float) -> float | None:
        if self.secrets is None:
            return None
        secret = self.secrets.get(modem_id)
        if secret is None:
            raise StoreServerAuthError("no secret is configured for it")
        auth_time = verify_request(payload, secret)
        if not abs(auth_time - now) <= self.auth_window:
            raise StoreServerAuthError(
                f"request time is {auth_time - now:+.0f} s from the server's clock"
            )
        return auth_time

    def _prune(self, now: float) -> None:
        if now < self._next_prune:
            return
        self._next_prune = now + self.prune_interval
        try:
            pruned = self.store.prune(now)
        except sqlite3.Error as exc:
            log.warning("cannot prune the store: %s", exc)
            return
        if pruned:
            log.info("pruned %d delivered or expired transmissions", pruned)


def _drop_forged(request: acomms_pb.StoreServerRequest) -> None:
    """Remove the outbox transmissions that claim another modem as their source."""
    forged = [t for t in request.outbox if t.src != request.modem_id]
    if not forged:
        return
    log.warning(
        "dropping %d transmission(s) from modem id %d that claim another source (src %s)",
        len(forged),
        request.modem_id,
        ", ".join(sorted({str(t.src) for t in forged})),
    )
    kept = [t for t in request.outbox if t.src == request.modem_id]
    del request.outbox[:]
    request.outbox.extend(kept)


def _error_reply(request: acomms_pb.StoreServerRequest, error: str) -> bytes:
    response = acomms_pb.StoreServerResponse(modem_id=request.modem_id)
    if request.HasField("request_id"):
        response.request_id = request.request_id
    status = acomms_pb.StoreServerResponseStatus(error=error)
    return serialize_rudics_packet(response.SerializeToString() + status.SerializeToString())


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
        except asyncio.CancelledError:  # shutting down: end quietly (asyncio 3.11 would log
            pass  # the cancellation of a client task as an unhandled exception)
        finally:
            writer.close()

    return await asyncio.start_server(client, host, port)
