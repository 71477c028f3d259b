"""The Micro-Modem emulators' acoustic channel, backed by netsim's packet-level physics.

`PhysicsChannel` implements the pluggable channel interface of `pygoby.acomms.mmsim.channel`
(attach / detach / transmit / do_work) on top of the sans-I/O `pygoby.netsim.channel.Channel`:

* every attached emulator is a node keyed by its modem TCP port (netsim's vehicle identity);
  `ports` maps emulator names to ports, or an emulator named by its port ("62000") needs none;
* positions are whatever the physics Channel knows: follow a NetSimManager with
  ``manager.on_nav(physics.channel.on_environment_nav_update)``, or feed scripted tracks with
  ``physics.channel.update_position(port, Position(...))``;
* `transmit` registers the packet as a Transmission starting at the clock's now; `do_work`
  polls the Channel at the clock's now and hands each reception to its receiver at its delivery
  time (end of reception + decode latency) with the physics' outcome: all frames good, some
  frames bad (the emulator reports those as BAD_CRC), or nothing at all (not detected, receiver
  busy, half-duplex; a control packet — cycle-init, ACK, ping, mini-packet — with a bad frame);
* `$CACST` numbers (SNR, SPL, Doppler, ...) come from `pygoby.netsim.channel.stats`;
* a ping reply carries the true travel time: the mean of the two legs' one-way travel times, each
  computed for the nodes' positions at the time (what the modem's `(round trip - TAT) / 2` gives);
* every transmission and reception is emitted by `signal_event` (the `on_event` argument is
  connected to it) as a dict (JSON-ready), which `pygoby.netsim.eventlog` writes as the run's
  event log.

Randomness is the Channel's own (seeded per transmission and receiver), so a run driven by a
virtual clock repeats exactly for the same seed.
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from pygoby.acomms.mmsim.channel import AcousticPacket, ChannelEndpoint
from pygoby.acomms.mmsim.channel import PacketKind as ModemPacketKind
from pygoby.acomms.mmsim.channel import Reception as ModemReception
from pygoby.netsim.channel import Channel, Outcome, PacketKind, Reception, Transmission
from pygoby.netsim.channel.stats import link_statistics
from pygoby.util.clock import Clock
from pygoby.util.signal import Signal

log = logging.getLogger(__name__)

EventSink = Callable[[dict], None]

# What each emulator packet is on the water: the cycle-init, ACK and mini-packets are short FSK
# packets; pings and their replies are ranging pulses.
PHYSICAL_KIND = {
    ModemPacketKind.DATA: PacketKind.DATA,
    ModemPacketKind.CYCLE: PacketKind.MINI,
    ModemPacketKind.ACK: PacketKind.MINI,
    ModemPacketKind.MINI: PacketKind.MINI,
    ModemPacketKind.PING: PacketKind.PING,
    ModemPacketKind.PING_REPLY: PacketKind.PING,
}


@dataclass(frozen=True)
class _Sent:
    """The payload of a Transmission: who sent which packet (and, for a ping reply, the
    travel time of the ping it answers)."""

    sender: ChannelEndpoint
    packet: AcousticPacket
    port: int
    first_leg_owtt: float | None = None


class PhysicsChannel:
    def __init__(
        self,
        channel: Channel,
        clock: Clock,
        ports: Mapping[str, int] | None = None,
        *,
        control_rate: int = 0,
        on_event: EventSink | None = None,
    ) -> None:
        """`control_rate`: the rate whose error model applies to cycle-inits, ACKs, pings and
        mini-packets (FSK on a Micro-Modem, so rate 0 by default)."""
        self.channel = channel
        self.clock = clock
        self.ports = dict(ports or {})
        self.control_rate = control_rate
        self.signal_event = Signal()
        if on_event is not None:
            self.signal_event.connect(on_event)
        self._endpoints: dict[int, ChannelEndpoint] = {}
        self._answering: tuple[int, float] | None = None  # (port, owtt) of a ping being heard
        self._last_poll = -math.inf
        self.delivered: Counter[int] = Counter()  # packets handed to each port's modem

    # -- the mmsim Channel interface -----------------------------------------------------------

    def port_of(self, endpoint: ChannelEndpoint) -> int:
        port = self.ports.get(endpoint.name)
        if port is not None:
            return port
        try:
            return int(endpoint.name)
        except ValueError:
            raise ValueError(
                f"emulator {endpoint.name!r} has no modem port: name it by its port or list it "
                "in PhysicsChannel(ports=...)"
            ) from None

    def attach(self, endpoint: ChannelEndpoint) -> None:
        port = self.port_of(endpoint)
        existing = self._endpoints.get(port)
        if existing is not None and existing is not endpoint:
            raise ValueError(f"modem port {port} already has an emulator ({existing.name})")
        self._endpoints[port] = endpoint

    def detach(self, endpoint: ChannelEndpoint) -> None:
        port = self.port_of(endpoint)
        if self._endpoints.get(port) is endpoint:
            del self._endpoints[port]

    def transmit(self, sender: ChannelEndpoint, packet: AcousticPacket) -> None:
        port = self.port_of(sender)
        first_leg = None
        if packet.kind is ModemPacketKind.PING_REPLY and self._answering is not None:
            answering_port, owtt = self._answering
            if answering_port == port:
                first_leg = owtt
        data = packet.kind is ModemPacketKind.DATA
        tx = Transmission(
            source=port,
            # never before the last poll (a wall clock stepped back must not break the channel)
            start=max(self.clock.now(), self._last_poll),
            rate=packet.rate if data else self.control_rate,
            frames=max(1, len(packet.frames)) if data else 1,
            kind=PHYSICAL_KIND[packet.kind],
            dest=packet.dest,
            payload=_Sent(sender, packet, port, first_leg),
        )
        planned = self.channel.transmit(tx)
        if self.signal_event:  # (the event is only made when someone listens)
            self.signal_event.emit(
                {
                    "event": "tx",
                    "t": tx.start,
                    "port": port,
                    "src": packet.src,
                    "dest": packet.dest,
                    "kind": packet.kind._value_,
                    "rate": packet.rate,
                    "frames": tx.frames,
                    "duration": self.channel.duration_of(tx),
                    "bytes": sum(len(f) for f in packet.frames),
                    "receivers": len(planned),
                }  # fmt: skip
            )

    def do_work(self) -> None:
        now = max(self.clock.now(), self._last_poll)
        self._last_poll = now
        for reception in self.channel.poll(now):
            self._deliver(reception)

    def next_event_time(self) -> float | None:
        """When `do_work` next has something to deliver (for discrete-event loops)."""
        return self.channel.next_delivery()

    # -- delivery --------------------------------------------------------------------------------

    def _deliver(self, r: Reception) -> None:
        sent: _Sent = r.transmission.payload
        packet = sent.packet
        endpoint = self._endpoints.get(r.receiver)
        delivered = endpoint is not None and self._heard(r, packet)
        travel_time = r.owtt
        if packet.kind is ModemPacketKind.PING_REPLY and sent.first_leg_owtt is not None:
            travel_time = (sent.first_leg_owtt + r.owtt) / 2
        if self.signal_event:
            self._log_reception(r, sent, delivered, travel_time)
        if not delivered:
            return
        self.delivered[r.receiver] += 1
        assert endpoint is not None
        reception = ModemReception(
            arrival_time=r.arrival,
            frame_ok=None if r.outcome is Outcome.GOOD else list(r.frames_ok),
            travel_time=travel_time,
            stats=self._stats(r),
        )
        self._answering = (r.receiver, r.owtt) if packet.kind is ModemPacketKind.PING else None
        try:
            endpoint.receive(packet, reception)
        finally:
            self._answering = None

    @staticmethod
    def _heard(r: Reception, packet: AcousticPacket) -> bool:
        if r.outcome is Outcome.GOOD:
            return True
        # A data packet with bad frames is reported frame by frame (BAD_CRC); a control packet
        # with its only frame bad is never noticed by the host.
        return r.outcome is Outcome.BAD_FRAMES and packet.kind is ModemPacketKind.DATA

    def _stats(self, r: Reception) -> dict[str, float]:
        """The $CACST fields taken from the physics (the emulator fills the rest)."""
        band = self.channel.config.band_of(r.receiver)
        return link_statistics(r, band.carrier_hz, band.bandwidth_hz) or {}

    def _log_reception(self, r: Reception, sent: _Sent, delivered: bool, owtt: float) -> None:
        # (enum values read as `_value_`: the `value` property is a Python call per event)
        packet = sent.packet
        range_m, owtt, rl, snr, sinr, collision = _link_figures(
            r.range_m, owtt, r.received_level, r.noise_level, r.sinr
        )
        self.signal_event.emit(
            {
                "event": "rx",
                "t": r.deliver_at,
                "tx_t": r.transmission.start,
                "arrival": r.arrival,
                "port": r.receiver,
                "tx_port": sent.port,
                "src": packet.src,
                "dest": packet.dest,
                "kind": packet.kind._value_,
                "rate": packet.rate,
                "outcome": r.outcome._value_,
                "delivered": delivered,
                "frames": r.transmission.frames,
                "good_frames": r.good_frames,
                "range_m": range_m,
                "owtt": owtt,
                "rl": rl,
                "snr": snr,
                "sinr": sinr,
                "collision": collision,
            }  # fmt: skip
        )


def _link_figures(
    range_m: float, owtt: float, rl: float, noise: float, sinr: float
) -> tuple[float, float, float, float, float, bool]:
    """The rounded figures of an `rx` event (a link's recur: float rounding is slow, so they
    are remembered; not with a zero among them, whose key would be shared by -0.0)."""
    key = (range_m, owtt, rl, noise, sinr)
    figures = _figures.get(key)
    if figures is None:
        snr = rl - noise
        figures = (
            round(range_m, 3), round(owtt, 6), round(rl, 2), round(snr, 2), round(sinr, 2),
            sinr < snr - 0.01,
        )  # fmt: skip
        if 0.0 not in key:
            if len(_figures) >= _FIGURES_LIMIT:
                _figures.clear()
            _figures[key] = figures
    return figures


_figures: dict[tuple[float, ...], tuple[float, float, float, float, float, bool]] = {}
_FIGURES_LIMIT = 4096
