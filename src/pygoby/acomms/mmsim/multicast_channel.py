"""A perfect channel between emulator processes: packets travel as UDP multicast datagrams.

Each process attaches its local modems; a transmission is delivered at once to the other local
modems and sent to the group, where the other processes deliver it to theirs. Same semantics as
LoopbackChannel (no loss, no delay); it only spans processes. Multicast (and broadcast)
datagrams reach every socket bound to the port, which is why emulators of one host can share a
port (a unicast datagram would reach only one of them). `BroadcastChannel` does the same with
UDP broadcast to an address (Goby 1.1's iModemSim `BroadcastAddr`), to span hosts of a LAN.
"""

from __future__ import annotations

import asyncio
import base64
import json
import logging
import os
import socket
import struct

from pygoby.acomms.mmsim.channel import (
    AcousticPacket,
    ChannelEndpoint,
    LoopbackChannel,
    PacketKind,
    Reception,
)

log = logging.getLogger(__name__)


def packet_to_json(packet: AcousticPacket, sender: str) -> bytes:
    return json.dumps(
        {
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
        }  # fmt: skip
    ).encode()


def packet_from_json(data: bytes) -> tuple[str, AcousticPacket]:
    d = json.loads(data)
    packet = AcousticPacket(
        PacketKind(d["kind"]), int(d["src"]), int(d["dest"]), int(d["rate"]), bool(d["ack"]),
        [base64.b64decode(f) for f in d["frames"]], [int(a) for a in d["acked"]],
        int(d["num_frames"]), float(d["tx"]),
    )  # fmt: skip
    return str(d["sender"]), packet


class MulticastChannel(LoopbackChannel):
    def __init__(self, group: str = "239.255.42.99", port: int = 45454, travel_time: float = 0.0):
        super().__init__(travel_time)
        self.group, self.port = group, port
        self.token = f"{os.getpid()}-{id(self)}"
        self._sock: socket.socket | None = None

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        # SO_REUSEADDR only: with SO_REUSEPORT Linux hands each group datagram to just one
        # socket of the group instead of to every listener
        sock.bind(("", self.port))
        loopback = socket.inet_aton("127.0.0.1")
        sock.setsockopt(
            socket.IPPROTO_IP,
            socket.IP_ADD_MEMBERSHIP,
            struct.pack("4s4s", socket.inet_aton(self.group), loopback),
        )
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, loopback)
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
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
            self._sock.sendto(packet_to_json(packet, self.token), (self.group, self.port))

    def _readable(self) -> None:
        assert self._sock is not None
        try:
            data, _ = self._sock.recvfrom(65536)
            sender, packet = packet_from_json(data)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            log.warning("ignoring bad channel datagram: %s", exc)
            return
        if sender == self.token:
            return
        for endpoint in list(self.endpoints):
            endpoint.receive(packet, Reception(packet.tx_time + self.travel_time,
                                               travel_time=self.travel_time))  # fmt: skip


class BroadcastChannel(MulticastChannel):
    """The channel over UDP broadcast: datagrams go to `address:port` (e.g. 192.168.1.255)
    and are heard on `port` by every emulator of the hosts that address reaches."""

    def __init__(self, address: str, port: int, travel_time: float = 0.0) -> None:
        super().__init__(address, port, travel_time)

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
        sock.bind(("", self.port))
        sock.setblocking(False)
        self._sock = sock
        asyncio.get_running_loop().add_reader(sock.fileno(), self._readable)
