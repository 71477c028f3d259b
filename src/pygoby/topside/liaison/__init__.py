"""liaison: the MOOS community in a web browser (Scope, Commander, Acomms, Map).

`LiaisonState` keeps what the pages show (sans-I/O, fed MOOS mail); `WebServer` serves it with
Starlette/uvicorn in the running asyncio loop; `Liaison` is the MOOS client around them (run by
`pygoby.apps.liaison`, or embedded in pAcommsHandler). `LogLiaison` serves the same pages over
a recorded .alog (`pygoby liaison --log`), its state moved by `log_feed.LogPlayer`.
"""

from pygoby.topside.liaison.app import Liaison
from pygoby.topside.liaison.log_app import LogLiaison
from pygoby.topside.liaison.state import LiaisonState
from pygoby.topside.liaison.web import WebServer, is_loopback, make_app

__all__ = ["Liaison", "LiaisonState", "LogLiaison", "WebServer", "is_loopback", "make_app"]
