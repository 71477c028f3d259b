"""The `pygoby` command: each subsystem adds its own subcommands from its `cli` module."""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from pygoby import __version__
from pygoby.util.console import quiet_broken_pipe
from pygoby.util.errors import MissingExtraError

# Each module has `register(subparsers)`, which adds parsers whose `func(args) -> int` runs them.
SUBCOMMAND_MODULES = [
    "pygoby.dccl.cli",
    "pygoby.acomms.cli",
    "pygoby.moos.cli",
    "pygoby.apps.log_cli",
    "pygoby.frontseat.cli",
    "pygoby.netsim.cli",
    "pygoby.apps.topside_cli",
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pygoby", description=__doc__)
    parser.add_argument("-V", "--version", action="version", version=f"pygoby {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in SUBCOMMAND_MODULES:
        importlib.import_module(name).register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    def run() -> int:
        try:
            return int(args.func(args) or 0)
        except KeyboardInterrupt:
            return 130
        except MissingExtraError as exc:  # a feature installed by a pip extra
            print(f"pygoby {args.command}: {exc}", file=sys.stderr)
            return 1

    return quiet_broken_pipe(run)


if __name__ == "__main__":
    sys.exit(main())
