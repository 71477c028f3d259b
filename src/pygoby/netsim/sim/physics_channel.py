"""The Micro-Modem emulators' acoustic channel, backed by netsim's packet-level physics.

`PhysicsChannel` implements the pluggable channel interface of `pygoby.acomms.mmsim.channel`
(attach / detach / transmit / do_work) on top of the sans-I/O `pygoby.netsim.channel.Channel`:

* every attached emulator is a node keyed by its modem TCP port (netsim's vehicle identity);
  `ports` maps emulator names to ports, or an emulator named by its port ("62000") needs none;
* positions are whatever the physics Channel knows: follow a NetSimManager with
  ``manager.on_nav(physics.channel.on_environment_nav_update)``, or feed scripted tracks with
  ``physics.channel.update_position(port, NavFix(...))``;
* `transmit` registers the packet as a Transmission starting at its `tx_time` and lasting its
  `duration` (the emulator's duration table, pygoby.acomms.mmsim.timing); `do_work` asks the
  Channel at the clock's now which receptions have locked their receivers (the emulator prints
  `$CARXP`) and which have been delivered (end of reception + decode latency), and hands each
  delivery to its receiver with the physics' outcome: all frames good, some frames bad (the
  emulator reports those as BAD_CRC), or nothing at all (not detected, receiver busy,
  half-duplex; a control packet — cycle-init, ACK, ping, mini-packet — with a bad frame);
* `next_event_time` is the next delivery. A detection is reported at the next `do_work` after
  its arrival (a real-time run calls it every few ms), or, with `detections_with_receptions`
  (discrete-event runs, where nothing depends on when `$CARXP` is printed), just before its
  reception ends: the receiver's driver then wakes once for both;
* `$CACST` numbers (SNR, SPL, Doppler, ...) come from `pygoby.netsim.channel.stats`; ping replies
  are timed by the emulators themselves (travel times from the arrival times the physics gives);
* every transmission and reception is emitted by `signal_event` (the `on_event` argument is
  connected to it) as a dict (JSON-ready), which `pygoby.netsim.report.eventlog` writes as the run's
  event log; an event is only made when someone listens, and `transmissions` and `outcomes`
  (receptions by outcome) count them in any case.

Randomness is the Channel's own (seeded per transmission and receiver), so a run driven by a
virtual clock repeats exactly for the same seed.
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import cast

from pygoby.acomms.mmsim.channel import (
    AcousticPacket,
    ChannelEndpoint,
    ModemPacketKind,
    ModemReception,
)
from pygoby.netsim.channel import Channel, Outcome, PacketKind, Reception, Transmission
from pygoby.netsim.channel.stats import link_statistics
from pygoby.util.clock import Clock
from pygoby.util.signal import Signal

log = logging.getLogger(__name__)

EventSink = Callable[[dict], None]

# What each emulator packet is on the water: data and FDP packets carry frames at their rate; the
# cycle-init, ACK, mini-packets and hardware-control packets are short FSK packets; pings,
# their replies and the other signals (sweeps, navigation pings) are pulses.
PHYSICAL_KIND = {
    ModemPacketKind.DATA: PacketKind.DATA,
    ModemPacketKind.FDP: PacketKind.DATA,
    ModemPacketKind.CYCLE: PacketKind.MINI,
    ModemPacketKind.ACK: PacketKind.MINI,
    ModemPacketKind.MINI: PacketKind.MINI,
    ModemPacketKind.HW_CONTROL: PacketKind.MINI,
    ModemPacketKind.PING: PacketKind.PING,
    ModemPacketKind.PING_REPLY: PacketKind.PING,
    ModemPacketKind.SIGNAL: PacketKind.PING,
}


@dataclass(frozen=True)
class _Sent:
    """The payload of a Transmission: who sent which packet."""

    sender: ChannelEndpoint
    packet: AcousticPacket
    port: int


class PhysicsChannel:
    def __init__(
        self,
        channel: Channel,
        clock: Clock,
        ports: Mapping[str, int] | None = None,
        *,
        control_rate: int = 0,
        on_event: EventSink | None = None,
        detections_with_receptions: bool = False,
    ) -> None:
        """`control_rate`: the rate whose error model applies to cycle-inits, ACKs, pings and
        mini-packets (FSK on a Micro-Modem, so rate 0 by default)."""
        self.channel = channel
        self.clock = clock
        self.ports = dict(ports or {})
        self.control_rate = control_rate
        self.signal_event: Signal[dict[str, object]] = Signal()
        if on_event is not None:
            self.signal_event.connect(on_event)
        self._endpoints: dict[int, ChannelEndpoint] = {}
        self._last_poll = -math.inf
        self._air_free: dict[int, float] = {}  # by port: the end of its last transmission
        # detections held until their receptions end: (receiver, transmission number) -> arrival
        self._held: dict[tuple[int, int], float] | None = {} if detections_with_receptions else None
        self.transmissions: Counter[str] = Counter()  # by kind (cycle, data, ping, ...)
        self.outcomes: Counter[str] = Counter()  # receptions by outcome
        self.delivered: Counter[int] = Counter()  # packets handed to each port's modem

    # -- the mmsim ModemChannel interface --------------------------------------------------------

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
        kind = packet.kind
        if kind in _FRAMED:
            rate, frames = packet.rate, max(1, len(packet.frames))
        else:
            rate, frames = self.control_rate, 1
        # never before the last poll (a wall clock stepped back, or an emulator running late in
        # real time, must not break the channel), nor before the sender's previous packet ended
        # (one transducer: a late cycle-init moved to the last poll still precedes its data)
        start = max(packet.tx_time, self._last_poll, self._air_free.get(port, -math.inf))
        self._air_free[port] = start + packet.duration
        tx = Transmission(
            source=port,
            start=start,
            rate=rate,
            frames=frames,
            kind=PHYSICAL_KIND[kind],
            duration=packet.duration,
            dest=packet.dest,
            payload=_Sent(sender, packet, port),
        )
        planned = self.channel.transmit(tx)
        self.transmissions[kind._value_] += 1
        if self.signal_event:  # (the event is only made when someone listens)
            self.signal_event.emit(
                {
                    "event": "tx",
                    "t": tx.start,
                    "port": port,
                    "src": packet.src,
                    "dest": packet.dest,
                    "kind": kind._value_,
                    "rate": packet.rate,
                    "frames": tx.frames,
                    "duration": packet.duration,
                    "bytes": sum(len(f) for f in packet.frames),
                    "receivers": len(planned),
                }
            )

    def do_work(self) -> None:
        now = max(self.clock.now(), self._last_poll)
        self._last_poll = now
        held = self._held
        if held is None:
            for d in self.channel.detections(now):
                self._detect(d.receiver, d.transmission, d.arrival)
            for reception in self.channel.poll(now):
                self._deliver(reception)
            return
        detected: list = []
        receptions = self.channel.poll(now, detected)
        for d in detected:
            held[d.receiver, d.sequence] = d.arrival
        for reception in receptions:
            arrival = held.pop((reception.receiver, reception.sequence), None)
            if arrival is not None:
                self._detect(reception.receiver, reception.transmission, arrival)
            self._deliver(reception)

    def _detect(self, receiver: int, transmission: Transmission, arrival: float) -> None:
        endpoint = self._endpoints.get(receiver)
        if endpoint is not None:
            sent = cast(_Sent, transmission.payload)  # (what transmit() gave the channel)
            endpoint.detect(sent.packet, arrival)

    def next_event_time(self) -> float | None:
        """When `do_work` next has something to deliver (for discrete-event loops)."""
        return self.channel.next_delivery()

    # -- delivery --------------------------------------------------------------------------------

    def _deliver(self, r: Reception) -> None:
        sent = cast(_Sent, r.transmission.payload)
        packet = sent.packet
        endpoint = self._endpoints.get(r.receiver)
        delivered = endpoint is not None and self._heard(r, packet)
        self.outcomes[r.outcome._value_] += 1
        if self.signal_event:
            self._log_reception(r, sent, delivered)
        if not delivered:
            return
        self.delivered[r.receiver] += 1
        assert endpoint is not None
        reception = ModemReception(
            arrival_time=r.arrival,
            frame_ok=None if r.outcome is Outcome.GOOD else list(r.frames_ok),
            stats=self._stats(r),
        )
        endpoint.receive(packet, reception)

    @staticmethod
    def _heard(r: Reception, packet: AcousticPacket) -> bool:
        if r.outcome is Outcome.GOOD:
            return True
        # A data or FDP packet with bad frames is reported as such (BAD_CRC); a control packet
        # with its only frame bad is never noticed by the host.
        return r.outcome is Outcome.BAD_FRAMES and packet.kind in _FRAMED

    def _stats(self, r: Reception) -> dict[str, float]:
        """The $CACST fields taken from the physics (the emulator fills the rest)."""
        band = self.channel.config.band_of(r.receiver)
        return link_statistics(r, band.carrier_hz, band.bandwidth_hz) or {}

    def _log_reception(self, r: Reception, sent: _Sent, delivered: bool) -> None:
        # (enum values read as `_value_`: the `value` property is a Python call per event)
        packet = sent.packet
        range_m, owtt, rl, snr, sinr, collision = _link_figures(
            r.range_m, r.owtt, r.received_level, r.noise_level, r.sinr
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
            }
        )


_FRAMED = (ModemPacketKind.DATA, ModemPacketKind.FDP)


def _link_figures(
    range_m: float, owtt: float, rl: float, noise: float, sinr: float
) -> tuple[float, float, float, float, float, bool]:
    """The rounded figures of an `rx` event."""
    snr = rl - noise
    return (
        round(range_m, 3),
        round(owtt, 6),
        round(rl, 2),
        round(snr, 2),
        round(sinr, 2),
        sinr < snr - 0.01,
    )
