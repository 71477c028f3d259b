"""$GPRMC output: the sentence vectors, and a manager writing to a real pty."""

from __future__ import annotations

import os
import select

import pytest
from netsim_vectors import from_vector_dict, of_kind

from pygoby.netsim.manager.config import parse_config
from pygoby.netsim.manager.core import NetSimManager
from pygoby.netsim.manager.gprmc import GpsOutputs, gprmc_sentence
from pygoby.netsim.manager.protocol import encode_line, message_class, request_class
from pygoby.util.clock import VirtualClock


@pytest.mark.parametrize("vector", of_kind("gprmc"), ids=lambda v: v["id"])
def test_gprmc_vectors(vector):
    nav = from_vector_dict(message_class("NavUpdate"), vector["nav"])
    assert gprmc_sentence(nav, vector["system_time_utc_s"]) == vector["sentence"]


def test_manager_writes_gprmc_to_a_serial_port():
    (vector,) = [v for v in of_kind("gprmc") if v["id"] == "gprmc-seed"]
    master, slave = os.openpty()
    try:
        config = parse_config(
            'sim_env_pair { modem_tcp_port: 62003 endpoint_ip_address: "127.0.0.1" '
            "environment_id: 1 }\n"
            "env_bounds { environment_id: 1 lat_min: 71 lon_min: -150 lat_max: 79 "
            "lon_max: -140 depth_max: 3813 }\n"
            f'gps_out {{ modem_tcp_port: 62003 serial {{ port: "{os.ttyname(slave)}" '
            "baud: 4800 } }\n"
        )
        manager = NetSimManager(config)
        outputs = GpsOutputs.open_serial(config, VirtualClock(vector["system_time_utc_s"]))
        manager.on_nav(outputs.on_nav_update)
        request = request_class()(id=1)
        request.nav.append(from_vector_dict(message_class("NavUpdate"), vector["nav"]))
        manager.connection("127.0.0.1").receive(encode_line(request))
        received = b""
        while not received.endswith(b"\r\n"):
            ready, _, _ = select.select([master], [], [], 5)
            assert ready, "no $GPRMC written"
            received += os.read(master, 1024)
        assert received.decode() == vector["sentence"]
    finally:
        os.close(master)
        os.close(slave)
