"""`make demo` (examples/two_vehicles/run_demo.py) runs the two-vehicle mission over netsim's
acoustic physics: the AUV drives away, travel times and losses grow with range, and it exits 0."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from pygoby.cli import main as pygoby_main
from pygoby.moos.alog.files import AlogFile
from pygoby.moos.alog.tools import summarize
from pygoby.moosacomms.alog_series import AcommsVariables, log_series
from pygoby.netsim.report.eventlog import read_events

pytestmark = pytest.mark.e2e

DEMO = Path(__file__).resolve().parents[2] / "examples" / "two_vehicles" / "run_demo.py"

SLOT_LINE = re.compile(
    r"^t=\s*(\d+) s .*range (\S+) km  owtt (\S+) s \| topside: .* lost (\d+)/(\d+) "
    r"\| unicorn: .* lost (\d+)/(\d+)$"
)


def test_demo_exits_zero_with_traffic_both_ways_and_range_effects(tmp_path):
    event_log = tmp_path / "events.jsonl"
    done = subprocess.run(
        [sys.executable, str(DEMO), "--event-log", str(event_log)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    out = done.stdout
    assert "demo finished OK" in out
    assert "command 1 acknowledged" in out and "unicorn: command received" in out
    assert re.search(r"slot 0 \(topside\)", out) and re.search(r"slot 1 \(unicorn\)", out)
    delivered = int(re.search(r"(\d+) messages delivered end to end", out).group(1))
    assert delivered >= 20  # a status each way per 20 s TDMA cycle while in range + commands
    assert "Traceback" not in done.stderr

    # per-slot lines: range, travel time and lost packets of both vehicles
    rows = [m.groups() for line in out.splitlines() if (m := SLOT_LINE.match(line))]
    rows = [tuple(float(v) for v in row) for row in rows if row[1] != "-"]
    assert len(rows) > 50
    first, last = rows[0], rows[-1]
    assert first[1] < 0.5 and last[1] > 2.5  # km: the AUV drove away
    assert last[2] > first[2] + 1.0  # s: the travel time grew with it (~0.67 s per km)
    assert first[3] == first[5] == 0  # nothing lost near the ship
    assert last[3] > 0 and last[5] > 0  # both directions lose packets far away
    assert last[4] > last[3] and last[6] > last[5]  # ... but not all of them

    # the event log the final output points at, for `pygoby netsim report`
    assert f"pygoby netsim report {event_log}" in out
    events = read_events(event_log)
    rx = [e for e in events if e["event"] == "rx"]
    assert {e["event"] for e in events} == {"tx", "rx"}
    assert {e["port"] for e in rx} == {62101, 62102}
    near = [e for e in rx if e["range_m"] < 1000]  # SNR > 20 dB
    far = [e for e in rx if e["range_m"] > 3000]  # SNR < -3 dB: most frames fail
    assert near and far
    assert all(e["outcome"] == "good" for e in near)
    assert any(e["outcome"] != "good" for e in far)
    assert all(abs(e["owtt"] * 1500 - e["range_m"]) < 1 for e in rx)  # 1500 m/s sound speed

    # each community's pLogger wrote its .alog in the log directory the output names
    assert f"logs: {tmp_path}" in out
    alog_lines = re.findall(
        r"^  ([a-z]+)_\S+\.alog: (\d+) lines, (\d+) variables; `pygoby log summary (\S+)`$",
        out,
        re.M,
    )
    assert {name for name, *_ in alog_lines} == {"topside", "unicorn"}
    for _, lines, variables, path in alog_lines:
        assert Path(path).is_relative_to(tmp_path)
        log = AlogFile(path)
        table = summarize(log)
        assert log.reader.bad_lines == 0  # every line an entry (no value of many lines)
        assert sum(row.count for row in table.values()) == int(lines) > 0
        assert len(table) == int(variables)
        assert "ACOMMS_MODEM_TRANSMIT" in table and "NAV_X" in table

    # the figures of the day: `pygoby log plot` over both vehicles' logs, read as data
    logs = [path for *_, path in alog_lines]
    mission = DEMO.parent / "unicorn.moos"
    series = log_series(logs, AcommsVariables.of_mission(mission, "pAcommsHandler"))
    assert set(series.transmissions) == set(series.receptions) == {1, 2}
    for modem in (1, 2):
        assert len(series.transmissions[modem]) >= 20  # one DATA transmission per cycle
        assert len(series.receptions[modem]) >= 20
        snr = [db for _t, db in series.snr_in[modem]]
        assert snr[0] > 20 and snr[-1] < snr[0] - 10  # the link weakens as the AUV leaves
    assert len(series.acked["pygoby.examples.Command"]) >= 1  # the topside's commands
    unicorn = series.tracks["unicorn"].points
    assert abs(unicorn[-1][0] - unicorn[0][0]) + abs(unicorn[-1][1] - unicorn[0][1]) > 2000
    figures = tmp_path / "figures"
    plot = [sys.executable, "-m", "pygoby.cli", "log", "plot", *logs, "--mission", str(mission)]
    done = subprocess.run([*plot, "-o", str(figures)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in figures.glob("*.png")) == [
        "acks.png",
        "link_quality.png",
        "tracks.png",
        "transmissions.png",
    ]

    # `log convert --mission`: the DCCL messages in the AUV's received frames as columns
    unicorn_log = next(path for name, *_, path in alog_lines if name == "unicorn")
    out = tmp_path / "unicorn.jsonl"
    assert (
        pygoby_main(["log", "convert", unicorn_log, "-o", str(out), "--mission", str(mission)]) == 0
    )
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    received = [r for r in rows if r["name"] == "ACOMMS_MODEM_RECEIVE" and "SimpleStatus.src" in r]
    assert received and all(r["SimpleStatus.src"] == "1" for r in received)  # the topside's
    commands = [r for r in rows if r["name"] == "COMMAND_IN"]  # a key=value translator post
    assert commands and all(r["Command.dest"] == "2" for r in commands)
