"""Simulated time / wall time of the discrete-event netsim simulation (`make bench`).

Every node runs the real stack in process — Micro-Modem emulator on the netsim physics,
Micro-Modem driver, TDMA MAC (goby's default 15 s slots), queue with a DCCL status message —
on one virtual clock. Targets: >= 10,000x real time for 8 nodes over a simulated day, >= 1,000x
for 100 nodes (issue 17; issue 6 asked 5,000x and 100x). The measured ratio is printed and
stored in the benchmark's extra_info. A rate-0 slot is two packets on the water (the FSK
cycle-init, then the data), so `tx` counts twice the slots and `tx_data` the data packets.
"""

from __future__ import annotations

import pytest

from pygoby.netsim.sim.scenario import parse_scenario
from pygoby.netsim.sim.simulation import Simulation


def tdma_scenario(nodes: int, duration: float, spacing: float, columns: int) -> str:
    lines = [f"duration: {duration}", "origin { lat: 42 lon: -70 }", "mac { rate: 0 }"]
    for i in range(nodes):
        x, y = spacing * (i % columns), spacing * (i // columns)
        lines.append(
            f"node {{ modem_id: {i + 1} track {{ waypoint {{ x: {x} y: {y} depth: 10 }} }} }}"
        )
    return "\n".join(lines)


def measure(benchmark, scenario_text: str):
    scenario = parse_scenario(scenario_text)
    summary = benchmark.pedantic(
        lambda: Simulation(scenario).run_virtual(), rounds=1, iterations=1, warmup_rounds=0
    )
    benchmark.extra_info["simulated_s"] = summary.simulated_seconds
    benchmark.extra_info["wall_s"] = round(summary.wall_seconds, 3)
    benchmark.extra_info["speedup"] = round(summary.speedup)
    print()
    for line in summary.lines():
        print("   ", line)
    return summary


@pytest.mark.benchmark(group="netsim-sim")
def test_8_nodes_tdma_status_for_a_simulated_day(benchmark):
    summary = measure(benchmark, tdma_scenario(8, 86400, 1000, 4))
    assert summary.events["tx_data"] >= 86400 / 15 - 8  # every slot used
    assert summary.status_received > 0.9 * summary.events["tx_data"] * 7


@pytest.mark.benchmark(group="netsim-sim")
def test_100_nodes_tdma_status_two_cycles(benchmark):
    summary = measure(benchmark, tdma_scenario(100, 3000, 500, 10))
    assert summary.events["tx_data"] >= 3000 / 15 - 100
    assert summary.status_received > 0.9 * summary.events["tx_data"] * 99
