"""Throughput and latency through the embedded MOOSDB (run by `make bench`).

The DB runs as its own process (`pygoby moosdb`), as the C++ MOOSDB would; publishers and
subscribers are pygoby clients sharing one event loop in this process. Two runs per topology:

* flood: every publisher sends as fast as its client drains; figures are notifications
  delivered per second (summed over subscribers) and the latency under that load;
* paced: every publisher sends 200 notifications/s; latency p50/p99 at light load.

Latency = subscriber receive time - the message's time stamp (both the same wall clock).
Each figure is the median of three runs; they are printed and stored in the benchmark's
extra_info; nothing is asserted about them. The machine has 2 cores: the DB process and the
client process compete for them, so flood figures vary by +-30 % from run to run.
"""

from __future__ import annotations

import asyncio
import re
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pygoby.moos.client import MOOSClient

PYGOBY = str(Path(sys.executable).with_name("pygoby"))
TOPOLOGIES = [(1, 1), (4, 4), (1, 16)]


@pytest.fixture(scope="module")
def db_port():
    proc = subprocess.Popen([PYGOBY, "moosdb", "--port", "0"], stdout=subprocess.PIPE, text=True)
    match = re.search(r":(\d+)$", proc.stdout.readline().strip())
    assert match
    yield int(match.group(1))
    proc.send_signal(signal.SIGINT)
    proc.wait(10)


def _percentile(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    ordered = sorted(values)
    return ordered[min(int(q * len(ordered)), len(ordered) - 1)]


async def _run(port: int, n_pub: int, n_sub: int, per_pub: int, rate: float | None) -> dict:
    tag = f"{n_pub}x{n_sub}_{'flood' if rate is None else 'paced'}_{time.monotonic_ns()}"
    latencies: list[float] = []
    received = [0]

    def on_message(msg):
        received[0] += 1
        latencies.append(time.time() - msg.time)

    subs = [MOOSClient(f"sub{i}_{tag}", port=port, on_message=on_message) for i in range(n_sub)]
    pubs = [MOOSClient(f"pub{i}_{tag}", port=port) for i in range(n_pub)]
    for client in subs + pubs:
        await client.connect()
    var = f"BENCH_{tag}"
    for sub in subs:
        sub.subscribe(var)
        await sub.flush()
    await asyncio.sleep(0.3)
    expected = n_pub * per_pub * n_sub

    async def publish(client: MOOSClient) -> None:
        for i in range(per_pub):
            client.publish(var, float(i), time=time.time())
            if rate is not None:
                await asyncio.sleep(1.0 / rate)
            elif i % 200 == 199:
                await client.flush()

    start = time.perf_counter()
    await asyncio.gather(*(publish(c) for c in pubs))
    deadline = time.perf_counter() + 30
    while received[0] < expected and time.perf_counter() < deadline:
        await asyncio.sleep(0.005)
    elapsed = time.perf_counter() - start
    for client in subs + pubs:
        await client.close()
    return {
        "delivered": received[0],
        "expected": expected,
        "per_second": received[0] / elapsed,
        "p50_ms": 1000 * _percentile(latencies, 0.50),
        "p99_ms": 1000 * _percentile(latencies, 0.99),
        "mean_ms": 1000 * statistics.fmean(latencies) if latencies else float("nan"),
    }


@pytest.mark.parametrize(("n_pub", "n_sub"), TOPOLOGIES, ids=[f"{p}x{s}" for p, s in TOPOLOGIES])
@pytest.mark.parametrize("mode", ["flood", "paced"])
def test_moosdb_delivery(benchmark, db_port, n_pub, n_sub, mode):
    per_pub = 20_000 // n_pub if mode == "flood" else 400
    rate = None if mode == "flood" else 200.0

    def median_of_three():
        runs = [asyncio.run(_run(db_port, n_pub, n_sub, per_pub, rate)) for _ in range(3)]
        return {key: statistics.median(r[key] for r in runs) for key in runs[0]}

    result = benchmark.pedantic(median_of_three, rounds=1, iterations=1)
    benchmark.extra_info.update(result)
    print(
        f"\n{n_pub} pub x {n_sub} sub ({mode}): {result['per_second']:.0f} notifications/s, "
        f"latency p50 {result['p50_ms']:.2f} ms, p99 {result['p99_ms']:.2f} ms "
        f"({result['delivered']}/{result['expected']} delivered)"
    )
