"""End to end: the basic (ABC) frontseat simulator on TCP, iFrontSeat with the `basic_simulator`
driver, a scripted helm and the embedded MOOSDB, all at MOOSTimeWarp 10 (spec
goby-moos-apps.md 5.9 "typical session").

The helm's DESIRED_* reach the simulator, whose vehicle converges on them, and its NAV comes
back as NAV_* and IFS_NODE_STATUS. Faults: the simulator goes away (FS_ERROR, NOT_CONNECTED)
and comes back (STANDBY -> LISTEN -> COMMAND); the mission ends and NAV stops (FS_ERROR,
NOT_PROVIDING_DATA) until a new START; the helm parks, another process claims IVPHELM_STATE,
or the helm falls silent past helm_state_timeout (HELM_ERROR); garbage from the simulator is
skipped. The simulator's received lines show that no command is sent outside
INTERFACE_COMMAND."""

from __future__ import annotations

import asyncio
import contextlib
import math

import pytest

from pygoby.apps.ifrontseat import iFrontSeat
from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.simulator.core import BasicFrontSeatSimulator
from pygoby.frontseat.simulator.server import SimulatorServer
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.timewarp import moos_clock
from pygoby.moos.translator import parse_for_moos, serialize_for_moos

from .acomms_mission import Recorder

pytestmark = pytest.mark.e2e

WARP = 10

MISSION = """\
ServerHost = localhost
ServerPort = {db_port}
Community = auv1
MOOSTimeWarp = {warp}
LatOrigin = 42.5
LongOrigin = -70.5
ProcessConfig = iFrontSeat
{{
  common {{ log: false  app_tick: 5  verbosity: QUIET }}
  driver_library: "basic_simulator"
  frontseat_cfg {{
    helm_running_timeout: 100
    helm_state_timeout: 5
    status_period: 1
    [goby.middleware.frontseat.protobuf.basic_simulator_config] {{
      tcp_address: "127.0.0.1"
      tcp_port: {sim_port}
      start {{ lat: 42.5  lon: -70.5  control_freq: 2 }}
    }}
  }}
}}
"""

WATCH = [
    "IFS_STATUS",
    "IFS_NODE_STATUS",
    "IFS_RAW_IN",
    "IFS_COMMAND_RESPONSE",
    "NAV_X",
    "NAV_Y",
    "NAV_HEADING",
    "NAV_SPEED",
    "NAV_DEPTH",
]


class RecordingSimulator(BasicFrontSeatSimulator):
    """The simulator, keeping every line it received."""

    def __init__(self) -> None:
        super().__init__()
        self.received: list[str] = []

    def handle_line(self, line: str) -> list[str]:
        self.received.append(line)
        return super().handle_line(line)

    def commands(self) -> list[str]:
        return [line for line in self.received if line.startswith("CMD")]


class Simulator:
    """A SimulatorServer served by a task, stoppable and restartable on the same port."""

    def __init__(self, port: int = 0) -> None:
        self.sim = RecordingSimulator()
        self.server = SimulatorServer(port, host="127.0.0.1", simulator=self.sim)
        self.task: asyncio.Task | None = None

    async def start(self) -> int:
        port = await self.server.start()
        self.task = asyncio.create_task(self.server.serve())
        return port

    async def stop(self) -> None:
        if self.task is not None:
            self.task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self.task
            self.task = None


class ScriptedHelm:
    """pHelmIvP as iFrontSeat sees it: IVPHELM_STATE and DESIRED_* every 0.1 s (1 s warped)."""

    def __init__(self, port: int) -> None:
        self.client = MOOSClient("pHelmIvP", port=port, clock=moos_clock(WARP))
        self.state = "DRIVE"
        self.desired = {"DESIRED_HEADING": 90.0, "DESIRED_DEPTH": 10.0, "DESIRED_SPEED": 2.0}
        self.task: asyncio.Task | None = None

    async def start(self) -> None:
        await self.client.connect()

    def run(self) -> None:
        self.task = asyncio.create_task(self._posts())

    async def _posts(self) -> None:
        while True:
            self.client.publish("IVPHELM_STATE", self.state)
            for var, value in self.desired.items():  # DESIRED_SPEED last: it makes the request
                self.client.publish(var, value)
            await asyncio.sleep(0.1)

    async def stop_posting(self) -> None:
        if self.task is not None:
            self.task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self.task
            self.task = None

    async def close(self) -> None:
        await self.stop_posting()
        await self.client.close()


def status_of(value) -> object:
    status = frontseat_pb.InterfaceStatus()
    parse_for_moos(value, status)
    return status


async def until(predicate, timeout: float = 10.0) -> None:
    async with asyncio.timeout(timeout):
        while not predicate():
            await asyncio.sleep(0.01)


async def test_helm_simulator_round_trip_and_faults(tmp_path):
    simulator = Simulator()
    sim_port = await simulator.start()
    async with contextlib.AsyncExitStack() as stack:
        stack.push_async_callback(lambda: simulator.stop())
        db = await stack.enter_async_context(MOOSDB(port=0, clock=moos_clock(WARP)))
        recorder = Recorder("tester", db.port)
        await recorder.start(WATCH)
        stack.push_async_callback(recorder.close)
        helm = ScriptedHelm(db.port)
        await helm.start()
        stack.push_async_callback(helm.close)
        path = tmp_path / "auv1.moos"
        path.write_text(MISSION.format(db_port=db.port, warp=WARP, sim_port=sim_port))
        app = iFrontSeat.from_mission(path)
        states: list[int] = []
        app.interface.signal_state_change.connect(lambda status: states.append(status.state))
        await stack.enter_async_context(app)
        interface = app.interface

        def in_state(state: int) -> bool:
            return interface.state == state

        # Connected: START, then CTRL,STATE:PAYLOAD and NAV -> LISTEN (no helm yet).
        await until(lambda: in_state(frontseat_pb.INTERFACE_LISTEN))
        assert simulator.sim.received[0].startswith("START,LAT:42.5,LON:-70.5,DURATION:0,FREQ:2,")
        assert simulator.sim.received[0].endswith(f",WARP:{WARP}")

        # LISTEN: a command request (also one made from DESIRED_SPEED) never reaches the
        # simulator.
        request = frontseat_pb.CommandRequest(request_id=5)
        course = request.desired_course
        course.time, course.heading, course.speed, course.depth = 1.0, 180.0, 1.0, 30.0
        helm.client.publish("IFS_COMMAND_REQUEST", serialize_for_moos(request))
        helm.client.publish("DESIRED_SPEED", 1.0)
        await until(
            lambda: (
                app.dynamic_vars.get("IFS_COMMAND_REQUEST", None) is not None
                and app.dynamic_vars["IFS_COMMAND_REQUEST"].src == "iFrontSeat"
            )
        )
        await asyncio.sleep(0.3)  # a few more of the app's ticks
        assert interface.state == frontseat_pb.INTERFACE_LISTEN
        assert simulator.sim.commands() == []

        # The helm drives: COMMAND; the vehicle turns east, speeds up and dives.
        helm.run()
        await until(lambda: in_state(frontseat_pb.INTERFACE_COMMAND))
        vehicle = simulator.sim.vehicle
        await until(lambda: (vehicle.heading, vehicle.speed, vehicle.z) == (90.0, 2.0, -10.0))
        assert set(simulator.sim.commands()) == {"CMD,HEADING:90,SPEED:2,DEPTH:10"}
        await recorder.wait_for("NAV_SPEED", lambda v: v == 2.0)
        await recorder.wait_for("NAV_DEPTH", lambda v: v == 10.0)
        assert recorder.values("NAV_HEADING")[-1] == 90.0
        node = frontseat_pb.NodeStatus()
        parse_for_moos(
            await recorder.wait_for(
                "IFS_NODE_STATUS", lambda v: "depth: 10 " in v and "over_ground: 2 " in v
            ),
            node,
        )
        assert node.name == "auv1" and node.global_fix.depth == 10.0
        assert node.local_fix.x > 0 and math.isclose(node.global_fix.lat, 42.5, abs_tol=1e-3)
        response = frontseat_pb.CommandResponse()
        parse_for_moos(await recorder.wait_for("IFS_COMMAND_RESPONSE"), response)
        assert response.request_successful and response.request_id >= 65536
        await recorder.wait_for(
            "IFS_STATUS", lambda v: status_of(v).state == frontseat_pb.INTERFACE_COMMAND
        )

        # Garbage from the simulator is seen raw, skipped, and changes nothing.
        simulator.server.link.write("NAV,LAT:north,LON:-70\r\nnot a message\r\n")
        await recorder.wait_for("IFS_RAW_IN", lambda v: "not a message" in v)
        assert interface.state == frontseat_pb.INTERFACE_COMMAND

        # The helm parks: HELM_ERROR, and no command goes out until it drives again.
        helm.state = "PARK"
        await until(lambda: in_state(frontseat_pb.INTERFACE_HELM_ERROR))
        assert interface.status().helm_error == frontseat_pb.ERROR_HELM_PARKED
        sent = len(simulator.sim.commands())
        await asyncio.sleep(0.5)  # five DESIRED_SPEED posts
        assert len(simulator.sim.commands()) == sent
        helm.state = "DRIVE"
        await until(lambda: in_state(frontseat_pb.INTERFACE_COMMAND))
        await until(lambda: len(simulator.sim.commands()) > sent)

        # Another process posts IVPHELM_STATE: the helm is not running -> HELM_ERROR.
        recorder.client.publish("IVPHELM_STATE", "DRIVE", time=app.moos_time())
        await until(lambda: in_state(frontseat_pb.INTERFACE_HELM_ERROR))
        assert interface.status().helm_error == frontseat_pb.ERROR_HELM_NOT_RUNNING
        await until(lambda: in_state(frontseat_pb.INTERFACE_COMMAND))  # the helm's next post

        # The helm hangs (no more posts): HELM_ERROR after helm_state_timeout (5 s warped), no
        # command goes out meanwhile; when it posts again: back to COMMAND.
        await helm.stop_posting()
        sent = len(simulator.sim.commands())
        await until(lambda: in_state(frontseat_pb.INTERFACE_HELM_ERROR))
        assert interface.status().helm_error == frontseat_pb.ERROR_HELM_NOT_RUNNING
        assert interface.helm_state == frontseat_pb.HELM_NOT_RUNNING
        assert len(simulator.sim.commands()) == sent
        helm.run()
        await until(lambda: in_state(frontseat_pb.INTERFACE_COMMAND))

        # The simulator goes away: FS_ERROR (not connected); it comes back on the same port:
        # STANDBY -> LISTEN -> COMMAND, and the new vehicle is driven to the helm's course.
        await simulator.stop()
        await until(lambda: in_state(frontseat_pb.INTERFACE_FS_ERROR))
        assert interface.status().frontseat_error == frontseat_pb.ERROR_FRONTSEAT_NOT_CONNECTED
        await recorder.wait_for(
            "IFS_STATUS", lambda v: status_of(v).state == frontseat_pb.INTERFACE_FS_ERROR
        )
        mark = len(states)
        simulator = Simulator(sim_port)
        await simulator.start()
        await until(lambda: in_state(frontseat_pb.INTERFACE_COMMAND))
        assert states[mark - 1 :] == [
            frontseat_pb.INTERFACE_FS_ERROR,
            frontseat_pb.INTERFACE_STANDBY,
            frontseat_pb.INTERFACE_LISTEN,
            frontseat_pb.INTERFACE_COMMAND,
        ]
        assert simulator.sim.received[0].startswith("START,")
        vehicle = simulator.sim.vehicle
        await until(lambda: (vehicle.heading, vehicle.speed, vehicle.z) == (90.0, 2.0, -10.0))

        # The mission ends (a 1 s mission started through IFS_RAW_OUT): CTRL,STATE:IDLE ->
        # LISTEN, NAV stops -> FS_ERROR (not providing data) after the driver's 10 s (1 s
        # wall). iFrontSeat sends nothing in FS_ERROR; an operator's START on the
        # simulator brings the data back, and the interface back to COMMAND.
        start = "START,LAT:42.5,LON:-70.5,DURATION:1,FREQ:2,WARP:10"
        recorder.client.publish(
            "IFS_RAW_OUT",
            serialize_for_moos(frontseat_pb.Raw(raw=start.encode())),
            time=app.moos_time(),
        )
        await until(lambda: in_state(frontseat_pb.INTERFACE_FS_ERROR))
        assert interface.status().frontseat_error == frontseat_pb.ERROR_FRONTSEAT_NOT_PROVIDING_DATA
        assert start in simulator.sim.received
        mark = len(states)
        _, operator = await asyncio.open_connection("127.0.0.1", sim_port)
        operator.write(b"START,LAT:42.5,LON:-70.5,FREQ:2,WARP:10\r\n")
        await until(lambda: in_state(frontseat_pb.INTERFACE_COMMAND))
        operator.close()
        assert states[mark:] == [
            frontseat_pb.INTERFACE_STANDBY,
            frontseat_pb.INTERFACE_LISTEN,
            frontseat_pb.INTERFACE_COMMAND,
        ]

    assert all(
        line.startswith(("START", "CMD,HEADING:90,SPEED:2,DEPTH:10"))
        for line in simulator.sim.received
    )


async def test_the_frontseat_link_is_served_through_a_moosdb_outage(tmp_path):
    # The MOOSDB goes away: iFrontSeat keeps reading its frontseat and running the interface,
    # so it sees the helm fall silent (HELM_ERROR) instead of freezing in COMMAND.
    simulator = Simulator()
    sim_port = await simulator.start()
    async with contextlib.AsyncExitStack() as stack:
        stack.push_async_callback(lambda: simulator.stop())
        db = MOOSDB(port=0, clock=moos_clock(WARP))
        await db.start()
        stack.push_async_callback(lambda: db.stop())
        helm = ScriptedHelm(db.port)
        await helm.start()
        stack.push_async_callback(helm.close)
        path = tmp_path / "auv1.moos"
        path.write_text(MISSION.format(db_port=db.port, warp=WARP, sim_port=sim_port))
        app = await stack.enter_async_context(iFrontSeat.from_mission(path))
        helm.run()
        await until(lambda: app.interface.state == frontseat_pb.INTERFACE_COMMAND)
        port = db.port
        await db.stop()
        await until(lambda: app.interface.state == frontseat_pb.INTERFACE_HELM_ERROR)
        assert not app.connected
        assert app.interface.status().helm_error == frontseat_pb.ERROR_HELM_NOT_RUNNING
        db = MOOSDB(port=port, clock=moos_clock(WARP))
        await db.start()
        await until(lambda: app.interface.state == frontseat_pb.INTERFACE_COMMAND)
