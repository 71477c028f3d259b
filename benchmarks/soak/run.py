"""`make soak`: the hostile-client and kill -9 scenarios of issue 16, each for a bounded time on
loopback, with their figures (requests answered, latency p50/p99, the server's RSS before and
after, messages lost). Not part of `make test`; exit status 1 when a scenario broke a promise
(a request unanswered, a freeze, memory growing without bound, a message lost, a process left
behind).

    .venv/bin/python -m benchmarks.soak.run [--seconds S] [--only TEXT] [--list]   # from the repository root
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import tempfile
import time
from pathlib import Path

from benchmarks.soak.kit import HEADER, Figures
from benchmarks.soak.scenarios import SCENARIOS


def time_limit(seconds: float) -> float:
    """What a scenario of `seconds` may take in all (start-up, final checks, restarts)."""
    return 4 * seconds + 90


async def run_one(name: str, seconds: float) -> Figures:
    figures = Figures()
    with tempfile.TemporaryDirectory(prefix="pygoby-soak-") as workdir:
        try:
            async with asyncio.timeout(time_limit(seconds)):
                return await SCENARIOS[name](seconds, Path(workdir))
        except TimeoutError:
            figures.failures.append(f"did not finish within {time_limit(seconds):g} s")
        except Exception as exc:  # a scenario that cannot run is a failure, not a crash of all
            figures.failures.append(f"scenario error: {type(exc).__name__}: {exc}")
    return figures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--seconds", type=float, default=20.0, help="per scenario (default %(default)s)"
    )
    parser.add_argument("--only", help="run the scenarios whose name contains this text")
    parser.add_argument("--list", action="store_true", help="list the scenarios and exit")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.CRITICAL)  # the clients' reconnect warnings are expected
    names = [n for n in SCENARIOS if args.only is None or args.only.lower() in n.lower()]
    if args.list:
        print("\n".join(names))
        return 0
    width = max(len(n) for n in names)
    print(f"soak: {len(names)} scenarios, {args.seconds:g} s each", flush=True)
    print(f"{'scenario':<{width}} {HEADER}  result", flush=True)
    failed = 0
    for name in names:
        started = time.monotonic()
        figures = asyncio.run(run_one(name, args.seconds))
        took = time.monotonic() - started
        verdict = "ok" if not figures.failures else "FAIL: " + "; ".join(figures.failures)
        print(f"{name:<{width}} {figures.line()}  {verdict}", flush=True)
        details = [*figures.notes, f"{took:.0f} s"]
        print(f"{'':<{width}}   ({'; '.join(details)})", flush=True)
        failed += bool(figures.failures)
    print(f"soak: {len(names) - failed} of {len(names)} scenarios kept every promise", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
