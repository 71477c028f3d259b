"""A frontseat driver plug-in for the iFrontSeat tests, loaded by module path
(`tests.apps.ifs_loopback_driver`). Its "vehicle" sits at the configured position and takes
each commanded course at once; while `online` it reports a navigation solution every
`nav_period` seconds (providing data until 3 periods pass without one). The test sets
`fs_state` (the command state) and `online`, and reads what the driver was asked to send.

Its configuration is an extension of the frontseat Config (`[pygoby.test.loopback_config]`),
loaded when the module is imported, as a third-party driver's would be.
"""

from __future__ import annotations

from pathlib import Path

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.interface import InterfaceBase
from pygoby.protobuf import default_loader

_loader = default_loader()
_loader.load_file(Path(__file__).with_name("ifs_loopback_driver.proto"))
LOOPBACK_CONFIG = _loader.pool.FindExtensionByName("pygoby.test.loopback_config")


class LoopbackFrontSeat(InterfaceBase):
    def __init__(self, cfg, clock=None) -> None:
        super().__init__(cfg, clock)
        self.settings = self.cfg.Extensions[LOOPBACK_CONFIG]
        self.fs_state = frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS
        self.online = True
        self.course = frontseat_pb.DesiredCourse(time=0)
        self.last_nav = -float("inf")
        self.started = self.stopped = 0
        self.commands: list = []
        self.data: list = []
        self.raws: list = []

    async def start(self) -> None:
        self.started += 1

    async def stop(self) -> None:
        self.stopped += 1

    def send_command_to_frontseat(self, command) -> None:
        self.commands.append(command)
        self.course.CopyFrom(command.desired_course)
        if command.response_requested:
            self.signal_command_response(
                frontseat_pb.CommandResponse(request_successful=True, request_id=command.request_id)
            )

    def send_data_to_frontseat(self, data) -> None:
        self.data.append(data)

    def send_raw_to_frontseat(self, raw) -> None:
        self.raws.append(raw)
        self.signal_raw_to_frontseat(raw)

    def frontseat_state(self) -> int:
        return self.fs_state

    def frontseat_providing_data(self) -> bool:
        return self.clock.now() - self.last_nav < 3 * self.settings.nav_period

    def loop(self) -> None:
        now = self.clock.now()
        if not self.online or now - self.last_nav < self.settings.nav_period:
            return
        self.last_nav = now
        status = frontseat_pb.NodeStatus()
        status.global_fix.lat, status.global_fix.lon = self.settings.lat, self.settings.lon
        status.global_fix.depth = self.course.depth
        status.pose.heading = self.course.heading
        status.pose.pitch = 2.0
        status.speed.over_ground = self.course.speed
        status.source.position = frontseat_pb.Source.GPS
        self.compute_missing(status)
        self.signal_raw_from_frontseat(
            frontseat_pb.Raw(raw=f"NAV,HEADING:{status.pose.heading:g}".encode())
        )
        self.signal_data_from_frontseat(frontseat_pb.InterfaceData(node_status=status))


def frontseat_driver_load(cfg, clock=None) -> LoopbackFrontSeat:
    return LoopbackFrontSeat(cfg, clock)
