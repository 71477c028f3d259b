"""`pygoby bluefin_frontseat_simulator PORT ...` and `pygoby basic_frontseat_simulator PORT ...`:
the frontseat simulators, as their console scripts (the arguments are theirs)."""

from __future__ import annotations

import argparse
import importlib

# subcommand -> module whose main(argv) runs it
SIMULATORS = {
    "bluefin_frontseat_simulator": (
        "pygoby.frontseat.bluefin.server",
        "Bluefin vehicle (Huxley) simulator for iFrontSeat's bluefin driver",
    ),
    "basic_frontseat_simulator": (
        "pygoby.frontseat.simulator.server",
        "basic (ABC) frontseat simulator for iFrontSeat's abc driver",
    ),
}


def register(subparsers: argparse._SubParsersAction) -> None:
    for name, (module, help_text) in SIMULATORS.items():
        # every argument, -h and options included, goes to the simulator's own parser: no help
        # here and no option prefix ("\0" never starts an argument)
        sub = subparsers.add_parser(name, help=help_text, add_help=False, prefix_chars="\0")
        sub.add_argument("args", nargs="*")
        sub.set_defaults(func=lambda args, module=module, name=name: _run(module, name, args.args))


def _run(module: str, name: str, argv: list[str]) -> int:
    main = importlib.import_module(module).main
    return int(main(argv, prog=f"pygoby {name}") or 0)
