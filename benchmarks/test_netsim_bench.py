"""netsim_manager under load: 64 clients each sending 10 NavUpdates per second to one manager
process, measuring the response latency (p50 / p99 / max) and the share of requests answered.

`make bench` runs the short run (5 s) and the full 60 s run of the issue. A run with garbage clients alongside checks that
bad input does not cost the well-behaved clients their answers.
"""

from __future__ import annotations

import asyncio
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

from pygoby.netsim.manager.client import NetSimClient
from pygoby.netsim.manager.protocol import encode_line, request_class

CLIENTS = 64
RATE_HZ = 10.0
FIRST_PORT = 62000


def _config(tmp_path: Path) -> Path:
    pairs = "".join(
        f'sim_env_pair {{ modem_tcp_port: {FIRST_PORT + i} endpoint_ip_address: "127.0.0.1" '
        "environment_id: 0 }\n"
        for i in range(CLIENTS)
    )
    bounds = "env_bounds { environment_id: 0 lat_min: 41 lon_min: -71 lat_max: 43 lon_max: -69 "
    path = tmp_path / "manager.pb.cfg"
    path.write_text(pairs + bounds + "depth_max: 500 }\n")
    return path


class ManagerProcess:
    """`netsim_manager` in its own process on an ephemeral loopback port."""

    def __init__(self, config: Path) -> None:
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "pygoby.netsim.manager.server",
                str(config),
                "--listen",
                "127.0.0.1",
                "--port",
                "0",
                "-v",
            ],
            stderr=subprocess.PIPE,
            text=True,
        )
        deadline = time.monotonic() + 30
        self.port = 0
        while time.monotonic() < deadline:
            line = self.process.stderr.readline()
            found = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
            if found:
                self.port = int(found.group(1))
                break
        assert self.port, "netsim_manager did not start"
        # Keep draining its log so the pipe never blocks it.
        self._drain = subprocess.Popen(
            ["cat"], stdin=self.process.stderr, stdout=subprocess.DEVNULL
        )

    def stop(self) -> None:
        self.process.terminate()
        self.process.wait(10)
        self._drain.wait(10)

    def alive(self) -> bool:
        return self.process.poll() is None


async def _vehicle(
    port: int, modem_port: int, duration: float, phase: float, latencies: list, counts: dict
) -> None:
    sent_at: dict[int, float] = {}

    def on_response(response) -> None:
        start = sent_at.pop(response.request_id, None)
        if start is not None and response.status == response.UPDATE_ACCEPTED:
            latencies.append(time.perf_counter() - start)
            counts["answered"] += 1

    client = NetSimClient("127.0.0.1", port, on_response=on_response)
    await client.start()
    await client.wait_connected(10)
    await asyncio.sleep(phase)
    period = 1.0 / RATE_HZ
    begin = time.perf_counter()
    k = 0
    while (next_time := begin + k * period) < begin + duration:
        await asyncio.sleep(max(0.0, next_time - time.perf_counter()))
        nav = NetSimClient.nav(
            modem_tcp_port=modem_port,
            time=time.time(),
            lat=42.0 + 1e-5 * k,
            lon=-70.0,
            depth=10.0,
            speed=1.0,
            heading=90.0,
        )
        request = client.tracker.build([nav])
        sent_at[request.id] = time.perf_counter()
        assert client.send_request(request) is not None
        counts["sent"] += 1
        k += 1
    for _ in range(100):  # wait up to 1 s for the last answers
        if not sent_at:
            break
        await asyncio.sleep(0.01)
    await client.close()


async def _garbage(port: int, stop: asyncio.Event) -> None:
    _reader, writer = await asyncio.open_connection("127.0.0.1", port)
    blobs = [
        os.urandom(65536),
        b"Z" * (1 << 20),
        b"no separators\n" * 1000,
        b"NETSIM|netsim.protobuf.Nope|CAA=\n" * 500,
        b"NETSIM|netsim.protobuf.NetSimManagerRequest|**not base64**\n" * 500,
    ]
    i = 0
    while not stop.is_set():
        writer.write(blobs[i % len(blobs)])
        await writer.drain()
        i += 1
        if i % len(blobs) == 1 and i > len(blobs):  # 10 MiB without a newline, then resync
            for _ in range(10):
                writer.write(b"Y" * (1 << 20))
            writer.write(b"\n")
        await asyncio.sleep(0.05)
    writer.close()


async def _load(port: int, duration: float, garbage_clients: int = 0) -> dict:
    latencies: list[float] = []
    counts = {"sent": 0, "answered": 0}
    stop = asyncio.Event()
    garbage = [asyncio.create_task(_garbage(port, stop)) for _ in range(garbage_clients)]
    await asyncio.gather(
        *(
            _vehicle(port, FIRST_PORT + i, duration, i / CLIENTS / RATE_HZ, latencies, counts)
            for i in range(CLIENTS)
        )
    )
    stop.set()
    await asyncio.gather(*garbage, return_exceptions=True)
    latencies.sort()
    n = len(latencies)
    return {
        "sent": counts["sent"],
        "answered": counts["answered"],
        "success_rate": counts["answered"] / counts["sent"] if counts["sent"] else 0.0,
        "p50_ms": 1000 * statistics.median(latencies) if n else None,
        "p99_ms": 1000 * latencies[min(n - 1, int(0.99 * n))] if n else None,
        "max_ms": 1000 * latencies[-1] if n else None,
    }


def _run_load(benchmark, tmp_path, duration: float, garbage_clients: int = 0) -> dict:
    manager = ManagerProcess(_config(tmp_path))
    try:
        result = benchmark.pedantic(
            lambda: asyncio.run(_load(manager.port, duration, garbage_clients)),
            rounds=1,
            iterations=1,
        )
        assert manager.alive(), "netsim_manager died under load"
    finally:
        manager.stop()
    benchmark.extra_info.update(result)
    print(
        f"\n{CLIENTS} clients x {RATE_HZ:g} Hz x {duration:g} s, {garbage_clients} garbage: "
        f"{result}"
    )
    assert result["sent"] >= CLIENTS * RATE_HZ * duration * 0.95
    assert result["answered"] == result["sent"]
    return result


def test_manager_load_short(benchmark, tmp_path):
    _run_load(benchmark, tmp_path, duration=5.0)


def test_manager_load_short_with_garbage_clients(benchmark, tmp_path):
    _run_load(benchmark, tmp_path, duration=5.0, garbage_clients=4)


def test_manager_load_full_60s(benchmark, tmp_path):
    _run_load(benchmark, tmp_path, duration=60.0)


def test_channel_transmit_and_poll_8_nodes(benchmark):
    from pygoby.netsim.channel import Channel, ChannelConfig, NavFix, Transmission

    def run() -> int:
        channel = Channel(ChannelConfig(), seed=1)
        delivered = 0
        for k in range(50):
            for i in range(8):  # fresh positions (1 km apart, moving) before each transmission
                position = NavFix(42.0 + 0.009 * i, -70.0, 10.0, 10.0 * k, 1.5, 45.0 * i)
                channel.update_position(62000 + i, position)
            channel.transmit(Transmission(62000 + k % 8, 10.0 * k, rate=1, frames=3))
            delivered += len(channel.poll(10.0 * k + 9.9))
        return delivered

    assert benchmark(run) == 50 * 7


def test_line_decoder_throughput(benchmark):
    from pygoby.netsim.manager.protocol import LineDecoder, request_names

    request = request_class()(id=1)
    request.nav.add(modem_tcp_port=62000, time=1.7e9, lat=42, lon=-70, depth=1, speed=1, heading=0)
    stream = encode_line(request) * 1000

    def run() -> int:
        return len(LineDecoder(request_names()).feed(stream))

    assert benchmark(run) == 1000
