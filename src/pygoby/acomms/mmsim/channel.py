"""The acoustic channel between emulated Micro-Modems, and how to plug in another one.

Interface (what a physics channel, e.g. in pygoby.netsim, implements):

* `attach(endpoint)` / `detach(endpoint)`: a modem joins or leaves the water. An endpoint is a
  `ChannelEndpoint`: it has `modem_id` (its current acoustic address, may change at run time via
  NVRAM `SRC`), `name` (stable, e.g. for looking up its position) and `receive(packet, reception)`.
* `transmit(sender, packet)`: the sender starts an acoustic transmission now
  (`packet.tx_time` is the sender's clock). The channel decides which endpoints hear it, when, and
  how well, and calls `endpoint.receive(packet, reception)` for each of them — at once (as the
  loopback channel does) or later from its own `do_work()` / event loop, at
  `reception.arrival_time`. Every attached endpoint except the sender is a candidate: modems hear
  packets whatever their destination (the modem itself decides what to do with them).
* `do_work()`: called regularly by whoever runs the modems (the asyncio server calls it at
  ~20 Hz); a channel that delivers later uses it to deliver due receptions. Optional work.

`Reception` carries what the physics decided: arrival time, per-frame CRC outcome, the one-way
travel time (used for ping replies) and optional `$CACST` statistics overrides (e.g. `snr_in`,
`mse_equalizer`, `doppler`, `spl`: any ReceiveStatistics field name).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Protocol


class PacketKind(enum.Enum):
    DATA = "data"  # cycle-init + data frames (a local transmission)
    CYCLE = "cycle"  # a third-party cycle-init (poll) asking `src` to send to `dest`
    ACK = "ack"  # acoustic acknowledgement of frames
    PING = "ping"  # two-way ping request ($CCMPC)
    PING_REPLY = "ping_reply"
    MINI = "mini"  # 13-bit mini-packet ($CCMUC)


@dataclass
class AcousticPacket:
    kind: PacketKind
    src: int
    dest: int
    rate: int = 0
    ack_requested: bool = False
    frames: list[bytes] = field(default_factory=list)
    acked_frames: list[int] = field(default_factory=list)  # Micro-Modem numbering (1-based)
    num_frames: int = 0  # for CYCLE: frames requested
    tx_time: float = 0.0


@dataclass
class Reception:
    arrival_time: float
    frame_ok: list[bool] | None = None  # None: every frame good
    travel_time: float = 0.0  # one-way travel time (s)
    stats: dict[str, float] = field(default_factory=dict)

    def frame_good(self, index: int) -> bool:
        return self.frame_ok is None or (index < len(self.frame_ok) and self.frame_ok[index])


class ChannelEndpoint(Protocol):
    @property
    def modem_id(self) -> int: ...

    @property
    def name(self) -> str: ...

    def receive(self, packet: AcousticPacket, reception: Reception) -> None: ...


class Channel(Protocol):
    def attach(self, endpoint: ChannelEndpoint) -> None: ...

    def detach(self, endpoint: ChannelEndpoint) -> None: ...

    def transmit(self, sender: ChannelEndpoint, packet: AcousticPacket) -> None: ...

    def do_work(self) -> None: ...


class LoopbackChannel:
    """A perfect channel: every other modem hears every packet at once, without errors.

    `travel_time` (s) is only reported to ping replies (so ranging gives a fixed answer).
    """

    def __init__(self, travel_time: float = 0.0) -> None:
        self.travel_time = travel_time
        self.endpoints: list[ChannelEndpoint] = []

    def attach(self, endpoint: ChannelEndpoint) -> None:
        if endpoint not in self.endpoints:
            self.endpoints.append(endpoint)

    def detach(self, endpoint: ChannelEndpoint) -> None:
        if endpoint in self.endpoints:
            self.endpoints.remove(endpoint)

    def transmit(self, sender: ChannelEndpoint, packet: AcousticPacket) -> None:
        for endpoint in list(self.endpoints):
            if endpoint is not sender:
                endpoint.receive(
                    packet,
                    Reception(packet.tx_time + self.travel_time, travel_time=self.travel_time),
                )

    def do_work(self) -> None:
        pass
