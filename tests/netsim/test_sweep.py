"""`pygoby netsim sweep` / `sweep-report` on local processes: plans, runs, the table, resume
after an interruption, retry after a worker process is killed, the report."""

from __future__ import annotations

import math
import signal

import pyarrow.parquet as pq
import pytest

from pygoby.cli import main
from pygoby.errors import ConfigError
from pygoby.netsim.channel.geometry import WGS84
from pygoby.netsim.sim.scenario import channel_config, parse_scenario
from pygoby.netsim.sim.simulation import Simulation
from pygoby.netsim.sweep.plan import expand, parse_sweep
from pygoby.netsim.sweep.report import read_results, success_by_range, wilson_interval
from pygoby.netsim.sweep.run import execute_run
from tests.netsim.sweep_helpers import (
    REPO,
    descendants,
    deterministic,
    kill_group,
    kill_when_stored,
    read_table,
    resume,
    run_files,
    start_sweep,
    stored_runs,
    sweep_text,
    wait_for,
    write_sweep,
)
from tests.netsim.test_sim_cli import png_size

pytestmark = pytest.mark.e2e


def plan_of(text: str):
    sweep, base = parse_sweep(text)
    return expand(sweep, base, None, text)


# -- plans -----------------------------------------------------------------------------------------


def test_grid_plan_has_every_combination_and_replicate():
    plan = plan_of(sweep_text())
    assert len(plan.runs) == 4 * 2 * 2
    assert [c.name for c in plan.columns] == ["spacing_m", "mac.rate"]
    assert [c.kind for c in plan.columns] == [float, int]
    points = {r.params for r in plan.runs}
    assert points == {
        (("spacing_m", s), ("mac.rate", rate))
        for s in (1000.0, 2000.0, 3000.0, 4000.0)
        for rate in (1, 5)
    }
    assert sorted({r.seed for r in plan.runs}) == [1, 2]
    assert len({r.run_id for r in plan.runs}) == len(plan.runs)
    # the run ids depend only on what runs: the same file gives the same ids
    assert [r.run_id for r in plan_of(sweep_text()).runs] == [r.run_id for r in plan.runs]


def test_each_run_is_the_scenario_with_its_values():
    plan = plan_of(sweep_text())
    run = next(r for r in plan.runs if dict(r.params) == {"spacing_m": 3000.0, "mac.rate": 5})
    scenario = parse_scenario(run.scenario_text)
    assert scenario.mac.rate == 5 and scenario.seed == run.seed
    assert [n.modem_id for n in scenario.node] == [1, 2, 3]
    a, c = scenario.node[0].track.waypoint[0], scenario.node[2].track.waypoint[0]
    assert WGS84.inv(a.lon, a.lat, c.lon, c.lat)[2] == pytest.approx(6000.0, abs=1e-6)
    assert not scenario.HasField("event_log")


def test_random_sampling_is_repeatable_and_inside_the_spans():
    text = """scenario { duration: 60 origin { lat: 42 lon: -70 } }
layout { nodes: 2 }
axis { field: "layout.spacing" span { from: 500 to: 8000 log: true } }
axis { field: "layout.nodes" span { from: 2 to: 6 } }
axis { field: "channel.half_duplex" value: "true" value: "false" }
sampling: RANDOM random_samples: 30 sampling_seed: 4
"""
    plan = plan_of(text)
    assert len(plan.runs) == 30
    values = [dict(r.params) for r in plan.runs]
    assert all(500 <= v["layout.spacing"] <= 8000 for v in values)
    assert {v["layout.nodes"] for v in values} <= {2, 3, 4, 5, 6}
    assert all(isinstance(v["layout.nodes"], int) for v in values)
    assert {v["channel.half_duplex"] for v in values} == {True, False}
    assert [r.run_id for r in plan_of(text).runs] == [r.run_id for r in plan.runs]
    other = plan_of(text.replace("sampling_seed: 4", "sampling_seed: 5"))
    assert [r.params for r in other.runs] != [r.params for r in plan.runs]


def test_any_scenario_field_with_indices_and_enums():
    text = """scenario {
  duration: 60 origin { lat: 42 lon: -70 }
  node { modem_id: 1 track { waypoint { x: 0 } } }
  node { modem_id: 2 track { waypoint { x: 1000 } } }
}
axis { field: "node[1].track.waypoint[0].x" value: "2500" value: "5e3" }
axis { field: "mac.type" value: "MAC_FIXED_DECENTRALIZED" }
axis { field: "seed" value: "7" value: "8" }
"""
    plan = plan_of(text)
    assert len(plan.runs) == 4
    assert {r.seed for r in plan.runs} == {7, 8}
    scenario = parse_scenario(plan.runs[-1].scenario_text)
    assert scenario.node[1].track.waypoint[0].x == 5000.0
    assert dict(plan.runs[0].params)["mac.type"] == "MAC_FIXED_DECENTRALIZED"


@pytest.mark.parametrize(
    "axis, message",
    [
        ('field: "mac.nonsense" value: "1"', "MACConfig has no field 'nonsense'"),
        ('field: "node.modem_id" value: "1"', "node is repeated: give an index"),
        ('field: "node[5].modem_id" value: "1"', "node[5] does not exist"),
        ('field: "mac.rate" value: "fast"', "mac.rate: expects an integer, not 'fast'"),
        ('field: "mac.rate" value: "1.5"', "mac.rate: expects an integer, not '1.5'"),
        ('field: "channel.spreading" value: "x"', "channel.spreading: expects a number, not 'x'"),
        ('field: "mac.type" value: "ALOHA"', "is not one of"),
        ('field: "channel" value: "1"', "must end at a number"),
        ('field: "mac.rate"', "give either values or a span"),
        ('field: "layout.nodes" value: "2"', "needs a layout"),
        ('field: "seed" value: "1" name: "run_id"', "used twice"),
    ],
)
def test_axis_mistakes_name_file_line_and_field(tmp_path, axis, message):
    path = tmp_path / "bad.pb.cfg"
    text = (
        "scenario { duration: 60 origin { lat: 42 lon: -70 }\n"
        "  node { modem_id: 1 track { waypoint { x: 0 } } } }\n"
        f"axis {{ {axis} }}\n"
    )
    path.write_text(text)
    with pytest.raises(ConfigError) as caught:
        sweep, base = parse_sweep(text, path)
        expand(sweep, base, path, text)
    assert message in str(caught.value)
    field = axis.split('"')[1]
    assert str(caught.value).startswith(f"{path}:3: {field}: ")


def test_sweep_file_mistakes(tmp_path):
    with pytest.raises(ConfigError, match=r"bad\.pb\.cfg:2:"):
        parse_sweep("scenario { }\naxis { fild: 1 }\n", tmp_path / "bad.pb.cfg")
    with pytest.raises(ConfigError, match="exactly one of scenario"):
        parse_sweep('axis { field: "seed" value: "1" }')
    with pytest.raises(ConfigError, match='speed must be "max"'):
        parse_sweep('scenario { speed: "1" } axis { field: "seed" value: "1" }')
    with pytest.raises(ConfigError, match="replicates must be 1"):
        plan_of(
            "scenario { node { modem_id: 1 track { waypoint { x: 0 } } } origin { lat: 1 "
            'lon: 1 } } axis { field: "seed" value: "1" } replicates: 2'
        )
    assert main(["netsim", "sweep", str(tmp_path / "missing.pb.cfg")]) == 1


# -- one run ---------------------------------------------------------------------------------------


def test_run_rows_count_every_link_and_agree_with_the_simulation():
    plan = plan_of(sweep_text())
    run = next(r for r in plan.runs if dict(r.params) == {"spacing_m": 2000.0, "mac.rate": 5})
    result = execute_run(run)
    assert len(result.rows) == 3 * 2  # ordered pairs of 3 nodes
    events = []
    summary = Simulation(parse_scenario(run.scenario_text), on_event=events.append).run_virtual()
    data_rx = [e for e in events if e["event"] == "rx" and e["kind"] == "data"]
    rows = result.rows
    assert sum(r["received"] for r in rows) == len(data_rx)
    assert sum(r["good"] for r in rows) == sum(e["outcome"] == "good" for e in data_rx)
    assert sum(r["messages"] for r in rows) == summary.status_received
    for r in rows:
        assert r["received"] == sum(
            r[o] for o in ("good", "bad_frames", "not_detected", "receiver_busy", "half_duplex")
        )
        assert r["rate"] == 5 and r["spacing_m"] == 2000.0 and r["nodes"] == 3
        assert r["range_m"] == pytest.approx(2000.0 * abs(r["src"] - r["dest"]), rel=1e-3)
        assert r["latency_mean_s"] > r["owtt_mean_s"] > 0
    again = execute_run(run)
    assert [{k: v for k, v in r.items() if k != "wall_s"} for r in again.rows] == [
        {k: v for k, v in r.items() if k != "wall_s"} for r in rows
    ]


# -- sweeps through the CLI ------------------------------------------------------------------------


def test_sweep_in_one_process_and_on_two_gives_the_same_table(tmp_path, capsys):
    sweep = write_sweep(tmp_path)
    assert main(["netsim", "sweep", str(sweep), "-o", str(tmp_path / "one"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "16 runs on 1 local process" in out and "16 run now, 0 already stored" in out
    assert main(["netsim", "sweep", str(sweep), "-o", str(tmp_path / "two"), "--jobs", "2"]) == 0
    one, two = read_table(tmp_path / "one"), read_table(tmp_path / "two")
    assert one.num_rows == 16 * 6
    assert deterministic(one).equals(deterministic(two))
    assert (tmp_path / "one" / "sweep.pb.cfg").read_text() == sweep.read_text()
    # started again: every run is stored, nothing runs
    assert main(["netsim", "sweep", str(sweep), "-o", str(tmp_path / "one")]) == 0
    assert "0 run now, 16 already stored" in capsys.readouterr().out


def test_interrupted_sweep_resumes_without_running_anything_twice(tmp_path):
    # longer runs, and the signal at the first stored run: on a loaded machine the test's
    # polling can lag the sweep by several runs, and the sweep must still be half-way
    sweep = write_sweep(tmp_path, duration=3600)
    output = tmp_path / "out"
    process = start_sweep(sweep, "--jobs", "1", cwd=tmp_path)
    try:
        wait_for(lambda: len(stored_runs(output)) >= 1, 60, "a stored run")
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=30)
    finally:
        kill_group(process)
    assert process.returncode == 130
    before = run_files(output)
    assert 1 <= len(before) < 16, "the sweep must have been interrupted half-way"
    assert f"interrupted: {len(before)} of 16 runs are stored" in err
    assert not list((output / "runs").glob(".*")), "no partial file is left behind"
    resume(sweep, "--jobs", "1", cwd=tmp_path, output=output, before=before, total=16)
    reference = tmp_path / "reference"
    assert main(["netsim", "sweep", str(sweep), "-o", str(reference), "--jobs", "1"]) == 0
    assert deterministic(read_table(output)).equals(deterministic(read_table(reference)))


def test_killed_sweep_keeps_every_stored_run(tmp_path):
    sweep = write_sweep(tmp_path, duration=1800)
    output = tmp_path / "out"
    before = kill_when_stored(start_sweep(sweep, "--jobs", "2", cwd=tmp_path), output, 2)
    assert len(before) < 16
    for name in before:  # every file there is a whole run
        assert pq.read_table(output / "runs" / name).num_rows == 6
    resume(sweep, "--jobs", "2", cwd=tmp_path, output=output, before=before, total=16)


def test_a_killed_worker_process_has_its_runs_retried(tmp_path):
    sweep = write_sweep(tmp_path, duration=3600, replicates=1)  # 8 runs of ~0.2 s
    output = tmp_path / "out"
    process = start_sweep(sweep, "--jobs", "2", cwd=tmp_path)
    try:
        # the pool's workers are forked by the forkserver: grandchildren of the sweep
        wait_for(
            lambda: len([p for p, d in descendants(process.pid).items() if d == 2]) == 2,
            60,
            "two worker processes",
        )
        wait_for(lambda: len(stored_runs(output)) >= 1, 60, "a stored run")
        victim = min(p for p, d in descendants(process.pid).items() if d == 2)
        signal_sent = len(stored_runs(output))
        import os

        os.kill(victim, signal.SIGKILL)
        out, err = process.communicate(timeout=120)
    finally:
        kill_group(process)
    assert signal_sent < 8
    assert process.returncode == 0, err
    assert "a worker process died" in err
    assert "8 run now, 0 already stored, 0 failed" in out
    reference = tmp_path / "reference"
    assert main(["netsim", "sweep", str(sweep), "-o", str(reference), "--jobs", "1"]) == 0
    assert deterministic(read_table(output)).equals(deterministic(read_table(reference)))


# -- report ----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "successes, trials, low, high",
    # Newcombe (1998), Stat. Med. 17:857, table I, method 3 (Wilson score, no continuity correction)
    [
        (81, 263, 0.2553, 0.3662),
        (15, 148, 0.0624, 0.1605),
        (0, 20, 0.0, 0.1611),
        (1, 29, 0.0061, 0.1718),
    ],
)
def test_wilson_interval_matches_published_values(successes, trials, low, high):
    a, b = wilson_interval(successes, trials)
    assert a == pytest.approx(low, abs=5e-5) and b == pytest.approx(high, abs=5e-5)
    assert all(math.isnan(x) for x in wilson_interval(0, 0))


def test_sweep_report_draws_the_figures_and_the_page(tmp_path, capsys):
    sweep = write_sweep(tmp_path, replicates=1)
    output = tmp_path / "out"
    assert main(["netsim", "sweep", str(sweep), "-o", str(output), "--jobs", "1"]) == 0
    assert main(["netsim", "sweep-report", str(output)]) == 0
    report = output / "report"
    for name in ("success_vs_range", "snr_vs_range"):
        width, height = png_size(report / f"{name}.png")
        assert width >= 600 and height >= 400
    # three nodes in every run: no figure against the node count (it had a single x value)
    assert not (report / "throughput_vs_nodes.png").exists()
    assert not (report / "latency_vs_nodes.png").exists()
    page = (report / "index.html").read_text()
    assert "not drawn: every run has 3 nodes" in page
    assert all(f'src="{n}.png"' in page for n in ("success_vs_range", "snr_vs_range"))
    assert "95 % Wilson" in page and "8 runs" in page
    rows = read_results(output).to_pylist()
    points = success_by_range(rows)
    assert {p.rate for p in points} == {1, 5}
    close = next(p for p in points if p.rate == 1 and p.range_m == 1000)
    assert close.sent == sum(
        r["sent"] for r in rows if r["rate"] == 1 and round(r["range_m"]) == 1000
    )
    assert close.success > 0.9  # 1 km at spreading 2: SNR far above rate 1's table
    capsys.readouterr()
    assert main(["netsim", "sweep-report", str(tmp_path / "nothing")]) == 1
    assert (
        f"{tmp_path / 'nothing'} does not exist: give the output folder of `pygoby netsim sweep`"
        in capsys.readouterr().err
    )
    assert main(["netsim", "sweep-report", str(tmp_path)]) == 1
    assert f"no results.parquet in {tmp_path}: " in capsys.readouterr().err


def test_example_sweep_plans_and_its_readme_shows_the_figures(capsys):
    """examples/netsim/sweep_range_rate.pb.cfg (figures: `make figures`)."""
    example = REPO / "examples" / "netsim" / "sweep_range_rate.pb.cfg"
    assert main(["netsim", "sweep", str(example), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "48 runs; results would go to sweep_range_rate_results" in out
    assert "spacing_m=1500.0, vehicles=8, mac_rate=5" in out
    readme = (example.parent / "README.md").read_text()
    for name in ("success_vs_range", "throughput_vs_nodes", "latency_vs_nodes", "snr_vs_range"):
        assert f"(figures/{name}.png)" in readme
        width, height = png_size(example.parent / "figures" / f"{name}.png")
        assert width >= 600 and height >= 400


def test_propagation_model_and_sound_speed_formula_as_axes():
    text = """scenario { duration: 60 origin { lat: 42 lon: -70 }
  channel { water { temperature: 10 } propagation { bellhop { water_depth: 50 } } } }
layout { nodes: 2 }
axis { field: "channel.propagation.model" value: "EMPIRICAL" value: "BELLHOP" }
axis { field: "channel.water.sound_speed_formula" value: "MACKENZIE_1981" value: "UNESCO_1983" }
"""
    plan = plan_of(text)
    assert [dict(r.params) for r in plan.runs][1] == {
        "channel.propagation.model": "EMPIRICAL",
        "channel.water.sound_speed_formula": "UNESCO_1983",
    }
    bellhop = parse_scenario(plan.runs[3].scenario_text)
    config = channel_config(bellhop)
    assert config.propagation is not None and config.propagation.settings.water_depth == 50
    assert config.sound_speed(10.0) != channel_config(
        parse_scenario(plan.runs[2].scenario_text)
    ).sound_speed(10.0)
    assert channel_config(parse_scenario(plan.runs[0].scenario_text)).propagation is None


def test_sweep_report_draws_the_node_count_figures_when_the_node_count_is_swept(tmp_path):
    text = sweep_text(duration=300, replicates=1).replace(
        'axis { field: "layout.spacing" name: "spacing_m" span { from: 1000 to: 4000 steps: 4 } }',
        'axis { field: "layout.nodes" name: "vehicles" value: "2" value: "3" }',
    )
    assert "layout.nodes" in text
    sweep = tmp_path / "sweep.pb.cfg"
    sweep.write_text(text)
    output = tmp_path / "out"
    assert main(["netsim", "sweep", str(sweep), "-o", str(output), "--jobs", "1"]) == 0
    assert main(["netsim", "sweep-report", str(output)]) == 0
    report = output / "report"
    for name in ("throughput_vs_nodes", "latency_vs_nodes"):
        width, height = png_size(report / f"{name}.png")
        assert width >= 600 and height >= 400
    assert "not drawn" not in (report / "index.html").read_text()
