"""`pygoby liaison ...`: the liaison app as a pygoby subcommand."""

from __future__ import annotations

import argparse


def _run_liaison(args: argparse.Namespace) -> int:
    from pygoby.apps.liaison import main

    return main(args.rest)


def register(subparsers: argparse._SubParsersAction) -> None:
    liaison = subparsers.add_parser(
        "liaison",
        help="the community in a web browser: Scope, Commander, Acomms, Map (--log FILE.alog: a recorded one)",
        add_help=False,
        prefix_chars="\x00",  # every argument, options included, goes to the app
    )
    liaison.add_argument(
        "rest",
        nargs=argparse.REMAINDER,
        help="mission.moos [AppName] [options], or --log FILE.alog [--mission M.moos] [--port P]",
    )
    liaison.set_defaults(func=_run_liaison)
