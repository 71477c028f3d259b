"""liaison as an attacker on the same machine meets it: a page on a rebinding DNS name, a page
of another site, a client without the launch token, save/load names that lead out of the save
folder, a filter that would freeze a regex engine, more live streams than allowed. The server
is real (uvicorn on a loopback socket, its own pages' state fed MOOS mail); no MOOSDB needed."""

from __future__ import annotations

import asyncio
import http.client
import json
import socket
import string

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pygoby.topside.commander import SaveFileError
from pygoby.topside.errors import ScopeFilterError
from pygoby.topside.liaison.access import Access, SaveFolder
from pygoby.topside.liaison.feed import PageSnapshots, ScopeStream
from pygoby.topside.liaison.models import FILTER_MAX, ScopeFilter

from .liaison_server import Served, served


async def call(function, *args, **kwargs):
    return await asyncio.to_thread(function, *args, **kwargs)


# ---------------------------------------------------------------------------------- Host, Origin, token
@pytest.mark.timeout(30)
async def test_rebinding_host_foreign_origin_and_missing_token_are_refused(tmp_path):
    async with served(tmp_path) as s:
        assert f"/scope?token={s.token}" in s.web.url  # printed at start-up, as Jupyter does
        # a page on a rebinding name: its requests carry its own name as Host
        for method, path in (("GET", "/api/commander/types"), ("GET", "/scope")):
            status, text = await call(s.request, method, path, None, {"Host": "attacker.example"})
            assert status == 403 and "Host" in text
        body = {"action": "set", "type": "pygoby.examples.Command", "field": "heading", "text": "9"}
        status, _ = await call(s.post, body, {"Host": f"attacker.example:{s.web.port}"})
        assert status == 403
        # another site's page (a same-origin header it managed to add notwithstanding)
        status, text = await call(s.post, body, {"Origin": "http://attacker.example"})
        assert status == 403 and "other sites" in text
        # no token: reading on loopback is fine, changing is not
        assert (await call(s.request, "GET", "/api/commander/types"))[0] == 200
        status, _ = await call(s.post, body, {"Authorization": ""})
        assert status == 401
        status, _ = await call(s.post, body, {"Authorization": "Bearer wrong"})
        assert status == 401
        # the bound address, localhost and the page's own origin pass
        for host in (f"127.0.0.1:{s.web.port}", f"localhost:{s.web.port}"):
            status, reply = await call(s.post, body, {"Host": host, "Origin": f"http://{host}"})
            assert status == 200 and json.loads(reply)["ok"], reply
        assert s.state.commander.open("pygoby.examples.Command").value("heading") == "9"


@pytest.mark.timeout(30)
async def test_the_printed_url_leaves_the_token_as_the_pages_cookie(tmp_path):
    async with served(tmp_path) as s:

        def first_page() -> str:
            connection = http.client.HTTPConnection("127.0.0.1", s.web.port, timeout=10)
            connection.request("GET", f"/scope?token={s.token}")
            response = connection.getresponse()
            response.read()
            connection.close()
            return response.getheader("set-cookie")

        cookie = await call(first_page)
        assert cookie.startswith(f"liaison_token_{s.web.port}={s.token}")
        assert "HttpOnly" in cookie and "SameSite=Strict" in cookie
        name_value = cookie.split(";")[0]
        body = {"action": "open", "type": "pygoby.examples.Command"}
        status, _ = await call(s.post, body, {"Authorization": "", "Cookie": name_value})
        assert status == 200


def test_host_rules():
    loopback = Access("127.0.0.1", "t", 1)
    assert loopback.host_allowed("127.0.0.1:1") and loopback.host_allowed("LOCALHOST:8080")
    assert loopback.host_allowed("[::1]:1") and not loopback.host_allowed("attacker.example")
    assert not loopback.host_allowed("127.0.0.1.attacker.example") and not loopback.host_allowed("")
    everywhere = Access("0.0.0.0", "t", 1, ["topside.local"])
    assert everywhere.host_allowed("192.168.1.5:1") and everywhere.host_allowed("topside.local")
    assert not everywhere.host_allowed("attacker.example")
    assert everywhere.host_allowed(f"{socket.gethostname()}:54321")
    assert not everywhere.origin_allowed("http://attacker.example") and everywhere.origin_allowed(
        None
    )
    # off loopback every request needs the token, reading too
    assert everywhere.refusal("GET", {"host": "10.0.0.2"}, "", {})[0] == 401
    assert everywhere.refusal("GET", {"host": "10.0.0.2"}, "token=t", {}) is None


# ---------------------------------------------------------------------------------- save folder
@pytest.mark.timeout(30)
async def test_save_and_load_stay_in_the_save_folder(tmp_path):
    outside = tmp_path / "outside.txt"
    outside.write_text("secret")
    async with served(tmp_path) as s:
        errors = set()
        for action in ("save", "load"):
            for name in (
                "../outside.txt",
                str(outside),
                "/nonexistent/file",
                "a/../../outside.txt",
                "",
                "..",
            ):
                status, reply = await call(
                    s.post, {"action": action, "type": "pygoby.examples.Command", "path": name}
                )
                assert status == 422, (action, name)
                errors.add(json.loads(reply)["error"])
        assert errors == {SaveFolder.REFUSED}  # one text: nothing learned about the server's files
        assert outside.read_text() == "secret"
        assert (await call(s.post, {"action": "save", "path": "mine/one.txt"}))[0] == 200
        assert "message::" in (s.save_dir / "mine" / "one.txt").read_text()
        status, reply = await call(s.post, {"action": "load", "path": "mine/one.txt"})
        assert status == 200 and json.loads(reply)["warnings"] == []


def test_a_link_out_of_the_save_folder_is_refused(tmp_path):
    folder = tmp_path / "saves"
    folder.mkdir()
    (folder / "out").symlink_to(tmp_path)
    with pytest.raises(SaveFileError, match="inside liaison's save folder"):
        SaveFolder(folder).path("out/x.txt")


@given(st.text(alphabet=string.ascii_letters + "./\\~:\0 ", max_size=30))
def test_save_names_resolve_inside_the_folder_or_are_refused(tmp_path_factory, name):
    folder = tmp_path_factory.getbasetemp() / "fuzzed_saves"
    try:
        path = SaveFolder(folder).path(name)
    except SaveFileError as err:
        assert str(err) == SaveFolder.REFUSED
    else:
        assert path.is_relative_to(folder.resolve()) and path != folder.resolve()


# ---------------------------------------------------------------------------------- Scope filter
@pytest.mark.timeout(20)
def test_scope_filters_are_globs_or_words_never_regexes():
    names = ["NAV_X", "NAV_Y", "ACOMMS_MODEM_RECEIVE", "DB_TIME", "x" * 30_000 + "!"]
    assert [n for n in names if ScopeFilter("nav_*")(n)] == ["NAV_X", "NAV_Y"]
    assert [n for n in names if ScopeFilter("modem, db_")(n)] == ["ACOMMS_MODEM_RECEIVE", "DB_TIME"]
    assert [n for n in names if ScopeFilter("NAV_?")(n)] == ["NAV_X", "NAV_Y"]
    assert all(ScopeFilter("")(n) for n in names)
    # a regex engine spends minutes on these against the long name; a glob has no backtracking
    assert not any(ScopeFilter(r"((\w+)+)+!")(n) for n in names)
    assert ScopeFilter("*" + "?*" * 90 + "!")(names[-1])
    with pytest.raises(ScopeFilterError, match=f"at most {FILTER_MAX} characters"):
        ScopeFilter("x" * (FILTER_MAX + 1))


@given(
    st.text(alphabet="ab*?", max_size=8),
    st.text(alphabet="abAB", max_size=10),
)
def test_scope_glob_terms_match_as_fnmatch_does(term, name):
    import fnmatch

    expected = fnmatch.fnmatchcase(
        name.lower(), term if "*" in term or "?" in term else f"*{term}*"
    )
    assert ScopeFilter(term)(name) is expected


@pytest.mark.timeout(30)
async def test_a_too_long_filter_is_refused(tmp_path):
    async with served(tmp_path) as s:
        status, text = await call(s.request, "GET", f"/api/events?page=scope&filter={'x' * 300}")
        assert status == 400 and "at most" in text


# ---------------------------------------------------------------------------------- live streams
def test_one_snapshot_per_tick_and_deltas_to_each_stream(tmp_path):
    s = Served(tmp_path)
    s.web._socket.close()
    for i in range(50):
        s.mail(f"VAR_{i:02d}", float(i))
    built = []
    rows_json = s.state.scope.rows_json
    s.state.scope.rows_json = lambda now: built.append(now) or rows_json(now)  # counts builds
    snapshots = PageSnapshots(s.state)
    streams = [ScopeStream(ScopeFilter("")) for _ in range(5)] + [
        ScopeStream(ScopeFilter("VAR_1*"))
    ]
    from collections import Counter

    snapshots.build(Counter(scope=len(streams)))
    first = [json.loads(stream.message(snapshots)) for stream in streams]
    assert len(built) == 1
    assert [len(m["changed"]) for m in first] == [50] * 5 + [10] and all(m["full"] for m in first)
    s.clock += 0.2
    s.mail("VAR_10", 99.0)
    snapshots.build(Counter(scope=len(streams)))
    second = [json.loads(stream.message(snapshots)) for stream in streams]
    assert len(built) == 2
    for message in second:  # only the row that changed
        assert not message["full"] and [r["key"] for r in message["changed"]] == ["VAR_10"]
        assert message["changed"][0]["value"] == "99" and message["removed"] == []


@pytest.mark.timeout(30)
async def test_live_streams_are_capped(tmp_path):
    async with served(tmp_path, max_streams=3) as s:
        s.mail("NAV_X", 1.0)
        readers = []
        for _ in range(3):
            reader, writer = await asyncio.open_connection("127.0.0.1", s.web.port)
            writer.write(b"GET /api/events?page=scope HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
            await writer.drain()
            head = await reader.readuntil(b"\r\n\r\n")
            assert head.startswith(b"HTTP/1.1 200")
            assert b'"full": true' in await reader.readuntil(b"\n\n")
            readers.append((reader, writer))
        status, text = await call(s.request, "GET", "/api/events?page=map")
        assert status == 503 and "max_streams" in text
        _, writer = readers.pop()
        writer.close()
        for _ in range(100):  # the server sees the closed stream at its next tick
            status, _ = await call(s.request, "HEAD", "/api/events?page=nopage")
            if s.web.feed.open_streams < 3:
                break
            await asyncio.sleep(0.05)
        assert s.web.feed.open_streams == 2
        for _, writer in readers:
            writer.close()
