"""Where a sweep's runs execute: local worker processes (default) or a Dask cluster.

Both hand each `RunSpec` to `execute_run` somewhere and report every outcome back to the
process that stores the results (so cluster workers need no shared file system):
``executor.run(runs, done=..., failed=...)`` calls `done(run, result)` for each finished run and
`failed(run, reason)` for each run that raised (a simulation error is deterministic: it is not
run again) or whose worker died `max_attempts` times.

* `LocalExecutor(jobs)`: a `concurrent.futures.ProcessPoolExecutor` of `jobs` processes (all
  cores by default) with `jobs` runs in flight at a time; if a worker process dies the pool is
  replaced and the runs that were in flight are submitted again. `jobs=1` runs everything in
  this process, one after the other (no pool: the baseline of `make bench`).
* `DaskExecutor(address)`: a Dask distributed client of an existing scheduler
  (``dask scheduler`` / ``dask worker tcp://HOST:8786`` with pygoby installed on every worker).
  The scheduler itself moves the runs of a worker that dies to the others (up to its
  `distributed.scheduler.allowed-failures` times, 3 by default, then `KilledWorker`).
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import traceback
from collections import Counter
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from pygoby.netsim.errors import NetsimError
from pygoby.netsim.sweep.plan import RunSpec
from pygoby.netsim.sweep.run import RunResult, execute_run
from pygoby.util.errors import MissingExtraError
from pygoby.util.extras import needs_extra

log = logging.getLogger(__name__)

Done = Callable[[RunSpec, RunResult], None]
Failed = Callable[[RunSpec, str], None]
MAX_ATTEMPTS = 3


class SweepExecutorError(NetsimError):
    """The executor cannot run at all (no cluster at that address, engine not installed)."""


def _error_text(exc: BaseException) -> str:
    return "".join(traceback.format_exception(exc)).rstrip()


def default_jobs() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


class LocalExecutor:
    def __init__(self, jobs: int | None = None, max_attempts: int = MAX_ATTEMPTS) -> None:
        self.jobs = jobs if jobs is not None else default_jobs()
        if self.jobs < 1:
            raise ValueError("jobs must be at least 1")
        self.max_attempts = max_attempts
        self.description = f"{self.jobs} local process{'es' if self.jobs > 1 else ''}"

    def run(self, runs: Iterable[RunSpec], done: Done, failed: Failed) -> None:
        runs = list(runs)
        if self.jobs == 1:
            for run in runs:
                try:
                    result = execute_run(run)
                except Exception as exc:  # a run's own failure is reported, the sweep goes on
                    failed(run, _error_text(exc))
                else:
                    done(run, result)
            return
        attempts: Counter = Counter()
        queue = list(reversed(runs))  # pop() takes them in plan order
        while queue:
            queue = self._run_pool(queue, attempts, done, failed)

    def _run_pool(self, queue: list[RunSpec], attempts: Counter, done: Done, failed: Failed):
        """Run until the queue is empty (returns []) or a worker dies (returns what is left,
        the runs that were in flight first)."""
        # forkserver: workers fork from a clean server that has imported the simulator once
        # (not from this process, whose progress display runs a thread)
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["pygoby.netsim.sweep.run"])
        pool = ProcessPoolExecutor(max_workers=self.jobs, mp_context=context)
        in_flight: dict[Future, RunSpec] = {}
        try:
            broken = False
            while (queue or in_flight) and not broken:
                while queue and len(in_flight) < self.jobs:
                    run = queue.pop()
                    try:
                        in_flight[pool.submit(execute_run, run)] = run
                    except BrokenProcessPool:  # a worker died since the last wait
                        queue.append(run)  # (never started)
                        broken = True
                        break
                if broken:
                    break
                finished, _ = wait(in_flight, return_when=FIRST_COMPLETED)
                for future in finished:
                    if isinstance(future.exception(), BrokenProcessPool):
                        broken = True  # the run stays in flight: it runs again
                        continue
                    run = in_flight.pop(future)
                    if (error := future.exception()) is not None:
                        failed(run, _error_text(error))
                    else:
                        done(run, future.result())
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown(wait=True, cancel_futures=True)
        if not broken:
            return []
        retry = []
        for future, run in list(in_flight.items()):  # finished while the pool broke
            if future.done() and not future.cancelled() and future.exception() is None:
                done(run, future.result())
                del in_flight[future]
        for run in in_flight.values():
            attempts[run.run_id] += 1
            if attempts[run.run_id] >= self.max_attempts:
                failed(run, f"its worker process died {attempts[run.run_id]} times")
            else:
                retry.append(run)
        log.warning("a worker process died; %d run(s) in flight will run again", len(retry))
        return queue + list(reversed(retry))


class DaskExecutor:
    def __init__(self, address: str, connect_timeout: float = 30.0) -> None:
        self.address = address
        self.connect_timeout = connect_timeout
        self.description = f"Dask cluster {address}"

    def run(self, runs: Iterable[RunSpec], done: Done, failed: Failed) -> None:
        try:
            with needs_extra("cluster", "--cluster (Dask distributed)"):
                from distributed import Client, as_completed
        except MissingExtraError as exc:
            raise SweepExecutorError(str(exc)) from None
        try:
            client = Client(self.address, timeout=self.connect_timeout, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise SweepExecutorError(
                f"cannot connect to the scheduler {self.address}: {exc}"
            ) from None
        with client:
            futures = {
                client.submit(execute_run, run, key=f"netsim-run-{run.run_id}", pure=False): run
                for run in runs
            }
            try:
                for future in as_completed(futures, loop=client.loop):
                    run = futures[future]
                    try:
                        result = future.result()
                    except Exception as exc:  # the run's own error, or KilledWorker
                        failed(run, _error_text(exc))
                    else:
                        done(run, result)
                    future.release()
            except BaseException:
                client.cancel(list(futures))
                raise
