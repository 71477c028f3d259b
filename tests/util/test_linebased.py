"""Line links over real loopback TCP and a pty pair (serial)."""

import asyncio
import os

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.util.errors import LinkClosedError
from pygoby.util.linebased import (
    LineSplitter,
    MemoryLink,
    SerialLink,
    TCPClientLink,
    TCPServerLink,
    open_pty_pair,
)
from tests.hypothesis_profiles import examples


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


def test_splitter_drops_an_over_long_line_whole_and_keeps_the_next():
    """An over-long line is dropped up to its delimiter: no tail of it comes out as a line."""
    s = LineSplitter("\r\n", max_line_bytes=8)
    assert s.feed(b"ok\r\n0123456") == ["ok"]
    assert s.feed(b"789abcdef") == [] and s.discarded == 1
    assert s.feed(b"tail-of-the-long-line\r") == []
    assert s.feed(b"\nnext\r\n") == ["next"]
    assert s.feed(b"0123456789\r\nafter\r\n") == ["after"] and s.discarded == 2
    assert s.feed(b"12345678\r\n") == ["12345678"]  # exactly the limit is a line
    assert s.feed(b"12345678\r") == [] and s.feed(b"\n") == ["12345678"]  # split delimiter


def test_splitter_scans_each_byte_once():
    """A long line trickled in small pieces costs time in proportion to its length."""
    s = LineSplitter("\r", max_line_bytes=1 << 20)
    calls = 0
    real_find = bytearray.find

    class CountingBuffer(bytearray):
        def find(self, sub, start=0, *args):
            nonlocal calls
            calls += len(self) - start
            return real_find(self, sub, start, *args)

    s._buffer = CountingBuffer()
    for _ in range(2000):
        s.feed(b"x" * 100)
    assert s.feed(b"\r") == ["x" * 200_000]
    assert calls < 3 * 200_000  # rescanning from the start each time would be ~2000x more


@settings(max_examples=examples(300), deadline=None)
@given(
    stream=st.lists(st.sampled_from([b"a", b"bc", b"\r", b"\n", b"\r\n", b"xyz" * 5])).map(
        b"".join
    ),
    cuts=st.lists(st.integers(min_value=0, max_value=200)),
    delimiter=st.sampled_from(["\r", "\r\n"]),
)
def test_splitter_same_lines_however_the_stream_is_cut(stream, cuts, delimiter):
    limit = 6
    splitter = LineSplitter(delimiter, max_line_bytes=limit)
    got = []
    start = 0
    for cut in [*sorted(cuts), len(stream)]:
        got += splitter.feed(stream[start:cut])
        start = max(start, cut)
    complete = stream.split(delimiter.encode())[:-1]
    assert got == [line.decode("latin-1") for line in complete if len(line) <= limit]
    assert splitter.discarded == sum(len(line) > limit for line in complete) + splitter._discarding
