"""Line links over real loopback TCP and a pty pair (serial)."""

import asyncio
import os

import pytest

from pygoby.util.errors import LinkClosedError
from pygoby.util.linebased import (
    LineSplitter,
    MemoryLink,
    SerialLink,
    TCPClientLink,
    TCPServerLink,
    open_pty_pair,
)


async def lines_from(link, count, timeout=5.0):
    got = []
    async with asyncio.timeout(timeout):
        while len(got) < count:
            got += link.read_lines()
            await asyncio.sleep(0.01)
    return got


def test_splitter_handles_partial_lines_and_custom_delimiter():
    s = LineSplitter("\r")
    assert s.feed(b"$CA") == []
    assert s.feed(b"RXD,1\r$CAA") == ["$CARXD,1"]
    assert s.feed(b"CK\rx\r") == ["$CAACK", "x"]


def test_memory_link_refuses_writes_when_closed():
    link = MemoryLink()
    with pytest.raises(LinkClosedError):
        link.write("x")


async def test_tcp_client_and_server_exchange_lines():
    server = TCPServerLink(0, host="127.0.0.1", delimiter="\r")
    server.open()
    port = await server.wait_listening()
    client = TCPClientLink("127.0.0.1", port, delimiter="\r", reconnect_interval=0.2)
    client.open()
    await client.wait_open()
    await server.wait_open()
    client.write("hello\rwor")
    client.write("ld\r")
    assert await lines_from(server, 2) == ["hello", "world"]
    server.write("back\r")
    assert await lines_from(client, 1) == ["back"]
    client.close()
    server.close()


async def test_tcp_client_reconnects_after_server_restart():
    server = TCPServerLink(0, host="127.0.0.1")
    server.open()
    port = await server.wait_listening()
    client = TCPClientLink("127.0.0.1", port, reconnect_interval=0.2)
    client.open()
    await client.wait_open()
    assert client.connections == 1
    server.close()
    async with asyncio.timeout(5):
        while client.is_open:
            await asyncio.sleep(0.02)
    with pytest.raises(LinkClosedError):
        client.write("lost\r\n")
    server2 = TCPServerLink(port, host="127.0.0.1")
    server2.open()
    await server2.wait_listening()
    await client.wait_open(timeout=5)
    assert client.connections == 2  # tells a driver its peer may have restarted
    client.write("again\r\n")
    assert await lines_from(server2, 1) == ["again"]
    client.close()
    server2.close()


async def test_serial_link_over_pty():
    master, path = open_pty_pair()
    link = SerialLink(path, 19200, delimiter="\r")
    link.open()
    try:
        os.write(master, b"$CAREV,1\r")
        assert await lines_from(link, 1) == ["$CAREV,1"]
        link.write("$CCCFG,SRC,1*31\r\n")
        await asyncio.sleep(0.05)
        assert os.read(master, 100) == b"$CCCFG,SRC,1*31\r\n"
    finally:
        link.close()
        os.close(master)


async def test_server_wait_listening_raises_the_bind_error():
    first = TCPServerLink(0, host="127.0.0.1")
    first.open()
    port = await first.wait_listening()
    second = TCPServerLink(port, host="127.0.0.1")
    second.open()
    with pytest.raises(OSError):
        await second.wait_listening()
    second.close()
    first.close()


def test_memory_link_counts_connections():
    link = MemoryLink()
    link.open()
    link.open()
    link.close()
    link.open()
    assert link.connections == 2
