"""iNetSimManager: reports a MOOS vehicle to netsim_manager (positions and receive statistics).

Subscribes to the vehicle's NAV_LAT/NAV_LONG (or NAV_X/NAV_Y with LatOrigin/LongOrigin),
NAV_DEPTH, NAV_SPEED and NAV_HEADING and sends a NavUpdate for its `modem_tcp_port` every
`nav_period` seconds; every Micro-Modem reception pAcommsHandler posts (ACOMMS_MODEM_RECEIVE)
is pushed as ReceiveStats. The manager's answer is posted to NETSIM_STATUS when it changes.
The reporting itself is `pygoby.netsim.manager.navreporter.NavReporter`; the manager connection
(reconnecting) is `pygoby.netsim.manager.client.NetSimClient`.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

from pygoby.acomms import messages as acomms_pb
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.protocol import MOOSMessage
from pygoby.netsim.manager.client import NetSimClient, status_name
from pygoby.netsim.manager.navreporter import NavReporter
from pygoby.netsim.manager.protocol import NetSimManagerResponse
from pygoby.protobuf.pygoby.netsim.inetsimmanager_config_pb2 import iNetSimManagerConfig


class iNetSimManager(GobyMOOSApp):  # noqa: N801 - the program's name
    config_class = iNetSimManagerConfig
    cfg: iNetSimManagerConfig
    default_name = "iNetSimManager"

    def __init__(self, cfg: iNetSimManagerConfig, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        common = cfg.common
        origin = None
        if common.HasField("lat_origin") and common.HasField("lon_origin"):
            origin = (common.lat_origin, common.lon_origin)
        self.reporter = NavReporter(
            cfg.modem_tcp_port,
            origin,
            {p.modem_id: p.modem_tcp_port for p in cfg.modem_port},
            cfg.port_of_id_offset,
        )
        self.netsim = NetSimClient(cfg.manager_host, cfg.manager_port, on_response=self._answer)
        self.last_status: str | None = None
        names = {
            cfg.lat_var: "lat",
            cfg.lon_var: "lon",
            cfg.x_var: "x",
            cfg.y_var: "y",
            cfg.depth_var: "depth",
            cfg.speed_var: "speed",
            cfg.heading_var: "heading",
        }
        for var, name in names.items():
            self.subscribe(var, functools.partial(self._nav, name))
        self.subscribe_pb(cfg.modem_receive_var, acomms_pb.ModemTransmission, self._modem_receive)
        self.register_timer(cfg.nav_period, self.send_nav)

    async def start(self, connect_timeout: float | None = None) -> None:
        await self.netsim.start()
        await super().start(connect_timeout)

    async def stop(self) -> None:
        await super().stop()
        await self.netsim.close()

    def _nav(self, name: str, msg: MOOSMessage) -> None:
        if not msg.is_double:
            self.log.warning("%s is not a number: %r", msg.key, msg.value)
            return
        self.reporter.update(name, float(msg.value), msg.time)

    def send_nav(self) -> None:
        nav = self.reporter.nav_update()
        if nav is not None:
            self.netsim.send_navs([nav])

    def _modem_receive(self, transmission: acomms_pb.ModemTransmission) -> None:
        stats = self.reporter.receive_stats(transmission)
        if stats and self.netsim.send_stats(stats) is None:
            self.log.info("not connected to netsim_manager: %d receive stats dropped", len(stats))

    def _answer(self, response: NetSimManagerResponse) -> None:
        status = status_name(response)
        if status != "UPDATE_ACCEPTED":
            self.log.warning("netsim_manager refused request %d: %s", response.request_id, status)
        if status != self.last_status:
            self.last_status = status
            self.publish(self.cfg.status_var, status)


def main(argv: Sequence[str] | None = None) -> int:
    return iNetSimManager.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
