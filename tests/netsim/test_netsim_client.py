"""netsim client: request numbering against the vector, and a real manager on loopback
(responses, futures, callbacks, dropped-while-disconnected requests, reconnection)."""

from __future__ import annotations

import asyncio

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from netsim_vectors import from_vector_dict, of_kind

from pygoby.netsim.manager.client import MAX_REQUEST_ID, NetSimClient, RequestTracker, status_name
from pygoby.netsim.manager.config import parse_config
from pygoby.netsim.manager.core import NetSimManager
from pygoby.netsim.manager.protocol import (
    LEGACY_REQUEST_NAME,
    encode_line,
    request_class,
    response_class,
)
from pygoby.netsim.manager.server import ManagerServer
from tests.hypothesis_profiles import examples

LOOPBACK = {v["name"]: v["textformat"] for v in of_kind("manager_config")}["loopback"]


def _nav(port=62000, lat=42.0, t=1.7e9):
    return NetSimClient.nav(
        modem_tcp_port=port, time=t, lat=lat, lon=-70.0, depth=5.0, speed=1.0, heading=90.0
    )


def test_id_sequence_vector():
    (vector,) = of_kind("client_sequence")
    tracker = RequestTracker()
    for step in vector["steps"]:
        request = tracker.build(from_vector_dict(request_class(), step["decoded"]).nav)
        assert tracker.encode(request).decode() == step["request_line"]


def test_ids_wrap_to_zero_and_legacy_name():
    tracker = RequestTracker(legacy_names=True, first_id=MAX_REQUEST_ID)
    assert [tracker.take_id() for _ in range(3)] == [MAX_REQUEST_ID, 0, 1]
    line = tracker.encode(tracker.build())
    assert line.startswith(b"NETSIM|" + LEGACY_REQUEST_NAME.encode() + b"|")


@pytest.mark.parametrize("first_id", [-1, MAX_REQUEST_ID + 1])
def test_first_id_must_be_a_request_id(first_id):
    with pytest.raises(ValueError, match="within 0.."):
        RequestTracker(first_id=first_id)


@pytest.fixture
async def server():
    server = ManagerServer(NetSimManager(parse_config(LOOPBACK)), "127.0.0.1", 0)
    await server.start()
    yield server
    await server.close()


async def test_responses_match_requests_and_callbacks_see_them(server):
    seen = []
    client = NetSimClient("127.0.0.1", server.bound_port, on_response=seen.append)
    await client.start()
    await client.wait_connected(5)
    futures = [client.send_navs([_nav()]), client.send_navs([_nav(port=62003)])]
    first, second = await asyncio.gather(*futures)
    assert (first.request_id, status_name(first)) == (0, "UPDATE_ACCEPTED")
    assert (second.request_id, status_name(second)) == (1, "UPDATE_FAILED_INVALID_SOURCE_ADDRESS")
    assert [r.request_id for r in seen] == [0, 1]
    await client.close()


async def test_legacy_client_gets_legacy_answers(server):
    client = NetSimClient("127.0.0.1", server.bound_port, legacy_names=True)
    await client.start()
    await client.wait_connected(5)
    response = await client.send_navs([_nav()])
    assert status_name(response) == "UPDATE_ACCEPTED"
    await client.close()


async def test_reconnects_and_sends_newest_position(unused_tcp_port):
    manager = NetSimManager(parse_config(LOOPBACK))
    client = NetSimClient("127.0.0.1", unused_tcp_port, backoff_initial=0.05, backoff_max=0.2)
    await client.start()
    # Not connected: requests are dropped, their ids used up, only the newest nav kept.
    assert client.send_navs([_nav(lat=41.9)]) is None
    assert client.send_navs([_nav(lat=42.1)]) is None
    server = ManagerServer(manager, "127.0.0.1", unused_tcp_port)
    await server.start()
    await client.wait_connected(5)
    for _ in range(100):
        if manager.position(62000) is not None:
            break
        await asyncio.sleep(0.02)
    assert manager.position(62000).lat == 42.1
    # The server goes away: a waiting request fails, and the client comes back by itself.
    await server.close()
    for _ in range(100):
        if not client.connected:
            break
        await asyncio.sleep(0.02)
    assert not client.connected
    server = ManagerServer(manager, "127.0.0.1", unused_tcp_port)
    await server.start()
    await client.wait_connected(5)
    response = await client.send_navs([_nav(lat=42.2)])
    assert response.request_id == 3  # ids 0 and 1 were dropped, 2 went out on reconnect
    assert client.connections == 2
    await client.close()
    await server.close()


async def test_pending_request_fails_when_connection_drops():
    async def swallow(reader, writer):
        await reader.read(100)
        writer.close()

    server = await asyncio.start_server(swallow, "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    client = NetSimClient("127.0.0.1", port, backoff_initial=10)
    await client.start()
    await client.wait_connected(5)
    future = client.send_navs([_nav()])
    with pytest.raises(ConnectionError):
        await asyncio.wait_for(future, 5)
    await client.close()
    server.close()
    await server.wait_closed()


@settings(max_examples=examples(200), deadline=None)
@given(st.lists(st.binary(max_size=64), max_size=20))
def test_fuzz_tracker_survives_garbage_and_still_matches(chunks):
    loop = asyncio.new_event_loop()
    try:
        tracker = RequestTracker()
        future = loop.create_future()
        request = tracker.build()
        tracker.expect(request.id, future)
        for chunk in chunks:
            tracker.feed(chunk)
        answer = response_class()(request_id=request.id, status=1)
        tracker.feed(b"\n" + encode_line(answer))
        assert future.done() and future.result().request_id == request.id
    finally:
        loop.close()
