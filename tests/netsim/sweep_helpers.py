"""Shared by the sweep tests: small sweep files, running the CLI, comparing tables."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

REPO = Path(__file__).resolve().parents[2]


def sweep_text(duration: float = 900, replicates: int = 2, output: str = "out") -> str:
    """16 runs (4 spacings x 2 rates x 2 seeds) of three nodes in a line."""
    return f"""
scenario {{
  duration: {duration}
  origin {{ lat: 42 lon: -70 }}
  channel {{ spreading: 2 }}
  mac {{ slot_seconds: 10 rate: 1 }}
}}
layout {{ nodes: 3 spacing: 1000 }}
axis {{ field: "layout.spacing" name: "spacing_m" span {{ from: 1000 to: 4000 steps: 4 }} }}
axis {{ field: "mac.rate" value: "1" value: "5" }}
replicates: {replicates}
output: "{output}"
"""


def write_sweep(directory: Path, **kwargs) -> Path:
    path = directory / "sweep.pb.cfg"
    path.write_text(sweep_text(**kwargs))
    return path


def deterministic(table: pa.Table) -> pa.Table:
    """The table without wall_s (the one column that depends on where and when a run ran),
    NaN (a mean of nothing) as null so that Table.equals compares it."""
    table = table.drop_columns(["wall_s"])
    for i, column in enumerate(table.columns):
        if pa.types.is_floating(column.type):
            table = table.set_column(i, table.field(i), pc.if_else(pc.is_nan(column), None, column))
    return table


def read_table(output: Path) -> pa.Table:
    return pq.read_table(output / "results.parquet")


def start_sweep(sweep_file: Path, *args: str, cwd: Path) -> subprocess.Popen:
    """`pygoby netsim sweep` as its own process (group), as a user starts it."""
    return subprocess.Popen(
        [sys.executable, "-m", "pygoby.cli", "netsim", "sweep", str(sweep_file), *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def wait_for(condition, timeout: float, what: str, interval: float = 0.02) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(interval)


def stored_runs(output: Path) -> set[str]:
    return {p.stem for p in (output / "runs").glob("*.parquet")}


def descendants(pid: int) -> dict[int, int]:
    """{descendant pid: depth} of a process (1 = child), from /proc."""
    found, frontier = {}, [(pid, 0)]
    while frontier:
        parent, depth = frontier.pop()
        try:
            children = Path(f"/proc/{parent}/task/{parent}/children").read_text().split()
        except OSError:
            continue
        for child in map(int, children):
            found[child] = depth + 1
            frontier.append((child, depth + 1))
    return found


def kill_group(process: subprocess.Popen) -> None:
    """End a sweep started by start_sweep and everything it started (its own session)."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGKILL)
    process.communicate(timeout=30)


def run_files(output: Path) -> dict[str, int]:
    """{stored run file: its modification time in ns}."""
    return {p.name: p.stat().st_mtime_ns for p in (output / "runs").glob("*.parquet")}


def kill_when_stored(process: subprocess.Popen, output: Path, count: int) -> dict[str, int]:
    """SIGKILL a running sweep (no chance to clean up) once `count` runs are stored; returns
    the run files then."""
    try:
        wait_for(lambda: len(stored_runs(output)) >= count, 120, f"{count} stored runs")
    finally:
        kill_group(process)
    return run_files(output)


def resume(
    sweep_file: Path, *args: str, cwd: Path, output: Path, before: dict[str, int], total: int
) -> None:
    """Start the sweep again: it runs exactly the runs missing and leaves the stored ones be."""
    process = start_sweep(sweep_file, *args, cwd=cwd)
    out, err = process.communicate(timeout=180)
    assert process.returncode == 0, err
    assert f"{total - len(before)} run now, {len(before)} already stored, 0 failed" in out
    after = run_files(output)
    assert len(after) == total and all(after[name] == t for name, t in before.items())
