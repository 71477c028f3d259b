"""Sweeps and the BELLHOP channel (`make bench`; issue 19).

* A 200-run sweep (8 nodes, one simulated hour each: 10 spacings x 2 rates x 10 seeds) on all
  of this machine's cores (local worker processes) and in one process: runs/s and the speed-up.
  The two tables must be identical (wall_s aside).
* The BELLHOP propagation model: an 8-node scenario (nodes at 8 depths, so 8 source-depth
  fields) for one simulated hour with the empirical model and with BELLHOP; the cost per
  simulated hour, how much of it is tracing (once per field, then cached) and what each packet
  costs once the fields are cached.
"""

from __future__ import annotations

import os
import time

import pytest

from pygoby.netsim.sim.scenario import parse_scenario
from pygoby.netsim.sim.simulation import Simulation
from pygoby.netsim.sweep.engine import run_sweep
from pygoby.netsim.sweep.executors import LocalExecutor, default_jobs
from pygoby.netsim.sweep.plan import expand, parse_sweep
from pygoby.netsim.sweep.store import ResultStore, results_schema
from tests.netsim.sweep_helpers import deterministic

SWEEP = """
scenario {
  duration: 3600
  origin { lat: 42 lon: -70 }
  channel { spreading: 2 }
  mac { slot_seconds: 10 rate: 1 }
}
layout { nodes: 8 pattern: GRID spacing: 1000 }
axis { field: "layout.spacing" span { from: 500 to: 5000 steps: 10 } }
axis { field: "mac.rate" value: "1" value: "5" }
replicates: 10
"""


def sweep_once(plan, directory, jobs):
    store = ResultStore(directory, results_schema(plan.columns))
    outcome = run_sweep(plan, store, LocalExecutor(jobs))
    assert outcome.executed == len(plan.runs) and not outcome.failed
    return outcome


@pytest.mark.timeout(3600)
@pytest.mark.benchmark(group="netsim-sweep")
def test_200_run_sweep_local_processes_against_one_process(benchmark, tmp_path):
    sweep, base = parse_sweep(SWEEP)
    plan = expand(sweep, base, None, SWEEP)
    assert len(plan.runs) == 200
    load_before = os.getloadavg()[0]  # (a shared machine: other work slows both measurements)
    one = sweep_once(plan, tmp_path / "one", 1)
    jobs = default_jobs()
    many = benchmark.pedantic(
        lambda: sweep_once(plan, tmp_path / "many", jobs), rounds=1, iterations=1, warmup_rounds=0
    )
    assert deterministic(one.table).equals(deterministic(many.table))
    rate_one, rate_many = 200 / one.wall_s, 200 / many.wall_s
    benchmark.extra_info.update(
        {
            "runs": 200,
            "jobs": jobs,
            "one_process_s": round(one.wall_s, 2),
            "local_processes_s": round(many.wall_s, 2),
            "one_process_runs_per_s": round(rate_one, 2),
            "local_runs_per_s": round(rate_many, 2),
            "speedup": round(rate_many / rate_one, 2),
            "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)],
        }
    )
    print(
        f"\n    200 runs (8 nodes, 1 simulated hour each): one process {one.wall_s:.1f} s "
        f"({rate_one:.2f} runs/s); {jobs} local processes {many.wall_s:.1f} s "
        f"({rate_many:.2f} runs/s): speed-up {rate_many / rate_one:.2f}x (load average "
        f"{load_before:.1f} before, {os.getloadavg()[0]:.1f} after)"
    )


BELLHOP_SCENARIO = """duration: 3600
origin {{ lat: 42 lon: -70 }}
channel {{ spreading: 1.5 water {{ temperature: 12 }} propagation {{ model: {model}
  bellhop {{ water_depth: 100 ssp {{ a: 0 b: 1520 }} ssp {{ a: 30 b: 1518 }}
             ssp {{ a: 60 b: 1505 }} ssp {{ a: 100 b: 1503 }} }} }} }}
mac {{ slot_seconds: 10 rate: 1 }}
{nodes}
"""


def bellhop_scenario(model: str):
    nodes = "\n".join(
        f"node {{ modem_id: {i + 1} track {{ waypoint {{ x: {1000 * (i % 4)} y: {1000 * (i // 4)} "
        f"depth: {5 + 10 * i} }} }} }}"
        for i in range(8)
    )
    return parse_scenario(BELLHOP_SCENARIO.format(model=model, nodes=nodes))


@pytest.mark.benchmark(group="netsim-bellhop")
def test_bellhop_model_cost_per_simulated_hour(benchmark):
    """CPU seconds (this process: the comparison does not depend on other work on the machine)."""
    started = time.process_time()
    Simulation(bellhop_scenario("EMPIRICAL")).run_virtual()
    empirical_cpu = time.process_time() - started
    sims = []

    def run():
        sim = Simulation(bellhop_scenario("BELLHOP"))
        sims.append(sim)
        started = time.process_time()
        summary = sim.run_virtual()
        sims.append(time.process_time() - started)
        return summary

    summary = benchmark.pedantic(run, rounds=1, iterations=1, warmup_rounds=0)
    sim, bellhop_cpu = sims
    model = sim.channel.config.propagation
    receptions = summary.events["rx"]
    assert model.traced == 8 and receptions > 0
    cached_cpu = bellhop_cpu - model.tracing_cpu_seconds
    per_reception_us = (cached_cpu - empirical_cpu) / receptions * 1e6
    benchmark.extra_info.update(
        {
            "simulated_s": 3600,
            "empirical_cpu_s": round(empirical_cpu, 3),
            "bellhop_cpu_s": round(bellhop_cpu, 3),
            "fields_traced": model.traced,
            "tracing_cpu_s": round(model.tracing_cpu_seconds, 3),
            "tracing_wall_s": round(model.tracing_seconds, 3),
            "receptions": receptions,
            "extra_us_per_reception_cached": round(per_reception_us, 2),
        }
    )
    print(
        f"\n    one simulated hour, 8 nodes at 8 depths, {receptions} receptions (CPU time): "
        f"empirical {empirical_cpu:.2f} s; BELLHOP {bellhop_cpu:.2f} s = {model.traced} fields "
        f"traced in {model.tracing_cpu_seconds:.2f} s + {cached_cpu:.2f} s simulation "
        f"({per_reception_us:+.1f} us per reception once cached)"
    )
