"""Throughput, server CPU and latency of the embedded MOOSDB (run by `make bench`).

The DB runs as its own process (`pygoby moosdb`, as the C++ MOOSDB would); every publisher
and subscriber is a separate load-generator process (`moos_load.py`) that batches like libMOOS,
so that Python clients are not what limits the figures:

* flood, at 1 publisher x 1 subscriber, 4 x 4 and 1 x 16 (64-byte strings): notifications
  delivered per second (summed over subscribers) and the DB process's CPU time (user + system)
  per delivered notification — the figure that does not depend on what else the 2 cores run;
* paced, 1 x 1 at 1,000 notifications/s: latency p50/p99 (subscriber's wall clock at receipt
  minus the publisher's time stamp at sending);
* a GobyMOOSApp (in this process) subscribed to a variable that a load generator publishes at
  100,000 notifications/s for a bounded time: how many its handler saw, this process's CPU time
  per handled notification (client and app: below 10 us it keeps up on one free core), how far
  behind it was when the publisher stopped, and this process's resident memory before, at its
  peak and after.

Each figure is the median of three runs; they are printed and stored in the benchmark's
extra_info; nothing is asserted about them. `PYGOBY_BENCH_MOOSDB` runs another DB instead, for
side-by-side figures: a command line with `{port}`, e.g.
`PYGOBY_BENCH_MOOSDB="MOOSDB --moos_port={port} --moos_suicide_disable"` for the C++ one, or
the DB of another pygoby checkout. `PYGOBY_BENCH_LOADGEN` replaces the load generator (a
command taking moos_load.py's arguments, e.g. one built on libMOOS).
"""

from __future__ import annotations

import asyncio
import json
import os
import shlex
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

import pytest

PYGOBY = str(Path(sys.executable).with_name("pygoby"))
LOAD = str(Path(__file__).with_name("moos_load.py"))
TOPOLOGIES = [(1, 1), (4, 4), (1, 16)]
FLOOD_DELIVERIES = 400_000  # per run, summed over subscribers
PACED_RATE = 1000.0
PACED_SECONDS = 3.0
CLOCK_TICK = os.sysconf("SC_CLK_TCK")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def moosdb():
    """(port, pid) of a MOOSDB process for the whole module."""
    port = _free_port()
    template = os.environ.get("PYGOBY_BENCH_MOOSDB", f"{PYGOBY} moosdb --port {{port}}")
    proc = subprocess.Popen(
        shlex.split(template.format(port=port)),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 10
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            break
        except OSError:
            if time.monotonic() > deadline or proc.poll() is not None:
                raise RuntimeError(f"no MOOSDB on port {port} ({template})") from None
            time.sleep(0.05)
    print(f"\nMOOSDB under test: {template.format(port=port)}")
    yield port, proc.pid
    proc.terminate()
    proc.wait(10)


def _cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICK  # utime + stime


def _spawn(*args: str) -> subprocess.Popen:
    command = shlex.split(os.environ.get("PYGOBY_BENCH_LOADGEN", "")) or [sys.executable, LOAD]
    return subprocess.Popen(
        [*command, *args], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )


def _wait_ready(procs: list[subprocess.Popen]) -> None:
    for proc in procs:
        line = proc.stdout.readline()
        if line.strip() != "ready":
            raise RuntimeError(f"load generator failed to start: {line!r}")


def _result(proc: subprocess.Popen) -> dict:
    out, _ = proc.communicate(timeout=120)
    return json.loads([line for line in out.splitlines() if line.startswith("{")][-1])


def _percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(int(q * len(ordered)), len(ordered) - 1)] if ordered else float("nan")


def run_load(
    port: int, db_pid: int, n_pub: int, n_sub: int, per_pub: int, rate: float | None = None
) -> dict:
    tag = f"{n_pub}x{n_sub}_{time.monotonic_ns()}"
    var = f"BENCH_{tag}"
    expect = n_pub * per_pub
    subs = [
        _spawn(
            "sub",
            "--port",
            str(port),
            "--name",
            f"s{i}_{tag}",
            "--var",
            var,
            "--expect",
            str(expect),
            *(["--latency"] if rate else []),
        )
        for i in range(n_sub)
    ]
    _wait_ready(subs)
    pubs = [
        _spawn(
            "pub",
            "--port",
            str(port),
            "--name",
            f"p{i}_{tag}",
            "--var",
            var,
            "--count",
            str(per_pub),
            *(["--rate", str(rate), "--batch", "1"] if rate else []),
        )
        for i in range(n_pub)
    ]
    _wait_ready(pubs)
    cpu0 = _cpu_seconds(db_pid)
    for pub in pubs:
        pub.stdin.write("go\n")
        pub.stdin.flush()
    received = [_result(s) for s in subs]
    cpu1 = _cpu_seconds(db_pid)
    sent = [_result(pub) for pub in pubs]
    delivered = sum(r["received"] for r in received)
    elapsed = max(r["last"] for r in received) - min(s["start"] for s in sent)
    latencies = [x for r in received for x in r["latencies"]]
    return {
        "delivered": delivered,
        "expected": expect * n_sub,
        "per_second": delivered / elapsed,
        "server_cpu_us": 1e6 * (cpu1 - cpu0) / max(delivered, 1),
        "p50_ms": 1000 * _percentile(latencies, 0.50),
        "p99_ms": 1000 * _percentile(latencies, 0.99),
    }


def _median_of_three(run) -> dict:
    runs = [run() for _ in range(3)]
    return {key: statistics.median(r[key] for r in runs) for key in runs[0]}


@pytest.mark.parametrize(("n_pub", "n_sub"), TOPOLOGIES, ids=[f"{p}x{s}" for p, s in TOPOLOGIES])
def test_moosdb_flood(benchmark, moosdb, n_pub, n_sub):
    port, pid = moosdb
    per_pub = FLOOD_DELIVERIES // (n_pub * n_sub)
    result = benchmark.pedantic(
        lambda: _median_of_three(lambda: run_load(port, pid, n_pub, n_sub, per_pub)),
        rounds=1,
        iterations=1,
    )
    benchmark.extra_info.update(result)
    print(
        f"\n{n_pub} pub x {n_sub} sub flood: {result['per_second']:,.0f} notifications/s, "
        f"server CPU {result['server_cpu_us']:.2f} us/notification "
        f"({result['delivered']}/{result['expected']} delivered)"
    )


def test_moosdb_paced_latency(benchmark, moosdb):
    port, pid = moosdb
    count = int(PACED_RATE * PACED_SECONDS)
    result = benchmark.pedantic(
        lambda: _median_of_three(lambda: run_load(port, pid, 1, 1, count, PACED_RATE)),
        rounds=1,
        iterations=1,
    )
    benchmark.extra_info.update(result)
    print(
        f"\n1 pub x 1 sub paced at {PACED_RATE:.0f}/s: latency p50 {result['p50_ms']:.3f} ms, "
        f"p99 {result['p99_ms']:.3f} ms ({result['delivered']}/{result['expected']} delivered)"
    )


APP_FLOOD_RATE = 100_000
APP_FLOOD_SECONDS = 5.0


def _rss_bytes() -> int:
    return int(Path("/proc/self/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")


async def _app_flood(port: int) -> dict:
    from pygoby.moos.app import GobyMOOSApp
    from tests.moos.example_app import config_class as test_app_config

    class FloodApp(GobyMOOSApp):
        config_class = test_app_config()

        def __init__(self, cfg, **kwargs):
            super().__init__(cfg, **kwargs)
            self.handled = 0
            self.subscribe("FLOOD", self.on_flood)

        def on_flood(self, msg):
            self.handled += 1

    cfg = FloodApp.config_class()
    cfg.common.app_tick = 10
    cfg.common.log = False  # no log file in the working directory
    app = FloodApp(cfg, name=f"flood_app_{time.monotonic_ns()}", port=port)
    await app.start(connect_timeout=5.0)
    await asyncio.sleep(0.5)
    count = int(APP_FLOOD_RATE * APP_FLOOD_SECONDS)
    pub = _spawn(
        "pub",
        "--port",
        str(port),
        "--name",
        f"flooder_{time.monotonic_ns()}",
        "--var",
        "FLOOD",
        "--count",
        str(count),
        "--rate",
        str(APP_FLOOD_RATE),
        "--batch",
        "500",
    )
    await asyncio.to_thread(_wait_ready, [pub])
    rss = [_rss_bytes()]
    cpu0 = time.process_time()
    pub.stdin.write("go\n")
    pub.stdin.flush()
    while pub.poll() is None:
        await asyncio.sleep(0.25)
        rss.append(_rss_bytes())
    sent = _result(pub)
    behind = count - app.handled
    deadline = time.monotonic() + 30
    while app.handled < count and time.monotonic() < deadline:
        await asyncio.sleep(0.05)
    caught_up = time.monotonic() - sent["end"]
    cpu = time.process_time() - cpu0
    rss.append(_rss_bytes())
    await app.stop()
    return {
        "sent": sent["sent"],
        "offered_per_second": sent["sent"] / (sent["end"] - sent["start"]),
        "handled": app.handled,
        "app_cpu_us": 1e6 * cpu / max(app.handled, 1),
        "behind_at_end": behind,
        "caught_up_s": caught_up,
        "rss_start_mb": rss[0] / 2**20,
        "rss_1s_mb": rss[min(4, len(rss) - 1)] / 2**20,  # a second into the flood
        "rss_peak_mb": max(rss) / 2**20,
        "rss_end_mb": rss[-1] / 2**20,
    }


def test_goby_moos_app_under_a_flood(benchmark, moosdb):
    port, _ = moosdb
    result = benchmark.pedantic(lambda: asyncio.run(_app_flood(port)), rounds=1, iterations=1)
    benchmark.extra_info.update(result)
    print(
        f"\nGobyMOOSApp, {APP_FLOOD_RATE:,} notifications/s for {APP_FLOOD_SECONDS:g} s "
        f"({result['offered_per_second']:,.0f}/s offered): handled {result['handled']}/"
        f"{result['sent']} at {result['app_cpu_us']:.2f} us CPU each (client + app), "
        f"{result['behind_at_end']} behind when "
        f"the publisher stopped, all handled {result['caught_up_s']:.2f} s after; RSS "
        f"{result['rss_start_mb']:.1f} MB at start, {result['rss_1s_mb']:.1f} MB after 1 s, "
        f"{result['rss_peak_mb']:.1f} MB peak, {result['rss_end_mb']:.1f} MB at the end"
    )
