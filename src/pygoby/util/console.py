"""Console programs that end quietly when their reader goes away (`pygoby ... | head`)."""

from __future__ import annotations

import os
import select
import sys
from collections.abc import Callable

BROKEN_PIPE_STATUS = 128 + 13  # as a program killed by SIGPIPE, the shell's convention


def quiet_broken_pipe(run: Callable[[], int]) -> int:
    """`run()`'s status; when standard output is a pipe whose reader has gone, no traceback:
    the rest of the output is discarded and the status is 141."""
    try:
        status = run()
        sys.stdout.flush()
        return status
    except BrokenPipeError:
        if not _stdout_reader_gone():
            raise  # another pipe's or a socket's: not the console's to hide
        # later writes (and the interpreter's final flush) go nowhere instead of raising again
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return BROKEN_PIPE_STATUS


def _stdout_reader_gone() -> bool:
    """Whether standard output is a pipe whose reading end is closed (poll reports an error on
    the writing end then)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # (replaced by an object without a descriptor)
        return False
    poller = select.poll()
    poller.register(fd, select.POLLOUT)
    return any(events & select.POLLERR for _, events in poller.poll(0))
