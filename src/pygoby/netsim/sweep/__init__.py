"""Parameter sweeps of netsim scenarios: many independent, seeded discrete-event runs.

`plan` reads a sweep file and expands it into runs; `run` executes one run and tallies it per
link; `executors` run them on local processes or a Dask cluster; `store` keeps one Parquet file
per run (atomically) and the consolidated table; `engine` ties them together (resume, failures);
`report` draws the standard figures; `cli` is `pygoby netsim sweep` / `sweep-report`.
"""
