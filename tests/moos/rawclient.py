"""A bare MOOS connection for DB tests: the bytes a client sends, nothing done for it."""

from __future__ import annotations

import asyncio

from pygoby.moos import protocol as p


async def raw_connect(port: int, name: str | None = None, asynchronous: bool = True):
    """A TCP connection to the DB on `port`; with `name`, handshaken (welcome read) as an
    asynchronous client, or as a synchronous one (its mail waits for its next packet)."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    if name is not None:
        handshake = p.handshake_message(name, 0.0, asynchronous)
        writer.write(p.PROTOCOL_STRING + p.encode_packet([handshake]))
        await writer.drain()
        framer = p.PacketFramer()
        while True:
            buf, spans = framer.feed(await asyncio.wait_for(reader.read(4096), 2))
            if spans:
                assert p.decode_packet(buf, *spans[0])[0].msg_type == p.WELCOME
                break
    return reader, writer


async def closed_by_peer(reader: asyncio.StreamReader, timeout: float) -> bool:
    """Did the DB close (or reset) the connection within `timeout`?"""
    try:
        async with asyncio.timeout(timeout):
            while await reader.read(65536):
                pass
    except ConnectionError:
        return True  # reset: the DB aborted with our bytes unread
    except TimeoutError:
        return False
    return True
