"""run_until_signal: SIGINT or SIGTERM cancels the program's coroutine, whose cleanup runs,
and the process exits 0 without a traceback."""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest

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
