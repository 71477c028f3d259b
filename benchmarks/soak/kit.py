"""The soak's parts: real server processes on loopback, a measured client (a probe) beside
hostile clients, and the figures each scenario prints (requests answered, latency p99, the
server's RSS before and after, messages lost).

A hostile-client scenario is one line of `scenarios.SCENARIOS`:

    "name": hostile(SERVER_SPEC, probe, [Garbage(...), NonReader(...), Trickle(...)]),

SERVER_SPEC says how to start the server process and read its port; the probe talks to it the
way a real client does and counts what is answered; the hostiles misbehave at the same time.
"""

from __future__ import annotations

import asyncio
import contextlib
import re
import signal
import socket
import statistics
import sys
import time
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

VENV_BIN = Path(sys.executable).parent
FREEZE_SECONDS = 1.0  # a probe answered later than this: the server froze
RSS_GROWTH_LIMIT_MB = 100.0  # more under hostile clients: memory is not bounded
ANSWER_TIMEOUT = 10.0  # s a probe waits for one answer before counting it unanswered
STOP_WITHIN = 7.0  # s for a server to end after SIGTERM (pygoby.util.aiorun.STOP_GRACE + margin)


# -- figures ---------------------------------------------------------------------------------


@dataclass
class Figures:
    """What one scenario measured; `failures` says what broke the issue's promises."""

    requests: int = 0
    answered: int = 0
    latencies: list[float] = field(default_factory=list)  # s
    rss_before_mb: float | None = None
    rss_after_mb: float | None = None
    lost: int | None = None
    rss_peak_mb: float | None = None  # sampled while the hostiles ran
    given_ms: tuple[float | None, float | None] | None = None  # (p50, p99) measured elsewhere
    latency_limit: float = FREEZE_SECONDS  # s; a p99 above it breaks the scenario's promise
    notes: list[str] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)

    def answer(self, seconds: float) -> None:
        self.answered += 1
        self.latencies.append(seconds)

    @property
    def p99_ms(self) -> float | None:
        if not self.latencies:
            return self.given_ms[1] if self.given_ms else None
        ordered = sorted(self.latencies)
        return 1000 * ordered[min(len(ordered) - 1, int(0.99 * len(ordered)))]

    @property
    def p50_ms(self) -> float | None:
        if not self.latencies:
            return self.given_ms[0] if self.given_ms else None
        return 1000 * statistics.median(self.latencies)

    def judge(self) -> None:
        """The generic promises: every request answered, no freeze, bounded memory, no loss."""
        if self.answered < self.requests:
            self.failures.append(
                f"{self.requests - self.answered} of {self.requests} requests unanswered"
            )
        p99 = self.p99_ms
        if p99 is not None and p99 > 1000 * self.latency_limit:
            self.failures.append(f"latency p99 {p99:.0f} ms (more than {self.latency_limit:g} s)")
        if self.rss_before_mb is not None and self.rss_after_mb is not None:
            growth = self.rss_after_mb - self.rss_before_mb
            if growth > RSS_GROWTH_LIMIT_MB:
                self.failures.append(f"RSS grew {growth:.0f} MB")
        if self.lost:
            self.failures.append(f"{self.lost} messages lost")

    def line(self) -> str:
        def number(value: float | None, fmt: str) -> str:
            return "-" if value is None else format(value, fmt)

        rss = f"{number(self.rss_before_mb, '.0f')} -> {number(self.rss_after_mb, '.0f')}"
        return (
            f"{self.requests:>9} {self.answered:>9} {number(self.p50_ms, '.1f'):>8} "
            f"{number(self.p99_ms, '.1f'):>8} {rss:>12} {number(self.lost, 'd'):>5}"
        )


HEADER = f"{'requests':>9} {'answered':>9} {'p50 ms':>8} {'p99 ms':>8} {'RSS MB':>12} {'lost':>5}"


# -- processes -------------------------------------------------------------------------------


def rss_mb(pid: int) -> float | None:
    """Resident memory of a process (Linux /proc), MB."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        return None
    return None


@dataclass(frozen=True)
class ServerSpec:
    """How to run a server: its command (`{port}` is replaced, 0 = any) and the regex of the
    line (stdout or stderr) that gives the port it listens on."""

    name: str
    argv: Sequence[str]
    ready: str  # regex with one group: the port


class ServerProcess:
    def __init__(self, spec: ServerSpec, cwd: Path, port: int = 0) -> None:
        self.spec, self.cwd, self.requested_port = spec, cwd, port
        self.proc: asyncio.subprocess.Process | None = None
        self.port = 0
        self._drains: list[asyncio.Task[None]] = []

    async def start(self, timeout: float = 30.0) -> int:
        argv = [a.replace("{port}", str(self.requested_port)) for a in self.spec.argv]
        self.proc = await asyncio.create_subprocess_exec(
            *argv, cwd=self.cwd, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE
        )
        found: asyncio.Future[int] = asyncio.get_running_loop().create_future()
        for stream in (self.proc.stdout, self.proc.stderr):
            assert stream is not None
            self._drains.append(asyncio.create_task(self._drain(stream, found)))
        try:
            async with asyncio.timeout(timeout):
                self.port = await found
        except TimeoutError:
            await self.kill9()
            raise RuntimeError(f"{self.spec.name} did not start listening") from None
        self.requested_port = self.port  # a restart comes back on the same port
        return self.port

    async def _drain(self, stream: asyncio.StreamReader, found: asyncio.Future[int]) -> None:
        """Read everything the server writes (a full pipe would block it), looking for the port."""
        pattern = re.compile(self.spec.ready)
        text = ""
        while data := await stream.read(65536):
            if found.done():
                continue
            text = (text + data.decode(errors="replace"))[-4096:]
            if match := pattern.search(text):
                found.set_result(int(match.group(1)))

    @property
    def alive(self) -> bool:
        return self.proc is not None and self.proc.returncode is None

    def rss_mb(self) -> float | None:
        return rss_mb(self.proc.pid) if self.alive and self.proc is not None else None

    async def kill9(self) -> None:
        if self.alive and self.proc is not None:
            self.proc.send_signal(signal.SIGKILL)
            await self.proc.wait()
        if self._drains:  # they end at the pipes' EOF, which closes the pipes' transports
            _, pending = await asyncio.wait(self._drains, timeout=2.0)
            for task in pending:
                task.cancel()
        self._drains.clear()

    async def terminate(self) -> float | None:
        """SIGTERM; the seconds it took to end, or None (then it is killed)."""
        if not self.alive or self.proc is None:
            return None
        started = time.monotonic()
        self.proc.send_signal(signal.SIGTERM)
        try:
            async with asyncio.timeout(STOP_WITHIN):
                await self.proc.wait()
        except TimeoutError:
            await self.kill9()
            return None
        took = time.monotonic() - started
        await self.kill9()  # the drains
        return took


def venv_command(name: str, *args: str) -> list[str]:
    return [str(VENV_BIN / name), *args]


# -- hostile clients -------------------------------------------------------------------------


class Hostile:
    """A misbehaving client: `run(port, stop)` until `stop` is set."""

    async def run(self, port: int, stop: asyncio.Event) -> None:
        raise NotImplementedError


@dataclass
class Garbage(Hostile):
    """Writes each blob in turn, again and again, never reading (reconnects when dropped)."""

    blobs: Sequence[bytes]
    pause: float = 0.05

    async def run(self, port: int, stop: asyncio.Event) -> None:
        index = 0
        while not stop.is_set():
            with contextlib.suppress(OSError):
                _, writer = await asyncio.open_connection("127.0.0.1", port)
                try:
                    while not stop.is_set():
                        writer.write(self.blobs[index % len(self.blobs)])
                        index += 1
                        await writer.drain()
                        await asyncio.sleep(self.pause)
                finally:
                    writer.transport.abort()
            await asyncio.sleep(self.pause)


@dataclass
class NonReader(Hostile):
    """Sends `request` (e.g. a subscription) now and then and never reads what comes back."""

    request: bytes
    period: float = 0.01

    async def run(self, port: int, stop: asyncio.Event) -> None:
        with contextlib.suppress(OSError):
            _, writer = await asyncio.open_connection("127.0.0.1", port)
            writer.get_extra_info("socket").setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            try:
                while not stop.is_set() and not writer.is_closing():
                    writer.write(self.request)
                    await asyncio.sleep(self.period)
            finally:
                writer.transport.abort()


@dataclass
class Trickle(Hostile):
    """Sends `prefix`, then one byte every `period` s: never silent, never finished."""

    prefix: bytes
    period: float = 0.5

    async def run(self, port: int, stop: asyncio.Event) -> None:
        while not stop.is_set():
            with contextlib.suppress(OSError):
                _, writer = await asyncio.open_connection("127.0.0.1", port)
                try:
                    writer.write(self.prefix)
                    while not stop.is_set() and not writer.is_closing():
                        await asyncio.sleep(self.period)
                        writer.write(b"\0")
                        await writer.drain()
                finally:
                    writer.transport.abort()
            await asyncio.sleep(self.period)


@dataclass
class IdleConnections(Hostile):
    """Opens `count` connections that say nothing."""

    count: int

    async def run(self, port: int, stop: asyncio.Event) -> None:
        writers = []
        try:
            for _ in range(self.count):
                with contextlib.suppress(OSError):
                    writers.append((await asyncio.open_connection("127.0.0.1", port))[1])
            await stop.wait()
        finally:
            for writer in writers:
                writer.transport.abort()


# -- the generic hostile-client scenario -----------------------------------------------------

Probe = Callable[[int, float, Figures], Awaitable[None]]  # (port, seconds, figures)


def hostile(
    spec: ServerSpec, probe: Probe, hostiles: Sequence[Hostile]
) -> Callable[[float, Path], Awaitable[Figures]]:
    """A scenario: `spec`'s server, `probe` measuring it for the run's seconds while `hostiles`
    misbehave beside it; then SIGTERM must end the server."""

    async def scenario(seconds: float, workdir: Path) -> Figures:
        figures = Figures()
        server = ServerProcess(spec, workdir)
        port = await server.start()
        try:
            await probe(port, 1.0, Figures())  # warm-up, not counted
            figures.rss_before_mb = server.rss_mb()
            stop = asyncio.Event()
            sampler = asyncio.create_task(_sample_rss_peak(server, figures, stop))
            tasks = [asyncio.create_task(h.run(port, stop)) for h in hostiles]
            await asyncio.sleep(0.5)  # the hostiles are in
            await probe(port, seconds, figures)
            figures.rss_after_mb = server.rss_mb()
            stop.set()
            await sampler
            if figures.rss_peak_mb is not None:
                figures.notes.append(f"RSS peak {figures.rss_peak_mb:.0f} MB")
            # a hostile blocked writing to a server that stopped reading is cancelled
            _, pending = await asyncio.wait(tasks, timeout=1.0)
            for task in pending:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
            await stop_or_fail(server, figures)
        finally:
            await server.kill9()
        figures.judge()
        return figures

    return scenario


async def _sample_rss_peak(server: ServerProcess, figures: Figures, stop: asyncio.Event) -> None:
    while not stop.is_set():
        rss = server.rss_mb()
        if rss is not None:
            figures.rss_peak_mb = max(rss, figures.rss_peak_mb or 0.0)
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(0.1):
                await stop.wait()


async def stop_or_fail(server: ServerProcess, figures: Figures) -> None:
    """SIGTERM must end a server that is still alive within STOP_WITHIN s."""
    if not server.alive:
        figures.failures.append(f"{server.spec.name} died")
        return
    took = await server.terminate()
    if took is None:
        figures.failures.append(
            f"{server.spec.name} did not end within {STOP_WITHIN:g} s of SIGTERM"
        )
    else:
        figures.notes.append(f"ended {took:.2f} s after SIGTERM")


async def paced(seconds: float, period: float, step: Callable[[int], Awaitable[None]]) -> None:
    """Call `step(k)` every `period` s for `seconds` (each step may take longer: no overlap)."""
    loop = asyncio.get_running_loop()
    begin = loop.time()
    k = 0
    while loop.time() - begin < seconds:
        await step(k)
        k += 1
        await asyncio.sleep(max(0.0, begin + k * period - loop.time()))
