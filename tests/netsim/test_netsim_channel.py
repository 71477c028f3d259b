"""The sans-I/O Channel: delays, levels, detection, interference, half-duplex, lock, bands,
staleness, determinism, and feeding it from a NetSimManager."""

from __future__ import annotations

import dataclasses

import pytest
from netsim_vectors import of_kind

from pygoby.netsim.channel import (
    Band,
    Channel,
    ChannelConfig,
    LogisticModel,
    NavFix,
    Outcome,
    PacketKind,
    RateErrorModels,
    Transmission,
)
from pygoby.netsim.channel.absorption import thorp
from pygoby.netsim.channel.geometry import WGS84
from pygoby.netsim.channel.levels import noise_level_integrated, transmission_loss
from pygoby.netsim.manager.config import parse_config
from pygoby.netsim.manager.core import NetSimManager
from pygoby.netsim.manager.protocol import encode_line, message_class, request_class

ORIGIN = (42.0, -70.0)
T0 = 1_700_000_000.0


def at(east_m: float, north_m: float = 0.0, depth: float = 10.0, **kw) -> NavFix:
    lon, lat, _ = WGS84.fwd(ORIGIN[1], ORIGIN[0], 90.0, east_m)
    lon, lat, _ = WGS84.fwd(lon, lat, 0.0, north_m)
    return NavFix(lat, lon, depth, time=kw.pop("time", T0), **kw)


def channel(nodes: dict[int, NavFix], seed: int = 1, **config) -> Channel:
    ch = Channel(ChannelConfig(**config), seed=seed)
    for port, position in nodes.items():
        ch.update_position(port, position)
    return ch


def test_single_packet_delay_level_and_sinr():
    ch = channel({62000: at(0), 62001: at(1500)})
    planned = ch.transmit(Transmission(62000, T0 + 10, rate=1, frames=3))
    ((port, arrival),) = planned
    assert port == 62001
    assert arrival == pytest.approx(T0 + 11.0, abs=1e-6)  # 1500 m at 1500 m/s
    assert ch.next_delivery() == pytest.approx(T0 + 14.25, abs=1e-6)
    assert ch.poll(T0 + 14.2) == []
    (rx,) = ch.poll(T0 + 14.3)
    assert rx.receiver == 62001 and rx.outcome is Outcome.GOOD
    assert rx.frames_ok == (True, True, True) and rx.good_frames == 3
    assert rx.owtt == pytest.approx(1.0, abs=1e-6)
    assert (rx.arrival, rx.end) == pytest.approx((T0 + 11.0, T0 + 14.25), abs=1e-6)
    expected_rl = 185 - transmission_loss(1500, thorp(25), 1.5)
    assert rx.received_level == pytest.approx(expected_rl, abs=1e-4)
    assert rx.noise_level == pytest.approx(noise_level_integrated(25, 5000, 0.5, 5), abs=1e-9)
    assert rx.sinr == pytest.approx(expected_rl - rx.noise_level, abs=1e-9)
    assert ch.poll(T0 + 100) == []


def test_sound_speed_profile_and_fixed_noise():
    ch = channel(
        {1: at(0, depth=0), 2: at(0, depth=1000)},
        sound_speed=lambda z: 1500 + 0.017 * z,
        noise_level=60.0,
    )
    ch.transmit(Transmission(1, T0, kind=PacketKind.PING))
    (rx,) = ch.poll(T0 + 10)
    assert rx.end - rx.arrival == 0.5
    assert rx.noise_level == 60.0
    assert 1000 / 1517 < rx.owtt < 1000 / 1500


def test_moving_receiver_arrives_later_when_opening():
    still = channel({1: at(0), 2: at(3000)}, moving_receivers=True)
    away = channel({1: at(0), 2: at(3000, speed=2.0, heading=90.0)}, moving_receivers=True)
    frozen = channel({1: at(0), 2: at(3000, speed=2.0, heading=90.0)}, moving_receivers=False)
    (a,), (b,), (c,) = (ch.transmit(Transmission(1, T0)) for ch in (still, away, frozen))
    assert a[1] - T0 == pytest.approx(2.0, abs=1e-6)
    assert b[1] - T0 == pytest.approx(3000 / 1498, abs=1e-5)
    assert c[1] == a[1]
    (rx,) = away.poll(T0 + 10)
    assert rx.closing_speed == pytest.approx(-2.0, abs=1e-3)


def test_far_receiver_does_not_detect():
    ch = channel({1: at(0), 2: at(60000)}, spreading=2.0)
    ch.transmit(Transmission(1, T0, rate=5))
    (rx,) = ch.poll(T0 + 100)
    assert rx.outcome is Outcome.NOT_DETECTED and rx.frames_ok == ()


def test_half_duplex_loses_reception_overlapping_own_transmission():
    ch = channel({1: at(0), 2: at(1500)})
    ch.transmit(Transmission(1, T0))  # reaches 2 over [T0+1, T0+4.25]
    ch.transmit(Transmission(2, T0 + 3.0))  # 2 transmits during it
    results = ch.poll(T0 + 20)
    by_receiver = {r.receiver: r for r in results}
    assert by_receiver[2].outcome is Outcome.HALF_DUPLEX
    # 1 hears 2's packet over [T0+4, T0+7.25], after its own [T0, T0+3.25]: kept
    assert by_receiver[1].outcome is Outcome.GOOD


def test_half_duplex_can_be_switched_off():
    ch = channel({1: at(0), 2: at(1500)}, half_duplex=False)
    ch.transmit(Transmission(1, T0))
    ch.transmit(Transmission(2, T0 + 3.0))
    assert {r.receiver: r.outcome for r in ch.poll(T0 + 20)} == {2: Outcome.GOOD, 1: Outcome.GOOD}


def test_collision_first_arrival_locks_and_interference_breaks_it():
    # Receiver 3 between 1 (1500 m) and 2 (1000 m, so louder); 2 starts 0.5 s after 1.
    ch = channel({1: at(-1500), 2: at(1000), 3: at(0)})
    ch.transmit(Transmission(1, T0, rate=5, frames=8))
    ch.transmit(Transmission(2, T0 + 0.5, rate=5, frames=8))
    at3 = {r.transmission.source: r for r in ch.poll(T0 + 20) if r.receiver == 3}
    # 1 arrived first and locked the receiver, but 2 drowns it: rate 5 fails every frame.
    assert at3[1].sinr < 0
    assert at3[1].outcome is Outcome.BAD_FRAMES
    assert at3[1].bad_frames == 8 and at3[1].good_frames == 0
    # 2 was detectable (louder than 1) but the receiver was busy with 1.
    assert at3[2].sinr > 3.1
    assert at3[2].outcome is Outcome.RECEIVER_BUSY


def test_equal_power_packet_arriving_during_another_is_not_detected():
    ch = channel({1: at(-1500), 2: at(1500), 3: at(0)})
    ch.transmit(Transmission(1, T0, rate=5))
    ch.transmit(Transmission(2, T0 + 0.5, rate=5))
    at3 = {r.transmission.source: r for r in ch.poll(T0 + 20) if r.receiver == 3}
    assert at3[1].sinr == pytest.approx(0.0, abs=0.01)
    assert at3[2].outcome is Outcome.NOT_DETECTED


def test_receiver_free_again_after_locked_packet_ends():
    ch = channel({1: at(-1500), 2: at(1500), 3: at(0)})
    ch.transmit(Transmission(1, T0, rate=5))
    ch.transmit(Transmission(2, T0 + 3.25, rate=5))  # arrives exactly when the first ends
    at3 = [r.outcome for r in ch.poll(T0 + 20) if r.receiver == 3]
    assert at3 == [Outcome.GOOD, Outcome.GOOD]


def test_other_band_is_invisible():
    ch = channel({1: at(0), 2: at(1000), 3: at(2000)}, node_bands={3: Band(10000, 5000)})
    assert [port for port, _ in ch.transmit(Transmission(1, T0))] == [2]


def test_stale_and_unknown_positions_are_absent():
    ch = channel({1: at(0), 2: at(1000, time=T0 - 61)})
    assert ch.transmit(Transmission(1, T0)) == []
    assert ch.transmit(Transmission(99, T0 + 1)) == []


def test_a_stale_position_is_logged_once_per_position(caplog):
    ch = channel({1: at(0), 2: at(1000, time=T0 - 61)})
    with caplog.at_level("WARNING", logger="pygoby.netsim.channel.model"):
        ch.transmit(Transmission(1, T0))
        ch.transmit(Transmission(1, T0 + 10))
        assert [r.getMessage()[:29] for r in caplog.records] == ["node 2 is absent from the cha"]
        ch.update_position(2, at(1000, time=T0 - 61 + 1))  # a newer, still stale position
        ch.transmit(Transmission(1, T0 + 20))
        ch.update_position(2, at(1000, time=T0 + 25))  # fresh again: heard, nothing logged
        assert [port for port, _ in ch.transmit(Transmission(1, T0 + 30))] == [2]
    assert (
        len(caplog.records) == 2 and "position_staleness = 60 s" in caplog.records[1].getMessage()
    )


def test_transmission_in_the_past_of_a_poll_is_refused():
    ch = channel({1: at(0), 2: at(1000)})
    ch.poll(T0 + 5)
    with pytest.raises(ValueError, match="past"):
        ch.transmit(Transmission(1, T0 + 4))


def _noisy_run(seed: int, poll_step: float | None) -> list:
    # FER 0.5 per frame at the link's SINR, so outcomes depend on the draws.
    probe = channel({1: at(0), 2: at(2000), 3: at(2500, 500)})
    probe.transmit(Transmission(1, T0))
    sinr = probe.poll(T0 + 10)[0].sinr
    models = RateErrorModels(by_rate={1: LogisticModel(sinr, 2.0)})
    ch = channel({1: at(0), 2: at(2000), 3: at(2500, 500)}, seed=seed, error_models=models)
    results = []
    t = T0
    for k in range(20):
        start = T0 + 10 * k
        if poll_step is not None:
            while t < start:
                results += ch.poll(t)
                t += poll_step
        ch.transmit(Transmission(1 + k % 2, start, rate=1, frames=8))
    results += ch.poll(T0 + 1000)
    return [(r.sequence, r.receiver, r.outcome, r.frames_ok) for r in results]


def test_seeded_runs_repeat_exactly_whatever_the_poll_pattern():
    once = _noisy_run(seed=5, poll_step=None)
    often = _noisy_run(seed=5, poll_step=0.7)
    assert once == often
    assert any(outcome is Outcome.BAD_FRAMES for _, _, outcome, _ in once)
    assert any(outcome is Outcome.GOOD for _, _, outcome, _ in once)
    assert _noisy_run(seed=6, poll_step=None) != once


def test_frame_draws_come_from_the_documented_generator():
    """Each reception draws from random.Random("seed:sequence:receiver") (one shared generator,
    reseeded, must give the same stream), and next_delivery follows the pending receptions."""
    import random

    ch = channel({1: at(0), 2: at(3900), 3: at(0, 3950), 4: at(2000, 2000)}, seed=9)
    config = ch.config
    pending_ends = []
    for k in range(24):
        start = T0 + 2.1 * k
        planned = ch.transmit(Transmission(1 + k % 4, start, rate=1, frames=3))
        pending_ends += [arrival + 3.25 for _, arrival in planned]
        assert ch.next_delivery() == pytest.approx(min(pending_ends), abs=1e-9)
        polled = ch.poll(start)
        assert len(polled) == sum(end <= start for end in pending_ends)
        pending_ends = [end for end in pending_ends if end > start]
        for r in polled:
            if r.outcome in (Outcome.GOOD, Outcome.BAD_FRAMES):
                fer = config.error_models.frame_error(r.transmission.rate, r.sinr)
                rng = random.Random(f"9:{r.sequence}:{r.receiver}")
                assert r.frames_ok == tuple(rng.random() > fer for _ in range(3))
    assert ch.poll(T0 + 100)
    assert ch.next_delivery() is None


def test_decode_latency_delays_delivery():
    ch = channel({1: at(0), 2: at(1500)}, decode_latency=0.5)
    ch.transmit(Transmission(1, T0))
    assert ch.poll(T0 + 4.3) == []
    (rx,) = ch.poll(T0 + 4.8)
    assert rx.deliver_at == pytest.approx(T0 + 4.75, abs=1e-6)


def test_channel_follows_manager_positions():
    config_text = {v["name"]: v["textformat"] for v in of_kind("manager_config")}["loopback"]
    manager = NetSimManager(parse_config(config_text))
    ch = Channel(ChannelConfig(), seed=0)
    manager.on_nav(ch.on_environment_nav_update)
    connection = manager.connection("127.0.0.1")
    request = request_class()(id=1)
    for port, position in ((62000, at(0)), (62001, at(2000))):
        fields = dataclasses.asdict(position)
        request.nav.append(message_class("NavUpdate")(modem_tcp_port=port, **fields))
    connection.receive(encode_line(request))
    ((port, arrival),) = ch.transmit(Transmission(62000, T0 + 1))
    assert port == 62001 and arrival - (T0 + 1) == pytest.approx(2000 / 1500, abs=1e-6)


def test_synthesized_receive_statistics():
    from pygoby.netsim.channel.stats import link_statistics, receive_statistics

    ch = channel({1: at(-1500), 2: at(1000), 3: at(0, speed=2.0, heading=270.0)})
    ch.transmit(Transmission(1, T0, rate=5, frames=8))
    ch.transmit(Transmission(2, T0 + 0.5, rate=5, frames=8))
    at3 = {r.transmission.source: r for r in ch.poll(T0 + 20) if r.receiver == 3}
    stats = receive_statistics(at3[1], source_id=1, dest_id=3)
    assert stats.IsInitialized()
    assert (stats.mode, stats.psk_error_code) == (1, 3)  # BAD_CRC, BAD_CRC_AT_LEAST_ONE_FRAME
    assert (stats.number_frames, stats.number_bad_frames, stats.rate) == (8, 8, 5)
    assert stats.snr_in == max(-10, round(at3[1].sinr))
    assert stats.time == round(at3[1].arrival * 1e6)
    assert stats.doppler == pytest.approx(2.0, abs=0.05)  # receiver heading west towards 1
    assert stats.packet_type == 3  # PSK
    assert receive_statistics(at3[2], source_id=2, dest_id=3) is None  # receiver was busy
    link = link_statistics(at3[1])  # what the emulators take from the physics
    assert link == {name: getattr(stats, name) for name in link}
    assert {"snr_in", "doppler", "spl", "carrier_freq"} <= set(link)
    assert link_statistics(at3[2]) is None
    # It fits a ReceiveStats push to the manager.
    push = message_class("ReceiveStats")(
        modem_tcp_port=3, tx_modem_tcp_port=1, packet_success=False, mm_stats=stats
    )
    assert push.IsInitialized()


def test_link_statistics_of_recurring_levels_are_computed_the_same():
    """The integer fields of a link's levels are remembered; the Doppler (which keeps the sign
    of a zero) is not: each reception of the link gets its own."""
    from pygoby.netsim.channel import stats

    ch = channel({1: at(0), 2: at(1000)})
    ch.transmit(Transmission(1, T0))
    (reception,) = ch.poll(T0 + 20)
    first = stats.link_statistics(reception)
    for closing in (0.0, -0.0, -0.04, 1.26, 7.0):
        moving = dataclasses.replace(reception, closing_speed=closing)
        again = stats.link_statistics(moving)
        doppler = min(max(round(closing, 1), -3.0), 3.0)
        assert again == {**first, "doppler": doppler}
        assert list(again) == list(first)  # $CACST order
        assert str(again["doppler"]) == str(doppler)  # -0.0 stays -0.0
    again["snr_in"] = 99  # the caller's own dict
    assert stats.link_statistics(reception) == first


def test_protocol_model_ranges_and_collisions():
    from pygoby.netsim.channel.frame_errors import ProtocolModel

    nodes = {1: at(0), 2: at(1999), 3: at(-2200), 4: at(2800, 100), 5: at(-3100)}
    ch = channel(nodes, protocol_model=ProtocolModel())
    assert sorted(port for port, _ in ch.transmit(Transmission(1, T0, frames=2))) == [2, 3, 4]
    outcomes = {r.receiver: (r.outcome, r.frames_ok) for r in ch.poll(T0 + 20)}
    assert outcomes == {
        2: (Outcome.GOOD, (True, True)),
        3: (Outcome.BAD_FRAMES, (False, False)),  # detected, beyond communication range
        4: (Outcome.NOT_DETECTED, ()),  # only interferes
    }
    # 4 (800 m from 2) transmits while 1's packet reaches 2: the overlap destroys both at 2.
    ch.transmit(Transmission(1, T0 + 30))
    ch.transmit(Transmission(4, T0 + 30.5))
    at2 = [r.outcome for r in ch.poll(T0 + 50) if r.receiver == 2]
    assert at2 == [Outcome.BAD_FRAMES, Outcome.BAD_FRAMES]
