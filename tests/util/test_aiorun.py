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

PROGRAM = """
import asyncio
from pygoby.util.aiorun import run_until_signal

async def serve():
    try:
        print("ready", flush=True)
        await asyncio.Future()
    finally:
        print("closed", flush=True)

run_until_signal(serve())
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_ends_the_program_cleanly(signum):
    proc = subprocess.Popen([sys.executable, "-c", PROGRAM], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        assert proc.stdout.readline() == "ready\n"
        proc.send_signal(signum)
        out, err = proc.communicate(timeout=10)
    finally:
        proc.kill()
    assert (proc.returncode, out, err) == (0, "closed\n", "")


def test_an_error_of_the_program_propagates():
    from pygoby.util.aiorun import run_until_signal

    async def fails():
        raise OSError("address in use")

    with pytest.raises(OSError, match="address in use"):
        run_until_signal(fails())


STUCK_PROGRAM = """
import asyncio, time
from pygoby.util.aiorun import run_until_signal

async def serve():
    try:
        print("ready", flush=True)
        await asyncio.Future()
    finally:
        time.sleep(3600)  # a cleanup that blocks the event loop

run_until_signal(serve(), name="stuck_server")
"""


def test_a_program_whose_cleanup_hangs_still_ends_after_the_grace():
    proc = subprocess.Popen([sys.executable, "-c", STUCK_PROGRAM], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        assert proc.stdout.readline() == "ready\n"
        started = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=STOP_GRACE + 10)
    finally:
        proc.kill()
    assert time.monotonic() - started >= STOP_GRACE
    assert proc.returncode == 128 + signal.SIGTERM
    assert err == f"stuck_server: did not stop within {STOP_GRACE:g} s; exiting now\n"


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


CHOKED_PROGRAM = """
import asyncio, sys
from pygoby.util.aiorun import run_until_signal

async def serve():
    try:
        print("ready", flush=True)
        await asyncio.Future()
    finally:
        sys.stderr.write("x" * 10_000_000)  # into a pipe nobody reads: blocks for ever
        sys.stderr.flush()

run_until_signal(serve(), name="choked_server")
"""


def test_a_program_blocked_on_a_full_stderr_pipe_still_ends():
    proc = subprocess.Popen([sys.executable, "-c", CHOKED_PROGRAM], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        assert proc.stdout.readline() == "ready\n"
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=STOP_GRACE + 5) == 128 + signal.SIGTERM  # stderr still unread
    finally:
        proc.kill()
        proc.communicate()
