"""Running a long-lived asyncio program from a console script."""

from __future__ import annotations

import asyncio
import contextlib
import signal
from collections.abc import Coroutine
from typing import Any


def run_until_signal(main: Coroutine[Any, Any, Any]) -> None:
    """`asyncio.run(main)` until SIGINT or SIGTERM cancels it: the coroutine's `finally` blocks
    close what it opened, and the program ends without a traceback."""

    async def runner() -> None:
        task = asyncio.ensure_future(main)
        loop = asyncio.get_running_loop()
        for signum in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(signum, task.cancel)
        with contextlib.suppress(asyncio.CancelledError):
            await task

    asyncio.run(runner())
