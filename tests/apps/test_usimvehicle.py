"""uSimVehicle: kinematics (sans I/O) and the app's NAV_* posts, steering and scripted events."""

from __future__ import annotations

import asyncio

import pytest

from pygoby.apps.usimvehicle import VehicleModel, uSimVehicle
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB


def test_model_moves_along_heading_and_steers_at_bounded_rates():
    v = VehicleModel(heading=90.0, speed=2.0)
    v.step(10.0)
    assert (v.x, v.y) == pytest.approx((20.0, 0.0))
    v.desired_heading, v.desired_speed, v.desired_depth = 350.0, 0.0, 3.0
    v.step(1.0)  # 10 deg/s the short way round (through 0), 0.5 m/s^2, 0.5 m/s dive
    assert (v.heading, v.speed, v.depth) == pytest.approx((80.0, 1.5, 0.5))
    for _ in range(20):
        v.step(1.0)
    assert (v.heading, v.speed, v.depth) == pytest.approx((350.0, 0.0, 3.0))
    v.desired_depth = -5.0
    v.step(100.0)
    assert v.depth == 0.0  # never above the surface


MISSION = """\
ServerHost = localhost
ServerPort = {port}
Community = alpha
ProcessConfig = uSimVehicle
{{
  common {{ log: false  app_tick: 20  verbosity: QUIET }}
  start_x: 10  start_heading: 90  start_speed: 1  nav_period: 0.1  turn_rate: 90
  event {{ time: 0.2  var: "SCRIPTED"  sval: "hello" }}
  event {{ time: 0.3  var: "SCRIPTED_D"  dval: 7 }}
}}
"""


async def test_app_posts_nav_steers_and_runs_script(tmp_path):
    async with MOOSDB(port=0) as db, MOOSClient("tester", port=db.port) as tester:
        path = tmp_path / "m.moos"
        path.write_text(MISSION.format(port=db.port))
        for var in ("NAV_X", "NAV_HEADING", "SCRIPTED", "SCRIPTED_D"):
            tester.subscribe(var)
        await tester.flush()
        async with uSimVehicle.from_mission(path):
            seen: dict[str, list] = {}
            async with asyncio.timeout(10):
                while len(seen.get("SCRIPTED_D", [])) < 1 or len(seen.get("NAV_X", [])) < 3:
                    msg = await tester.receive()
                    seen.setdefault(msg.key, []).append(msg.value)
            assert seen["SCRIPTED"] == ["hello"] and seen["SCRIPTED_D"] == [7.0]
            xs = seen["NAV_X"]
            assert xs[0] >= 10.0 and xs[-1] > xs[0]  # moving east
            tester.publish("DESIRED_HEADING", 180.0)
            tester.publish("DESIRED_HEADING", "south")  # not a double: warned and ignored
            async with asyncio.timeout(10):
                while True:
                    msg = await tester.receive()
                    if msg.key == "NAV_HEADING" and msg.value == 180.0:
                        break
