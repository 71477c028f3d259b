"""liaison: the community in a web browser (Scope, Commander, Acomms, Map), after goby3's
goby_liaison, on a MOOS community with pAcommsHandler; or over a recorded mission.

    pygoby liaison mission.moos [AppName]      (ProcessConfig = liaison, optional)
    pygoby liaison --example_config
    pygoby liaison --log FILE.alog [--mission M.moos] [--port P]

The messages the Commander page can send, the queues and the MAC cycle come from the mission's
pAcommsHandler block (`liaison { commander { pacommshandler_name } }`). pAcommsHandler serves
the same pages itself when its block has a `liaison { ... }` section. Serves on 127.0.0.1 by
default; any other address requires the access token printed at start-up. The app is
`pygoby.topside.liaison.Liaison`.

With `--log`, no MOOSDB: Scope, Acomms and Map show the log at the time of a slider, with play,
pause and speed (`pygoby.topside.liaison.log_app`); `--mission` names the acomms variables and
their message types.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from pygoby.errors import PygobyError
from pygoby.topside.liaison.app import Liaison
from pygoby.util.aiorun import run_until_signal

COMMAND = "pygoby liaison"


def tcp_port(text: str) -> int:
    port = int(text)  # argparse says "invalid tcp_port value" for what is no number
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"{port} is no TCP port (0 to 65535)")
    return port


def log_main(argv: Sequence[str]) -> int:
    parser = argparse.ArgumentParser(
        prog=COMMAND, description="liaison's Scope, Acomms and Map over a recorded .alog"
    )
    parser.add_argument("--log", required=True, metavar="FILE.alog", help="the log to replay")
    parser.add_argument(
        "--mission", metavar="M.moos", help="its mission: pAcommsHandler's variables and types"
    )
    parser.add_argument("--port", type=tcp_port, help="TCP port (default 54321; 0: any free port)")
    args = parser.parse_args(argv)
    from pygoby.topside.liaison.log_app import LogLiaison  # the web stack, only when asked for

    print(f"liaison: indexing {args.log}", file=sys.stderr, flush=True)
    try:
        liaison = LogLiaison(args.log, args.mission, port=args.port)
    except (PygobyError, OSError) as err:
        print(f"{COMMAND}: {err}", file=sys.stderr)
        return 1
    run_until_signal(liaison.serve_forever(), "liaison")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if any(arg == "--log" or arg.startswith("--log=") for arg in args):
        return log_main(args)
    return Liaison.main(argv, prog="liaison", command=COMMAND)


if __name__ == "__main__":
    raise SystemExit(main())
