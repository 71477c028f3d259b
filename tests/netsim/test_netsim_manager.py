"""netsim_manager: configuration, request processing against the exchange vectors, and a real
TCP server on loopback with well-behaved and garbage clients side by side."""

from __future__ import annotations

import asyncio
import os
import random
import socket
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from netsim_vectors import of_kind, to_vector_dict

from pygoby.netsim.manager.config import EXAMPLE_CONFIG, ConfigError, parse_config
from pygoby.netsim.manager.core import NetSimManager, peer_ip_string
from pygoby.netsim.manager.protocol import (
    LineDecoder,
    ReceivedMessage,
    encode_line,
    message_class,
    request_class,
    request_names,
    response_names,
)
from pygoby.netsim.manager.server import ManagerServer
from tests.hypothesis_profiles import examples

CONFIGS = {v["name"]: v["textformat"] for v in of_kind("manager_config")}


def _manager(name: str, **overrides) -> NetSimManager:
    config = parse_config(CONFIGS[name])
    for key, value in overrides.items():
        setattr(config, key, value)
    return NetSimManager(config)


# -- configuration -----------------------------------------------------------------------------


@pytest.mark.parametrize("vector", of_kind("manager_config"), ids=lambda v: v["id"])
def test_reference_configs_load(vector):
    config = parse_config(vector["textformat"])
    assert config.manager_tcp_port == 61999
    assert len(config.sim_env_pair) >= 4


@pytest.mark.parametrize("vector", of_kind("manager_config_invalid"), ids=lambda v: v["id"])
def test_invalid_configs_fail_with_the_first_upstream_error(vector):
    with pytest.raises(ConfigError) as info:
        parse_config(vector["textformat"])
    assert str(info.value) == vector["expected_error"]


def test_upstream_goby3_blocks_are_accepted_but_typos_are_not():
    upstream = (
        'app { glog_config { tty_verbosity: DEBUG1 } }\ninterprocess { platform: "audioserver" }\n'
        + CONFIGS["audioserver"]
        + 'gps_out { modem_tcp_port: 62000 serial { port: "/dev/ttyUSB0" baud: 4800 '
        "flow_control: NONE } }\n"
    )
    config = parse_config(upstream)
    assert config.gps_out[0].serial.baud == 4800
    with pytest.raises(ConfigError, match="sim_env_par"):
        parse_config(CONFIGS["loopback"] + "sim_env_par { }\n")
    with pytest.raises(ConfigError, match="latmin"):
        parse_config("env_bounds { environment_id: 0 latmin: 1 }\n")


def test_missing_required_field_is_a_config_error():
    with pytest.raises(ConfigError, match="depth_max"):
        parse_config("env_bounds { environment_id: 0 lat_min: 0 lon_min: 0 lat_max: 1 lon_max: 1 }")


def test_example_config_is_valid():
    assert len(parse_config(EXAMPLE_CONFIG).sim_env_pair) == 2


def test_console_script_prints_example_config():
    result = subprocess.run(
        [sys.executable, "-m", "pygoby.netsim.manager.server", "--example_config"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert result.stdout == EXAMPLE_CONFIG


# -- request processing ------------------------------------------------------------------------


@pytest.mark.parametrize("vector", of_kind("exchange"), ids=lambda v: v["id"])
def test_exchange_vectors(vector):
    # Upstream behaviour (NaN accepted) is checked here; pygoby's default is tested below.
    manager = _manager(vector["config"], reject_nonfinite_position=False)
    forwarded, stats = [], []
    manager.on_nav(forwarded.append)
    manager.on_stats(stats.append)
    replies = manager.connection(vector["peer_ip"]).receive(vector["request_line"].encode())
    assert replies == [vector["response_line"].encode()]
    assert [to_vector_dict(f) for f in forwarded] == vector["forwarded"]
    assert len(stats) == vector["stats_republished"]
    for update in forwarded:
        assert manager.position(update.nav.modem_tcp_port) == update.nav


def test_nonfinite_position_rejected_by_default():
    (vector,) = [v for v in of_kind("exchange") if v["id"] == "ex-nan-lat"]
    manager = _manager(vector["config"])
    (reply,) = manager.connection(vector["peer_ip"]).receive(vector["request_line"].encode())
    (event,) = LineDecoder(response_names()).feed(reply)
    assert event.message.status == event.message.UPDATE_FAILED_OUT_OF_DEFINED_REGION
    assert manager.positions() == {}


def test_latest_position_per_port_is_kept():
    manager = _manager("loopback")
    connection = manager.connection("127.0.0.1")
    nav_cls = message_class("NavUpdate")
    for i, port in enumerate((62000, 62001, 62000)):
        request = request_class()(id=i)
        request.nav.append(
            nav_cls(
                modem_tcp_port=port,
                time=100.0 + i,
                lat=42.0,
                lon=-70.0,
                depth=1.0 + i,
                speed=0.0,
                heading=0.0,
            )
        )
        connection.receive(encode_line(request))
    assert manager.position(62000).time == 102.0
    assert manager.position(62001).depth == 2.0
    assert manager.position(62002) is None


def test_ipv4_mapped_peer_is_compared_as_dotted_ipv4():
    assert peer_ip_string("::ffff:127.0.0.1") == "127.0.0.1"
    assert peer_ip_string("10.0.0.5") == "10.0.0.5"
    assert peer_ip_string("::1") == "::1"


# -- real TCP server ---------------------------------------------------------------------------


def _nav_request(request_id: int, port: int = 62000):
    request = request_class()(id=request_id)
    request.nav.append(
        message_class("NavUpdate")(
            modem_tcp_port=port,
            time=1.7e9,
            lat=42.0,
            lon=-70.0,
            depth=5.0,
            speed=1.0,
            heading=90.0,
        )
    )
    return request


async def _read_responses(reader, decoder, count):
    events = []
    while len(events) < count:
        data = await asyncio.wait_for(reader.read(65536), 5)
        assert data, "server closed the connection"
        events += decoder.feed(data)
    return events


@pytest.fixture
async def server():
    server = ManagerServer(_manager("loopback"), "127.0.0.1", 0)
    await server.start()
    yield server
    await server.close()


async def test_tcp_request_response_and_status_codes(server):
    reader, writer = await asyncio.open_connection("127.0.0.1", server.bound_port)
    writer.write(encode_line(_nav_request(1)) + encode_line(_nav_request(2, port=62003)))
    writer.write(encode_line(_nav_request(3, port=62999)))
    events = await _read_responses(reader, LineDecoder(response_names()), 3)
    statuses = [(e.message.request_id, e.message.status) for e in events]
    assert statuses == [(1, 1), (2, 3), (3, 2)]
    assert server.manager.position(62000).lat == 42.0
    writer.close()
    await writer.wait_closed()


async def _garbage_client(port: int, payloads: list[bytes]) -> None:
    _reader, writer = await asyncio.open_connection("127.0.0.1", port)
    for payload in payloads:
        writer.write(payload)
        await writer.drain()
        await asyncio.sleep(0)
    writer.close()
    await writer.wait_closed()


async def test_garbage_clients_do_not_disturb_well_behaved_ones(server):
    rng = random.Random(7)
    port = server.bound_port
    garbage = [
        [os.urandom(4096) for _ in range(64)],  # random bytes
        [b"Z" * (1 << 20) for _ in range(10)] + [b"\n"],  # a 10 MiB line
        [b"no separators at all\n" * 500],
        [b"NETSIM|netsim.protobuf.Unknown|CAA=\n" * 200],
        [b"NETSIM|netsim.protobuf.NetSimManagerRequest|!!!not base64***\n" * 200],
    ]
    garbage_tasks = [asyncio.create_task(_garbage_client(port, g)) for g in garbage]

    async def good_client(n: int) -> list[int]:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        decoder = LineDecoder(response_names())
        ids = []
        for i in range(20):
            writer.write(encode_line(_nav_request(n * 1000 + i)))
            (event,) = await _read_responses(reader, decoder, 1)
            assert isinstance(event, ReceivedMessage)
            assert event.message.status == 1
            ids.append(event.message.request_id)
            await asyncio.sleep(rng.random() * 0.005)
        writer.close()
        await writer.wait_closed()
        return ids

    results = await asyncio.gather(*(good_client(n) for n in range(4)))
    await asyncio.gather(*garbage_tasks)
    for n, ids in enumerate(results):
        assert ids == [n * 1000 + i for i in range(20)]
    # The server is still up and answering after all of it.
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(b"\xff\xfe garbage\n" + encode_line(_nav_request(99)))
    (event,) = await _read_responses(reader, LineDecoder(response_names()), 1)
    assert event.message.request_id == 99
    writer.close()
    await writer.wait_closed()


async def test_wrong_base64_is_answered_as_a_partial_request(server):
    """A line whose base64 is garbage still gets exactly one answer (upstream behaviour)."""
    reader, writer = await asyncio.open_connection("127.0.0.1", server.bound_port)
    writer.write(b"NETSIM|netsim.protobuf.NetSimManagerRequest|////\n")
    (event,) = await _read_responses(reader, LineDecoder(response_names()), 1)
    assert (event.message.request_id, event.message.status) == (0, 1)
    writer.close()
    await writer.wait_closed()


_pieces = st.sampled_from(
    [
        b"NETSIM|",
        b"netsim.protobuf.NetSimManagerRequest|",
        b"NetSimManagerRequest|",
        b"netsim.protobuf.NetSimManagerResponse|",
        b"CAA=",
        b"CEIS",
        b"////",
        b"|",
        b"\n",
        b"\r\n",
    ]
)


@settings(max_examples=examples(200), deadline=None)
@given(st.lists(st.one_of(st.binary(max_size=40), _pieces), max_size=40))
def test_fuzz_manager_answers_each_request_line_exactly_once(chunks):
    manager = _manager("loopback")
    connection = manager.connection("127.0.0.1")
    stream = b"".join(chunks) + b"\n"
    replies = [r for chunk in chunks for r in connection.receive(chunk)]
    replies += connection.receive(b"\n")
    expected = [
        e for e in LineDecoder(request_names()).feed(stream) if isinstance(e, ReceivedMessage)
    ]
    assert len(replies) == len(expected)
    decoded = LineDecoder(response_names()).feed(b"".join(replies))
    assert [e.message.request_id for e in decoded] == [e.message.id for e in expected]


async def test_close_with_a_client_blocked_on_output_logs_no_traceback(server):
    # issue 25, item 13: at SIGTERM the manager cancels every client's task; one that waited
    # for a peer that never reads must end quietly, not as an "Exception in callback" traceback
    loop = asyncio.get_running_loop()
    reported: list[dict] = []
    loop.set_exception_handler(lambda _loop, context: reported.append(context))
    sock = socket.socket()
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    sock.connect(("127.0.0.1", server.bound_port))
    sock.setblocking(False)
    _, writer = await asyncio.open_connection(sock=sock)
    burst = encode_line(_nav_request(1)) * 200
    for _ in range(100):  # answers pile up unread until the server waits in drain()
        writer.write(burst)
        await asyncio.sleep(0.01)
    await server.close()
    await asyncio.sleep(0.1)  # the task's done callbacks run
    writer.transport.abort()
    assert reported == []
