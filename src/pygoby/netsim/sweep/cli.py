"""`pygoby netsim sweep SWEEP_FILE` and `pygoby netsim sweep-report RESULTS -o DIR`.

`sweep` expands a sweep file (`pygoby.netsim.protobuf.Sweep`, TextFormat: a base scenario, axes
over its fields, grid or random sampling, seeds) into independent discrete-event runs, runs the
ones not yet stored on local processes (all cores; `--jobs N`) or on a Dask cluster
(`--cluster tcp://HOST:8786`), stores each run as it finishes and writes the tidy table
`OUTPUT/results.parquet` (one row per run and link). Started again, it resumes: stored runs are
not run again. `sweep-report` draws the standard figures (PNG) and an HTML page from a table.
"""

from __future__ import annotations

import argparse
import logging
import shutil
import sys
from pathlib import Path

from pygoby.util.progress import RunProgress


def add_subcommands(subparsers: argparse._SubParsersAction) -> None:
    sweep = subparsers.add_parser(
        "sweep",
        help="run a parameter sweep of scenarios (resumable; local or Dask cluster)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sweep.add_argument("sweep_file", help="sweep file (protobuf TextFormat, see examples/netsim)")
    sweep.add_argument("-o", "--output", help="results directory (default: the file's output)")
    where = sweep.add_mutually_exclusive_group()
    where.add_argument(
        "-j",
        "--jobs",
        type=int,
        help="local worker processes (default: all cores; 1: in this process)",
    )
    where.add_argument(
        "--cluster", metavar="tcp://HOST:PORT", help="Dask distributed scheduler to run on instead"
    )
    sweep.add_argument("--dry-run", action="store_true", help="list the runs, run nothing")
    sweep.add_argument("-v", "--verbose", action="count", default=0)
    sweep.set_defaults(func=sweep_command)
    report = subparsers.add_parser(
        "sweep-report", help="figures (PNG) and an HTML page from a sweep's results"
    )
    report.add_argument("results", help="results directory or results.parquet")
    report.add_argument("-o", "--output", help="report directory (default: RESULTS/report)")
    report.set_defaults(func=sweep_report_command)


def _fail(command: str, message: str, code: int = 1) -> int:
    print(f"pygoby netsim {command}: {message}", file=sys.stderr)
    return code


def sweep_command(args: argparse.Namespace) -> int:
    from pygoby.netsim.errors import ScenarioError
    from pygoby.netsim.sweep.engine import run_sweep
    from pygoby.netsim.sweep.executors import DaskExecutor, LocalExecutor, SweepExecutorError
    from pygoby.netsim.sweep.plan import plan_sweep
    from pygoby.netsim.sweep.store import ResultStore, results_schema

    logging.basicConfig(
        level=logging.WARNING - 10 * args.verbose,
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    try:
        plan = plan_sweep(args.sweep_file)
    except ScenarioError as exc:
        return _fail("sweep", str(exc))
    output = Path(args.output or plan.output)
    if args.dry_run:
        for run in plan.runs:
            params = ", ".join(f"{k}={v}" for k, v in run.params)
            print(f"{run.run_id}  point {run.point:4d}  seed {run.seed:4d}  {params}")
        print(f"{len(plan.runs)} runs; results would go to {output}")
        return 0
    if args.jobs is not None and args.jobs < 1:
        return _fail("sweep", "--jobs must be at least 1", 2)
    executor = DaskExecutor(args.cluster) if args.cluster else LocalExecutor(args.jobs)
    try:
        store = ResultStore(output, results_schema(plan.columns))
        shutil.copyfile(args.sweep_file, output / "sweep.pb.cfg")
    except OSError as exc:
        return _fail("sweep", f"cannot write to {output}: {exc.strerror}")
    print(
        f"sweep: {len(plan.runs)} runs on {executor.description}; results in {output}", flush=True
    )
    try:
        with RunProgress("sweep", unit="runs") as progress:
            outcome = run_sweep(
                plan, store, executor, lambda done, total: progress.update(done, total)
            )
    except KeyboardInterrupt:
        stored = len(store.stored() & {r.run_id for r in plan.runs})
        print(
            f"\ninterrupted: {stored} of {len(plan.runs)} runs are stored in {output}; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    except SweepExecutorError as exc:
        return _fail("sweep", str(exc))
    rate = outcome.executed / outcome.wall_s if outcome.wall_s > 0 else 0.0
    print(
        f"sweep: {outcome.total} runs: {outcome.executed} run now, {outcome.already_stored} "
        f"already stored, {len(outcome.failed)} failed; {outcome.wall_s:.1f} s "
        f"({rate:.2f} runs/s)"
    )
    rows = outcome.table.num_rows if outcome.table is not None else 0
    print(f"results: {store.table_path} ({rows} rows)")
    if outcome.failed:
        print(
            f"failed runs (reasons in {store.failed_dir}): {', '.join(sorted(outcome.failed))}",
            file=sys.stderr,
        )
        return 1
    return 0


def sweep_report_command(args: argparse.Namespace) -> int:
    from pygoby.netsim.sweep.report import read_results, results_path, write_sweep_report
    from pygoby.netsim.sweep.store import RESULTS_FILE

    source = Path(args.results)
    table_path = results_path(source)
    if not table_path.is_file():
        missing = (
            f"no {RESULTS_FILE} in {source}" if source.is_dir() else f"{source} does not exist"
        )
        return _fail(
            "sweep-report",
            f"{missing}: give the output folder of `pygoby netsim sweep` "
            f"(it writes {RESULTS_FILE} there); run the sweep first",
        )
    try:
        table = read_results(table_path)
    except OSError as exc:
        return _fail("sweep-report", f"cannot read {table_path}: {exc}")
    if table.num_rows == 0:
        return _fail("sweep-report", f"no results in {source}")
    out = (
        Path(args.output)
        if args.output
        else (source if source.is_dir() else source.parent) / "report"
    )
    for path in write_sweep_report(table, out):
        print(f"wrote {path}")
    return 0
