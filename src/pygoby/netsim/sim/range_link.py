"""netsim's packet-level acoustic model for one sender and one receiver at given positions: the
link model of the Micro-Modem emulators' multicast channel (`iModemSim` with positions), where
each emulator process knows only its own modem and the sender's position a packet carries.

    link = RangeLink(ChannelConfig(), seed=1)
    heard = link([lat, lon, depth], [lat, lon, depth], packet)   # mmsim ModemReception, or None

Travel time and received level come from the range (and depths); frames are lost as the
rate's error model draws them. Each packet is judged on its own: no interference between
packets of different senders (each process sees one sender at a time).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from pygoby.acomms.mmsim.channel import AcousticPacket, ModemReception
from pygoby.netsim.channel.geometry import NavFix
from pygoby.netsim.channel.model import Channel, ChannelConfig, Outcome, PacketKind, Transmission
from pygoby.netsim.sim.physics_channel import PHYSICAL_KIND

_SENDER, _RECEIVER = 1, 2


class RangeLink:
    def __init__(
        self, config: ChannelConfig | None = None, seed: int = 0, control_rate: int = 0
    ) -> None:
        """`control_rate`: the rate whose error model applies to cycle-inits, ACKs, pings and
        mini-packets (FSK on a Micro-Modem)."""
        self.config = config or ChannelConfig()
        self.seed = seed
        self.control_rate = control_rate
        self._count = itertools.count()

    def __call__(
        self, sender: Sequence[float], receiver: Sequence[float], packet: AcousticPacket
    ) -> ModemReception | None:
        kind = PHYSICAL_KIND[packet.kind]
        framed = kind is PacketKind.DATA
        channel = Channel(self.config, seed=self.seed * 1_000_003 + next(self._count))
        for port, (lat, lon, depth) in ((_SENDER, sender), (_RECEIVER, receiver)):
            channel.update_position(port, NavFix(lat, lon, depth, time=packet.tx_time))
        channel.transmit(
            Transmission(
                source=_SENDER,
                start=packet.tx_time,
                rate=packet.rate if framed else self.control_rate,
                frames=max(1, len(packet.frames)) if framed else 1,
                kind=kind,
                duration=packet.duration,
                dest=packet.dest,
            )
        )
        for reception in channel.poll(math.inf):
            if reception.outcome is Outcome.GOOD:
                return ModemReception(reception.arrival)
            if reception.outcome is Outcome.BAD_FRAMES and framed:
                return ModemReception(reception.arrival, frame_ok=list(reception.frames_ok))
        return None  # not detected, or a control packet with a bad frame
