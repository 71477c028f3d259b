"""iFrontSeat on the embedded MOOSDB (real TCP) with the loopback test driver
(tests/apps/ifs_loopback_driver.py, loaded by module path through the plug-in loader): the
IFS_* variables, the state machine seen from MOOS (helm posts, frontseat state, data loss),
commands passed only in INTERFACE_COMMAND, status posts, NAV_* and the legacy variables."""

from __future__ import annotations

import asyncio
import logging
import math

import pytest

from pygoby.apps.ifrontseat import iFrontSeat
from pygoby.frontseat import messages as frontseat_pb
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.translator import parse_for_moos, serialize_for_moos
from pygoby.util.geodesy import UTMGeodesy

from .acomms_mission import Recorder

pytestmark = pytest.mark.e2e

DRIVER = "tests.apps.ifs_loopback_driver"

MISSION = f"""\
ServerHost = localhost
ServerPort = @PORT@
Community = auv1
LatOrigin = 42.5
LongOrigin = -70.5
ProcessConfig = iFrontSeat
{{
  common {{ log: false  app_tick: 20  verbosity: QUIET }}
  driver_library: "{DRIVER}"
  frontseat_cfg {{
    helm_running_timeout: 60
    frontseat_connected_timeout: 60
    status_period: 1
    [pygoby.test.loopback_config] {{ nav_period: 0.05  lat: 42.51  lon: -70.5 }}
  }}
  legacy_cfg {{ publish_fs_bs_ready: true }}
}}
"""

WATCH = [
    "IFS_STATUS",
    "IFS_NODE_STATUS",
    "IFS_DATA_IN",
    "IFS_RAW_IN",
    "IFS_RAW_OUT",
    "IFS_COMMAND_REQUEST",
    "IFS_COMMAND_RESPONSE",
    "NAV_X",
    "NAV_Y",
    "NAV_LAT",
    "NAV_LONG",
    "NAV_DEPTH",
    "NAV_HEADING",
    "NAV_YAW",
    "NAV_SPEED",
    "NAV_PITCH",
    "GPS_UPDATE_RECEIVED",
    "FRONTSEAT_READY",
    "BACKSEAT_READY",
]

PB = "@PB[goby.middleware.frontseat.protobuf.{}] "


def parsed(cls, value):
    out = cls()
    parse_for_moos(value, out)
    return out


def status_is(state, **fields):
    def check(value) -> bool:
        status = parsed(frontseat_pb.InterfaceStatus, value)
        return status.state == state and all(getattr(status, k) == v for k, v in fields.items())

    return check


class Community:
    """DB + iFrontSeat + a recorder/poster ("tester") + the helm's MOOS client ("pHelmIvP")."""

    def __init__(self, tmp_path, mission: str = MISSION) -> None:
        self.tmp_path, self.mission = tmp_path, mission

    async def __aenter__(self) -> Community:
        self.db = MOOSDB(port=0)
        await self.db.start()
        path = self.tmp_path / "auv1.moos"
        path.write_text(self.mission.replace("@PORT@", str(self.db.port)))
        self.recorder = Recorder("tester", self.db.port)
        await self.recorder.start(WATCH)
        self.helm = MOOSClient("pHelmIvP", port=self.db.port)
        await self.helm.connect()
        self.app = iFrontSeat.from_mission(path)
        self.driver = self.app.interface
        await self.app.start(connect_timeout=5)
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.app.stop()
        await self.helm.close()
        await self.recorder.close()
        await self.db.stop()

    def post(self, var: str, value, client: MOOSClient | None = None) -> None:
        (client or self.recorder.client).publish(var, value)

    async def handled(self, var: str, src: str, value=None, timeout: float = 5) -> None:
        """Until the app has handled `src`'s post of `var` (with `value`, if given)."""
        async with asyncio.timeout(timeout):
            while True:
                msg = self.app.dynamic_vars.get(var)
                if msg is not None and msg.src == src and value in (None, msg.value):
                    return
                await asyncio.sleep(0.01)

    async def state(self, state: int, timeout: float = 5) -> None:
        async with asyncio.timeout(timeout):
            while self.app.interface.state != state:
                await asyncio.sleep(0.01)


async def test_ifs_variables_and_the_state_machine(tmp_path, caplog):
    async with Community(tmp_path) as c:
        r, driver = c.recorder, c.driver
        assert driver.started == 1
        # The driver got the community's name and datum; its NAV flows: STANDBY -> LISTEN.
        assert driver.cfg.name == "auv1" and driver.cfg.sim_warp_factor == 1
        assert (driver.cfg.origin.lat, driver.cfg.origin.lon) == (42.5, -70.5)
        await r.wait_for("IFS_STATUS", status_is(frontseat_pb.INTERFACE_LISTEN))
        status_text = await r.wait_for("IFS_STATUS")
        assert status_text.startswith(PB.format("InterfaceStatus"))
        assert await r.wait_for("FRONTSEAT_READY") == 1.0
        assert await r.wait_for("BACKSEAT_READY") == 0.0

        # NAV_* and IFS_NODE_STATUS / IFS_DATA_IN / IFS_RAW_IN from the frontseat's solution.
        node = parsed(frontseat_pb.NodeStatus, await r.wait_for("IFS_NODE_STATUS"))
        assert node.name == "auv1" and node.global_fix.lat == 42.51
        data = parsed(frontseat_pb.InterfaceData, await r.wait_for("IFS_DATA_IN"))
        assert data.node_status.global_fix.lon == -70.5
        raw = await r.wait_for("IFS_RAW_IN")
        assert (
            raw.startswith(PB.format("Raw"))
            and parsed(frontseat_pb.Raw, raw).raw == b"NAV,HEADING:0"
        )
        assert await r.wait_for("NAV_LAT") == 42.51 and await r.wait_for("NAV_LONG") == -70.5
        x, y = UTMGeodesy(42.5, -70.5).to_local(42.51, -70.5)  # 0.01 deg north of the datum
        assert await r.wait_for("NAV_X") == x and await r.wait_for("NAV_Y") == y
        assert math.isclose(y, 1111.0, abs_tol=5.0)
        assert math.isclose(await r.wait_for("NAV_PITCH"), math.radians(2.0))
        assert (await r.wait_for("GPS_UPDATE_RECEIVED")).startswith("Timestamp=17")

        # LISTEN: a command request is dropped, even the one made from DESIRED_*; data passes.
        request = frontseat_pb.CommandRequest(request_id=7)
        request.desired_course.time, request.desired_course.heading = 1.0, 45.0
        c.post("IFS_COMMAND_REQUEST", serialize_for_moos(request))
        await c.handled("IFS_COMMAND_REQUEST", "tester")
        for var, value in (
            ("DESIRED_HEADING", 90.0),
            ("DESIRED_DEPTH", 5.0),
            ("DESIRED_SPEED", 1.5),
        ):
            c.post(var, value, c.helm)
        legacy = parsed(
            frontseat_pb.CommandRequest,
            await r.wait_for("IFS_COMMAND_REQUEST", lambda v: "65536" in v),
        )
        assert legacy.response_requested and legacy.request_id == 65536
        assert (legacy.desired_course.heading, legacy.desired_course.speed) == (90.0, 1.5)
        await c.handled("IFS_COMMAND_REQUEST", "iFrontSeat")
        c.post(
            "IFS_DATA_OUT", serialize_for_moos(frontseat_pb.InterfaceData(dccl_message=b"\x01\x02"))
        )
        async with asyncio.timeout(5):
            while not driver.data:
                await asyncio.sleep(0.01)
        assert driver.data[0].dccl_message == b"\x01\x02"
        assert driver.commands == []

        # The helm drives: LISTEN -> COMMAND; the next DESIRED_SPEED (after the 1 s blackout)
        # reaches the frontseat and its response comes back.
        c.post("IVPHELM_STATE", "DRIVE", c.helm)
        await c.state(frontseat_pb.INTERFACE_COMMAND)
        assert await r.wait_for("BACKSEAT_READY", lambda v: v == 1.0) == 1.0
        await r.wait_for(
            "IFS_STATUS",
            status_is(
                frontseat_pb.INTERFACE_COMMAND,
                helm_state=frontseat_pb.HELM_DRIVE,
                frontseat_state=frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS,
            ),
        )
        await asyncio.sleep(1.05)
        c.post("DESIRED_SPEED", 1.2, c.helm)
        response = await r.wait_for("IFS_COMMAND_RESPONSE")
        assert response.startswith(PB.format("CommandResponse"))
        assert parsed(frontseat_pb.CommandResponse, response).request_id == 65537
        assert [cmd.request_id for cmd in driver.commands] == [65537]
        course = driver.commands[0].desired_course
        assert (course.heading, course.speed, course.depth) == (90.0, 1.2, 5.0)
        assert await r.wait_for("NAV_HEADING", lambda v: v == 90.0) == 90.0
        assert math.isclose(await r.wait_for("NAV_YAW", lambda v: v != 0.0), -math.pi / 2)
        assert await r.wait_for("NAV_SPEED", lambda v: v == 1.2) == 1.2
        assert await r.wait_for("NAV_DEPTH", lambda v: v == 5.0) == 5.0

        # Raw text from another process goes to the frontseat once; the app's own IFS_RAW_OUT
        # post of what the driver wrote is not sent again.
        c.post("IFS_RAW_OUT", serialize_for_moos(frontseat_pb.Raw(raw=b"HELLO")))
        await c.handled("IFS_RAW_OUT", "iFrontSeat")
        assert [raw.raw for raw in driver.raws] == [b"HELLO"]

        # Garbage is logged and skipped.
        c.app.log.addHandler(caplog.handler)  # the app's log does not propagate
        with caplog.at_level(logging.WARNING):
            c.post(
                "IFS_COMMAND_REQUEST", "@PB[goby.middleware.frontseat.protobuf.CommandRequest] x:"
            )
            await c.handled("IFS_COMMAND_REQUEST", "tester")
            c.post("DESIRED_ROLL", "level", c.helm)  # (a new variable: the DB keeps types)
            await c.handled("DESIRED_ROLL", "pHelmIvP", "level")
        assert "cannot parse IFS_COMMAND_REQUEST" in caplog.text
        assert "DESIRED_ROLL is not a number" in caplog.text
        assert len(driver.commands) == 1

        # PARK -> HELM_ERROR; commands are dropped; DRIVE -> STANDBY -> LISTEN -> COMMAND.
        c.post("IVPHELM_STATE", "PARK", c.helm)
        await r.wait_for(
            "IFS_STATUS",
            status_is(frontseat_pb.INTERFACE_HELM_ERROR, helm_error=frontseat_pb.ERROR_HELM_PARKED),
        )
        c.post("IFS_COMMAND_REQUEST", serialize_for_moos(request))
        await c.handled("IFS_COMMAND_REQUEST", "tester")
        assert len(driver.commands) == 1
        c.post("IVPHELM_STATE", "DRIVE", c.helm)
        await c.state(frontseat_pb.INTERFACE_COMMAND)
        c.post("IFS_COMMAND_REQUEST", serialize_for_moos(request))
        async with asyncio.timeout(5):
            while len(driver.commands) < 2:
                await asyncio.sleep(0.01)
        assert driver.commands[1] == request

        # IVPHELM_STATE from any other process: the helm is not running -> HELM_ERROR.
        c.post("IVPHELM_STATE", "DRIVE")
        await r.wait_for(
            "IFS_STATUS",
            status_is(
                frontseat_pb.INTERFACE_HELM_ERROR,
                helm_error=frontseat_pb.ERROR_HELM_NOT_RUNNING,
                helm_state=frontseat_pb.HELM_NOT_RUNNING,
            ),
        )
        c.post("IVPHELM_STATE", "DRIVE", c.helm)
        await c.state(frontseat_pb.INTERFACE_COMMAND)

        # The frontseat falls silent -> FS_ERROR (not providing data); back -> COMMAND.
        driver.online = False
        await r.wait_for(
            "IFS_STATUS",
            status_is(
                frontseat_pb.INTERFACE_FS_ERROR,
                frontseat_error=frontseat_pb.ERROR_FRONTSEAT_NOT_PROVIDING_DATA,
            ),
        )
        driver.online = True
        await c.state(frontseat_pb.INTERFACE_COMMAND)

        # A new datum from LAT_ORIGIN: the local grid moves (0.01 deg south of the vehicle now).
        c.post("LAT_ORIGIN", 42.52)
        await c.handled("LAT_ORIGIN", "tester")
        assert await r.wait_for("NAV_Y", lambda v: v < 0) < -1100

    assert driver.stopped == 1


RENAMED = MISSION.replace(
    "  legacy_cfg { publish_fs_bs_ready: true }",
    """  moos_var { prefix: "FS_"  status: "STAT"  data_to_frontseat: "TO_VEHICLE" }
  legacy_cfg { subscribe_ctd: true  publish_nav: false }""",
).replace("status_period: 1", "status_period: 1  require_helm: false")


async def test_renamed_variables_ctd_samples_and_no_helm_required(tmp_path):
    async with Community(tmp_path, RENAMED) as c:
        r, driver = c.recorder, c.driver
        for var in ("FS_STAT", "FS_TO_VEHICLE", "FS_NODE_STATUS"):
            r.client.subscribe(var)
        # require_helm: false -> COMMAND without a helm.
        status = await r.wait_for("FS_STAT", status_is(frontseat_pb.INTERFACE_COMMAND), timeout=10)
        assert (
            parsed(frontseat_pb.InterfaceStatus, status).helm_state == frontseat_pb.HELM_NOT_RUNNING
        )
        await r.wait_for("FS_NODE_STATUS")
        assert r.values("IFS_STATUS") == [] and r.values("NAV_LAT") == []  # publish_nav: false

        # CTD_*: each CTD_TEMPERATURE makes a sample at the last fix, completed, posted on
        # the renamed data_to_frontseat variable, and (LISTEN/COMMAND) given to the driver.
        for var, value in (
            ("CTD_CONDUCTIVITY", 4.2914),
            ("CTD_PRESSURE", 100.0),
            ("CTD_TEMPERATURE", 15.0),
        ):
            c.post(var, value)
        posted = frontseat_pb.InterfaceData()
        parse_for_moos(await r.wait_for("FS_TO_VEHICLE"), posted)
        sample = posted.ctd_sample
        assert (sample.global_fix.lat, sample.global_fix.lon) == (42.51, -70.5)
        assert sample.pressure == 100.0e4 and sample.temperature == 15.0
        # 4.2914 S/m is C(35, 15 degC, 0 dbar); at 100 dbar it is a little less saline
        assert 34.9 < sample.salinity < 35.0
        assert 1500 < sample.sound_speed < 1520 and 1020 < sample.density < 1030
        assert math.isclose(sample.global_fix.depth, 99.3, abs_tol=0.5)  # 100 dbar at 42.5 N
        async with asyncio.timeout(5):
            while not driver.data:
                await asyncio.sleep(0.01)
        assert driver.data[0] == posted
