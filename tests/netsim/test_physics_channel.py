"""Micro-Modem emulators talking through the netsim physics (PhysicsChannel), in process, on a
virtual clock: delivery at the arrival time, true ranging, per-frame errors, collisions,
half-duplex, losses growing with range, seeded repeatability."""

from __future__ import annotations

import dataclasses
import datetime as dt

import pytest

from pygoby.acomms.drivers.micromodem.statistics import parse_cst
from pygoby.acomms.mmsim import MicroModemModel
from pygoby.acomms.mmsim.timing import DEFAULT_TIMING
from pygoby.netsim.channel import Channel, ChannelConfig, NavFix
from pygoby.netsim.channel.absorption import thorp
from pygoby.netsim.channel.geometry import WGS84
from pygoby.netsim.channel.levels import transmission_loss
from pygoby.netsim.report.eventlog import EventLogWriter, read_events
from pygoby.netsim.sim.physics_channel import PhysicsChannel
from pygoby.util.clock import VirtualClock
from pygoby.util.nmea import NMEASentence
from pygoby.util.timeline import Timeline

ORIGIN = (42.0, -70.0)
T0 = 1_700_000_000.0


def at(east_m: float, depth: float = 10.0, time: float = T0, **kw) -> NavFix:
    lon, lat, _ = WGS84.fwd(ORIGIN[1], ORIGIN[0], 90.0, east_m)
    return NavFix(lat, lon, depth, time=time, **kw)


class Net:
    """Emulators named by their modem port on one PhysicsChannel and one VirtualClock."""

    def __init__(self, east_m: dict[int, float], seed: int = 1, events=None, **config) -> None:
        self.clock = VirtualClock(T0)
        config.setdefault("position_staleness", 1e9)  # positions are set once, at T0
        self.physics = PhysicsChannel(
            Channel(ChannelConfig(**config), seed=seed), self.clock, on_event=events
        )
        self.timeline = Timeline(self.clock)
        self.modems: dict[int, MicroModemModel] = {}
        for i, (port, east) in enumerate(sorted(east_m.items()), 1):
            self.physics.channel.update_position(port, at(east))
            self.modems[i] = MicroModemModel(
                i, self.clock, self.physics, name=str(port), timeline=self.timeline
            )

    def say(self, modem_id: int, body: str) -> None:
        self.modems[modem_id].handle_line(NMEASentence.parse(body).message() + "\r\n")

    def send(self, src: int, dest: int, frames: list[bytes], rate: int = 1, ack: int = 0):
        self.say(src, f"$CCCYC,0,{src},{dest},{rate},{ack},{len(frames)}")
        for frame in frames:
            self.say(src, f"$CCTXD,{src},{dest},{ack},{frame.hex()}")

    def run_until(self, t: float) -> dict[int, list[NMEASentence]]:
        """Advance through every event up to t; the sentences each modem printed."""
        while True:
            times = [x for x in (self.physics.next_event_time(), self.timeline.next_time()) if x]
            if not times or min(times) > t:
                break
            self.clock.set(max(min(times), self.clock.now()))
            self.physics.do_work()
            self.timeline.run_due()
        self.clock.set(t)
        self.physics.do_work()
        self.timeline.run_due()
        return {
            i: [NMEASentence.parse(s.message()) for s in model.take_output()]
            for i, model in self.modems.items()
        }


def ids(sentences: list[NMEASentence], token: str) -> list[NMEASentence]:
    return [s for s in sentences if s.talker_id + s.sentence_id == token]


def test_data_arrives_at_end_of_reception_with_physics_stats_and_ack():
    net = Net({62000: 0.0, 62001: 1500.0})
    net.send(1, 2, [b"hello", b"world"], ack=1)
    air = DEFAULT_TIMING.data(1, 2)  # two rate-1 frames
    # it leaves once the host's sentences have crossed the 19200-baud serial line
    sent = [
        "$CCCYC,0,1,2,1,1,2",
        "$CADRQ,221320,1,2,1,64,1",
        "$CCTXD,1,2,1,68656c6c6f",
        "$CADRQ,221320,1,2,1,64,2",
        "$CCTXD,1,2,1,776f726c64",
    ]
    start = T0 + sum((len(body) + 5) * 10 / 19200 for body in sent)
    assert ids(net.run_until(start + 1.001)[2], "CARXP")  # the start arrives after 1 s
    assert net.run_until(start + 1.0 + air - 0.001)[2] == []
    out = net.run_until(start + 1.0 + air + 0.001)
    rxd = ids(out[2], "CARXD")
    assert [bytes.fromhex(s[5]) for s in rxd] == [b"hello", b"world"]
    (cst,) = ids(out[2], "CACST")
    stat = parse_cst(cst, dt.date(2023, 11, 14), new_clock_bitfield=True)
    # SNR from the physics (185 dB source, 1.5 km), not the emulator's constant 15 dB
    assert stat.snr_in == 30  # clamped at its 30 dB maximum
    assert stat.spl == round(185 - transmission_loss(1500, thorp(25), 1.5))
    assert stat.time == pytest.approx((start + 1.0) * 1e6, abs=100)  # true time of arrival
    # the ACK (a 1 s mini-packet) leaves when the data has been heard, is heard 2 s later
    assert ids(net.run_until(start + 3.0 + air - 0.001)[1], "CAACK") == []
    acks = ids(net.run_until(start + 3.0 + air + 0.001)[1], "CAACK")
    assert [(s[1], s[2], s[3]) for s in acks] == [("2", "1", "1"), ("2", "1", "2")]


def test_ping_reply_reports_true_travel_time():
    net = Net({62000: 0.0, 62001: 2345.6}, sound_speed=1490.0)
    net.say(1, "$CCMPC,1,2")
    out = net.run_until(T0 + 10)
    assert ids(out[2], "CAMPA")
    (mpr,) = ids(out[1], "CAMPR")
    assert (mpr[1], mpr[2]) == ("2", "1")
    assert float(mpr[3]) == pytest.approx(2345.6 / 1490, abs=1e-4)


def test_ping_to_moving_vehicle_averages_both_legs():
    net = Net({62000: 0.0, 62001: 3000.0}, sound_speed=1500.0)
    # node 2 drives away from node 1 at 3 m/s: the reply leg is longer than the ping leg
    net.physics.channel.update_position(62001, at(3000.0, speed=3.0, heading=90.0))
    net.say(1, "$CCMPC,1,2")
    (mpr,) = ids(net.run_until(T0 + 10)[1], "CAMPR")
    first = 3000 / 1497  # receiver opening at 3 m/s
    # the ping is 0.5 s on air; the reply leaves 50 ms (NVRAM TAT) after it has been heard
    reply_start = T0 + first + 0.5 + 0.05
    second = (3000 + 3 * (reply_start - T0)) / 1500
    assert float(mpr[3]) == pytest.approx((first + second) / 2, abs=2e-4)
    assert float(mpr[3]) > 3000 / 1500


def test_three_modems_collision_receiver_locks_on_first_arrival():
    net = Net({62000: 0.0, 62001: 1000.0, 62002: 2600.0})
    net.send(1, 2, [b"from-1"])  # heard by 2 from T0 + 0.667
    net.send(3, 2, [b"from-3"])  # arrives at T0 + 1.067, while 2 is locked
    out = net.run_until(T0 + 10)
    assert [bytes.fromhex(s[5]) for s in ids(out[2], "CARXD")] == [b"from-1"]


def test_half_duplex_transmitting_modem_misses_reception():
    events = []
    net = Net({62000: 0.0, 62001: 1500.0}, events=events.append)
    net.send(1, 2, [b"lost", b"2", b"3"])  # 3.25 s on the water
    net.clock.set(T0 + 2.0)  # node 2 starts transmitting while node 1's packet arrives
    net.send(2, 1, [b"also lost", b"2", b"3"])
    out = net.run_until(T0 + 20)
    assert ids(out[1], "CARXD") == [] and ids(out[2], "CARXD") == []
    outcomes = [e["outcome"] for e in events if e["event"] == "rx"]
    assert outcomes == ["half_duplex", "half_duplex"]


def test_bad_frames_reported_as_bad_crc():
    # a noisy channel where rate-1 frames fail about half the time
    net = Net({62000: 0.0, 62001: 4500.0}, seed=3, noise_level=110.0)
    bad = good = 0
    for k in range(20):
        net.send(1, 2, [b"a", b"b", b"c"])
        out = net.run_until(T0 + 10 * (k + 1))
        bad += len([s for s in ids(out[2], "CAMSG") if s[1] == "BAD_CRC"])
        good += len(ids(out[2], "CARXD"))
    assert bad > 0 and good > 0


def success_fraction(distance: float, trials: int = 40) -> float:
    net = Net({62000: 0.0, 62001: distance}, seed=7, noise_level=110.0)
    heard = 0
    for k in range(trials):
        net.send(1, 2, [b"x"])
        heard += len(ids(net.run_until(T0 + 10 * (k + 1))[2], "CARXD"))
    return heard / trials


def test_losses_grow_with_range():
    fractions = [success_fraction(d) for d in (3000, 4300, 4450, 4600, 5500)]
    assert fractions[0] == 1.0 and fractions[-1] == 0.0
    assert fractions == sorted(fractions, reverse=True)
    assert any(0 < f < 1 for f in fractions)


def exchange_log(tmp_path, seed: int) -> list[dict]:
    path = tmp_path / f"events-{seed}.jsonl"
    with EventLogWriter(path) as log:
        net = Net(
            {62000: 0.0, 62001: 4450.0, 62002: 2000.0}, seed=seed, events=log, noise_level=110.0
        )
        for k in range(15):
            net.send(1 + k % 3, 1 + (k + 1) % 3, [b"p", b"q", b"r"], ack=1)
            net.run_until(T0 + 12 * (k + 1))
    return read_events(path)


def test_identical_seeds_give_identical_runs(tmp_path):
    first, again = exchange_log(tmp_path, 11), exchange_log(tmp_path, 11)
    assert first == again and len(first) > 30
    other = exchange_log(tmp_path, 12)
    frames = lambda log: [e["good_frames"] for e in log if e["event"] == "rx"]  # noqa: E731
    assert frames(first) != frames(other)


def test_modem_without_port_is_refused():
    physics = PhysicsChannel(Channel(), VirtualClock(T0))
    with pytest.raises(ValueError, match="no modem port"):
        MicroModemModel(1, VirtualClock(T0), physics, name="alpha")
    model = MicroModemModel(
        1,
        VirtualClock(T0),
        PhysicsChannel(Channel(), VirtualClock(T0), ports={"alpha": 62005}),
        name="alpha",
    )
    assert model.channel.port_of(model) == 62005


def test_rx_event_figures_are_rounded():
    """Every rx event carries the reception's figures rounded, a zero and the sign of a
    negative zero included (links recur: the same figures each time)."""

    # (range, owtt, received level, noise, sinr) -> (range, owtt, rl, snr, sinr, collision)
    figures = {
        (1234.56789, 0.8230452, 120.4449, 62.3, 58.1449): (
            1234.568,
            0.823045,
            120.44,
            58.14,
            58.14,
            False,
        ),
        # a collision: the sinr is below the snr
        (1234.56789, 0.8230452, 120.4449, 62.3, 50.0): (
            1234.568,
            0.823045,
            120.44,
            58.14,
            50.0,
            True,
        ),
        # a zero: not remembered
        (0.0, 0.0, 185.0, 62.3, -0.004): (0.0, 0.0, 185.0, 122.7, -0.0, True),
        # -0.0 keeps its sign
        (10.0, 0.0066, 62.3, 62.3, -0.0): (10.0, 0.0066, 62.3, 0.0, -0.0, False),
    }
    cases = list(figures) * 2
    events: list[dict] = []
    net = Net({62000: 0.0, 62001: 1500.0}, events=events.append)
    # the physics' receptions, with the levels of the cases in turn
    physics_poll, scripted = net.physics.channel.poll, iter(cases)

    def poll(now):
        return [
            dataclasses.replace(
                r, range_m=rng, owtt=owtt, received_level=rl, noise_level=noise, sinr=sinr
            )
            for r in physics_poll(now)
            for rng, owtt, rl, noise, sinr in [next(scripted)]
        ]

    net.physics.channel.poll = poll
    for i in range(len(cases)):
        net.send(1, 2, [b"x"])
        net.run_until(T0 + 10 * (i + 1))
    rx = [e for e in events if e["event"] == "rx"]
    assert len(rx) == len(cases)
    for event, case in zip(rx, cases, strict=True):
        got = tuple(event[key] for key in ("range_m", "owtt", "rl", "snr", "sinr", "collision"))
        assert got == figures[case]
        assert [str(x) for x in got] == [str(x) for x in figures[case]]


def test_a_cycle_init_run_late_still_precedes_its_data():
    """Real time: the emulator's cycle-init went on the water late (after the channel's last
    poll, so the channel moved its start), its data on time. One transducer: the data starts
    when the cycle-init has ended, and the receiver hears both (regression: the late cycle-init
    overlapped its own data, a collision at a receiver 370 m away in the demo)."""
    from pygoby.acomms.mmsim.channel import AcousticPacket, ModemPacketKind

    events = []
    net = Net({62000: 0.0, 62001: 370.0}, events=events.append)
    sender = net.modems[1]
    net.clock.set(T0 + 0.004)
    net.physics.do_work()  # polled past the cycle-init's start
    cycle = AcousticPacket(ModemPacketKind.CYCLE, 1, 0, 0, num_frames=1, tx_time=T0, duration=1.0)
    data = AcousticPacket(
        ModemPacketKind.DATA, 1, 0, 0, frames=[b"status"], tx_time=T0 + 1.0, duration=3.2
    )
    net.physics.transmit(sender, cycle)
    net.clock.set(T0 + 1.0)
    net.physics.transmit(sender, data)
    net.run_until(T0 + 10)
    tx = [e for e in events if e["event"] == "tx"]
    assert tx[1]["t"] >= tx[0]["t"] + 1.0
    assert [(e["kind"], e["outcome"]) for e in events if e["event"] == "rx"] == [
        ("cycle", "good"),
        ("data", "good"),
    ]
