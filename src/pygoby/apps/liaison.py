"""liaison: the community in a web browser (Scope, Commander, Acomms, Map), after goby3's
goby_liaison, on a MOOS community with pAcommsHandler.

    pygoby liaison mission.moos [AppName]      (ProcessConfig = liaison, optional)
    pygoby liaison --example_config

The messages the Commander page can send, the queues and the MAC cycle come from the mission's
pAcommsHandler block (`liaison { commander { pacommshandler_name } }`). pAcommsHandler serves
the same pages itself when its block has a `liaison { ... }` section. Serves on 127.0.0.1 by
default; any other address requires the access token printed at start-up. The app is
`pygoby.topside.liaison.Liaison`.
"""

from __future__ import annotations

from collections.abc import Sequence

from pygoby.topside.liaison.app import Liaison


def main(argv: Sequence[str] | None = None) -> int:
    return Liaison.main(argv, prog="liaison", command="pygoby liaison")


if __name__ == "__main__":
    raise SystemExit(main())
