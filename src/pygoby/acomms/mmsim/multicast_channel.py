"""A perfect channel between emulator processes: packets travel as UDP multicast datagrams.

Each process attaches its local modems; a transmission is delivered to the other local modems
and sent to the group, where the other processes deliver it to theirs: the LoopbackChannel's
semantics (no loss, a fixed range), spanning processes. Multicast (and broadcast) datagrams
reach every socket bound to the port, which is why emulators of one host can share a port.
The socket is bound to the group address on the loopback interface and only datagrams sent
from 127.0.0.1 count: a unicast datagram, or one from another host, is never taken for an
acoustic packet. `BroadcastChannel` does the same with UDP broadcast to an address (Goby 1.1's
iModemSim `BroadcastAddr`), to span the hosts of a LAN.

With `position` (the local modem's [lat, lon, depth]) each datagram carries where it was sent
from, and with `link` a received packet is heard as that link model decides from the two
positions (travel time, lost frames, not heard at all) instead of perfectly.
"""

from __future__ import annotations

import asyncio
import base64
import json
import logging
import math
import os
import socket
import struct
from collections.abc import Callable, Sequence

from pygoby.acomms.mmsim.channel import (
    DEFAULT_SOUND_SPEED,
    AcousticPacket,
    ChannelEndpoint,
    LoopbackChannel,
    ModemPacketKind,
    ModemReception,
)
from pygoby.util.clock import Clock

log = logging.getLogger(__name__)

LOOPBACK = "127.0.0.1"
MAX_DATAGRAM = 16384
MAX_FRAMES, MAX_FRAME_BYTES = 8, 256  # (the largest packet: rate 5)
# (sender's [lat, lon, depth], receiver's, packet) -> how the receiver hears it (None: not at all)
LinkModel = Callable[[Sequence[float], Sequence[float], AcousticPacket], ModemReception | None]


def packet_to_json(
    packet: AcousticPacket, sender: str, position: Sequence[float] | None = None
) -> bytes:
    return json.dumps(
        {
            "pos": None if position is None else [float(v) for v in position],
            "sender": sender,
            "kind": packet.kind.value,
            "src": packet.src,
            "dest": packet.dest,
            "rate": packet.rate,
            "ack": packet.ack_requested,
            "frames": [base64.b64encode(f).decode() for f in packet.frames],
            "acked": packet.acked_frames,
            "num_frames": packet.num_frames,
            "tx": packet.tx_time,
            "duration": packet.duration,
            "hw": packet.hw_control,
            "reply": packet.reply,
        }
    ).encode()


def packet_from_json(data: bytes) -> tuple[str, AcousticPacket, list[float] | None]:
    """(sender, packet, sender's position or None); ValueError (or KeyError, TypeError) if the
    datagram is not a packet this channel sent."""
    d = json.loads(data)
    position = d.get("pos")
    if position is not None:
        position = [float(v) for v in position]
        if len(position) != 3 or not all(math.isfinite(v) for v in position):
            raise ValueError(f"bad position {position}")
    frames = [base64.b64decode(f, validate=True) for f in d["frames"]]
    if len(frames) > MAX_FRAMES or any(len(f) > MAX_FRAME_BYTES for f in frames):
        raise ValueError("more data than a packet carries")
    hw = d["hw"]
    packet = AcousticPacket(
        ModemPacketKind(d["kind"]),
        _int(d["src"]),
        _int(d["dest"]),
        _int(d["rate"]),
        bool(d["ack"]),
        frames,
        [_int(a) for a in d["acked"][:MAX_FRAMES]],
        _int(d["num_frames"]),
        float(d["tx"]),
        float(d["duration"]),
        None if hw is None else (_int(hw[0]), _int(hw[1]), _int(hw[2])),
        bool(d["reply"]),
    )
    if not 0 <= packet.duration < 3600:
        raise ValueError(f"bad duration {packet.duration}")
    return str(d["sender"]), packet, position


def _int(value: object) -> int:
    if type(value) is not int or not 0 <= value <= 255:
        raise ValueError(f"not a small integer: {value!r}")
    return value


class MulticastChannel(LoopbackChannel):
    def __init__(
        self,
        group: str = "239.255.42.99",
        port: int = 45454,
        clock: Clock | None = None,
        range_m: float = 0.0,
        sound_speed: float = DEFAULT_SOUND_SPEED,
        position: Callable[[], Sequence[float]] | None = None,
        link: LinkModel | None = None,
    ) -> None:
        super().__init__(clock, range_m, sound_speed)
        self.group, self.port = group, port
        self.position, self.link = position, link
        self.token = f"{os.getpid()}-{id(self)}"
        self._sock: socket.socket | None = None

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        # SO_REUSEADDR only: with SO_REUSEPORT Linux hands each group datagram to just one
        # socket of the group instead of to every listener. Bound to the group: only datagrams
        # sent to it arrive.
        sock.bind((self.group, self.port))
        loopback = socket.inet_aton(LOOPBACK)
        sock.setsockopt(
            socket.IPPROTO_IP,
            socket.IP_ADD_MEMBERSHIP,
            struct.pack("4s4s", socket.inet_aton(self.group), loopback),
        )
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, loopback)
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)  # never leaves the host
        sock.setblocking(False)
        self._sock = sock
        asyncio.get_running_loop().add_reader(sock.fileno(), self._readable)

    def close(self) -> None:
        if self._sock is not None:
            asyncio.get_running_loop().remove_reader(self._sock.fileno())
            self._sock.close()
            self._sock = None

    def transmit(self, sender: ChannelEndpoint, packet: AcousticPacket) -> None:
        super().transmit(sender, packet)
        if self._sock is not None:
            where = None if self.position is None else self.position()
            self._sock.sendto(packet_to_json(packet, self.token, where), (self.group, self.port))

    def _readable(self) -> None:
        assert self._sock is not None
        try:
            data, (address, _) = self._sock.recvfrom(MAX_DATAGRAM)
        except OSError as exc:
            log.warning("channel socket: %s", exc)
            return
        if not self._sender_ok(address):
            log.warning("ignoring a channel datagram from %s (not this host's loopback)", address)
            return
        try:
            sender, packet, where = packet_from_json(data)
        except (ValueError, KeyError, TypeError, IndexError) as exc:
            log.warning("ignoring bad channel datagram: %s", exc)
            return
        if sender == self.token:
            return
        if self.link is None or where is None or self.position is None:
            self.deliver(packet, list(self.endpoints))
            return
        heard = self.link(where, self.position(), packet)
        if heard is None:
            return  # too far, or lost in the noise
        for endpoint in list(self.endpoints):
            self.timeline.at(heard.arrival_time, self._detect, endpoint, packet, heard.arrival_time)
            self.timeline.at(
                heard.arrival_time + packet.duration, self._receive, endpoint, packet, heard
            )

    def _sender_ok(self, address: str) -> bool:
        return address == LOOPBACK


class BroadcastChannel(MulticastChannel):
    """The channel over UDP broadcast: datagrams go to `address:port` (e.g. 192.168.1.255)
    and are heard on `port` by every emulator of the hosts that address reaches. The socket is
    bound to `address`, so a unicast datagram to this host is never heard; any host the
    broadcast reaches may send (that is what the channel is for)."""

    def __init__(
        self,
        address: str,
        port: int,
        clock: Clock | None = None,
        range_m: float = 0.0,
        sound_speed: float = DEFAULT_SOUND_SPEED,
        position: Callable[[], Sequence[float]] | None = None,
        link: LinkModel | None = None,
    ) -> None:
        super().__init__(address, port, clock, range_m, sound_speed, position, link)

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
        sock.bind((self.group, self.port))
        sock.setblocking(False)
        self._sock = sock
        asyncio.get_running_loop().add_reader(sock.fileno(), self._readable)

    def _sender_ok(self, address: str) -> bool:
        return True
