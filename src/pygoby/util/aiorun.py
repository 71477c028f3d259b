"""Running a long-lived asyncio program from a console script, and ending its tasks.

* `run_until_signal(main)`: `asyncio.run(main)` until SIGINT or SIGTERM cancels it.
* `StopSignals`: what every console program does on SIGINT/SIGTERM: the first signal asks the
  program to stop (a callback run in its event loop) and starts a deadline; when the program
  has not ended by then, or at a second signal, the process ends at once. So a signal always
  ends the program within `STOP_GRACE` seconds, even when its stopping code hangs or its event
  loop is stuck in a blocking call.
* `cancel_and_wait(task)`: cancel a task and wait for its end without swallowing the
  cancellation of the caller (the bug of `task.cancel(); with suppress(CancelledError): await
  task`, which left apps alive after SIGTERM when it met a lost connection).
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import threading
from collections.abc import Callable, Coroutine
from typing import Any

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
STOP_GRACE = 5.0  # s a program has to end after SIGINT/SIGTERM before the process is ended


async def cancel_and_wait(task: asyncio.Future[Any] | None) -> None:
    """Cancel `task` and wait until it has ended; its own CancelledError is absorbed, any other
    exception it ended with is raised here. If the caller is cancelled while waiting, that
    cancellation propagates (the task then finishes cancelling on its own)."""
    if task is None:
        return
    task.cancel()
    await asyncio.wait({task})
    if not task.cancelled():
        task.result()


class StopSignals:
    """SIGINT/SIGTERM handling of one console program (use as a context manager in the thread
    that runs the event loop, i.e. the main thread).

    The handlers are plain `signal.signal` handlers rather than the event loop's, so they run
    even while the loop is blocked: the first signal schedules `request_stop` in `loop` and
    starts a timer thread; the timer (after `grace` s) or a second signal writes one line to
    stderr and ends the process with status 128 + the signal number.
    """

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        request_stop: Callable[[], object],
        name: str,
        grace: float = STOP_GRACE,
    ) -> None:
        self.loop = loop
        self.request_stop = request_stop
        self.name = name
        self.grace = grace
        self.received: int | None = None
        self._timer: threading.Timer | None = None
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> StopSignals:
        for signum in STOP_SIGNALS:
            self._previous[signum] = signal.signal(signum, self._on_signal)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._timer is not None:
            self._timer.cancel()
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)

    def _on_signal(self, signum: int, _frame: object) -> None:
        if self.received is not None:
            self._force(f"second {signal.Signals(signum).name}", signum)
            return
        self.received = signum
        self._timer = threading.Timer(
            self.grace, self._force, (f"did not stop within {self.grace:g} s", signum)
        )
        self._timer.daemon = True
        self._timer.start()
        self.loop.call_soon_threadsafe(self.request_stop)

    def _force(self, why: str, signum: int) -> None:
        # os.write: no buffered stream's lock, which a stuck main thread may hold; from a thread
        # of its own: stderr may be a full pipe nobody reads, and the exit must not wait on it
        line = f"{self.name}: {why}; exiting now\n".encode()
        writer = threading.Thread(target=os.write, args=(sys.stderr.fileno(), line), daemon=True)
        writer.start()
        writer.join(0.5)
        os._exit(128 + signum)


def run_until_signal(main: Coroutine[Any, Any, Any], name: str | None = None) -> None:
    """`asyncio.run(main)` until SIGINT or SIGTERM cancels it: the coroutine's `finally` blocks
    close what it opened, and the program ends without a traceback (within `STOP_GRACE` s in
    any case, see `StopSignals`)."""

    async def runner() -> None:
        task = asyncio.ensure_future(main)
        program = name or os.path.basename(sys.argv[0]) or "pygoby"
        with StopSignals(asyncio.get_running_loop(), task.cancel, program):
            try:
                await task
            except asyncio.CancelledError:
                if not task.cancelled():
                    raise

    asyncio.run(runner())
