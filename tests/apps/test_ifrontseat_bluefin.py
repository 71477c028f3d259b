"""examples/frontseat/bluefin_auv.moos run through iFrontSeat: the Bluefin vehicle simulator,
the embedded MOOSDB, iFrontSeat and a scripted helm in one process, time-warped. The interface
reaches INTERFACE_COMMAND, the vehicle follows the helm's DESIRED_*, TRIM_CONTROL comes back as
TRIM_REPORT, ACOMMS_RAW_INCOMING reaches the vehicle as $BPTMR and CTD_* as $BPCTD."""

from __future__ import annotations

import asyncio
import contextlib
from pathlib import Path

from pygoby.apps.ifrontseat import iFrontSeat
from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.bluefin.server import HuxleyServer
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.timewarp import moos_clock
from pygoby.moos.translator.translator import post_for_moos

MISSION = Path(__file__).resolve().parents[2] / "examples" / "frontseat" / "bluefin_auv.moos"
BLUEFIN = "goby.middleware.frontseat.protobuf.bluefin_config"
WARP = 10.0


def test_the_example_mission_reads():
    cfg = iFrontSeat.read_config(MissionFile.read(MISSION), "iFrontSeat")
    assert cfg.driver_library == "libgoby_frontseat_bluefin.so.30"
    bf = cfg.frontseat_cfg.Extensions[frontseat_pb.BLUEFIN_CONFIG]
    assert (bf.huxley_tcp_port, bf.reconnect_interval) == (29500, 2)
    legacy = cfg.legacy_cfg
    assert legacy.pub_sub_bf_commands and legacy.subscribe_acomms_raw and legacy.subscribe_ctd


async def test_the_example_mission_drives_the_bluefin_vehicle():
    clock = moos_clock(WARP)
    async with contextlib.AsyncExitStack() as stack:
        server = HuxleyServer(0, clock=clock)
        port = await server.start()
        serving = asyncio.create_task(server.serve())
        stack.callback(serving.cancel)
        db = await stack.enter_async_context(MOOSDB(port=0, clock=clock))
        overrides = [
            ("common", f"time_warp_multiplier: {WARP:g}  verbosity: WARN"),
            (
                "frontseat_cfg",
                f'[{BLUEFIN}] {{ huxley_tcp_address: "127.0.0.1"  huxley_tcp_port: {port} }}',
            ),
        ]
        app = iFrontSeat.from_mission(MISSION, overrides=overrides, port=db.port)
        assert app.cfg.legacy_cfg.pub_sub_bf_commands  # the mission's legacy_cfg is kept
        await stack.enter_async_context(app)

        latest: dict[str, object] = {}

        def seen(msg: MOOSMessage) -> None:
            latest[msg.key] = msg.dval if msg.is_double else msg.string

        watcher = MOOSClient("watch", port=db.port, clock=clock, on_message=seen)
        await watcher.connect()
        stack.push_async_callback(watcher.close)
        for var in ("NAV_HEADING", "NAV_SPEED", "NAV_DEPTH", "TRIM_REPORT", "FRONTSEAT_READY"):
            watcher.subscribe(var)
        helm = MOOSClient("pHelmIvP", port=db.port, clock=clock)
        await helm.connect()
        stack.push_async_callback(helm.close)

        async def until(done, virtual_s: float) -> None:
            async with asyncio.timeout(virtual_s / WARP):
                while not done():
                    helm.publish("IVPHELM_STATE", "DRIVE")
                    helm.publish("DESIRED_HEADING", 90.0)
                    helm.publish("DESIRED_DEPTH", 10.0)
                    helm.publish("DESIRED_SPEED", 1.5)
                    await asyncio.sleep(1.0 / WARP)

        await until(lambda: app.interface.state == frontseat_pb.INTERFACE_COMMAND, 30)
        await until(
            lambda: (
                abs(latest.get("NAV_HEADING", 0) - 90) < 0.5
                and abs(latest.get("NAV_SPEED", 0) - 1.5) < 0.01
                and abs(latest.get("NAV_DEPTH", 0) - 10) < 0.1
            ),
            40,
        )
        assert latest["FRONTSEAT_READY"] == 1.0

        # a backseat CTD (legacy CTD_*: S/m, dbar, C) goes to the vehicle as $BPCTD (S/m, kPa)
        helm.publish("CTD_CONDUCTIVITY", 4.2)
        helm.publish("CTD_PRESSURE", 10.0)
        helm.publish("CTD_TEMPERATURE", 10.5)
        helm.publish("TRIM_CONTROL", "true")
        raw = frontseat_pb.ModemRaw(raw=b"$CARXD,1,2,0,1,abcd*7F")
        post = post_for_moos("ACOMMS_RAW_INCOMING", raw, app.moos_technique)
        helm.publish(post.var, post.value)
        await until(lambda: "TRIM_REPORT" in latest, 20)
        assert latest["TRIM_REPORT"] == "status=2,error=0,trim_pitch=0.5,trim_roll=0"
        await until(lambda: any(s.sentence_id == "TMR" for s in server.simulator.received), 20)
        (tmr,) = [s for s in server.simulator.received if s.sentence_id == "TMR"]
        assert tmr.fields[2:] == ("3", "$CARXD:1:2:0:1:abcd/7F")
        await until(lambda: any(s.sentence_id == "CTD" for s in server.simulator.received), 20)
        (ctd,) = [s for s in server.simulator.received if s.sentence_id == "CTD"]
        assert ctd.fields[2:5] == ("4.2", "10.5", "100")
        assert app.interface.state == frontseat_pb.INTERFACE_COMMAND
