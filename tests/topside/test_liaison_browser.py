"""liaison in a real browser (headless Chromium driven by Playwright) against a real mission:
two communities with embedded MOOSDBs, pAcommsHandlers and emulated Micro-Modems. A command
composed in the page reaches the other vehicle and shows acknowledged; the scope shows a
variable changing; the map shows both vehicles. `make screenshots` writes each page to docs/images/
(the README shows them)."""

from __future__ import annotations

import asyncio
import os
import shutil
from pathlib import Path

import playwright.async_api as playwright_api  # a dev dependency: these tests never skip
import pytest

from pygoby.apps.liaison import Liaison
from tests.apps.acomms_mission import TwoCommunities

from .mission import topside_mission

pytestmark = pytest.mark.e2e

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
# `make screenshots` sets this to docs/images (the README's pictures); otherwise the shots go to
# the test's tmp dir, so a test run leaves the work tree as it found it
SCREENSHOTS_ENV = "PYGOBY_SCREENSHOTS"

LIAISON = """
ProcessConfig = liaison
{
  common { log: false  verbosity: WARN  app_tick: 20 }
  liaison {
    http_port: 0
    update_freq: 5
    node_report_var: "STATUS_REPORT_IN"
    commander { autosave_path: "%s"  command: "Command" }
  }
}
"""


@pytest.fixture
async def browser(tmp_path):
    if not Path(CHROMIUM).exists():
        pytest.fail("chromium is not installed (make test installs it: apt-get install chromium)")
    async with playwright_api.async_playwright() as pw:
        browser = await pw.chromium.launch_persistent_context(
            str(tmp_path / "chromium-profile"),
            executable_path=CHROMIUM,
            args=FLAGS,
            headless=True,
            viewport={"width": 1200, "height": 760},
        )
        yield browser
        await browser.close()


# every table and panel of the shown page whose content is wider than the box that clips it
# (the nearest ancestor that does not let it overflow), and a page wider than the window
CUT_OFF = """() => {
  const out = [];
  const section = document.querySelector('main section:not([hidden])');
  for (const el of section.querySelectorAll('table, .panel, pre, .slots')) {
    let clip = el.parentElement;
    while (clip !== document.body && getComputedStyle(clip).overflowX === 'visible') clip = clip.parentElement;
    const right = el.getBoundingClientRect().right, limit = clip.getBoundingClientRect().right;
    if (right > limit + 0.5 || el.scrollWidth > el.clientWidth + 1) out.push(el.id || el.className);
  }
  if (document.documentElement.scrollWidth > innerWidth) out.push('page');
  return out;
}"""


async def shot(page, name: str, tmp_path: Path) -> None:
    """The page at 1000 and 1200 px wide shows every column; the picture is taken at 1200."""
    for width in (1000, 1200):
        await page.set_viewport_size({"width": width, "height": 760})
        assert await page.evaluate(CUT_OFF) == [], f"{name} at {width} px cuts off content"
    folder = Path(os.environ.get(SCREENSHOTS_ENV) or tmp_path / "screenshots")
    folder.mkdir(parents=True, exist_ok=True)
    await page.screenshot(path=str(folder / f"liaison-{name}.png"))


@pytest.mark.timeout(180)
async def test_liaison_pages_in_chromium(tmp_path, browser):
    async with TwoCommunities(tmp_path) as net:
        (r1, r2) = net.recorders
        await net.ready()
        r1.client.subscribe("COMMAND_OUT")  # to see that preview publishes nothing, send once
        await r1.client.flush()
        path = topside_mission(net, tmp_path, LIAISON % (tmp_path / "autosave.txt"))
        liaison = Liaison.from_mission(path, "liaison")
        async with liaison:
            base = liaison.web.url.split("/scope")[0]
            page = await browser.new_page()
            console_errors: list[str] = []
            page.on(
                "console", lambda m: console_errors.append(m.text) if m.type == "error" else None
            )
            # the printed URL leaves the launch token as the page's cookie (and out of the
            # address bar); the Commander's POSTs need it
            await page.goto(liaison.web.url)
            await page.wait_for_function("!location.search.includes('token')")

            # Scope: NAV_X changes and the page follows; the history plot of NAV_X.
            r1.client.publish("NAV_X", 10.0)
            await page.goto(f"{base}/scope")
            cell = page.locator('#scope-table tr[data-key="NAV_X"] td.value')
            await cell.wait_for()
            await page.wait_for_function(
                "document.querySelector('#scope-table tr[data-key=\"NAV_X\"] td.value').textContent === '10'"
            )
            r1.client.publish("NAV_X", 25.0)
            await page.wait_for_function(
                "document.querySelector('#scope-table tr[data-key=\"NAV_X\"] td.value').textContent === '25'"
            )
            for var, value in {
                "NAV_Y": -40.0,
                "NAV_HEADING": 45.0,
                "NAV_SPEED": 1.0,
                "NAV_DEPTH": 0.0,
            }.items():
                r1.client.publish(var, value)
            # a normal click (the button held 150 ms) selects, however often the rows update,
            # and the History panel is in view
            r1.client.publish("LONG_TEXT", "x" * 3000)
            long_row = page.locator('#scope-table tr[data-key="LONG_TEXT"]')
            await long_row.wait_for()
            for key in ("NAV_Y", "NAV_HEADING", "NAV_SPEED", "NAV_X"):
                await page.locator(f'#scope-table tr[data-key="{key}"]').click(delay=150)
                assert await page.locator("#history-key").text_content() == key
                assert (
                    await page.locator("#scope-table tr.selected").get_attribute("data-key") == key
                )
                assert await page.locator("#history-canvas").is_visible()
                box = await page.locator("#history-canvas").bounding_box()
                assert box is not None and box["y"] >= 0 and box["y"] + box["height"] <= 760
            # a long value is one line until its expander opens it
            one_line = (await long_row.bounding_box())["height"]
            assert one_line < 40
            await long_row.locator("button.expander").click()
            assert (await long_row.bounding_box())["height"] > 3 * one_line
            await long_row.locator("button.expander").click()
            await page.evaluate("scrollTo(0, 0)")
            await page.wait_for_timeout(500)
            await shot(page, "scope", tmp_path)

            # Commander: compose a command, a refused value, send; it arrives and is acked.
            await page.goto(f"{base}/commander")
            # the configuration's commands; the rest (telemetry) behind "show all"
            options = page.locator("#cmd-type option")
            await page.locator('#cmd-type option[value="pygoby.examples.Command"]').wait_for(
                state="attached"
            )
            assert "pygoby.examples.SimpleStatus" not in await options.evaluate_all(
                "os => os.map(o => o.value)"
            )
            await page.check("#cmd-all")
            assert "pygoby.examples.SimpleStatus" in await options.evaluate_all(
                "os => os.map(o => o.value)"
            )
            await page.uncheck("#cmd-all")
            await page.select_option("#cmd-type", "pygoby.examples.Command")
            heading = page.locator('input[data-field="heading"]')
            await heading.wait_for()
            await heading.fill("400")
            error = page.locator('tr[data-field="heading"] .error')
            await error.filter(has_text="above the maximum 360").wait_for()
            for name, value in {
                "dest": "2",
                "command_id": "7",
                "heading": "90",
                "speed": "1.5",
                "depth": "20",
            }.items():
                box = page.locator(f'input[data-field="{name}"]')
                await box.fill(value)
                await box.dispatch_event("change")
            await page.wait_for_function(
                "!document.querySelector('input[data-field=\"heading\"]').classList.contains('invalid')"
            )
            await page.click("#cmd-preview")
            await (
                page.locator("#cmd-preview-text")
                .filter(has_text="COMMAND_OUT: dest=2,command_id=7,heading=90")
                .wait_for()
            )
            assert "COMMAND_OUT" not in r1.seen  # preview publishes nothing
            await page.click("#cmd-send")
            assert await r2.wait_for("DESIRED_HEADING", timeout=30) == 90.0
            assert "command_id=7" in await r2.wait_for("COMMAND_IN")
            status = page.locator('#cmd-records tr[data-id="1"] td.status')
            await status.filter(has_text="acknowledged").wait_for(timeout=30_000)
            await (
                page.locator("#cmd-notices .notice")
                .filter(has_text="Message acknowledged from queue: Command")
                .wait_for()
            )
            assert r1.values("COMMAND_OUT") == ["dest=2,command_id=7,heading=90,speed=1.5,depth=20"]
            assert "message::Command" in (tmp_path / "autosave.txt").read_text()
            await shot(page, "commander", tmp_path)

            # Map: vehicle 2 reports its position acoustically (STATUS_REPORT_IN at vehicle 1).
            for var, value in {
                "NAV_X": 300.0,
                "NAV_Y": 200.0,
                "NAV_SPEED": 1.5,
                "NAV_HEADING": 60.0,
                "NAV_DEPTH": 5.0,
            }.items():
                r2.client.publish(var, value)
            await r2.client.flush()
            r2.client.publish("SEND_STATUS", "now")
            await r1.wait_for("STATUS_REPORT_IN", timeout=30)
            await page.goto(f"{base}/map")
            await page.locator('#map-svg g.node[data-name="vehicle1"]').wait_for()
            await page.locator('#map-svg g.node[data-name="vehicle2"]').wait_for()
            await page.locator(
                '#map-svg line.link[data-from="vehicle2"][data-to="vehicle1"]'
            ).wait_for()
            # the grid reaches every edge of the map, whatever the window's shape
            reach = await page.evaluate(
                """() => {
                const map = document.querySelector('#map-svg').getBoundingClientRect();
                const lines = [...document.querySelectorAll('#map-svg .gridline')]
                  .map((l) => l.getBoundingClientRect());
                return [Math.min(...lines.map((r) => r.left)) - map.left,
                        map.right - Math.max(...lines.map((r) => r.right)),
                        Math.min(...lines.map((r) => r.top)) - map.top,
                        map.bottom - Math.max(...lines.map((r) => r.bottom))];
              }"""
            )
            assert all(gap <= 0 for gap in reach), reach
            await shot(page, "map", tmp_path)

            # Acomms: queues, the MAC cycle, transmissions and receptions with statistics.
            await page.goto(f"{base}/acomms")
            await page.locator('#acomms-queues tr[data-queue="pygoby.examples.Command"]').wait_for()
            await page.locator("#acomms-tx tbody tr").first.wait_for()
            await page.locator("#acomms-rx tbody tr").first.wait_for()
            await page.locator("#acomms-timeline li.acknowledged").first.wait_for()
            await page.locator("#acomms-slots .slot.current").wait_for()
            await shot(page, "acomms", tmp_path)
            # no 404 (the favicon was one); the 422s are the refused heading above
            assert [e for e in console_errors if "422" not in e] == []


LIAISON_GOBY11 = """
ProcessConfig = liaison
{
  common { log: false  verbosity: WARN  app_tick: 20 }
  liaison { http_port: 0  update_freq: 5 }
}
"""


@pytest.mark.timeout(240)
async def test_liaison_on_the_goby11_ccl_and_dccl_mission(tmp_path, browser):
    """The Goby 1.1 manual's ccl_and_dccl pair (under `pygoby antler`, as tests/goby11 runs
    it): CCL frames are named on the Acomms page, SIMPLE_STATUS (a time-triggered telemetry
    message) is behind 'show all' on the Commander page."""
    from tests.goby11.test_examples import localize, run_pair, wait_for

    directory, ports = localize(tmp_path, "ccl_and_dccl")
    mission = directory / "mm1.moos"
    mission.write_text(mission.read_text() + LIAISON_GOBY11)

    async def check():
        # the antlers' MOOSDBs are up within seconds, later on a busy machine
        loop = asyncio.get_running_loop()
        deadline = loop.time() + 60
        while True:
            try:
                _, writer = await asyncio.open_connection("127.0.0.1", ports["mm2"])
            except OSError:
                assert loop.time() < deadline, "mm2's MOOSDB never started"
                await asyncio.sleep(0.5)
                continue
            writer.close()
            break
        await wait_for(ports["mm2"], "STATUS_REPORT_IN", lambda v: "nav_x=100" in str(v))
        liaison = Liaison.from_mission(mission, "liaison")
        async with liaison:
            base = liaison.web.url.split("/scope")[0]
            page = await browser.new_page()
            await page.goto(liaison.web.url)
            await page.goto(f"{base}/acomms")
            named = page.locator("#acomms-rx td", has_text="Remus_State")
            await named.first.wait_for(timeout=120_000)
            assert await page.locator("#acomms-rx td", has_text="?").count() == 0
            await shot(page, "goby11-acomms", tmp_path)
            await page.goto(f"{base}/commander")
            options = page.locator("#cmd-type option")
            await page.locator("#cmd-all").wait_for()
            await page.wait_for_function("document.querySelectorAll('#cmd-type option').length")
            values = "os => os.map(o => o.value)"
            assert "SIMPLE_STATUS" not in await options.evaluate_all(values)
            await page.check("#cmd-all")
            assert "SIMPLE_STATUS" in await options.evaluate_all(values)

    await run_pair(directory, ports, check)


@pytest.mark.timeout(120)
async def test_liaison_over_a_recorded_log_in_chromium(tmp_path, browser):
    """`pygoby liaison --log liaison.alog --mission acomms.moos` (no MOOSDB): the slider moved
    to 25 s shows the log's values then on Scope, Acomms and Map; play at 10x on a virtual
    clock moves them on; the Commander is off with a note."""
    from pygoby.topside.liaison.log_app import LogLiaison
    from pygoby.util.clock import VirtualClock

    data = Path(__file__).resolve().parents[1] / "data" / "alog"
    clock = VirtualClock(5000.0)
    liaison = LogLiaison(data / "liaison.alog", data / "acomms.moos", port=0, clock=clock)
    async with liaison:
        base = liaison.web.url.split("/scope")[0]
        page = await browser.new_page()
        console_errors: list[str] = []
        page.on("console", lambda m: console_errors.append(m.text) if m.type == "error" else None)
        await page.goto(liaison.web.url)
        await page.wait_for_function("!location.search.includes('token')")
        await page.locator("#log-bar").wait_for()
        assert await page.locator('nav a[data-page="commander"]').is_hidden()
        assert "1 damaged lines skipped" in await page.locator("#log-file").text_content()

        # the slider to 25 s: NAV_X of 24.2 s (10 + 2 x 24), not yet MISSION_PHASE (30.3 s)
        await page.locator("#log-slider").fill("25")
        nav_x = "document.querySelector('#scope-table tr[data-key=\"NAV_X\"] td.value')"
        await page.wait_for_function(f"{nav_x} && {nav_x}.textContent === '58'")
        log_time = "document.querySelector('#log-time').textContent"
        await page.wait_for_function(f"{log_time}.startsWith('25.0 / 60.2 s ')")
        assert await page.locator('#scope-table tr[data-key="MISSION_PHASE"]').count() == 0
        await shot(page, "log-scope", tmp_path)

        await page.goto(f"{base}/acomms")
        await page.locator("#acomms-tx tbody tr").nth(1).wait_for()
        assert await page.locator("#acomms-tx tbody tr").count() == 2  # at 5.5 and 15.5 s
        rx = page.locator("#acomms-rx tbody tr").first.locator("td")
        assert await rx.nth(4).text_content() == "11"  # the SNR of the 18.5 s reception

        await page.goto(f"{base}/map")
        await page.locator('#map-svg g.node[data-name="logtest"]').wait_for()
        label = page.locator('#map-svg g.node[data-name="logtest"] text')
        assert await label.text_content() == "logtest (58, -29)"

        # play at 10x: 2 s of the virtual clock are 20 s of log
        await page.select_option("#log-speed", "10")
        await page.click("#log-play")
        await page.wait_for_function(
            "document.querySelector('#log-play').dataset.playing === 'true'"
        )
        clock.advance(2.0)
        await page.wait_for_function(
            "document.querySelector('#map-svg g.node[data-name=\"logtest\"] text')"
            ".textContent === 'logtest (98, -49)'"
        )
        await page.click("#log-play")  # pause
        await page.wait_for_function(
            "document.querySelector('#log-play').dataset.playing === 'false'"
        )
        await page.goto(f"{base}/scope")
        await page.wait_for_function(f"{nav_x} && {nav_x}.textContent === '98'")
        phase = page.locator('#scope-table tr[data-key="MISSION_PHASE"] td.value')
        assert await phase.text_content() == "survey"
        await page.wait_for_function(f"{log_time}.startsWith('45.0 / 60.2 s ')")

        await page.goto(f"{base}/commander")
        await page.locator("#cmd-log-note").wait_for()
        assert await page.locator("#cmd-send").is_hidden()
        assert console_errors == []
