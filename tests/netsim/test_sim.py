"""The discrete-event simulation: real drivers, MAC and queues over emulators and physics on one
virtual clock (status traffic, ranging, moving tracks, collisions, seeded repeatability)."""

from __future__ import annotations

import pytest

from pygoby.netsim.report.eventlog import EventLogWriter, read_events
from pygoby.netsim.report.plots import summary_lines
from pygoby.netsim.sim.scenario import ScenarioError, parse_scenario
from pygoby.netsim.sim.simulation import Simulation

ORIGIN = "origin { lat: 42 lon: -70 }"


def fixed(modem_id: int, x: float, y: float = 0.0, depth: float = 10.0) -> str:
    return (
        f"node {{ modem_id: {modem_id} track {{ waypoint {{ x: {x} y: {y} depth: {depth} }} }} }}"
    )


def run(text: str, tmp_path=None) -> tuple[Simulation, list[dict]]:
    events: list[dict] = []
    sim = Simulation(parse_scenario(text), on_event=events.append)
    sim.run_virtual()
    return sim, events


def test_three_nodes_exchange_status_in_tdma():
    sim, events = run(
        f"""duration: 600 {ORIGIN} mac {{ slot_seconds: 10 rate: 1 }}
        {fixed(1, 0)} {fixed(2, 1500)} {fixed(3, 0, 3000)}"""
    )
    txs = [e for e in events if e["event"] == "tx"]
    # one status packet per node per 30 s cycle, in the node's own slot (cycles start at
    # midnight UTC)
    assert 57 <= len(txs) <= 60
    for e in txs:
        slot_number = int((e["t"] % 86400) // 10)
        assert e["src"] == 1 + slot_number % 3
    rx = [e for e in events if e["event"] == "rx"]
    assert rx and all(e["outcome"] == "good" for e in rx)
    one_two = [e for e in rx if {e["src"], e["port"]} == {1, 62001}]
    assert one_two and all(e["owtt"] == pytest.approx(1.0, abs=1e-4) for e in one_two)
    # every node hears the others' status through driver, queue and DCCL
    for node in sim.nodes:
        others = {n.modem_id for n in sim.nodes} - {node.modem_id}
        assert set(node.received) == others
        assert min(node.received.values()) >= 18
    summary = sim.summary()
    assert summary.status_received == sum(1 for e in events if e["event"] == "app_rx")
    assert summary.simulated_seconds == pytest.approx(600)


def test_two_way_ping_slot_reports_true_range():
    _sim, events = run(
        f"""duration: 60 {ORIGIN} channel {{ sound_speed: 1490 }}
        mac {{ slot {{ src: 1 dest: 2 type: DRIVER_SPECIFIC slot_seconds: 10
                       [goby.acomms.micromodem.protobuf.transmission] {{ type: MICROMODEM_TWO_WAY_PING }} }} }}
        {fixed(1, 0)} {fixed(2, 2345.6)}"""
    )
    ranges = [e for e in events if e["event"] == "range"]
    assert len(ranges) >= 5
    for e in ranges:
        assert (e["port"], e["src"], e["dest"]) == (62000, 2, 1)
        assert e["owtt"] == [pytest.approx(2345.6 / 1490, abs=1e-4)]


def test_moving_vehicle_range_follows_its_track():
    sim, events = run(
        f"""duration: 1200 {ORIGIN} mac {{ slot_seconds: 10 }}
        {fixed(1, 0)}
        node {{ modem_id: 2 track {{ waypoint {{ t: 0 x: 500 depth: 5 }}
                                     waypoint {{ t: 1000 x: 2500 depth: 5 }} }} }}"""
    )
    heard_by_1 = [e for e in events if e["event"] == "rx" and e["port"] == 62000]
    assert heard_by_1
    for e in heard_by_1:
        elapsed = min(e["tx_t"] - sim.start, 1000)
        expected = 500 + 2 * elapsed  # 2 m/s east, then holding at 2500 m
        assert e["range_m"] == pytest.approx(expected, abs=8)  # + depth, travel-time motion


def test_overlapping_slots_collide():
    # slots shorter than a packet: transmissions overlap at the receivers
    _sim, events = run(
        f"""duration: 300 {ORIGIN} mac {{ slot_seconds: 1.5 rate: 1 }}
        {fixed(1, 0)} {fixed(2, 1000)} {fixed(3, 2000)}"""
    )
    outcomes = {e["outcome"] for e in events if e["event"] == "rx"}
    assert {"half_duplex", "receiver_busy"} & outcomes
    assert any(e["collision"] for e in events if e["event"] == "rx")
    assert any(line.startswith("collisions: ") for line in summary_lines(events))


MARGINAL = f"""duration: 900 {ORIGIN} channel {{ noise_level: 110 }} mac {{ slot_seconds: 8 rate: 1 }}
{fixed(1, 0)} {fixed(2, 4450)} {fixed(3, 2200, 1500)}"""


def logged(tmp_path, text: str, name: str) -> list[dict]:
    path = tmp_path / name
    with EventLogWriter(path) as writer:
        Simulation(parse_scenario(text), on_event=writer).run_virtual()
    return read_events(path)


def test_positions_set_directly_are_what_the_manager_forwards(caplog):
    """Discrete-event runs put the scripted positions straight into the channel; real-time runs
    post them to the manager, which forwards them. Same positions, same refusals (the manager
    stops at a node outside its region: deeper than 12000 m)."""
    text = f"""duration: 60 {ORIGIN} {fixed(1, 0)}
        node {{ modem_id: 2 track {{ waypoint {{ t: 0 x: 500 depth: 5 }}
                                     waypoint {{ t: 100 x: 900 y: 70 depth: 25 }} }} }}
        {fixed(3, 0, 300, depth=12500)} {fixed(4, 800)}"""
    direct, posted = Simulation(parse_scenario(text)), Simulation(parse_scenario(text))
    for sim in (direct, posted):
        sim.clock.advance(42.5)
    with caplog.at_level("WARNING"):
        direct.set_positions()
        posted.post_positions()
    assert caplog.text.count("scripted positions refused") == 2
    ports = [n.port for n in direct.nodes]
    assert [direct.channel.position(p) for p in ports] == [
        posted.channel.position(p) for p in ports
    ]
    assert direct.channel.position(ports[1]).speed > 0
    assert direct.channel.position(ports[2]) is None and direct.channel.position(ports[3]) is None


def test_same_seed_same_run_other_seed_other_run(tmp_path):
    first = logged(tmp_path, "seed: 5 " + MARGINAL, "a.jsonl")
    again = logged(tmp_path, "seed: 5 " + MARGINAL, "b.jsonl")
    other = logged(tmp_path, "seed: 6 " + MARGINAL, "c.jsonl")
    assert first == again
    outcomes = lambda log: [(e["t"], e["good_frames"]) for e in log if e["event"] == "rx"]  # noqa: E731
    assert outcomes(first) != outcomes(other)
    assert {"good", "bad_frames"} <= {e["outcome"] for e in first if e["event"] == "rx"}


@pytest.mark.parametrize(
    "text, reason",
    [
        ("", "at least one node"),
        (f"{ORIGIN} {fixed(1, 0)} {fixed(1, 10)}", "duplicate modem_id"),
        (f'speed: "fast" {fixed(1, 0)}', "speed"),
        ("node { modem_id: 1 }", "needs a track"),
        ("node { modem_id: 1 track { waypoint { x: 1 } } }", "origin"),
        (
            "node { modem_id: 1 track { waypoint { lat: 1 lon: 2 t: 5 } waypoint { lat: 1 lon: 2 t: 5 } } }",
            "increase",
        ),
        ("nodes { }", 'line 1: .*no field named "nodes"'),
    ],
)
def test_bad_scenarios_are_refused_with_the_reason(text, reason):
    with pytest.raises(ScenarioError, match=reason):
        parse_scenario(text)


def test_scenario_modem_timing_sets_the_emulators_durations():
    text = f"""duration: 120 {ORIGIN} mac {{ slot_seconds: 10 rate: 1 }}
        modem_timing {{ rate {{ rate: 1 lead: 2.0 per_frame: 0 }} mini_packet: 0.8 }}
        {fixed(1, 0)} {fixed(2, 1500)}"""
    _sim, events = run(text)
    data = [e for e in events if e["event"] == "tx" and e["kind"] == "data"]
    assert data and {e["duration"] for e in data} == {2.0}
    for bad in ("rate { rate: 9 lead: 1 }", "rate { rate: 1 lead: 0 per_frame: 0 }", "ping: -1"):
        with pytest.raises(ScenarioError, match="modem_timing"):
            parse_scenario(f"modem_timing {{ {bad} }} {fixed(1, 0)} {ORIGIN}")
