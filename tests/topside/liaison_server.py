"""liaison's state and web server on a loopback socket, fed MOOS mail by the test (no MOOSDB):
the pages of the commander tests' mission."""

from __future__ import annotations

import contextlib
import http.client
import json
from pathlib import Path

from pygoby.moos import protocol as p
from pygoby.moos.moosfile import MissionFile
from pygoby.moosacomms.acomms_config import read_acomms_config
from pygoby.protobuf import builtin_class
from pygoby.topside.commander import CommandSet
from pygoby.topside.liaison.state import LiaisonState
from pygoby.topside.liaison.web import WebServer

from .test_commander import MISSION


def http_request(
    port: int, method: str, path: str, body: object = None, headers: dict | None = None
) -> tuple[int, str]:
    """One plain HTTP/1.1 request to 127.0.0.1:port (a JSON body): (status, text)."""
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        data = json.dumps(body).encode() if body is not None else None
        connection.request(method, path, body=data, headers=headers or {})
        response = connection.getresponse()
        return response.status, response.read().decode()
    finally:
        connection.close()


class Served:
    """A WebServer on 127.0.0.1 and its state; `request` is a plain HTTP/1.1 request."""

    def __init__(self, tmp_path: Path, **settings) -> None:
        path = tmp_path / "m.moos"
        path.write_text(MISSION)
        acomms = read_acomms_config(MissionFile.read(path))
        cfg = builtin_class(
            "pygoby/apps/topside_config.proto", "pygoby.apps.protobuf.LiaisonConfig"
        )(http_port=0, update_freq=50, **settings)
        cfg.commander.autosave_path = ""
        self.posts: list = []
        self.clock = 1000.0
        self.state = LiaisonState(
            cfg,
            acomms,
            CommandSet.from_pacommshandler(acomms),
            community="topside",
            now=lambda: self.clock,
            publish=self.posts.append,
            start_time=0.0,
        )
        self.save_dir = tmp_path / "saves"
        self.web = WebServer(self.state, cfg, self.save_dir)
        self.token = self.web.token

    def request(
        self, method: str, path: str, body: dict | None = None, headers: dict | None = None
    ) -> tuple[int, str]:
        return http_request(self.web.port, method, path, body, headers)

    def post(self, body: dict, headers: dict | None = None) -> tuple[int, str]:
        sent = {
            "X-Liaison": "1",
            "Content-Type": "application/json",
            "Authorization": f"Bearer {self.token}",
            **(headers or {}),
        }
        return self.request("POST", "/api/commander", body, sent)

    def mail(self, key: str, value: str | float) -> None:
        self.state.handle(p.notify(key, value, time=self.clock, src="test"))


@contextlib.asynccontextmanager
async def served(tmp_path: Path, **settings):
    server = Served(tmp_path, **settings)
    await server.web.start()
    try:
        yield server
    finally:
        await server.web.stop()
