"""`pygoby netsim run` / `pygoby netsim report` and the real-time run over TCP."""

from __future__ import annotations

import asyncio
import contextlib
import json
import re
import struct
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms.mmsim.server import MMSimServer
from pygoby.cli import main
from pygoby.moos.timewarp import moos_clock
from pygoby.netsim.manager.protocol import LineDecoder, encode_line, request_class, response_names
from pygoby.netsim.report.eventlog import read_events
from pygoby.netsim.report.plots import bin_success, node_labels, timeline_window
from pygoby.netsim.sim.realtime import RealTimeRun
from pygoby.netsim.sim.scenario import ScenarioError, parse_scenario
from tests.hypothesis_profiles import examples

pytestmark = pytest.mark.e2e

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "netsim" / "tdma8.pb.cfg"

SMALL = """duration: 300
origin { lat: 42 lon: -70 }
mac { slot_seconds: 10 rate: 1 }
node { modem_id: 1 track { waypoint { x: 0 depth: 5 } } }
node { modem_id: 2 track { waypoint { t: 0 x: 500 depth: 5 } waypoint { t: 300 x: 9500 depth: 5 } } }
"""


def png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_run_then_report(tmp_path, capsys):
    scenario = tmp_path / "small.pb.cfg"
    scenario.write_text(SMALL)
    log = tmp_path / "events.jsonl"
    assert main(["netsim", "run", str(scenario), "--event-log", str(log), "--seed", "3"]) == 0
    out = capsys.readouterr().out
    assert "x real time" in out and f"event log: {log}" in out
    events = read_events(log)
    assert {"tx", "rx", "app_rx"} <= {e["event"] for e in events}
    assert main(["netsim", "report", str(log), "-o", str(tmp_path / "plots")]) == 0
    out = capsys.readouterr().out
    assert "data packets:" in out
    for name in ("success_vs_range", "success_vs_snr", "timeline"):
        width, height = png_size(tmp_path / "plots" / f"{name}.png")
        assert width > 500 and height > 200


def test_example_scenario_parses():
    scenario = parse_scenario(EXAMPLE.read_text())
    assert len(scenario.node) == 8 and scenario.speed == "max"


def test_run_refuses_bad_scenario(tmp_path, capsys):
    bad = tmp_path / "bad.pb.cfg"
    bad.write_text("node { modem_id: 1 }")
    assert main(["netsim", "run", str(bad)]) == 1
    assert "needs a track" in capsys.readouterr().err
    assert main(["netsim", "run", str(tmp_path / "missing.pb.cfg")]) == 1


def test_report_skips_garbage_lines_and_refuses_empty_logs(tmp_path, capsys):
    log = tmp_path / "log.jsonl"
    good = {"event": "tx", "t": 10.0, "port": 62000, "kind": "data", "duration": 3.25}
    log.write_text("not json\n[1, 2]\n" + json.dumps(good) + '\n{"event": 5}\n')
    assert read_events(log) == [good]
    assert main(["netsim", "report", str(log), "-o", str(tmp_path / "out")]) == 0
    empty = tmp_path / "empty.jsonl"
    empty.write_text("garbage\n")
    assert main(["netsim", "report", str(empty)]) == 1
    assert main(["netsim", "report", str(log), "--window", "x"]) == 2


def test_bin_success():
    binned = bin_success([0, 1, 2, 3, 9.9, 10], [True, True, False, True, False, False], bins=2)
    assert binned.counts == [4, 2] and binned.success == [0.75, 0.0]
    fixed = bin_success([-3.0, -1.0, 0.5], [False, True, True], width=2.0)
    assert fixed.centres == [-3.0, -1.0, 1.0] and fixed.success == [0.0, 1.0, 1.0]


REAL_TIME = """speed: "8"
duration: 40
origin { lat: 42 lon: -70 }
real_time { ephemeral_ports: true }
mac { slot_seconds: 5 rate: 1 }
node { modem_id: 1 track { waypoint { x: 0 depth: 5 } } }
node { modem_id: 2 track { waypoint { x: 1500 depth: 5 } } }
node { modem_id: 3 in_process_stack: false }
"""


async def test_real_time_run_over_tcp():
    events: list[dict] = []
    run = RealTimeRun(parse_scenario(REAL_TIME), on_event=events.append)
    async with run:
        assert all(isinstance(s, MMSimServer) for s in run.emulators.values())
        # an external vehicle simulator reports node 3's position to the manager over TCP
        reader, writer = await asyncio.open_connection("127.0.0.1", run.manager_port)
        request = request_class()(id=7)
        request.nav.add(
            modem_tcp_port=62002,
            time=run.clock.now(),
            lat=42.0,
            lon=-69.99,
            depth=5,
            speed=0,
            heading=0,
        )
        writer.write(encode_line(request))
        (answer,) = LineDecoder(response_names()).feed(await reader.readline())
        assert answer.message.request_id == 7 and answer.message.status == 1
        writer.close()
        # an external client talks to node 3's emulator over TCP
        modem_r, modem_w = await asyncio.open_connection("127.0.0.1", run.emulator_port(3))
        summary = await asyncio.wait_for(run.run(), 30)
        heard_by_3 = await modem_r.read(65536)
        modem_w.close()
    assert summary.status_received >= 2  # nodes 1 and 2 heard each other (driver over TCP)
    assert summary.external_deliveries[3] >= 1  # counted for node 3's external stack
    assert b"$CARXD" in heard_by_3  # and the channel delivered to node 3's emulator
    assert any(e["event"] == "rx" and e["port"] == 62002 for e in events)


def test_real_time_needs_a_speed_factor_or_a_clock():
    with pytest.raises(ValueError, match="virtual clock"):
        RealTimeRun(parse_scenario(SMALL))
    clock = moos_clock(25)  # e.g. sharing a MOOS time-warp clock with the apps of a mission
    run = RealTimeRun(parse_scenario(SMALL), clock=clock)
    assert run.clock is clock and run.sim.physics.clock is clock
    assert run.sim.start == pytest.approx(clock.now(), abs=5)


@settings(max_examples=examples(200), deadline=None)
@given(st.text(max_size=200))
def test_fuzz_scenario_parser_only_raises_scenario_error(text):
    with contextlib.suppress(ScenarioError):
        parse_scenario(text)


@settings(max_examples=examples(200), deadline=None)
@given(
    st.lists(
        st.one_of(
            st.text(max_size=60), st.dictionaries(st.text(max_size=5), st.integers(), max_size=3)
        )
    )
)
def test_fuzz_event_log_reader_skips_what_is_not_an_event(tmp_path_factory, lines):
    path = tmp_path_factory.mktemp("log") / "events.jsonl"
    text = "\n".join(json.dumps(x) if isinstance(x, dict) else x.replace("\n", " ") for x in lines)
    path.write_text(text, encoding="utf-8")
    events = read_events(path)
    assert all(isinstance(e, dict) and isinstance(e.get("event"), str) for e in events)


EXTERNAL = """speed: "8"
duration: 48
origin { lat: 42 lon: -70 }
real_time { ephemeral_ports: true }
mac { slot_seconds: 6 rate: 1 }
node { modem_id: 1 track { waypoint { x: 0 depth: 5 } } }
node { modem_id: 2 track { waypoint { x: 1500 depth: 5 } } }
node { modem_id: 3 in_process_stack: false track { waypoint { x: 700 depth: 5 } } }
"""


def test_real_time_cli_run_ends_cleanly_and_counts_external_deliveries(tmp_path):
    """`pygoby netsim run` in real time (8x): no traceback when it ends, progress on stderr
    (not a terminal: a line per tenth once it has run a few seconds), and the summary counts
    what reached the external stack's modem (node 3: nobody in process reads its queue)."""
    import subprocess
    import sys

    scenario = tmp_path / "external.pb.cfg"
    scenario.write_text(EXTERNAL)
    log = tmp_path / "events.jsonl"
    pygoby = Path(sys.executable).with_name("pygoby")
    done = subprocess.run(
        [pygoby, "netsim", "run", scenario, "--event-log", log],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "Exception" not in done.stderr, done.stderr
    lines = done.stdout.splitlines()
    external = [line for line in lines if line.startswith("packets delivered to external")]
    assert len(external) == 1 and re.fullmatch(
        r"packets delivered to external stacks' modems: modem 3: [1-9]\d*", external[0]
    ), lines
    progress = [line for line in done.stderr.splitlines() if line.startswith("simulated ")]
    assert progress and all(
        re.fullmatch(
            r"simulated [\d,]+/48 s \(\d+%\): packets \d+, messages \d+, [\d.,]+x real time(, ETA \d+ s)?",
            p,
        )
        for p in progress
    ), progress
    nodes = [e for e in read_events(log) if e["event"] == "node"]
    assert [(e["port"], e["modem_id"], e["external"]) for e in nodes] == [
        (62000, 1, False),
        (62001, 2, False),
        (62002, 3, True),
    ]


def test_timeline_covers_the_run_and_names_nodes_by_modem_id():
    events = [
        {"event": "node", "t": 100.0, "port": 62000, "modem_id": 7, "external": False},
        {"event": "tx", "t": 110.0, "port": 62000, "src": 7, "kind": "data", "duration": 3.0},
        {"event": "tx", "t": 7000.0, "port": 62005, "src": 4, "kind": "data", "duration": 3.0},
        {"event": "rx", "t": 7300.0, "arrival": 7299.0, "port": 62009, "outcome": "good"},
    ]
    assert node_labels(events) == {62000: "modem 7", 62005: "modem 4", 62009: "port 62009"}
    assert timeline_window(events, None) == (100.0, (0.0, 7200.0))  # the whole run
    assert timeline_window(events, (10.0, 20.0)) == (100.0, (10.0, 20.0))
