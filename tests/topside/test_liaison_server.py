"""liaison's server without a browser: pAcommsHandler serving it from a `liaison` block, the
access token off loopback, the POST header, the static files in the package."""

from __future__ import annotations

import asyncio
import json
import shutil
import socket
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from pygoby.topside.liaison import is_loopback
from tests.apps.acomms_mission import TwoCommunities

pytestmark = pytest.mark.e2e


def fetch(url: str, body: dict | None = None, headers: dict | None = None) -> tuple[int, str]:
    data = json.dumps(body).encode() if body is not None else None
    request = urllib.request.Request(url, data=data, headers=headers or {})
    try:
        with urllib.request.urlopen(request, timeout=5) as response:
            return response.status, response.read().decode()
    except urllib.error.HTTPError as err:
        return err.code, err.read().decode()


def test_loopback_addresses():
    assert is_loopback("127.0.0.1") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.5") and not is_loopback("")


@pytest.mark.timeout(60)
async def test_pacommshandler_serves_liaison_with_a_token_off_loopback(tmp_path, capsys):
    liaison = 'liaison { http_address: "0.0.0.0"  http_port: 0 }'
    async with TwoCommunities(tmp_path, extra=liaison) as net:
        web = net.apps[0].liaison.web
        assert web.token and f"?token={web.token}" in capsys.readouterr().out  # printed at start-up
        base = f"http://127.0.0.1:{web.port}"
        assert (await asyncio.to_thread(fetch, f"{base}/scope"))[0] == 401
        status, page = await asyncio.to_thread(fetch, f"{base}/scope?token={web.token}")
        assert status == 200 and '<script src="/static/liaison.js">' in page
        auth = {"Authorization": f"Bearer {web.token}"}
        status, script = await asyncio.to_thread(fetch, f"{base}/static/liaison.js", None, auth)
        assert status == 200 and "EventSource" in script  # shipped in the package, no CDN
        types = json.loads(
            (await asyncio.to_thread(fetch, f"{base}/api/commander/types", None, auth))[1]
        )
        assert {t["short"] for t in types["types"]} == {"Command", "SimpleStatus"}
        body = {"action": "open", "type": "Command"}
        assert (await asyncio.to_thread(fetch, f"{base}/api/commander", body, auth))[0] == 403
        status, reply = await asyncio.to_thread(
            fetch,
            f"{base}/api/commander",
            {**body, "action": "set", "field": "heading", "text": "999"},
            {**auth, "X-Liaison": "1", "Content-Type": "application/json"},
        )
        assert status == 422 and "above the maximum 360" in json.loads(reply)["error"]


@pytest.mark.timeout(60)
async def test_embedded_liaison_offers_the_goby11_xml_messages(tmp_path):
    """pAcommsHandler's own message set, XML files included, is the Commander page's (loaded
    once: no message defined twice); Goby 1.1's name=value posts, refusals with the bound."""
    from tests.goby11.test_examples import EXAMPLES

    extra = f'liaison {{ http_port: 0 }}\n  dccl_cfg {{ message_file {{ path: "{EXAMPLES}/xml/example1.xml" }} }}'
    async with TwoCommunities(tmp_path, extra=extra) as net:
        web = net.apps[0].liaison.web
        base = f"http://127.0.0.1:{web.port}"
        types = json.loads((await asyncio.to_thread(fetch, f"{base}/api/commander/types"))[1])
        assert {t["short"] for t in types["types"]} == {
            "Command",
            "SimpleStatus",
            "GoToCommand",
            "VehicleStatus",
        }
        headers = {
            "X-Liaison": "1",
            "Content-Type": "application/json",
            "Authorization": f"Bearer {web.token}",
        }

        async def command(**body) -> tuple[int, dict]:
            status, reply = await asyncio.to_thread(fetch, f"{base}/api/commander", body, headers)
            return status, json.loads(reply)

        status, reply = await command(
            action="set", type="GoToCommand", field="goto_x", text="20000"
        )
        assert status == 422 and "goto_x: 20000 is above the maximum 10000" in reply["error"]
        for field, text in (("Destination", "2"), ("goto_x", "150"), ("new_instructions", "dive")):
            assert (await command(action="set", type="GoToCommand", field=field, text=text))[
                0
            ] == 200
        status, reply = await command(action="preview", type="GoToCommand")
        assert reply["preview"]["posts"] == [
            "SPECIAL_INSTRUCTIONS: new_instructions=dive",
            "OUTGOING_COMMAND: Destination=2,type=goto,goto_x=150",
        ]
        fields = {f["name"]: f for f in reply["fields"]}
        assert (
            fields["new_instructions"]["editable"]
            and fields["new_instructions"]["source"] == "SPECIAL_INSTRUCTIONS"
        )


def test_a_taken_http_port_is_a_configuration_error(tmp_path):
    """`pygoby liaison` on a port another program holds: one line saying so and status 1 (it
    was uvicorn's traceback and SystemExit(3) from inside the running app)."""
    examples = Path(__file__).resolve().parents[2] / "examples" / "two_vehicles"
    for name in ("topside.moos", "two_vehicles.proto", "modemidlookup.txt"):
        shutil.copy(examples / name, tmp_path / name)
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        mission = tmp_path / "topside.moos"
        text = mission.read_text()
        assert text.count("liaison { node_report_var") == 1
        mission.write_text(
            text.replace(
                "liaison { node_report_var", f"liaison {{ http_port: {port} node_report_var"
            )
        )
        pygoby = str(Path(sys.executable).with_name("pygoby"))
        done = subprocess.run(
            [pygoby, "liaison", "topside.moos"],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert done.returncode == 1, done.stderr
    assert "Traceback" not in done.stderr
    assert (
        f"liaison: fatal configuration error: liaison: cannot serve the pages on 127.0.0.1:{port}"
        in done.stderr
    )
