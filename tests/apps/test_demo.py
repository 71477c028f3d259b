"""`make demo` (examples/two_vehicles/run_demo.py) runs the two-vehicle mission over netsim's
acoustic physics: the AUV drives away, travel times and losses grow with range, and it exits 0."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from pygoby.moos.alog.files import AlogFile
from pygoby.moos.alog.tools import summarize
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
        table = summarize(AlogFile(path))
        assert sum(row.count for row in table.values()) == int(lines) > 0
        assert len(table) == int(variables)
        assert "ACOMMS_MODEM_TRANSMIT" in table and "NAV_X" in table
