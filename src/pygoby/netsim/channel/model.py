"""The packet-level acoustic channel, sans-I/O.

API (what a modem emulator calls):

* ``channel = Channel(ChannelConfig(...), seed=1)``
* ``channel.update_position(port, NavFix(...))`` whenever a node's position is known, or
  ``manager.on_nav(channel.on_environment_nav_update)`` to follow a `NetSimManager`.
* ``channel.transmit(Transmission(source=62000, start=t, rate=1, frames=3))`` when a modem starts
  transmitting (start = simulation time now; transmissions must not be registered in the past
  of the last `poll`). Returns the receptions it will cause as ``[(receiver port, arrival)]``.
* ``channel.poll(now) -> list[Reception]``: every reception whose delivery time
  (end of reception + decode latency) is <= now, in delivery order, with its outcome: GOOD,
  BAD_FRAMES (some frame failed; ``frames_ok`` says which, deliver the leading good ones),
  NOT_DETECTED, RECEIVER_BUSY (arrived while the receiver was locked on another packet) or
  HALF_DUPLEX (overlapped the receiver's own transmission). Lost ones are returned too, so the
  emulator can decide what a real modem would report.
* ``channel.next_delivery()``: the earliest pending delivery time (for discrete-event loops).
* ``channel.detections(now) -> list[Detection]``: the receptions whose start has reached their
  receiver by `now` and that the receiver locked onto (a modem reports "packet detected" then),
  each once, in arrival order; their outcome is only known at delivery. Call it before
  ``poll(now)``: a poll forgets the detections nobody asked for.
* ``pygoby.netsim.channel.stats.receive_statistics(reception, source_id=, dest_id=)``: the
  Micro-Modem ``$CACST`` (ReceiveStatistics) to report for a reception (None if none).
* ``pygoby.netsim.channel.settings.environment_channel_configs(manager_config)``:
  ``{environment_id: (ChannelConfig, seed)}`` from the manager's TextFormat configuration.

Per transmission (source A at t0) and every other node B with a fresh position in an
overlapping band: range from A at t0 to B at arrival (B dead-reckoned, fixed-point solution),
``owtt = r / c``, reception interval ``[t0 + owtt, t0 + owtt + duration]``,
``RL = SL - TL(r, f)``. At arrival: detection (SINR against ambient noise plus receptions active
at that instant >= the rate's detection threshold) and receiver lock (the first detected packet
is the only one decoded until it ends). At the end: ``SINR = RL - (noise + every overlapping
reception at B)``, then one independent draw per frame from the rate's frame-error model.

With ``ChannelConfig(protocol_model=ProtocolModel(...))`` links are range-based instead
(UnetStack's protocol model, for deterministic MAC tests): decoded within the communication
range, detected only up to the detection range, and any overlap of two receptions at a node
destroys both; nodes beyond the interference range are not affected at all.

Modelling simplifications: a reception that locks the receiver keeps it locked until its end even
if the receiver's own transmission then aborts it; detection uses the interference present at
the instant of arrival, decoding the interference over the whole reception.

Determinism: each reception's draws come from a generator seeded by (seed, transmission number,
receiver port), so results depend only on the seed and the transmissions, not on how often or
when `poll` is called.
"""

from __future__ import annotations

import _random
import bisect
import enum
import functools
import hashlib
import heapq
import logging
import math
import random
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from pygoby.netsim.channel.absorption import thorp
from pygoby.netsim.channel.frame_errors import ProtocolModel, RateErrorModels
from pygoby.netsim.channel.geometry import NavFix, arrival_delay, closing_speed, slant_range
from pygoby.netsim.channel.levels import (
    noise_level_integrated,
    power_sum_db,
    sinr,
    transmission_loss,
)
from pygoby.netsim.channel.propagation import BellhopLoss
from pygoby.netsim.channel.soundspeed import SoundSpeedProfile, harmonic_mean_speed
from pygoby.netsim.channel.timing import Interval
from pygoby.protobuf.netsim.messages.netsim_pb2 import EnvironmentNavUpdate

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Band:
    carrier_hz: float = 25000.0
    bandwidth_hz: float = 5000.0

    def overlaps(self, other: Band) -> bool:
        return (
            abs(self.carrier_hz - other.carrier_hz) < (self.bandwidth_hz + other.bandwidth_hz) / 2
        )


class PacketKind(enum.Enum):
    DATA = "data"
    MINI = "mini"  # mini-packets, cycle-init, acknowledgements
    PING = "ping"  # ranging pings and their replies


DEFAULT_DURATIONS = {PacketKind.DATA: 3.25, PacketKind.MINI: 1.0, PacketKind.PING: 0.5}


@dataclass(frozen=True)
class ChannelConfig:
    """Every knob of the model, with its default."""

    sound_speed: float | SoundSpeedProfile = 1500.0  # m/s, or a profile c(depth)
    source_level: float = 185.0  # dB re 1 uPa @ 1 m
    spreading: float = 1.5  # k in k*10*log10(r)
    absorption: Callable[[float], float] = thorp  # f kHz -> dB/km
    noise_level: float | None = None  # in-band dB re 1 uPa; None: Stojanovic over the band
    shipping: float = 0.5
    wind: float = 5.0  # m/s
    band: Band = Band()
    node_bands: Mapping[int, Band] = field(default_factory=dict)  # per-port override
    error_models: RateErrorModels = field(default_factory=RateErrorModels)
    durations: Mapping[PacketKind, float] = field(default_factory=lambda: dict(DEFAULT_DURATIONS))
    half_duplex: bool = True
    receiver_lock: bool = True
    # Deterministic range-based links instead of SINR and error models (UnetStack's protocol
    # model): decoding within communication_range, any overlap of two receptions at a node
    # destroys both, no effect beyond interference_range. For MAC tests.
    protocol_model: ProtocolModel | None = None
    # Transmission loss without absorption (`propagation.BellhopLoss`: BELLHOP ray tracing);
    # None: the empirical spreading law k * 10 log10(r)
    propagation: BellhopLoss | None = None
    decode_latency: float = 0.0  # s between end of reception and delivery
    position_staleness: float = 60.0  # s; older positions make the node absent
    moving_receivers: bool = True  # solve the arrival time for a moving receiver

    def band_of(self, port: int) -> Band:
        return self.node_bands.get(port, self.band)


@dataclass(frozen=True)
class Transmission:
    source: int  # modem port of the transmitter
    start: float  # simulation time, seconds
    rate: int = 0
    frames: int = 1
    kind: PacketKind = PacketKind.DATA
    duration: float | None = None  # None: the configured duration for `kind`
    dest: int | None = None  # informational (modems filter by destination themselves)
    payload: object = None  # passed through untouched


class Outcome(enum.Enum):
    GOOD = "good"
    BAD_FRAMES = "bad_frames"
    NOT_DETECTED = "not_detected"
    RECEIVER_BUSY = "receiver_busy"
    HALF_DUPLEX = "half_duplex"


@dataclass(frozen=True)
class Reception:
    receiver: int
    transmission: Transmission
    sequence: int  # number of the transmission on this channel (0, 1, ...)
    arrival: float
    end: float
    deliver_at: float
    owtt: float  # true one-way travel time, s
    range_m: float
    received_level: float  # dB re 1 uPa
    noise_level: float  # ambient, in band
    sinr: float  # over the whole reception, interference included
    closing_speed: float  # m/s, positive when approaching
    outcome: Outcome
    frames_ok: tuple[bool, ...] = ()

    @property
    def good_frames(self) -> int:
        """Number of leading good frames (what is delivered)."""
        count = 0
        for ok in self.frames_ok:
            if not ok:
                break
            count += 1
        return count

    @property
    def bad_frames(self) -> int:
        return sum(not ok for ok in self.frames_ok)


@dataclass(frozen=True)
class Detection:
    """A reception whose signal has started at `receiver` and locked it (see `detections`)."""

    receiver: int
    transmission: Transmission
    sequence: int  # number of the transmission on this channel
    arrival: float


@dataclass
class _Pending:
    receiver: int
    transmission: Transmission
    sequence: int
    interval: Interval
    owtt: float
    range_m: float
    received_level: float
    closing_speed: float
    locked: bool | None = None  # decided once every earlier arrival is known
    detected: bool = False

    @property
    def arrival_order(self) -> tuple[float, int, int]:
        """The order in which arrivals are decided and receptions listed (and interference
        summed): by arrival, receiver, transmission."""
        return (self.interval.start, self.receiver, self.sequence)


_arrival_order = _Pending.arrival_order.fget  # type: ignore[attr-defined]  # (a property)


class Channel:
    def __init__(self, config: ChannelConfig | None = None, seed: int = 0) -> None:
        self.config = config if config is not None else ChannelConfig()
        self.seed = seed
        self._positions: dict[int, NavFix] = {}
        # Receptions at each receiver: finished ones (kept while they can still interfere), in
        # the order they finished (batches in arrival order), then pending ones, by arrival.
        self._finished_at: dict[int, list[_Pending]] = {}
        self._pending_at: dict[int, list[_Pending]] = {}
        self._undecided: list[tuple[tuple[float, int, int], _Pending]] = []  # heap, by arrival
        self._ends: list[tuple[float, int, int, _Pending]] = []  # heap of pending ones, by end
        self._own_tx: dict[int, list[Interval]] = {}
        self._locked_until: dict[int, float] = {}
        self._sequence = 0
        self._horizon = -math.inf  # last poll time
        self._pruned_at = -math.inf
        self._longest_configured = max(self.config.durations.values(), default=0.0)
        self._noise_cache: dict[Band, float] = {}
        self._quiet: dict[float, float] = {}  # noise level -> its power sum alone
        self._noise_by_port: dict[int, float] = {}
        self._rng = random.Random()
        self._detected: list[Detection] = []  # locked receptions not yet reported
        # The stale position last reported per node, so each one is logged once.
        self._stale_reported: dict[int, NavFix] = {}

    # -- positions -------------------------------------------------------------------------

    def update_position(self, port: int, position: NavFix) -> None:
        self._positions[port] = position

    def on_environment_nav_update(self, update: EnvironmentNavUpdate) -> None:
        """Listener for `NetSimManager.on_nav` (an EnvironmentNavUpdate)."""
        self.update_position(update.nav.modem_tcp_port, NavFix.from_nav(update.nav))

    def position(self, port: int) -> NavFix | None:
        """The last position reported for a node, however old."""
        return self._positions.get(port)

    def remove_node(self, port: int) -> None:
        self._positions.pop(port, None)

    def _fresh_position(self, port: int, t: float) -> NavFix | None:
        position = self._positions.get(port)
        if position is None:
            return None
        if t - position.time > self.config.position_staleness:
            if self._stale_reported.get(port) is not position:
                self._stale_reported[port] = position
                log.warning(
                    "node %d is absent from the channel: its last position (t=%.3f) is more than "
                    "position_staleness = %g s old at t=%.3f",
                    port,
                    position.time,
                    self.config.position_staleness,
                    t,
                )
            return None
        return position

    # -- physics ---------------------------------------------------------------------------

    def duration_of(self, tx: Transmission) -> float:
        return tx.duration if tx.duration is not None else self.config.durations[tx.kind]

    def noise_level(self, band: Band) -> float:
        if self.config.noise_level is not None:
            return self.config.noise_level
        level = self._noise_cache.get(band)
        if level is None:
            level = self._noise_cache[band] = noise_level_integrated(
                band.carrier_hz / 1000, band.bandwidth_hz, self.config.shipping, self.config.wind
            )
        return level

    def sound_speed(self, depth_a: float, depth_b: float) -> float:
        c = self.config.sound_speed
        return float(c) if isinstance(c, (int, float)) else harmonic_mean_speed(c, depth_a, depth_b)

    # -- events ----------------------------------------------------------------------------

    def transmit(self, tx: Transmission) -> list[tuple[int, float]]:
        """Register a transmission; returns the (receiver, arrival time) it will cause."""
        if tx.start < self._horizon:
            raise ValueError(
                f"transmission at {tx.start} is in the past of the last poll ({self._horizon})"
            )
        sequence = self._sequence
        self._sequence += 1
        duration = self.duration_of(tx)
        self._own_tx.setdefault(tx.source, []).append(Interval(tx.start, tx.start + duration))
        source = self._fresh_position(tx.source, tx.start)
        if source is None:
            return []
        source = source.at(tx.start)
        config = self.config
        tx_band = config.band_of(tx.source)
        alpha = config.absorption(tx_band.carrier_hz / 1000)
        protocol = config.protocol_model
        planned = []
        for port in sorted(self._positions):
            if port == tx.source:
                continue  # (its position was checked above)
            receiver = self._fresh_position(port, tx.start)
            if receiver is None:
                continue
            if not tx_band.overlaps(config.band_of(port)):
                continue
            c = self.sound_speed(source.depth, receiver.depth)
            if receiver.speed != 0:
                receiver_now = receiver.at(tx.start)
                if config.moving_receivers:
                    delay = arrival_delay(
                        functools.partial(_slant_range_at, source, receiver, tx.start), c
                    )
                else:
                    delay = slant_range(source, receiver_now) / c
            else:
                # a receiver that does not move is where it is: its reported position gives the
                # geodesic and closing speed of its dead-reckoned one (only lat, lon and depth
                # count), and the fixed point of arrival_delay is its first guess
                receiver_now = receiver
                delay = slant_range(source, receiver) / c
            arrival = tx.start + delay
            range_m = delay * c
            if protocol is not None and not protocol.interferes(range_m):
                continue
            pending = _Pending(
                receiver=port,
                transmission=tx,
                sequence=sequence,
                interval=Interval(arrival, arrival + duration),
                owtt=delay,
                range_m=range_m,
                received_level=config.source_level
                - self._loss(tx_band, source, receiver, range_m, alpha),
                closing_speed=closing_speed(source, receiver_now),
            )
            order = pending.arrival_order
            bisect.insort(self._pending_at.setdefault(port, []), pending, key=_arrival_order)
            heapq.heappush(self._undecided, (order, pending))
            heapq.heappush(self._ends, (pending.interval.end, sequence, port, pending))
            planned.append((port, arrival))
        return planned

    def _loss(
        self, band: Band, source: NavFix, receiver: NavFix, range_m: float, alpha: float
    ) -> float:
        propagation = self.config.propagation
        if propagation is None:
            return transmission_loss(range_m, alpha, self.config.spreading)
        loss = propagation.loss(band.carrier_hz, source.depth, receiver.depth, range_m)
        return loss + alpha * range_m / 1000

    def next_delivery(self) -> float | None:
        if not self._ends:
            return None
        return self._ends[0][0] + self.config.decode_latency

    def detections(self, now: float) -> list[Detection]:
        """Receptions locked onto by `now` (see the module's documentation), each once. With
        the protocol model, those within the detection range."""
        self._horizon = max(self._horizon, now)
        self._decide_locks(now)
        detected, self._detected = self._detected, []
        return detected

    def poll(self, now: float, detections: list[Detection] | None = None) -> list[Reception]:
        """Receptions delivered by `now` (no transmission may be registered before `now` later).
        `detections`: a list to append `detections(now)` to (one call for both)."""
        self._horizon = max(self._horizon, now)
        self._decide_locks(now)
        if detections is not None:
            detections += self._detected
        self._detected.clear()
        latency = self.config.decode_latency
        ends = self._ends
        due = []
        while ends and ends[0][0] + latency <= now:
            due.append(heapq.heappop(ends)[3])
        if not due:
            return []
        # finished before finishing (they interfere with each other), in arrival order
        due.sort(key=_arrival_order)
        for p in due:
            self._pending_at[p.receiver].remove(p)
            self._finished_at.setdefault(p.receiver, []).append(p)
        due.sort(key=lambda p: (p.interval.end, p.receiver, p.sequence))
        at_receiver: dict[int, list[_Pending]] = {}
        results = []
        for p in due:
            receptions = at_receiver.get(p.receiver)
            if receptions is None:
                receptions = at_receiver[p.receiver] = self._receptions_at(p.receiver)
            results.append(self._finish(p, receptions))
        self._prune(now)
        return results

    # -- internals -------------------------------------------------------------------------

    def _receptions_at(self, receiver: int) -> list[_Pending]:
        """Every finished and pending reception at a receiver, in that order (interference
        sums depend on it)."""
        return self._finished_at.get(receiver, []) + self._pending_at.get(receiver, [])

    def _noise_at(self, port: int) -> float:
        """noise_level of the node's band, by port (the configuration is frozen; a Band's
        hash is a Python call)."""
        noise = self._noise_by_port.get(port)
        if noise is None:
            noise = self._noise_by_port[port] = self.noise_level(self.config.band_of(port))
        return noise

    def _quiet_level(self, noise: float) -> float:
        """power_sum_db of the noise alone (what sinr subtracts without interferers), once per
        noise level."""
        level = self._quiet.get(noise)
        if level is None:
            level = self._quiet[noise] = power_sum_db((noise,))
        return level

    def _decide_locks(self, now: float) -> None:
        """Detection and receiver lock for every reception that has started by `now`, in
        arrival order (all earlier arrivals are known by then)."""
        config = self.config
        undecided = self._undecided
        at_receiver: dict[int, list[_Pending]] = {}  # (the lists do not change meanwhile)
        while undecided and undecided[0][0][0] <= now:
            p = heapq.heappop(undecided)[1]
            start = p.interval.start
            if config.protocol_model is not None:  # decided in _protocol_outcome
                p.detected = p.locked = True
                if p.range_m <= config.protocol_model.detection_range:
                    self._detected.append(Detection(p.receiver, p.transmission, p.sequence, start))
                continue
            receptions = at_receiver.get(p.receiver)
            if receptions is None:
                receptions = at_receiver[p.receiver] = self._receptions_at(p.receiver)
            others = [
                q.received_level
                for q in receptions
                if q is not p and q.interval.start <= start < q.interval.end
            ]
            noise = self._noise_at(p.receiver)
            if others:
                level = sinr(p.received_level, noise, others)
            else:
                level = p.received_level - self._quiet_level(noise)
            threshold = config.error_models.detection_threshold(p.transmission.rate)
            p.detected = level >= threshold or not config.receiver_lock
            if not config.receiver_lock:
                p.locked = True
                if p.detected:
                    self._detected.append(Detection(p.receiver, p.transmission, p.sequence, start))
                continue
            free = self._locked_until.get(p.receiver, -math.inf) <= start
            transmitting = False
            if config.half_duplex:
                for own in self._own_tx.get(p.receiver, ()):
                    if own.start <= start < own.end:
                        transmitting = True
                        break
            p.locked = p.detected and free and not transmitting
            if p.locked:
                self._locked_until[p.receiver] = p.interval.end
                self._detected.append(Detection(p.receiver, p.transmission, p.sequence, start))

    def _finish(self, p: _Pending, at_receiver: list[_Pending]) -> Reception:
        """`at_receiver`: every finished and pending reception at p's receiver."""
        config = self.config
        noise = self._noise_at(p.receiver)
        start, end = p.interval.start, p.interval.end
        interferers = [
            q.received_level
            for q in at_receiver
            if q is not p and start < q.interval.end and end > q.interval.start  # overlaps
        ]
        if interferers:
            level = sinr(p.received_level, noise, interferers)
        else:
            level = p.received_level - self._quiet_level(noise)
        frames_ok: tuple[bool, ...] = ()
        half_duplex = False
        if config.half_duplex:
            for own in self._own_tx.get(p.receiver, ()):
                if own.start < end and own.end > start:  # overlaps
                    half_duplex = True
                    break
        if half_duplex:
            outcome = Outcome.HALF_DUPLEX
        elif config.protocol_model is not None:
            outcome, frames_ok = self._protocol_outcome(
                p, config.protocol_model, self._random(p), collided=bool(interferers)
            )
        elif not p.detected:
            outcome = Outcome.NOT_DETECTED
        elif not p.locked:
            outcome = Outcome.RECEIVER_BUSY
        else:
            fer = config.error_models.frame_error(p.transmission.rate, level)
            frames = p.transmission.frames
            if fer >= 1.0:  # (random() < 1: every draw would fail)
                frames_ok = (False,) * frames
            elif fer <= 0.0:  # (every draw would succeed, but for one exactly 0.0: 2**-53)
                frames_ok = (True,) * frames
            else:
                draw = self._random(p).random
                frames_ok = tuple([draw() > fer for _ in range(frames)])
            outcome = Outcome.GOOD if all(frames_ok) else Outcome.BAD_FRAMES
        return Reception(
            receiver=p.receiver,
            transmission=p.transmission,
            sequence=p.sequence,
            arrival=start,
            end=end,
            deliver_at=end + config.decode_latency,
            owtt=p.owtt,
            range_m=p.range_m,
            received_level=p.received_level,
            noise_level=noise,
            sinr=level,
            closing_speed=p.closing_speed,
            outcome=outcome,
            frames_ok=frames_ok,
        )

    def _random(self, p: _Pending) -> random.Random:
        """The reception's own generator, random.Random(f"{seed}:{sequence}:{receiver}"),
        seeded only when a draw decides something: one generator object, reseeded the way
        Random.seed seeds it from a str (version 2: the text and its SHA-512 as one integer),
        without its Python wrapper and without allocating the state each time."""
        key = f"{self.seed}:{p.sequence}:{p.receiver}".encode()
        rng = self._rng
        _random.Random.seed(rng, int.from_bytes(key + hashlib.sha512(key).digest()))
        rng.gauss_next = None  # type: ignore[attr-defined]  # (Random's cached normal variate)
        return rng

    @staticmethod
    def _protocol_outcome(
        p: _Pending, model: ProtocolModel, rng: random.Random, collided: bool
    ) -> tuple[Outcome, tuple[bool, ...]]:
        if not (model.detected(p.range_m) and rng.random() < model.p_detection):
            return Outcome.NOT_DETECTED, ()
        decoded = (
            not collided
            and p.range_m <= model.communication_range
            and rng.random() < model.p_decoding
        )
        frames = p.transmission.frames
        return (
            (Outcome.GOOD, (True,) * frames) if decoded else (Outcome.BAD_FRAMES, (False,) * frames)
        )

    def _prune(self, now: float) -> None:
        """Forget receptions and own transmissions that can no longer overlap anything."""
        longest = self._longest_configured
        # Pruning later than possible changes nothing (what it would have dropped overlaps
        # nothing still to come), so prune about once per packet length, not at every poll.
        if now - self._pruned_at < longest:
            return
        self._pruned_at = now
        # a pending reception outlasts these only with its own (explicit) duration
        longest = max(
            [longest, *(d for *_, p in self._ends if (d := p.transmission.duration) is not None)]
        )
        horizon = now - self.config.decode_latency - longest
        for port, finished in self._finished_at.items():
            self._finished_at[port] = [p for p in finished if p.interval.end > horizon]
        for port, intervals in self._own_tx.items():
            self._own_tx[port] = [i for i in intervals if i.end > horizon]


def _slant_range_at(source: NavFix, receiver: NavFix, start: float, tau: float) -> float:
    """The slant range from `source` to where `receiver` is `tau` s after `start`."""
    return slant_range(source, receiver.at(start + tau))
