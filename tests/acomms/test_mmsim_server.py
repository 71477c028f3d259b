"""The emulator's asyncio edges: a client that never reads, a pty nobody reads, and the
multicast channel's socket (regressions from the hardening review)."""

import asyncio
import json
import socket

import pytest

from pygoby.acomms.mmsim import LoopbackChannel, MicroModemModel
from pygoby.acomms.mmsim.channel import AcousticPacket, ModemPacketKind
from pygoby.acomms.mmsim.multicast_channel import (
    BroadcastChannel,
    MulticastChannel,
    packet_to_json,
)
from pygoby.acomms.mmsim.server import ANONYMOUS_PTY, MMSimServer
from pygoby.util.clock import WallClock
from pygoby.util.nmea import NMEASentence

pytestmark = pytest.mark.e2e

QUERY_ALL = (NMEASentence.parse("$CCCFQ,ALL").message() + "\r\n").encode()  # ~70 lines back


async def ask(port: int, body: str) -> str:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        writer.write((NMEASentence.parse(body).message() + "\r\n").encode())
        async with asyncio.timeout(10):
            return (await reader.readline()).decode().strip()
    finally:
        writer.close()


async def test_a_client_that_never_reads_cannot_grow_the_emulator():
    """Regression: writes never waited for a reader (+56 MB from a non-reading client)."""
    import tracemalloc

    channel = LoopbackChannel()
    server = MMSimServer(MicroModemModel(1, WallClock(), channel), channel)
    await server.start()
    tracemalloc.start()
    sock = socket.socket()
    # a small receive window: the kernel holds little of the unread answers, the emulator's
    # sends block soon (and the test does not spend its time filling megabytes of buffers)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 32 * 1024)
    sock.connect(("127.0.0.1", server.port))
    sock.setblocking(False)
    sent, blocked = 0, 0.0
    try:
        # up to ~10 MB of answers asked for, none read; the emulator stops reading this client
        # (its sends block) while its answers wait
        while sent < 20_000 * len(QUERY_ALL) and blocked < 2.0:
            try:
                sent += sock.send(QUERY_ALL * 20)
                await asyncio.sleep(0)
            except BlockingIOError:
                await asyncio.sleep(0.01)
                blocked += 0.01
        await asyncio.sleep(0.2)
        _, peak = tracemalloc.get_traced_memory()
        assert peak < 2_000_000  # (the unread answers piled up here before: +5 MB)
        # the emulator still serves everyone else
        assert (await ask(server.port, "$CCCFQ,SRC")).startswith("$CACFG,SRC,1*")
    finally:
        tracemalloc.stop()
        sock.close()
        await server.close()


async def test_a_pty_nobody_reads_does_not_freeze_the_emulator():
    channel = LoopbackChannel()
    server = MMSimServer(MicroModemModel(1, WallClock(), channel), channel, pty_path=ANONYMOUS_PTY)
    await server.start()
    try:
        reader, writer = await asyncio.open_connection("127.0.0.1", server.port)
        for _ in range(300):  # every answer goes to the pty too (nobody has it open)
            writer.write(QUERY_ALL)
            await writer.drain()
            await reader.read(1 << 16)
        assert server.pty_dropped > 0
        assert (await ask(server.port, "$CCCFQ,SRC")).startswith("$CACFG,SRC,1*")
        writer.close()
    finally:
        await server.close()


async def only_the_real_packet_is_heard(make_channel, address: str, forgeries) -> None:
    """Two channels on one port: `forgeries(port)` sends datagrams that must not count; a real
    mini-packet through the channel must arrive, alone."""
    import random

    port = random.randint(40000, 60000)
    clock = WallClock()
    here, there = make_channel(address, port, clock), make_channel(address, port, clock)
    listener = MicroModemModel(2, clock, here)
    talker = MicroModemModel(1, clock, there)
    for channel in (there, here):  # (a unicast datagram goes to the last socket bound)
        channel.open()
    try:
        forgeries(port)
        talker.handle_line("$CCMUC,1,2,0abc")  # a real one, through the channel
        heard = []
        async with asyncio.timeout(10):
            while not heard:
                for worker in (talker, there, listener, here):
                    worker.do_work()
                heard.extend(s for s in listener.take_output() if s.sentence_id == "MUA")
                await asyncio.sleep(0.01)
        await asyncio.sleep(0.3)
        here.do_work()
        heard.extend(s for s in listener.take_output() if s.sentence_id == "MUA")
        assert [s.fields[1:] for s in heard] == [("1", "2", "0ABC")]
    finally:
        for channel in (here, there):
            channel.close()


def forged_mini_packet() -> bytes:
    forged = AcousticPacket(
        ModemPacketKind.MINI, 7, 2, frames=[b"\x01\x02"], tx_time=WallClock().now()
    )
    return packet_to_json(forged, "intruder")


async def test_multicast_channel_takes_only_group_datagrams_from_this_host():
    """Regression: the channel socket bound 0.0.0.0 and took a unicast datagram from anyone for
    an acoustic packet."""
    group = "239.255.42.95"

    def forgeries(port: int) -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as unicast:
            unicast.sendto(forged_mini_packet(), ("127.0.0.1", port))
            unicast.sendto(b"not json", ("127.0.0.1", port))
            unicast.sendto(json.dumps({"frames": ["AAAA"] * 100}).encode(), (group, port))

    await only_the_real_packet_is_heard(MulticastChannel, group, forgeries)


async def test_broadcast_channel_hears_only_its_broadcast_address():
    """iModemSim's BroadcastAddr channel: bound to the broadcast address, so a unicast datagram
    to the host is never taken for an acoustic packet (127.255.255.255 stands for a LAN's)."""

    def forgeries(port: int) -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as unicast:
            unicast.sendto(forged_mini_packet(), ("127.0.0.1", port))

    await only_the_real_packet_is_heard(BroadcastChannel, "127.255.255.255", forgeries)
