"""Where a sweep's results live: one Parquet file per run, written atomically, and the table.

Layout of the output directory:

* `runs/<run_id>.parquet`: the rows of one finished run (written to a temporary file in the same
  directory, flushed to disk, then renamed: a file is there whole or not at all, so a sweep
  killed at any moment loses nothing that was stored and never leaves half a run);
* `failed/<run_id>.txt`: why a run failed (its own exception, or its worker died too often);
  removed when the run later succeeds;
* `results.parquet`: the tidy table of the sweep (every stored run of the current plan, in plan
  order), rewritten atomically at the end of `pygoby netsim sweep`;
* `sweep.pb.cfg`: a copy of the sweep file the table came from.

A run is identified by its run_id (a hash of its scenario and parameters), so starting the same
sweep again skips every run already in `runs/` and an edited sweep reuses the runs it shares.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable
from pathlib import Path

from pygoby.util.extras import needs_extra

with needs_extra("sim", "netsim sweeps"):
    import pyarrow as pa
    import pyarrow.parquet as pq

from pygoby.netsim.sweep.plan import AxisColumn, RunSpec

RESULTS_FILE = "results.parquet"  # the sweep's table, in its output folder

_ARROW = {int: pa.int64(), float: pa.float64(), bool: pa.bool_(), str: pa.string()}

HEAD_COLUMNS = [
    ("run_id", pa.string()),
    ("point", pa.int64()),
    ("replicate", pa.int64()),
    ("seed", pa.int64()),
]
TAIL_COLUMNS = [
    ("nodes", pa.int64()),
    ("duration_s", pa.float64()),
    ("src", pa.int64()),
    ("dest", pa.int64()),
    ("rate", pa.int64()),
    ("range_m", pa.float64()),
    ("sent", pa.int64()),
    ("frames_sent", pa.int64()),
    ("received", pa.int64()),
    ("good", pa.int64()),
    ("bad_frames", pa.int64()),
    ("not_detected", pa.int64()),
    ("receiver_busy", pa.int64()),
    ("half_duplex", pa.int64()),
    ("frames_good", pa.int64()),
    ("messages", pa.int64()),
    ("latency_mean_s", pa.float64()),
    ("latency_max_s", pa.float64()),
    ("acked", pa.int64()),
    ("snr_mean_db", pa.float64()),
    ("sinr_mean_db", pa.float64()),
    ("owtt_mean_s", pa.float64()),
    ("wall_s", pa.float64()),
]


def results_schema(columns: Iterable[AxisColumn]) -> pa.Schema:
    head = {name for name, _ in HEAD_COLUMNS}  # (a "seed" axis fills the seed column)
    axes = [(c.name, _ARROW[c.kind]) for c in columns if c.name not in head]
    return pa.schema(HEAD_COLUMNS + axes + TAIL_COLUMNS)


def _write_atomically(table: pa.Table, path: Path) -> None:
    fd, temporary = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            pq.write_table(table, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


class ResultStore:
    def __init__(self, directory: str | Path, schema: pa.Schema) -> None:
        self.directory = Path(directory)
        self.schema = schema
        self.runs_dir = self.directory / "runs"
        self.failed_dir = self.directory / "failed"
        self.runs_dir.mkdir(parents=True, exist_ok=True)
        self.failed_dir.mkdir(exist_ok=True)

    @property
    def table_path(self) -> Path:
        return self.directory / RESULTS_FILE

    def run_path(self, run_id: str) -> Path:
        return self.runs_dir / f"{run_id}.parquet"

    def stored(self) -> set[str]:
        """run_ids of every run stored whole."""
        return {p.stem for p in self.runs_dir.glob("*.parquet")}

    def write_run(self, run_id: str, rows: list[dict]) -> None:
        _write_atomically(pa.Table.from_pylist(rows, schema=self.schema), self.run_path(run_id))
        (self.failed_dir / f"{run_id}.txt").unlink(missing_ok=True)

    def write_failure(self, run: RunSpec, reason: str) -> None:
        params = ", ".join(f"{k}={v}" for k, v in run.params)
        path = self.failed_dir / f"{run.run_id}.txt"
        path.write_text(f"point {run.point} ({params}), seed {run.seed}\n{reason}\n")

    def failures(self) -> set[str]:
        return {p.stem for p in self.failed_dir.glob("*.txt")}

    def read_run(self, run_id: str) -> pa.Table:
        return pq.read_table(self.run_path(run_id), schema=self.schema)

    def consolidate(self, runs: Iterable[RunSpec]) -> pa.Table:
        """The table of every stored run of `runs` (in their order), written to results.parquet."""
        stored = self.stored()
        tables = [self.read_run(r.run_id) for r in runs if r.run_id in stored]
        table = pa.concat_tables(tables) if tables else self.schema.empty_table()
        _write_atomically(table, self.table_path)
        return table
