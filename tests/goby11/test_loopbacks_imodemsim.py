"""Virtual serial pairs with stable links (util.pty, `pygoby loopbacks`) and iModemSim: two
emulators of one host sharing a UDP port (BroadcastAddr 127.0.0.1) hear each other, through
netsim's acoustic model at their positions unless the perfect channel is asked for."""

from __future__ import annotations

import asyncio
import os
import signal
import socket
import sys
from pathlib import Path

import pytest

from pygoby.acomms.mmsim.channel import AcousticPacket, ModemPacketKind, ModemReception
from pygoby.acomms.mmsim.multicast_channel import MulticastChannel
from pygoby.apps.imodemsim import MULTICAST_GROUP, iModemSim
from pygoby.errors import ConfigError
from pygoby.netsim.sim.range_link import RangeLink
from pygoby.util.clock import WallClock
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.pty import PtyEnd, PtyError, PtyPair, is_live, open_serial, partner_of

pytestmark = pytest.mark.e2e

PYGOBY = str(Path(sys.executable).with_name("pygoby"))


async def read_until(fd: int, needle: bytes, timeout: float = 5.0) -> bytes:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    data = b""
    while needle not in data:
        assert loop.time() < deadline, f"{needle!r} not seen; got {data!r}"
        try:
            data += os.read(fd, 4096)
        except BlockingIOError:
            await asyncio.sleep(0.01)
    return data


def test_partner_names():
    assert partner_of("/tmp/ttyLOOPA1") == Path("/tmp/ttyLOOPA2")
    assert partner_of("/tmp/ttyLOOPB2") == Path("/tmp/ttyLOOPB1")
    assert partner_of("/dev/ttyUSB") is None


async def test_pair_relays_both_ways_and_cleans_up(tmp_path):
    a, b = tmp_path / "ttyLOOPA1", tmp_path / "ttyLOOPA2"
    pair = PtyPair(a, b).start()
    try:
        assert is_live(a) and is_live(b)
        fa, fb = open_serial(a), open_serial(b)
        os.write(fa, b"$CCCFQ,ALL\r\n")
        assert await read_until(fb, b"\r\n") == b"$CCCFQ,ALL\r\n"
        os.write(fb, b"\x00\xff binary too\r\n")
        assert await read_until(fa, b"too\r\n") == b"\x00\xff binary too\r\n"
        with pytest.raises(PtyError, match="belong to a running process"):
            PtyPair(a, b).open()
        os.close(fa)
        os.close(fb)
    finally:
        pair.close()
    assert not a.exists() and not a.is_symlink() and not is_live(a)


async def test_stale_links_are_replaced_and_files_refused(tmp_path):
    a, b = tmp_path / "ttyLOOPB1", tmp_path / "ttyLOOPB2"
    a.symlink_to("/dev/pts/999999")  # left by a process that died
    b.symlink_to("/dev/pts/999998")
    (tmp_path / ".ttyLOOPB1+ttyLOOPB2.lock").write_text("12345\n")  # its lock, not held
    assert not is_live(a)
    pair = PtyPair(a, b).start()
    try:
        assert os.readlink(a).startswith("/dev/pts/") and Path(os.readlink(a)).exists()
    finally:
        pair.close()
    (tmp_path / "ttyLOOPC1").write_text("not a tty")
    with pytest.raises(PtyError, match="exists and is not a link"):
        PtyPair(tmp_path / "ttyLOOPC1", tmp_path / "ttyLOOPC2").open()
    assert not (tmp_path / "ttyLOOPC2").exists()  # nothing left behind


async def test_single_end(tmp_path):
    end = PtyEnd(tmp_path / "ttyMODEM").open()
    try:
        fd = open_serial(tmp_path / "ttyMODEM")
        os.write(fd, b"hello\r\n")
        assert await read_until(end.master, b"\r\n") == b"hello\r\n"
        os.close(fd)
    finally:
        end.close()
    assert not (tmp_path / "ttyMODEM").is_symlink()


async def test_loopbacks_command(tmp_path):
    prefix = str(tmp_path / "ttyLOOP")
    proc = await asyncio.create_subprocess_exec(
        PYGOBY, "loopbacks", "--prefix", prefix, "--pairs", "A,B", stdout=asyncio.subprocess.PIPE
    )
    try:
        lines = [await asyncio.wait_for(proc.stdout.readline(), 20) for _ in range(2)]
        assert lines[0].decode().strip() == f"loopback {prefix}A1 <-> {prefix}A2"
        fa, fb = open_serial(prefix + "B1"), open_serial(prefix + "B2")
        os.write(fb, b"ping\r\n")
        assert await read_until(fa, b"\r\n") == b"ping\r\n"
        os.close(fa)
        os.close(fb)
        second = await asyncio.create_subprocess_exec(
            PYGOBY, "loopbacks", "--prefix", prefix, "--pairs", "A", stderr=asyncio.subprocess.PIPE
        )
        _, err = await asyncio.wait_for(second.communicate(), 20)
        assert second.returncode == 1 and b"belong to a running process" in err
    finally:
        proc.send_signal(signal.SIGINT)
        await asyncio.wait_for(proc.wait(), 10)
    assert proc.returncode == 0 and not Path(prefix + "A1").is_symlink()


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def imodemsim_mission(tmp_path: Path, letter: str, udp_port: int, extra: str = "") -> Path:
    path = tmp_path / f"mm{letter}.moos"
    path.write_text(f"""ServerHost = localhost
ServerPort = 1
Community = mm{letter}

ProcessConfig = iModemSim
{{
  AppTick = 4
  CommsTick = 4
  Port = {tmp_path}/ttyLOOP{letter}1
  Speed = 19200
  IPPort = {udp_port}
  BroadcastAddr = 127.0.0.1
  InputLocType = constant_local
  ConstantPosX = 0
  ConstantPosY = 0
  ConstantDepth = 0
{extra}}}
""")
    return path


async def test_two_imodemsims_sharing_a_port_hear_each_other(tmp_path):
    """Seed 003's layout: both emulators on UDP port X with BroadcastAddr 127.0.0.1 (plain
    unicast would reach only one socket); each makes its /tmp/ttyLOOP pair itself."""
    udp = free_udp_port()
    (tmp_path / "ttyLOOPA1").symlink_to("/dev/pts/999999")  # stale links of an earlier run
    (tmp_path / "ttyLOOPA2").symlink_to("/dev/pts/999998")
    apps = [iModemSim.from_mission(imodemsim_mission(tmp_path, x, udp)) for x in "AB"]
    for app in apps:
        await app.start()
    try:
        host_a, host_b = (open_serial(tmp_path / f"ttyLOOP{x}2") for x in "AB")
        os.write(host_a, b"$CCCFG,SRC,1\r\n")
        os.write(host_b, b"$CCCFG,SRC,2\r\n")
        await read_until(host_a, b"$CACFG,SRC,1")
        await read_until(host_b, b"$CACFG,SRC,2")
        os.write(host_a, b"$CCMUC,1,2,0123\r\n")
        assert b"$CAMUA,1,2,0123" in await read_until(host_b, b"$CAMUA")
        os.write(host_b, b"$CCMUC,2,1,1ABC\r\n")
        assert b"$CAMUA,2,1,1ABC" in await read_until(host_a, b"$CAMUA")
        os.close(host_a)
        os.close(host_b)
    finally:
        for app in apps:
            await app.stop()
    assert not (tmp_path / "ttyLOOPA1").is_symlink() and not (tmp_path / "ttyLOOPB2").is_symlink()


async def test_imodemsim_uses_a_pair_made_by_loopbacks(tmp_path):
    pair = PtyPair(tmp_path / "ttyLOOPA1", tmp_path / "ttyLOOPA2").start()
    app = iModemSim.from_mission(imodemsim_mission(tmp_path, "A", free_udp_port()))
    assert app.pair is None
    await app.start()
    try:
        host = open_serial(tmp_path / "ttyLOOPA2")
        os.write(host, b"$CCCFQ,SRC\r\n")
        assert b"$CACFG,SRC," in await read_until(host, b"$CACFG")
        os.close(host)
    finally:
        await app.stop()
        pair.close()


@pytest.mark.parametrize(
    ("extra", "reason"),
    [
        ("IPPort = 70000\n", "IPPort: 70000 is not a UDP port"),
        ("BroadcastAddr = far.away\n", "BroadcastAddr: 'far.away' is not an IPv4 address"),
        ("InputLocType = gps\n", "InputLocType: 'gps' is not one of"),
        ("Speed = fast\n", "Speed: must be a number, not 'fast'"),
        ("ChannelModel = bellhop\n", "ChannelModel: 'bellhop' is not one of range, perfect"),
    ],
)
def test_imodemsim_configuration_errors(tmp_path, extra, reason):
    """Each names the mission line of the setting (the house rule: file:line: field: reason)."""
    path = imodemsim_mission(tmp_path, "A", 40000, extra)
    text = path.read_text()
    key = extra.split("=")[0].strip()
    lines = [
        line
        for line in text.splitlines()
        if not line.strip().startswith(key + " ") or line.strip() + "\n" == extra
    ]
    path.write_text("\n".join(lines) + "\n")
    line = next(n for n, text in enumerate(lines, start=1) if text.strip() + "\n" == extra)
    with pytest.raises(ConfigError, match=rf"^{path}:{line}: {reason}"):
        iModemSim.from_mission(path)


def test_imodemsim_port_that_cannot_be_made(tmp_path):
    path = imodemsim_mission(tmp_path, "A", 40000)
    path.write_text(
        path.read_text().replace(f"Port = {tmp_path}/ttyLOOPA1", f"Port = {tmp_path}/modem")
    )
    with pytest.raises(ConfigError, match="only loopback names ending in 1 or 2"):
        iModemSim.from_mission(path)


async def test_example_config_is_a_block_imodemsim_reads(tmp_path):
    """`iModemSim --example_config` prints its own `name = value` lines (not the TextFormat
    `common` block of Goby apps), and that block, pasted into a mission, runs."""
    block = iModemSim.example_config()
    assert block.startswith("ProcessConfig = iModemSim\n{\n") and "common" not in block
    udp = free_udp_port()
    block = block.replace("/tmp/ttyLOOPA1", f"{tmp_path}/ttyLOOPA1").replace("49234", str(udp))
    path = tmp_path / "example.moos"
    path.write_text(f"ServerPort = 1\nCommunity = ex\n{block}")
    app = iModemSim.from_mission(path)
    try:
        assert (app.port_path, app.channel.port, app.position) == (
            f"{tmp_path}/ttyLOOPA1",
            udp,
            [0.0, 0.0, 0.0],
        )
        assert (app.cfg.common.app_tick, app.cfg.common.comm_tick) == (4, 4)
    finally:
        app.pair.close()


class Listener:
    """A channel endpoint that keeps what it hears."""

    def __init__(self, name: str) -> None:
        self.name, self.modem_id = name, 9
        self.heard: list[tuple[AcousticPacket, ModemReception]] = []

    def detect(self, packet, arrival) -> None:
        pass

    def receive(self, packet, reception) -> None:
        self.heard.append((packet, reception))


async def test_positions_travel_with_packets_and_the_range_decides(tmp_path):
    """Emulators in three processes' stead (three channels on one multicast port): 1.5 km away
    a packet arrives after range / 1500 m/s of travel; 11 km away it is not heard at all; with
    the perfect channel it is heard at once whatever the range."""
    udp = free_udp_port()
    geodesy = UTMGeodesy(42.35, -70.95)
    clock = WallClock()

    def at(y: float):
        lat, lon = geodesy.to_geo(0.0, y)
        return lambda: [lat, lon, 10.0]

    receiver = MulticastChannel(MULTICAST_GROUP, udp, clock, position=at(0), link=RangeLink())
    perfect = MulticastChannel(MULTICAST_GROUP, udp, clock, position=at(0))
    far = MulticastChannel(MULTICAST_GROUP, udp, clock, position=at(11_000))
    near = MulticastChannel(MULTICAST_GROUP, udp, clock, position=at(1_500))
    listeners = {"range": Listener("range"), "perfect": Listener("perfect")}
    receiver.attach(listeners["range"])
    perfect.attach(listeners["perfect"])
    channels = [receiver, perfect, far, near]
    for channel in channels:
        channel.open()
    try:
        for sender, src in ((far, 1), (near, 2)):
            packet = AcousticPacket(ModemPacketKind.MINI, src, 9, frames=[b"\x01\x23"])
            packet.tx_time, packet.duration = clock.now(), 0.5
            sender.transmit(Listener(f"sender{src}"), packet)
        async with asyncio.timeout(10):
            while len(listeners["perfect"].heard) < 2 or not listeners["range"].heard:
                for channel in channels:
                    channel.do_work()
                await asyncio.sleep(0.01)
    finally:
        for channel in channels:
            channel.close()
    assert sorted(p.src for p, _ in listeners["perfect"].heard) == [1, 2]
    ((packet, reception),) = listeners["range"].heard
    assert packet.src == 2
    assert reception.arrival_time - packet.tx_time == pytest.approx(1_500 / 1_500, abs=0.01)
    assert receiver.timeline.next_time() is None  # nothing of the far packet is on its way


def test_imodemsim_hears_through_the_range_model_unless_told_perfect(tmp_path):
    path = imodemsim_mission(tmp_path, "A", free_udp_port(), "  ConstantPosY = 1000\n")
    path.write_text(
        path.read_text().replace("Community", "LatOrigin = 42.35\nLongOrigin = -70.95\nCommunity")
    )
    app = iModemSim.from_mission(path)
    try:
        assert isinstance(app.channel.link, RangeLink)
        lat, lon, _depth = app.geo_position()
        assert (lat, lon) == pytest.approx(UTMGeodesy(42.35, -70.95).to_geo(0, 1000))
    finally:
        app.pair.close()
    path = imodemsim_mission(tmp_path, "B", free_udp_port(), "  ChannelModel = perfect\n")
    app = iModemSim.from_mission(path)
    try:
        assert app.channel.link is None
    finally:
        app.pair.close()
