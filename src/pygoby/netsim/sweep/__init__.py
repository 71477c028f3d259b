"""Parameter sweeps of netsim scenarios: many independent, seeded discrete-event runs.

`plan` reads a sweep file and expands it into runs; `run` executes one run and tallies it per
link; `executors` run them on local processes or a Dask cluster; `store` keeps one Parquet file
per run (atomically) and the consolidated table; `engine` ties them together (resume, failures);
`report` draws the standard figures; `cli` is `pygoby netsim sweep` / `sweep-report`.
"""

from pygoby.util.modules import lazy_exports

# imported on first use: `pygoby netsim --help` must not import the simulator, pyarrow or Dask
__getattr__, __dir__ = lazy_exports(
    globals(),
    {
        "DaskExecutor": "pygoby.netsim.sweep.executors",
        "LocalExecutor": "pygoby.netsim.sweep.executors",
        "ResultStore": "pygoby.netsim.sweep.store",
        "RunResult": "pygoby.netsim.sweep.run",
        "RunSpec": "pygoby.netsim.sweep.plan",
        "SweepExecutorError": "pygoby.netsim.sweep.executors",
        "SweepOutcome": "pygoby.netsim.sweep.engine",
        "SweepPlan": "pygoby.netsim.sweep.plan",
        "execute_run": "pygoby.netsim.sweep.run",
        "plan_sweep": "pygoby.netsim.sweep.plan",
        "read_results": "pygoby.netsim.sweep.report",
        "results_schema": "pygoby.netsim.sweep.store",
        "run_sweep": "pygoby.netsim.sweep.engine",
        "write_sweep_report": "pygoby.netsim.sweep.report",
    },
)

__all__ = [
    "DaskExecutor",
    "LocalExecutor",
    "ResultStore",
    "RunResult",
    "RunSpec",
    "SweepExecutorError",
    "SweepOutcome",
    "SweepPlan",
    "execute_run",
    "plan_sweep",
    "read_results",
    "results_schema",
    "run_sweep",
    "write_sweep_report",
]
