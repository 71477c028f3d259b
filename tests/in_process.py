"""Console commands run inside the test's process: the command's `main(argv)` with the test's
standard input and captured output, instead of a Python process per call (each costs a second of
imports). One test per console script still runs the installed script as a process."""

from __future__ import annotations

import io
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import pytest


@dataclass
class Completed:
    """What a `subprocess.run(..., capture_output=True, text=True)` would have given."""

    returncode: int
    stdout: str
    stderr: str


class Command:
    """`command(*argv, stdin=..., env=...)` runs `main(argv)`: stdin is the given text, env the
    variables set for this call only; stdout and stderr are captured (capsys)."""

    def __init__(
        self,
        main: Callable[[Sequence[str]], int | None],
        capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch,
    ) -> None:
        self.main, self.capsys, self.monkeypatch = main, capsys, monkeypatch

    def __call__(self, *argv: str, stdin: str = "", env: dict[str, str] | None = None) -> Completed:
        self.capsys.readouterr()  # (what the test printed before is not the command's)
        with self.monkeypatch.context() as patch:
            patch.setattr(sys, "stdin", io.StringIO(stdin))
            for name, value in (env or {}).items():
                patch.setenv(name, value)
            try:
                status = self.main(list(argv))
            except SystemExit as exit_:  # argparse's usage errors, sys.exit()
                status = _exit_status(exit_.code)
        out, err = self.capsys.readouterr()
        return Completed(status or 0, out, err)


def _exit_status(code: object) -> int:
    """The status of a process that ends with `sys.exit(code)`: None is 0, a number itself, and
    anything else is printed to stderr and is 1."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return 1
