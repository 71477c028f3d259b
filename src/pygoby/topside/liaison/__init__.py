"""liaison: the MOOS community in a web browser (Scope, Commander, Acomms, Map).

`LiaisonState` keeps what the pages show (sans-I/O, fed MOOS mail); `WebServer` serves it with
Starlette/uvicorn in the running asyncio loop. The MOOS app is `pygoby.apps.liaison`.
"""

from pygoby.topside.liaison.state import LiaisonState
from pygoby.topside.liaison.web import WebServer, is_loopback, make_app

__all__ = ["LiaisonState", "WebServer", "is_loopback", "make_app"]
