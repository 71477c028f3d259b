"""Running a sweep plan: skip what is stored, execute the rest, store each run as it finishes.

`run_sweep(plan, store, executor, progress)` is what `pygoby netsim sweep` does. Runs already
in the store are not executed again (resume); each finished run is written at once (atomically),
so an interrupted sweep keeps every run that finished; the table is consolidated at the end.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from pygoby.util.extras import needs_extra

with needs_extra("sim", "netsim sweeps"):
    import pyarrow as pa

from pygoby.netsim.sweep.plan import RunSpec, SweepPlan
from pygoby.netsim.sweep.run import RunResult
from pygoby.netsim.sweep.store import ResultStore

log = logging.getLogger(__name__)

Progress = Callable[[int, int], None]  # (runs done, total)


@dataclass
class SweepOutcome:
    total: int
    already_stored: int
    executed: int = 0
    failed: dict[str, str] = field(default_factory=dict)  # run_id -> reason
    wall_s: float = 0.0
    table: pa.Table | None = None

    @property
    def stored(self) -> int:
        return self.already_stored + self.executed


def run_sweep(
    plan: SweepPlan, store: ResultStore, executor, progress: Progress | None = None
) -> SweepOutcome:
    stored = store.stored()
    todo = [r for r in plan.runs if r.run_id not in stored]
    outcome = SweepOutcome(total=len(plan.runs), already_stored=len(plan.runs) - len(todo))
    started = time.perf_counter()
    if progress is not None:
        progress(outcome.already_stored, outcome.total)

    def done(run: RunSpec, result: RunResult) -> None:
        store.write_run(run.run_id, result.rows)
        outcome.executed += 1
        if progress is not None:
            progress(outcome.stored + len(outcome.failed), outcome.total)

    def failed(run: RunSpec, reason: str) -> None:
        store.write_failure(run, reason)
        outcome.failed[run.run_id] = reason
        log.error(
            "run %s (point %d, seed %d) failed: %s",
            run.run_id,
            run.point,
            run.seed,
            reason.splitlines()[-1],
        )
        if progress is not None:
            progress(outcome.stored + len(outcome.failed), outcome.total)

    if todo:
        executor.run(todo, done, failed)
    outcome.wall_s = time.perf_counter() - started
    outcome.table = store.consolidate(plan.runs)
    return outcome
