"""netsim_manager's request processing, sans-I/O.

`NetSimManager.handle_request(request, peer_ip)` applies netsim_manager's checks in its
order (for each nav: configured port -> source address -> region; stop at the first failure;
stats are passed on regardless) and returns a `RequestOutcome` with the one response to send,
the navs accepted for the simulation and the stats received. Accepted, complete navs become the
latest position of their modem port (`position(port)`, `positions()`); the signals `signal_nav`
and `signal_stats` (`on_nav(listener)` / `on_stats(listener)` connect to them) emit them as they
arrive (the channel and the modem emulators use this).

`ManagerConnection` adds the line protocol for one client connection: feed it the bytes received
and it returns the response lines to write, logging and skipping bad lines. It has no I/O of its
own; `pygoby.netsim.manager.server` runs it on asyncio TCP connections.

Difference from upstream (configurable, `reject_nonfinite_position`, default on): a NaN or
infinite lat, lon or depth is answered UPDATE_FAILED_OUT_OF_DEFINED_REGION; upstream accepts NaN
because every comparison with NaN is false, and forwards it.
"""

from __future__ import annotations

import ipaddress
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Final, cast

from pygoby.netsim.errors import LineError
from pygoby.netsim.manager.protocol import (
    LEGACY_RESPONSE_NAME,
    RESPONSE_NAME,
    EnvironmentNavUpdate,
    LineDecoder,
    NavUpdate,
    NetSimManagerRequest,
    NetSimManagerResponse,
    ReceiveStats,
    encode_line,
    request_names,
)
from pygoby.protobuf.netsim.messages.manager_config_pb2 import NetSimManagerConfig
from pygoby.util.signal import Signal

log = logging.getLogger(__name__)

NAV_FIELDS: Final = ("modem_tcp_port", "time", "lat", "lon", "depth", "speed", "heading")


def status_enum():
    return NetSimManagerResponse.Status


def peer_ip_string(address: str) -> str:
    """The dotted IPv4 form upstream compares against (IPv4-mapped IPv6 converted)."""
    try:
        ip = ipaddress.ip_address(address.split("%", 1)[0])
    except ValueError:
        return address
    if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is not None:
        return str(ip.ipv4_mapped)
    return str(ip)


@dataclass
class RequestOutcome:
    response: NetSimManagerResponse
    forwarded: list[EnvironmentNavUpdate] = field(default_factory=list)  # in order
    stats: list[ReceiveStats] = field(default_factory=list)  # in order


NavListener = Callable[[EnvironmentNavUpdate], None]  # called with each forwarded update
StatsListener = Callable[[ReceiveStats], None]  # called with each ReceiveStats


class NetSimManager:
    """The manager's state: configuration, latest position per modem port, listeners."""

    def __init__(self, config: NetSimManagerConfig) -> None:
        self.config = config
        self._pairs = {pair.modem_tcp_port: pair for pair in config.sim_env_pair}
        self._bounds = {bounds.environment_id: bounds for bounds in config.env_bounds}
        self._latest: dict[int, NavUpdate] = {}
        self.signal_nav: Signal[EnvironmentNavUpdate] = (
            Signal()
        )  # each forwarded EnvironmentNavUpdate
        self.signal_stats: Signal[ReceiveStats] = Signal()  # each ReceiveStats
        self._response_cls = NetSimManagerResponse
        # the status values, looked up once (each enum attribute access is a Python __getattr__)
        status = status_enum()
        self.accepted = status.UPDATE_ACCEPTED
        self._invalid_port = status.UPDATE_FAILED_INVALID_MODEM_TCP_PORT
        self._invalid_source = status.UPDATE_FAILED_INVALID_SOURCE_ADDRESS
        self._out_of_region = status.UPDATE_FAILED_OUT_OF_DEFINED_REGION
        self._env_nav_cls = EnvironmentNavUpdate

    # -- queries -------------------------------------------------------------------------

    def position(self, modem_tcp_port: int) -> NavUpdate | None:
        """Latest accepted NavUpdate of a modem port, or None."""
        return self._latest.get(modem_tcp_port)

    def positions(self) -> dict[int, NavUpdate]:
        return dict(self._latest)

    def environment_of(self, modem_tcp_port: int) -> int | None:
        pair = self._pairs.get(modem_tcp_port)
        return None if pair is None else pair.environment_id

    def on_nav(self, listener: NavListener) -> None:
        """Connect `listener` to `signal_nav`."""
        self.signal_nav.connect(listener)

    def on_stats(self, listener: StatsListener) -> None:
        """Connect `listener` to `signal_stats`."""
        self.signal_stats.connect(listener)

    # -- processing ----------------------------------------------------------------------

    def handle_request(self, request: NetSimManagerRequest, peer_ip: str) -> RequestOutcome:
        outcome = RequestOutcome(self._response_cls(request_id=request.id))
        result = self.accepted
        for nav in request.nav:
            result = self._check_nav(nav, peer_ip)
            if result != self.accepted:
                break
            if all(nav.HasField(name) for name in NAV_FIELDS):
                update = self._env_nav_cls(
                    environment_id=self._pairs[nav.modem_tcp_port].environment_id
                )
                update.nav.CopyFrom(nav)
                outcome.forwarded.append(update)
            else:
                missing = [name for name in NAV_FIELDS if not nav.HasField(name)]
                log.warning("nav for port %d lacks %s: not forwarded", nav.modem_tcp_port, missing)
        outcome.response.status = result
        outcome.stats.extend(request.stats)
        for update in outcome.forwarded:
            self._latest[update.nav.modem_tcp_port] = update.nav
            self.signal_nav.emit(update)
        for stats in outcome.stats:
            self.signal_stats.emit(stats)
        return outcome

    def _check_nav(self, nav: NavUpdate, peer_ip: str) -> int:
        return self.check_position(nav.modem_tcp_port, nav.lat, nav.lon, nav.depth, peer_ip)

    def check_position(
        self, modem_tcp_port: int, lat: float, lon: float, depth: float, peer_ip: str
    ) -> int:
        """The status a NavUpdate with these values from `peer_ip` gets (the checks of
        `handle_request`, for a caller with positions that are not messages)."""
        pair = self._pairs.get(modem_tcp_port)
        if pair is None:
            return self._invalid_port
        if peer_ip != pair.endpoint_ip_address:
            return self._invalid_source
        bounds = self._bounds[pair.environment_id]
        if self.config.reject_nonfinite_position and not (
            math.isfinite(lat) and math.isfinite(lon) and math.isfinite(depth)
        ):
            return self._out_of_region
        if (
            lat < bounds.lat_min
            or lat > bounds.lat_max
            or lon < bounds.lon_min
            or lon > bounds.lon_max
            or depth < bounds.depth_min
            or depth > bounds.depth_max
        ):
            return self._out_of_region
        return self.accepted

    def connection(self, peer_address: str) -> ManagerConnection:
        return ManagerConnection(self, peer_address)


class ManagerConnection:
    """One client connection: bytes in, response lines out."""

    def __init__(self, manager: NetSimManager, peer_address: str) -> None:
        self.manager = manager
        self.peer_ip = peer_ip_string(peer_address)
        self.decoder = LineDecoder(request_names(), manager.config.max_line_length)
        self.errors = 0  # bad lines on this connection (dropped or partial)

    def receive(self, data: bytes) -> list[bytes]:
        replies: list[bytes] = []
        for event in self.decoder.feed(data):
            if isinstance(event, LineError):
                self._log_bad_line(f"dropped line: {event}")
                continue
            if event.preamble != b"NETSIM":
                log.info("%s: preamble %r instead of NETSIM", self.peer_ip, event.preamble[:20])
            if event.parse_error:
                self._log_bad_line(f"{event.parse_error}; answering the partial request")
            # (the decoder was made with the request class: every message is one)
            request = cast(NetSimManagerRequest, event.message)
            outcome = self.manager.handle_request(request, self.peer_ip)
            name = LEGACY_RESPONSE_NAME if event.legacy else RESPONSE_NAME
            replies.append(encode_line(outcome.response, name))
        return replies

    def _log_bad_line(self, what: str) -> None:
        # A client sending garbage could produce thousands of errors a second: log the first
        # ones in full, then only every thousandth, so logging cannot starve other clients.
        self.errors += 1
        if self.errors <= 10 or self.errors % 1000 == 0:
            log.warning("%s: bad line #%d: %s", self.peer_ip, self.errors, what)
