"""The acoustic channel between emulated Micro-Modems, and how to plug in another one.

Interface (what a physics channel, e.g. in pygoby.netsim, implements):

* `attach(endpoint)` / `detach(endpoint)`: a modem joins or leaves the water. An endpoint is a
  `ChannelEndpoint`: it has `modem_id` (its current acoustic address, may change at run time via
  NVRAM `SRC`), `name` (stable, e.g. for looking up its position), `detect(packet, arrival)` and
  `receive(packet, reception)`.
* `transmit(sender, packet)`: the sender starts an acoustic transmission at `packet.tx_time`
  lasting `packet.duration` (the emulator's duration table, pygoby.acomms.mmsim.timing). The
  channel decides which endpoints hear it, when and how well. Every attached endpoint except the
  sender is a candidate: modems hear packets whatever their destination.
* For each endpoint that detects the packet: `detect(packet, arrival)` once the start of the
  signal reaches it (the modem prints `$CARXP`), then `receive(packet, reception)` once the
  signal has ended and is decoded (frames, statistics). A channel calls them from its own
  `do_work()`, which whoever runs the modems calls regularly (a discrete-event loop at
  `next_event_time()`); a late call is still made, with the true times in its arguments.

`ModemReception` carries what the channel decided: the arrival time of the signal's start, per-frame
CRC outcome and optional `$CACST` statistics overrides (any ReceiveStatistics field name, e.g.
`snr_in`, `mse_equalizer`, `doppler`, `spl`).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Protocol

from pygoby.util.clock import Clock, WallClock
from pygoby.util.timeline import Timeline

DEFAULT_SOUND_SPEED = 1500.0  # m/s


class ModemPacketKind(enum.Enum):
    DATA = "data"  # data frames at a rate (a PSK packet carries its cycle-init in its header)
    CYCLE = "cycle"  # a cycle-init mini-packet: rate 0's own, or a third-party poll
    ACK = "ack"  # acoustic acknowledgement of frames
    PING = "ping"  # two-way ping request ($CCMPC)
    PING_REPLY = "ping_reply"
    MINI = "mini"  # 13-bit user mini-packet ($CCMUC)
    FDP = "fdp"  # Micro-Modem 2 flexible data packet ($CCTDP)
    HW_CONTROL = "hw_control"  # hardware line control command ($CCMEC) and its reply
    SIGNAL = "signal"  # a sweep, sequence or navigation ping: heard by nobody here


@dataclass
class AcousticPacket:
    kind: ModemPacketKind
    src: int
    dest: int
    rate: int = 0
    ack_requested: bool = False
    frames: list[bytes] = field(default_factory=list)
    acked_frames: list[int] = field(default_factory=list)  # Micro-Modem numbering (1-based)
    num_frames: int = 0  # for CYCLE: frames requested
    tx_time: float = 0.0  # start of the signal (sender's clock)
    duration: float = 0.0  # s on the water
    hw_control: tuple[int, int, int] | None = None  # (line, mode, arg) of HW_CONTROL
    reply: bool = False  # HW_CONTROL: the answer to a command
    # the sentences every receiver prints alike for this packet ($CACYC, each $CARXD), made by
    # the first receiver (sentences are immutable) and dropped with the packet
    heard: dict = field(default_factory=dict, compare=False, repr=False)


@dataclass
class ModemReception:
    arrival_time: float  # when the start of the signal reached the receiver
    frame_ok: list[bool] | None = None  # None: every frame good
    stats: dict[str, float] = field(default_factory=dict)

    def frame_good(self, index: int) -> bool:
        return self.frame_ok is None or (index < len(self.frame_ok) and self.frame_ok[index])


class ChannelEndpoint(Protocol):
    @property
    def modem_id(self) -> int: ...

    @property
    def name(self) -> str: ...

    def detect(self, packet: AcousticPacket, arrival: float) -> None: ...

    def receive(self, packet: AcousticPacket, reception: ModemReception) -> None: ...


class ModemChannel(Protocol):
    def attach(self, endpoint: ChannelEndpoint) -> None: ...

    def detach(self, endpoint: ChannelEndpoint) -> None: ...

    def transmit(self, sender: ChannelEndpoint, packet: AcousticPacket) -> None: ...

    def do_work(self) -> None: ...

    def next_event_time(self) -> float | None: ...


class LoopbackChannel:
    """A perfect channel: every other modem hears every packet, without errors, `range_m`
    metres away (travel time `range_m / sound_speed`): the start of the signal is detected
    after the travel time, the packet is decoded when its end has arrived. No half-duplex, no
    collisions. `timeline`: share one with the modems (default: the channel's own on `clock`).
    """

    def __init__(
        self,
        clock: Clock | None = None,
        range_m: float = 0.0,
        sound_speed: float = DEFAULT_SOUND_SPEED,
        timeline: Timeline | None = None,
    ) -> None:
        if range_m < 0 or sound_speed <= 0:
            raise ValueError("the range must not be negative and the sound speed must be positive")
        self.timeline = timeline if timeline is not None else Timeline(clock or WallClock())
        self.travel_time = range_m / sound_speed
        self.endpoints: list[ChannelEndpoint] = []

    def attach(self, endpoint: ChannelEndpoint) -> None:
        if endpoint not in self.endpoints:
            self.endpoints.append(endpoint)

    def detach(self, endpoint: ChannelEndpoint) -> None:
        if endpoint in self.endpoints:
            self.endpoints.remove(endpoint)

    def transmit(self, sender: ChannelEndpoint, packet: AcousticPacket) -> None:
        self.deliver(packet, [e for e in self.endpoints if e is not sender])

    def deliver(self, packet: AcousticPacket, endpoints: list[ChannelEndpoint]) -> None:
        """Schedule `packet`'s detection and reception at `endpoints`."""
        arrival = packet.tx_time + self.travel_time
        for endpoint in endpoints:
            self.timeline.at(arrival, self._detect, endpoint, packet, arrival)
            self.timeline.at(
                arrival + packet.duration, self._receive, endpoint, packet, ModemReception(arrival)
            )

    def _detect(self, endpoint: ChannelEndpoint, packet: AcousticPacket, arrival: float) -> None:
        if endpoint in self.endpoints:  # (still attached)
            endpoint.detect(packet, arrival)

    def _receive(
        self, endpoint: ChannelEndpoint, packet: AcousticPacket, r: ModemReception
    ) -> None:
        if endpoint in self.endpoints:
            endpoint.receive(packet, r)

    def do_work(self) -> None:
        self.timeline.run_due()

    def next_event_time(self) -> float | None:
        return self.timeline.next_time()
