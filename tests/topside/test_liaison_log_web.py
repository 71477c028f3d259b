"""liaison over a recorded log, served (uvicorn on a loopback socket, plain HTTP requests): the
replay's endpoints on virtual time, and the access rules of live liaison in log mode too (Host,
Origin, token, X-Liaison), the Commander refused, no file named by a client."""

from __future__ import annotations

import asyncio
import contextlib
import http.client
import json
import re
import signal
import subprocess
import sys
from collections.abc import AsyncIterator
from pathlib import Path

import pytest

from pygoby.topside.liaison.log_app import LogLiaison
from pygoby.util.clock import VirtualClock

from .liaison_server import http_request

DATA = Path(__file__).resolve().parents[1] / "data" / "alog"
LOG, MISSION = DATA / "liaison.alog", DATA / "acomms.moos"


class LogServed:
    """A LogLiaison on 127.0.0.1 (any free port) on a VirtualClock; `request` is one plain
    HTTP/1.1 request (run in a thread: the server is in this test's event loop)."""

    def __init__(self) -> None:
        self.clock = VirtualClock(5000.0)
        self.liaison = LogLiaison(LOG, MISSION, port=0, clock=self.clock)
        self.port = self.liaison.web.port
        self.token = self.liaison.web.token

    async def request(
        self, method: str, path: str, body: object = None, headers: dict | None = None
    ) -> tuple[int, str]:
        return await asyncio.to_thread(http_request, self.port, method, path, body, headers)

    async def control(self, body: object, **headers: str) -> tuple[int, str]:
        sent = {
            "X-Liaison": "1",
            "Content-Type": "application/json",
            "Authorization": f"Bearer {self.token}",
            **headers,
        }
        return await self.request("POST", "/api/log", body, sent)

    async def status(self) -> dict:
        status, text = await self.request("GET", "/api/log")
        assert status == 200, text
        return json.loads(text)

    async def at(self, t: float) -> dict:
        """The status once the ticks (5 a second) have brought the pages to log time `t`."""
        for _ in range(100):
            status = await self.status()
            if status["caught_up"] and status["time"] == pytest.approx(t):
                return status
            await asyncio.sleep(0.05)
        raise AssertionError(f"the replay never got to {t}: {status}")


@contextlib.asynccontextmanager
async def log_served() -> AsyncIterator[LogServed]:
    served = LogServed()
    async with served.liaison:
        yield served


@pytest.mark.timeout(60)
async def test_the_replays_controls_move_the_pages_on_virtual_time():
    async with log_served() as s:
        status = await s.status()
        assert (
            status["replaying"]
            and status["file"] == "liaison.alog"
            and status["duration"] == pytest.approx(60.2)
        )
        assert (status["entries"], status["bad_lines"]) == (223, 1)
        assert str(LOG.parent) not in json.dumps(status)  # the file's name, never its folder

        code, text = await s.control({"action": "seek", "time": 25})
        assert code == 200 and json.loads(text)["target"] == 25.0
        await s.at(25.0)
        code, text = await s.request("GET", "/api/scope/history?key=NAV_X")
        points = json.loads(text)["points"]
        assert points[-1][1] == 58.0 and points[-1][0] - s.liaison.index.log_start < 25.0

        assert (await s.control({"action": "speed", "speed": 10}))[0] == 200
        assert (await s.control({"action": "play"}))[0] == 200
        s.clock.advance(2.0)  # 20 s of log at 10x
        assert (await s.at(45.0))["playing"]
        code, text = await s.request("GET", "/api/scope/history?key=NAV_X")
        assert json.loads(text)["points"][-1][1] == 98.0  # posted at 44.2 s
        assert (await s.control({"action": "pause"}))[0] == 200
        s.clock.advance(10.0)
        await asyncio.sleep(0.5)  # ticks on real time: a few of them
        assert not (await s.at(45.0))["playing"]

        # back: the pages are those of the earlier time again
        assert (await s.control({"action": "seek", "time": 5.0}))[0] == 200
        await s.at(5.0)
        code, text = await s.request("GET", "/api/scope/history?key=NAV_X")
        assert [v for _, v in json.loads(text)["points"]] == [10.0, 12.0, 14.0, 16.0, 18.0]


@pytest.mark.timeout(60)
async def test_requests_the_replay_does_not_take_are_refused_clearly():
    async with log_served() as s:
        for body, reason in (
            ({"action": "speed", "speed": 3}, "speed 3 is not one of"),
            ({"action": "seek", "time": "25"}, "`time` is a number"),
            ({"action": "seek"}, "`time` is a number"),
            ({"action": "open", "path": "/etc/passwd"}, "no action 'open'"),
            (["seek"], "a JSON object"),
        ):
            code, text = await s.control(body)
            assert code == 400 and reason in json.loads(text)["error"], (body, text)
        code, text = await s.request(
            "POST",
            "/api/log",
            None,
            {"X-Liaison": "1", "Authorization": f"Bearer {s.token}"},
        )
        assert code == 400


@pytest.mark.timeout(60)
async def test_log_mode_keeps_the_host_origin_and_token_rules_and_posts_nothing():
    async with log_served() as s:
        play = {"action": "play"}
        for path in ("/api/log", "/scope", "/api/events?page=scope"):
            code, text = await s.request("GET", path, None, {"Host": "attacker.example"})
            assert code == 403 and "Host" in text, path
        code, _ = await s.control(play, Host=f"attacker.example:{s.port}")
        assert code == 403
        code, text = await s.control(play, Origin="http://attacker.example")
        assert code == 403 and "other sites" in text
        assert (await s.control(play, Authorization=""))[0] == 401
        assert (await s.control(play, Authorization="Bearer wrong"))[0] == 401
        assert (await s.control(play, **{"X-Liaison": ""}))[0] == 403
        assert not (await s.status())["playing"]  # none of them played
        assert (await s.control(play, Origin=f"http://127.0.0.1:{s.port}"))[0] == 200
        assert (await s.status())["playing"]
        # the Commander sends, saves and loads nothing: there is no MOOSDB and no save folder
        for body in (
            {"action": "send", "type": "logtest.Status"},
            {"action": "load", "type": "logtest.Status", "path": "../../etc/passwd"},
        ):
            code, text = await s.request(
                "POST",
                "/api/commander",
                body,
                {"X-Liaison": "1", "Authorization": f"Bearer {s.token}"},
            )
            assert code == 409 and "replaying a log" in json.loads(text)["error"]


@pytest.mark.timeout(60)
async def test_a_live_liaison_has_no_replay(tmp_path):
    from .liaison_server import served

    async with served(tmp_path) as s:
        status, text = await asyncio.to_thread(s.request, "GET", "/api/log")
        assert status == 200 and json.loads(text) == {"replaying": False}
        headers = {"X-Liaison": "1", "Authorization": f"Bearer {s.token}"}
        status, text = await asyncio.to_thread(
            s.request, "POST", "/api/log", {"action": "play"}, headers
        )
        assert status == 404 and "not replaying a log" in text


@pytest.mark.e2e
@pytest.mark.timeout(60)
def test_pygoby_liaison_log_serves_until_interrupted():
    """The real command line as a subprocess: it indexes, prints the URL, serves the replay,
    and ends with status 0 at SIGINT."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "pygoby.cli", "liaison", "--log", str(LOG), "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        summary = proc.stdout.readline()
        assert (
            summary == "liaison: liaison.alog: 223 entries over 60.2 s, 1 damaged lines skipped\n"
        )
        match = re.fullmatch(
            r"liaison: serving http://127\.0\.0\.1:(\d+)/scope\?token=\S+\n", proc.stdout.readline()
        )
        assert match, "no URL printed"
        connection = http.client.HTTPConnection("127.0.0.1", int(match.group(1)), timeout=10)
        connection.request("GET", "/api/log")
        status = json.loads(connection.getresponse().read())
        connection.close()
        assert status["replaying"] and status["entries"] == 223 and status["time"] == 0.0
        assert status["community"] == "logtest"  # without --mission: that of MOOSDB_logtest
    finally:
        proc.send_signal(signal.SIGINT)
        code = proc.wait(10)
    assert code == 0, proc.stderr.read() if proc.stderr else ""
