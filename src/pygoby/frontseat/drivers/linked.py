"""What the shipped drivers share: a frontseat reached over a line-based TCP link.

The driver opens a `TCPClientLink` (which keeps reconnecting), `start()` waits a while for the
first connection but never fails (a frontseat that comes up later is picked up by the link),
and the frontseat's state and whether it provides data are kept by the driver as it reads.
"""

from __future__ import annotations

import asyncio
from typing import Any

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.interface import InterfaceBase
from pygoby.util.clock import Clock
from pygoby.util.linebased import LineLink, TCPClientLink

CONNECT_TIMEOUT = 10.0  # s start() waits for the first connection


class LinkedFrontSeat(InterfaceBase):
    """A driver whose frontseat is a TCP peer at `address`; `peer` names it in the log."""

    peer = "the frontseat"

    def __init__(
        self,
        cfg: Any,
        clock: Clock | None,
        *,
        connect_timeout: float,
    ) -> None:
        super().__init__(cfg, clock)
        self.connect_timeout = connect_timeout
        self._frontseat_state: frontseat_pb.FrontSeatState.ValueType = (
            frontseat_pb.FRONTSEAT_NOT_CONNECTED
        )
        self._providing_data = False
        self._last_nav_time: float | None = None

    def _attach_link(
        self, link: LineLink | None, host: str, port: int, reconnect_interval: float
    ) -> None:
        """Use `link` (tests, simulations) or a reconnecting TCP client to host:port."""
        self.address = f"{host}:{port}"
        self.link: LineLink = (
            link
            if link is not None
            else TCPClientLink(host, port, reconnect_interval=reconnect_interval)
        )

    # --- lifecycle ---------------------------------------------------------------------------

    async def start(self) -> None:
        """Open the link and wait up to `connect_timeout` s for the connection (never fails)."""
        self.link.open()
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.connect_timeout
        while not self.link.is_open and loop.time() < deadline:
            await asyncio.sleep(0.05)
        if not self.link.is_open:
            self.log.warning(
                "no connection to %s at %s after %g s; still trying",
                self.peer,
                self.address,
                self.connect_timeout,
            )

    async def stop(self) -> None:
        self.link.close()

    # --- InterfaceBase hooks -------------------------------------------------------------------

    def frontseat_state(self) -> frontseat_pb.FrontSeatState.ValueType:
        return self._frontseat_state

    def frontseat_providing_data(self) -> bool:
        return self._providing_data
