"""End-to-end messages per simulated hour through the two-vehicle demo mission in fast mode.

The mission of examples/two_vehicles (`run_mission` of its run_demo.py: two MOOS communities,
pAcommsHandler + uSimVehicle each, emulated Micro-Modems over loopback TCP hearing each other
through netsim's physics, two 10 s TDMA slots) runs time-warped in this process, as `make demo`
does. Each slot carries one rate-0 packet (32 bytes), so the mission's design caps delivery near
one message per slot (360 per simulated hour) plus packed commands; a warp the machine cannot
keep up with shows as slots lost to "clock skew" and a lower figure. The run stops while the AUV
is within ~2 km of the ship, before the demo's channel starts losing packets to range.
The figures go to the benchmark's extra_info; nothing about them is asserted.
"""

import asyncio
from pathlib import Path

import pytest

from pygoby.util.modules import import_module_or_file

DEMO = Path(__file__).resolve().parents[1] / "examples" / "two_vehicles" / "run_demo.py"
run_mission = import_module_or_file(str(DEMO)).run_mission

SIMULATED_SECONDS = 450.0


@pytest.mark.parametrize("warp", [25, 100])
def test_two_vehicle_mission_messages_per_simulated_hour(benchmark, warp):
    def run():
        return asyncio.run(run_mission(warp, SIMULATED_SECONDS, say=lambda text: None))

    result = benchmark.pedantic(run, rounds=1, iterations=1)
    benchmark.extra_info.update(
        warp=warp,
        simulated_s=round(result.simulated_seconds),
        wall_s=round(result.real_seconds, 1),
        delivered=result.delivered,
        messages_per_simulated_hour=round(result.per_simulated_hour),
        acked_commands=sum(v.acked["command"] for v in result.vehicles),
    )
    print(
        f"\nwarp {warp}: {result.delivered} messages in {result.simulated_seconds:.0f} simulated s "
        f"({result.real_seconds:.1f} s wall) = {result.per_simulated_hour:.0f} per simulated hour"
    )
