"""The uField driver's own MOOS connection (goby3: a MOOS client named goby.moos.UFldDriver
to `moos_server:moos_port`), given to the driver by pAcommsHandler: acomms does not import moos,
so the link lives in the acomms-on-MOOS layer (pygoby.acomms.drivers.ufield.MailLink is its
interface)."""

from __future__ import annotations

import asyncio

from pygoby.moos.client import MOOSClient
from pygoby.moos.protocol import NOTIFY

CLIENT_NAME = "goby.moos.UFldDriver"


class MOOSMailLink:
    """A MOOSClient (inside the app's running asyncio loop) seen as the driver's MailLink."""

    def __init__(self, name: str = CLIENT_NAME) -> None:
        self.name = name
        self.client: MOOSClient | None = None
        self._closing: asyncio.Future[None] | None = None  # kept until the client has closed

    def open(self, host: str, port: int, variables: list[str]) -> None:
        self.client = MOOSClient(self.name, host, port)
        for variable in variables:
            self.client.subscribe(variable)
        self.client.start()

    def publish(self, variable: str, text: str) -> None:
        if self.client is not None:
            self.client.publish(variable, text)

    def fetch(self) -> list[tuple[str, str]]:
        if self.client is None:
            return []
        return [
            (m.key, m.string)
            for m in self.client.fetch()
            if m.msg_type == NOTIFY and not m.is_double
        ]

    def close(self) -> None:
        if self.client is not None:
            self._closing = asyncio.ensure_future(self.client.close())
            self.client = None
