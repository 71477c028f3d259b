"""Every server pygoby starts listens on loopback unless told otherwise (issue 16 item 14).

Each listener is started as a user starts it, with its defaults and port 0, and the address its
socket is bound to is read back from the socket itself.
"""

from __future__ import annotations

from pygoby.acomms import messages as m
from pygoby.acomms.drivers.store_server import StoreServerDriver
from pygoby.acomms.store_server import StoreServer, TransmissionStore, serve_store
from pygoby.cli import build_parser as pygoby_parser
from pygoby.frontseat.simulator import server as frontseat_server
from pygoby.netsim.manager import server as netsim_server
from pygoby.netsim.manager.config import EXAMPLE_CONFIG, parse_config
from pygoby.netsim.manager.core import NetSimManager
from pygoby.util.linebased import TCPServerLink

LOOPBACK = "127.0.0.1"


async def test_netsim_manager_listens_on_loopback_by_default():
    server = netsim_server.ManagerServer(NetSimManager(parse_config(EXAMPLE_CONFIG)), port=0)
    await server.start()
    try:
        assert server._server.sockets[0].getsockname()[0] == LOOPBACK
    finally:
        await server.close()
    assert netsim_server.build_parser().parse_args(["c.cfg"]).host is None  # config decides
    assert netsim_server.build_parser().parse_args(["c.cfg", "--host", "0.0.0.0"]).host == "0.0.0.0"


async def test_frontseat_simulator_listens_on_loopback_by_default():
    server = frontseat_server.SimulatorServer(0)
    await server.start()
    try:
        assert server.link._server.sockets[0].getsockname()[0] == LOOPBACK
    finally:
        server.close()
    assert frontseat_server.build_parser().parse_args(["0"]).host == LOOPBACK
    assert frontseat_server.build_parser().parse_args(["0", "--host", "0.0.0.0"]).host == "0.0.0.0"


async def test_store_server_listens_on_loopback_by_default():
    store = TransmissionStore()
    server = await serve_store(StoreServer(store), port=0)
    try:
        assert server.sockets[0].getsockname()[0] == LOOPBACK
    finally:
        server.close()
        store.close()
    assert pygoby_parser().parse_args(["store_server"]).host == LOOPBACK


def test_other_pygoby_servers_default_to_loopback():
    parser = pygoby_parser()
    for argv in (
        ["mmsim", "--port", "0", "--id", "1"],
        ["abc_modem_simulator", "--port", "0"],
        ["moosdb"],
    ):
        assert parser.parse_args(argv).host == LOOPBACK, argv


async def test_line_server_link_defaults_to_loopback_and_a_driver_binds_tcp_server():
    link = TCPServerLink(0)
    link.open()
    await link.wait_listening()
    try:
        assert link._server.sockets[0].getsockname()[0] == LOOPBACK
    finally:
        link.close()
    # a driver serving a networked modem binds `tcp_server` when given (all interfaces if not)
    cfg = m.DriverConfig(
        modem_id=1,
        tcp_port=0,
        tcp_server="127.0.0.2",
        connection_type=m.DriverConfig.CONNECTION_TCP_AS_SERVER,
    )
    driver = StoreServerDriver()
    assert driver._make_link(cfg, "\r").host == "127.0.0.2"
    cfg.ClearField("tcp_server")
    assert driver._make_link(cfg, "\r").host == "0.0.0.0"
