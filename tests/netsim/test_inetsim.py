"""iNetSimManager against an embedded MOOSDB and a real netsim_manager on TCP: NAV_* variables
become NavUpdates, pAcommsHandler's modem receptions become ReceiveStats, answers are posted."""

from __future__ import annotations

import asyncio
import logging

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.apps.inetsimmanager import iNetSimManager
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.translator import serialize_for_moos
from pygoby.netsim.manager.config import parse_config
from pygoby.netsim.manager.core import NetSimManager
from pygoby.netsim.manager.navreporter import NavReporter
from pygoby.netsim.manager.server import ManagerServer
from pygoby.util.geodesy import UTMGeodesy

MANAGER = """
sim_env_pair { modem_tcp_port: 62000 endpoint_ip_address: "127.0.0.1" environment_id: 0 }
sim_env_pair { modem_tcp_port: 62001 endpoint_ip_address: "127.0.0.1" environment_id: 0 }
env_bounds { environment_id: 0 lat_min: 41 lon_min: -72 lat_max: 43 lon_max: -69
             depth_min: 0 depth_max: 200 }
"""


def mission(db_port: int, manager_port: int, modem_port: int) -> str:
    return f"""\
ServerHost = localhost
ServerPort = {db_port}
Community  = alpha
LatOrigin  = 42.35
LongOrigin = -70.95

ProcessConfig = iNetSimManager
{{
  common {{ log: false  app_tick: 20  verbosity: QUIET }}
  modem_tcp_port: {modem_port}
  manager_port: {manager_port}
  nav_period: 0.1
}}
"""


def reception_with_stats(mode: int) -> object:
    rx = acomms_pb.ModemTransmission(src=2, dest=1, type=acomms_pb.ModemTransmission.DATA)
    stat = rx.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat.add(
        mode=mode,
        time=1_700_000_000_000_000,
        clock_mode=1,
        mfd_power=10,
        mfd_ratio=100,
        rate=1,
        source=2,
        dest=1,
        psk_error_code=0,
        packet_type=3,
        number_frames=3,
        number_bad_frames=0,
        snr_rss=40,
        snr_in=12,
        snr_out=20,
        snr_symbols=20,
        mse_equalizer=-12,
        data_quality_factor=200,
        doppler=0.4,
        stddev_noise=40,
        carrier_freq=25000,
        bandwidth=5000,
    )
    assert stat.IsInitialized()
    return rx


async def wait_for(condition, timeout: float = 5.0) -> None:
    async with asyncio.timeout(timeout):
        while not condition():
            await asyncio.sleep(0.02)


@pytest.fixture
async def manager():
    netsim = NetSimManager(parse_config(MANAGER))
    server = ManagerServer(netsim, "127.0.0.1", 0)
    await server.start()
    navs, stats = [], []
    netsim.on_nav(navs.append)
    netsim.on_stats(stats.append)
    yield server, navs, stats
    await server.close()


async def test_nav_and_receive_stats_reach_the_manager(tmp_path, manager):
    server, navs, stats = manager
    async with (
        MOOSDB(port=0, community="alpha") as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        path = tmp_path / "mission.moos"
        path.write_text(mission(db.port, server.bound_port, 62001))
        app = iNetSimManager.from_mission(path)
        async with app:
            tester.subscribe("NETSIM_STATUS")
            await app.netsim.wait_connected(5)
            for var, value in (
                ("NAV_X", 1200.0),
                ("NAV_Y", -300.0),
                ("NAV_DEPTH", 15.0),
                ("NAV_SPEED", 1.5),
                ("NAV_HEADING", -90.0),
            ):
                tester.publish(var, value)
            await wait_for(lambda: navs and navs[-1].nav.heading == 270.0)
            nav = navs[-1].nav
            lat, lon = UTMGeodesy(42.35, -70.95).to_geo(1200.0, -300.0)
            assert nav.modem_tcp_port == 62001
            assert (nav.lat, nav.lon) == (
                pytest.approx(lat, abs=1e-9),
                pytest.approx(lon, abs=1e-9),
            )
            assert (nav.depth, nav.speed) == (15.0, 1.5)
            status = await tester.receive(5)
            assert (status.key, status.value) == ("NETSIM_STATUS", "UPDATE_ACCEPTED")

            tester.publish("ACOMMS_MODEM_RECEIVE", serialize_for_moos(reception_with_stats(0)))
            tester.publish("ACOMMS_MODEM_RECEIVE", serialize_for_moos(reception_with_stats(1)))
            tester.publish(
                "ACOMMS_MODEM_RECEIVE", "@PB[goby.acomms.protobuf.ModemTransmission] src: "
            )
            await wait_for(lambda: len(stats) >= 2)
            assert [s.packet_success for s in stats] == [True, False]
            assert {(s.modem_tcp_port, s.tx_modem_tcp_port) for s in stats} == {(62001, 62001)}
            assert stats[0].mm_stats.snr_in == 12
            assert app.connected


async def test_refused_port_is_posted(tmp_path, manager, caplog):
    server, navs, _ = manager
    async with (
        MOOSDB(port=0, community="alpha") as db,
        MOOSClient("tester", port=db.port) as tester,
    ):
        path = tmp_path / "mission.moos"
        path.write_text(mission(db.port, server.bound_port, 62009))
        with caplog.at_level(logging.WARNING):
            app = iNetSimManager.from_mission(path)
            app.log.addHandler(caplog.handler)  # the app's log does not propagate to the root
            async with app:
                tester.subscribe("NETSIM_STATUS")
                await app.netsim.wait_connected(5)
                tester.publish("NAV_LAT", 42.1)
                tester.publish("NAV_LONG", -70.1)
                tester.publish("NAV_SPEED", "fast")  # not a number: ignored with a warning
                tester.publish("NAV_DEPTH", 3.0)
                status = await tester.receive(5)
                assert status.value == "UPDATE_FAILED_INVALID_MODEM_TCP_PORT"
        assert navs == []
        assert "NAV_SPEED is not a number" in caplog.text


def test_reporter_needs_position_and_depth():
    reporter = NavReporter(62000)
    reporter.update("x", 10.0, 1.0)
    reporter.update("y", 10.0, 1.0)
    reporter.update("depth", 5.0, 2.0)
    assert reporter.nav_update() is None  # x/y without an origin
    reporter.set_origin(42.0, -70.0)
    reporter.update("depth", float("nan"), 3.0)  # ignored
    nav = reporter.nav_update()
    assert nav is not None and nav.time == 2.0 and nav.depth == 5.0
    reporter.update("lat", 42.5, 4.0)
    reporter.update("lon", -70.5, 4.0)
    assert (reporter.nav_update().lat, reporter.nav_update().lon) == (42.5, -70.5)  # lat/lon win
    assert NavReporter(62000, modem_ports={3: 62100}).port_of(3) == 62100
    assert reporter.port_of(4) == 62003
    assert reporter.receive_stats(acomms_pb.ModemTransmission(src=1)) == []
