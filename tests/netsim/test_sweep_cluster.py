"""`pygoby netsim sweep --cluster`: a real Dask cluster on loopback (a scheduler and two workers,
separate processes started here) gives the same table as local processes; a worker killed
mid-sweep has its run moved to the other; a sweep client killed mid-sweep resumes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from pygoby.cli import main
from tests.netsim.sweep_helpers import (
    deterministic,
    kill_group,
    kill_when_stored,
    read_table,
    resume,
    start_sweep,
    stored_runs,
    wait_for,
    write_sweep,
)

pytestmark = pytest.mark.e2e

distributed = pytest.importorskip("distributed")  # (installed by `make test`: pygoby[dev])


def _dask(*args: str, cwd) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", *args],
        cwd=cwd,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """(scheduler address, {worker address: worker process}, a Client of our own)."""
    directory = tmp_path_factory.mktemp("dask")
    scheduler_file = directory / "scheduler.json"
    scheduler = _dask(
        "distributed.cli.dask_scheduler",
        "--host",
        "127.0.0.1",
        "--port",
        "0",
        "--no-dashboard",
        "--scheduler-file",
        str(scheduler_file),
        cwd=directory,
    )
    processes = [scheduler]
    try:
        wait_for(scheduler_file.exists, 60, "the Dask scheduler", interval=0.1)
        address = ""
        while not address:  # (the file may be caught half-written)
            try:
                address = json.loads(scheduler_file.read_text())["address"]
            except (json.JSONDecodeError, KeyError):
                time.sleep(0.05)
        for _ in range(2):
            processes.append(
                _dask(
                    "distributed.cli.dask_worker",
                    address,
                    "--nthreads",
                    "1",
                    "--no-nanny",
                    "--no-dashboard",
                    "--host",
                    "127.0.0.1",
                    "--local-directory",
                    str(directory),
                    cwd=directory,
                )
            )
        client = distributed.Client(address, timeout=60, set_as_default=False)
        client.wait_for_workers(2, timeout=60)
        pids = client.run(os.getpid)
        workers = {addr: next(p for p in processes if p.pid == pid) for addr, pid in pids.items()}
        yield address, workers, client
        client.close()
    finally:
        for process in processes:
            if process.poll() is None:
                process.terminate()
        for process in processes:
            try:  # (a worker whose scheduler has gone can sit out its reconnect time: no need)
                process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The sweep's table from one local process."""
    directory = tmp_path_factory.mktemp("reference")
    sweep = write_sweep(directory, duration=1800, replicates=1)  # 8 runs of 3 nodes
    assert main(["netsim", "sweep", str(sweep), "-o", str(directory / "out"), "--jobs", "1"]) == 0
    return deterministic(read_table(directory / "out"))


def test_cluster_sweep_gives_the_local_table(cluster, reference, tmp_path, capsys):
    address, _, _ = cluster
    sweep = write_sweep(tmp_path, duration=1800, replicates=1)
    assert (
        main(["netsim", "sweep", str(sweep), "-o", str(tmp_path / "out"), "--cluster", address])
        == 0
    )
    assert f"8 runs on Dask cluster {address}" in capsys.readouterr().out
    assert deterministic(read_table(tmp_path / "out")).equals(reference)


def test_cluster_sweep_resumes_after_its_client_is_killed(cluster, reference, tmp_path):
    address, _, _ = cluster
    sweep = write_sweep(tmp_path, duration=1800, replicates=1)
    output = tmp_path / "out"
    before = kill_when_stored(start_sweep(sweep, "--cluster", address, cwd=tmp_path), output, 2)
    assert 2 <= len(before) < 8
    resume(sweep, "--cluster", address, cwd=tmp_path, output=output, before=before, total=8)
    assert deterministic(read_table(output)).equals(reference)


def test_a_killed_cluster_worker_has_its_run_retried_elsewhere(cluster, reference, tmp_path):
    address, workers, client = cluster
    sweep = write_sweep(tmp_path, duration=1800, replicates=1)
    output = tmp_path / "out"
    process = start_sweep(sweep, "--cluster", address, cwd=tmp_path)
    try:
        busy: dict = {}

        def a_worker_is_running_a_run() -> bool:
            busy.clear()
            busy.update(
                {
                    w: keys
                    for w, keys in client.processing().items()
                    if any(str(k).startswith("netsim-run-") for k in keys)
                }
            )
            return bool(busy) and len(stored_runs(output)) >= 1

        wait_for(a_worker_is_running_a_run, 120, "a run in progress", interval=0.05)
        victim = sorted(busy)[0]
        running = {str(k).removeprefix("netsim-run-") for k in busy[victim]}
        workers[victim].send_signal(signal.SIGKILL)  # a worker machine lost mid-run
        workers[victim].wait(timeout=30)
        out, err = process.communicate(timeout=180)
    finally:
        kill_group(process)
    assert process.returncode == 0, err
    assert "8 run now, 0 already stored, 0 failed" in out
    assert running <= stored_runs(output), "the killed worker's run was run again elsewhere"
    assert len(client.scheduler_info()["workers"]) == 1
    assert deterministic(read_table(output)).equals(reference)


def test_no_scheduler_at_the_address_is_a_clear_error(tmp_path):
    from pygoby.netsim.sweep import DaskExecutor, SweepExecutorError, plan_sweep

    plan = plan_sweep(write_sweep(tmp_path, replicates=1))
    with pytest.raises(
        SweepExecutorError, match="cannot connect to the scheduler tcp://127.0.0.1:9"
    ):
        DaskExecutor("tcp://127.0.0.1:9", connect_timeout=1).run(plan.runs, None, None)
