"""Every modem driver pAcommsHandler can select, end to end: two communities (embedded MOOSDB +
pAcommsHandler each) exchange a DCCL status message through each driver type of seed 002's list
that pygoby implements (and UDP multicast), and through a driver installed as an entry point.
So no driver can be unreachable from a mission file again."""

from __future__ import annotations

import asyncio
import contextlib
import random
import socket

import pytest

from pygoby.acomms.abc_simulator import ABCSimulator, serve_abc
from pygoby.acomms.drivers import BUILTIN_DRIVERS, ENTRY_POINT_GROUP
from pygoby.acomms.store_server import StoreServer, TransmissionStore, serve_store
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB

from .acomms_mission import MicroModemLink, TwoCommunities, mission_clock

pytestmark = pytest.mark.e2e

NAV = {"NAV_X": 100.0, "NAV_Y": -50.0, "NAV_SPEED": 1.5, "NAV_HEADING": -90.0, "NAV_DEPTH": 10.0}
REPORT = "src=1,x=100,y=-50,speed=1.5,heading=270,depth=10"


def _free_port(kind: int = socket.SOCK_STREAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class ABCLink:
    """The ABC example modem simulator on loopback TCP."""

    async def start(self, stack: contextlib.AsyncExitStack, dbs: list[MOOSDB]) -> None:
        server = await serve_abc(ABCSimulator())
        stack.callback(server.close)
        self.port = server.sockets[0].getsockname()[1]

    def driver_cfg(self, modem_id: int) -> str:
        return f"""  driver_cfg {{ driver_type: DRIVER_ABC_EXAMPLE_MODEM
    connection_type: CONNECTION_TCP_AS_CLIENT tcp_server: "127.0.0.1" tcp_port: {self.port} }}
"""


class StoreServerLink:
    """A goby_store_server (pygoby's) both drivers poll."""

    async def start(self, stack: contextlib.AsyncExitStack, dbs: list[MOOSDB]) -> None:
        store = TransmissionStore()
        stack.callback(store.close)
        server = await serve_store(StoreServer(store), "127.0.0.1", 0)
        stack.callback(server.close)
        self.port = server.sockets[0].getsockname()[1]

    def driver_cfg(self, modem_id: int) -> str:
        return f"""  driver_cfg {{ driver_type: DRIVER_STORE_SERVER
    connection_type: CONNECTION_TCP_AS_CLIENT tcp_server: "127.0.0.1" tcp_port: {self.port}
    [goby.acomms.store_server.protobuf.config] {{ query_interval_seconds: 0.1 }} }}
"""


class UDPLink:
    """Two UDP sockets, each listing the other as its broadcast remote (modem_id 0: goby3 sends
    a broadcast only to those)."""

    async def start(self, stack: contextlib.AsyncExitStack, dbs: list[MOOSDB]) -> None:
        self.ports = {1: _free_port(socket.SOCK_DGRAM), 2: _free_port(socket.SOCK_DGRAM)}

    def driver_cfg(self, modem_id: int, driver: str = "driver_type: DRIVER_UDP") -> str:
        other = 3 - modem_id
        return f"""  driver_cfg {{ {driver}
    [goby.acomms.udp.protobuf.config] {{ local {{ port: {self.ports[modem_id]} }}
      remote {{ modem_id: 0 ip: "127.0.0.1" port: {self.ports[other]} }} }} }}
"""


class MulticastLink:
    """One multicast group on loopback (a port of its own, so parallel runs do not meet)."""

    async def start(self, stack: contextlib.AsyncExitStack, dbs: list[MOOSDB]) -> None:
        self.port = random.randint(40000, 60000)

    def driver_cfg(self, modem_id: int) -> str:
        return f"""  driver_cfg {{ driver_type: DRIVER_UDP_MULTICAST
    [goby.acomms.udp_multicast.protobuf.config] {{ listen_address: "127.0.0.1"
      multicast_address: "239.255.42.98" multicast_port: {self.port} }} }}
"""


class UFieldLink:
    """What MOOS-IvP's uField toolbox does between the communities (pShare, uFldNodeComms and
    uFldMessageHandler, which pygoby does not provide): a NODE_MESSAGE_LOCAL posted on one
    community becomes `<var_name> = <string_val>` on the addressed one."""

    async def start(self, stack: contextlib.AsyncExitStack, dbs: list[MOOSDB]) -> None:
        self.lookup = stack.enter_context(_temp_lookup())
        self.clients = {}
        for modem_id, db in zip((1, 2), dbs, strict=True):
            client = MOOSClient(f"shoreside_relay{modem_id}", port=db.port, clock=mission_clock())
            await client.connect()
            stack.push_async_callback(client.close)
            client.subscribe("NODE_MESSAGE_LOCAL")
            self.clients[f"vehicle{modem_id}"] = client
        for name, client in self.clients.items():
            task = asyncio.create_task(self._relay(name, client))
            stack.callback(task.cancel)

    async def _relay(self, source: str, client: MOOSClient) -> None:
        async for msg in client:
            fields = dict(part.split("=", 1) for part in msg.string.split(","))
            for name, target in self.clients.items():
                if name != source and fields["dest_node"] in (name, "all"):
                    target.publish(fields["var_name"], fields["string_val"])

    def driver_cfg(self, modem_id: int) -> str:
        # moos_server/moos_port come from the mission's ServerHost/ServerPort
        return f"""  driver_cfg {{ driver_type: DRIVER_UFIELD_SIM_DRIVER
    [goby.moos.ufld.protobuf.config] {{ modem_id_lookup_path: "{self.lookup}" }} }}
"""


@contextlib.contextmanager
def _temp_lookup():
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "modemidlookup.txt"
        path.write_text("0, broadcast, broadcast\n1, vehicle1, auv\n2, vehicle2, auv\n")
        yield path


class EntryPointLink(UDPLink):
    """A driver installed by another distribution under the entry point group (here pygoby's
    UDP driver class under the name `test_udp`), selected with driver_name."""

    def driver_cfg(self, modem_id: int, driver: str = 'driver_name: "test_udp"') -> str:
        return super().driver_cfg(modem_id, driver)


@pytest.fixture
def installed_test_driver(monkeypatch, tmp_path):
    dist_info = tmp_path / "site" / "pygoby_test_modem-1.0.dist-info"
    dist_info.mkdir(parents=True)
    (dist_info / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: pygoby-test-modem\nVersion: 1.0\n"
    )
    (dist_info / "entry_points.txt").write_text(
        f"[{ENTRY_POINT_GROUP}]\ntest_udp = pygoby.acomms.drivers.udp:UDPDriver\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path / "site"))


LINKS = {
    "DRIVER_WHOI_MICROMODEM": MicroModemLink,
    "DRIVER_ABC_EXAMPLE_MODEM": ABCLink,
    "DRIVER_UFIELD_SIM_DRIVER": UFieldLink,
    "DRIVER_STORE_SERVER": StoreServerLink,
    "DRIVER_UDP": UDPLink,
    "DRIVER_UDP_MULTICAST": MulticastLink,
}


def test_every_builtin_driver_has_an_end_to_end_test():
    assert set(LINKS) == set(BUILTIN_DRIVERS) - {"DRIVER_NONE"}


async def exchange_status(net: TwoCommunities) -> None:
    (r1, r2) = net.recorders
    await net.ready()
    for var, value in NAV.items():
        r1.client.publish(var, value)
    await r1.wait_for("ACOMMS_QSIZE")
    r1.client.publish("SEND_STATUS", "now")
    assert await r2.wait_for("STATUS_REPORT_IN", timeout=30) == REPORT


@pytest.mark.parametrize("driver_type", list(LINKS))
async def test_status_message_through_each_driver_type(tmp_path, driver_type):
    async with TwoCommunities(tmp_path, link=LINKS[driver_type]()) as net:
        assert [type(app.acomms.primary.driver).__name__ for app in net.apps] == [
            BUILTIN_DRIVERS[driver_type].rsplit(":", 1)[1]
        ] * 2
        await exchange_status(net)


async def test_status_message_through_an_installed_driver(tmp_path, installed_test_driver):
    async with TwoCommunities(tmp_path, link=EntryPointLink()) as net:
        assert type(net.apps[0].acomms.primary.driver).__name__ == "UDPDriver"
        await exchange_status(net)
