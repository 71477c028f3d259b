"""run_until_signal: SIGINT or SIGTERM cancels the program's coroutine, whose cleanup runs,
and the process exits 0 without a traceback; a cleanup that hangs cannot keep it alive.
cancel_and_wait: the caller's own cancellation is never swallowed."""

from __future__ import annotations

import asyncio
import signal
import subprocess
import sys
import time

import pytest

from pygoby.util.aiorun import STOP_GRACE, cancel_and_wait

pytestmark = pytest.mark.e2e

PROGRAM = """
import asyncio, sys, time
from pygoby.util.aiorun import run_until_signal

async def serve():
    try:
        print("ready", flush=True)
        await asyncio.Future()
    finally:
        CLEANUP

run_until_signal(serve(), name="a_server")
"""
CLEAN = 'print("closed", flush=True)'
STUCK = "time.sleep(3600)  # a cleanup that blocks the event loop"
CHOKED = 'sys.stderr.write("x" * 10_000_000); sys.stderr.flush()  # into a pipe nobody reads'


def signalled(
    cleanup: str, signum: int, read_stderr: bool = True
) -> tuple[subprocess.Popen, str, float]:
    """The program with `cleanup`, sent `signum` once ready: (process, stderr, seconds to end)."""
    proc = subprocess.Popen(
        [sys.executable, "-c", PROGRAM.replace("CLEANUP", cleanup)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline() == "ready\n"
        started = time.monotonic()
        proc.send_signal(signum)
        if not read_stderr:  # stderr stays full until the process has ended
            proc.wait(timeout=STOP_GRACE + 5)
        _, err = proc.communicate(timeout=STOP_GRACE + 5)
        return proc, err, time.monotonic() - started
    finally:
        proc.kill()


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_ends_the_program_cleanly(signum):
    proc, err, _ = signalled(CLEAN, signum)
    assert (proc.returncode, err) == (0, "")


def test_an_error_of_the_program_propagates():
    from pygoby.util.aiorun import run_until_signal

    async def fails():
        raise OSError("address in use")

    with pytest.raises(OSError, match="address in use"):
        run_until_signal(fails())


def test_a_program_whose_cleanup_hangs_still_ends_after_the_grace():
    proc, err, took = signalled(STUCK, signal.SIGTERM)
    assert took >= STOP_GRACE
    assert proc.returncode == 128 + signal.SIGTERM
    assert err == f"a_server: did not stop within {STOP_GRACE:g} s; exiting now\n"


def test_a_program_blocked_on_a_full_stderr_pipe_still_ends():
    proc, _, _ = signalled(CHOKED, signal.SIGTERM, read_stderr=False)
    assert proc.returncode == 128 + signal.SIGTERM


async def test_cancel_and_wait_does_not_swallow_the_callers_cancellation():
    async def obstinate():  # needs a while to wind up when cancelled
        try:
            await asyncio.Future()
        finally:
            await asyncio.sleep(0.2)

    async def closer(task):
        await cancel_and_wait(task)
        return "went on after being cancelled"

    worker = asyncio.ensure_future(obstinate())
    await asyncio.sleep(0)
    closing = asyncio.ensure_future(closer(worker))
    await asyncio.sleep(0.01)
    closing.cancel()  # the caller is cancelled while it waits for the worker's end
    with pytest.raises(asyncio.CancelledError):
        await closing
    await asyncio.wait({worker})
    assert worker.cancelled()


async def test_cancel_and_wait_raises_what_the_task_failed_with():
    async def fails_on_cancel():
        try:
            await asyncio.Future()
        except asyncio.CancelledError:
            raise OSError("disk gone") from None

    task = asyncio.ensure_future(fails_on_cancel())
    await asyncio.sleep(0)
    with pytest.raises(OSError, match="disk gone"):
        await cancel_and_wait(task)
    await cancel_and_wait(None)
