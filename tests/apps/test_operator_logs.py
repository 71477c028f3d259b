"""What an operator sees: pAcommsHandler's log at each verbosity on a two-vehicle run (the
console script in its own process, emulated Micro-Modems, embedded MOOSDBs), the file log,
show_gui's live view and its plain-text fallback."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import re
import sys
from pathlib import Path

import pytest
from textual.widgets import OptionList, RichLog, Static

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue import QueueManager
from pygoby.dccl import Codec
from pygoby.moos.appgui import AppGUI
from pygoby.moos.db import MOOSDB
from pygoby.util.clock import VirtualClock
from pygoby.util.glog import LIBRARY_ROOT

from .acomms_mission import (
    COMMAND,
    PROTO,
    STATUS,
    MicroModemLink,
    Recorder,
    TwoCommunities,
    mission_clock,
    mission_text,
    start_db,
)

pytestmark = pytest.mark.e2e

PACOMMSHANDLER = str(Path(sys.executable).with_name("pAcommsHandler"))
NAV = {"NAV_X": 100.0, "NAV_Y": -50.0, "NAV_SPEED": 1.5, "NAV_HEADING": -90.0, "NAV_DEPTH": 10.0}


def has(lines: list[str], pattern: str) -> bool:
    return any(re.search(pattern, line) for line in lines)


async def test_log_lines_at_each_verbosity_on_a_two_vehicle_run(tmp_path):
    commons = {
        1: f'log: true  log_path: "{tmp_path}"  log_verbosity: DEBUG2  verbosity: VERBOSE',
        2: "log: false  verbosity: DEBUG1",
    }
    async with contextlib.AsyncExitStack() as stack:
        dbs = []
        for modem_id in (1, 2):
            dbs.append(await start_db(stack, modem_id))
        link = MicroModemLink()
        await link.start(stack, dbs)
        procs, outputs = [], []
        for modem_id, db in zip((1, 2), dbs, strict=True):
            mission = tmp_path / f"vehicle{modem_id}.moos"
            mission.write_text(
                mission_text(
                    modem_id,
                    db.port,
                    0,
                    driver=link.driver_cfg(modem_id),
                    common=f"app_tick: 20 {commons[modem_id]}",
                )
            )
            out = tmp_path / f"vehicle{modem_id}.out"
            outputs.append(out)
            with open(out, "wb") as sink:
                procs.append(
                    await asyncio.create_subprocess_exec(
                        PACOMMSHANDLER, str(mission), stdout=sink, stderr=asyncio.subprocess.STDOUT
                    )
                )
        r1, r2 = Recorder("r1", dbs[0].port, link.clock), Recorder("r2", dbs[1].port, link.clock)
        for recorder in (r1, r2):
            await recorder.start(
                ["ACOMMS_ACK", "COMMAND_IN", "ACOMMS_NMEA_IN", "ACOMMS_MAC_SLOT_START", "DB_TIME"]
            )
            stack.push_async_callback(recorder.close)
        try:
            for recorder in (r1, r2):  # both apps running, their modems answering, and DB_TIME
                for var in ("ACOMMS_NMEA_IN", "ACOMMS_MAC_SLOT_START", "DB_TIME"):  # (a time)
                    await recorder.wait_for(var, timeout=60)
            for var, value in NAV.items():
                r1.client.publish(var, value)
            r1.client.publish("COMMAND_OUT", "dest=2,command_id=7,heading=90,speed=1.5,depth=20")
            await r2.wait_for("COMMAND_IN", timeout=60)
            await r1.wait_for("ACOMMS_ACK", timeout=60)
        finally:
            for proc in procs:
                proc.send_signal(2)
            assert [await asyncio.wait_for(proc.wait(), 15) for proc in procs] == [0, 0]

    v1 = outputs[0].read_text().splitlines()
    v2 = outputs[1].read_text().splitlines()
    v1_file = next(tmp_path.glob("pAcommsHandler_vehicle1_2*.txt")).read_text().splitlines()
    head = r"^pAcommsHandler \[\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d{3}\] "

    # VERBOSE (vehicle 1's terminal): the message's journey, one line per step
    assert has(v1, head + r"\{goby::moos::translator\}: created pygoby\.examples\.Command$")
    assert has(
        v1,
        head + r"\{goby::acomms::queue::push::1\}: pushed pygoby\.examples\.Command "
        r"\(1->2, \d+ B, ack requested\): queue size 1/100, priority [\d.e-]+$",
    )
    assert has(
        v1,
        r"\{goby::acomms::queue::pop::1\}: popped pygoby\.examples\.Command \(1->2, "
        r"\d+ B\) for frame 0 at priority [\d.e-]+; kept until acknowledged",
    )
    assert has(
        v1,
        r"\{goby::acomms::queue::out::1\}: transmit slot 0: 1->2, rate 1, \d frame\(s\), "
        r"\d+ B: pygoby\.examples\.Command \(ack requested\)$",
    )
    assert has(
        v1,
        r"\{goby::acomms::queue::in::1\}: received ACK 2->1 for frame\(s\) \[0\]: "
        r"acknowledges pygoby\.examples\.Command$",
    )
    assert has(v1, r"\{goby::acomms::amac::1\}: MAC MAC_FIXED_DECENTRALIZED started$")
    # ... and nothing of the levels below it
    assert not has(v1, r" [<>]{2} \$") and not has(v1, r"amac::1\}: slot|contest for")

    # DEBUG1 (vehicle 2's terminal): the modem's NMEA both ways, and the VERBOSE lines
    assert has(v2, r"\{goby::acomms::modemdriver::out::WHOI_MICROMODEM::2\}: >> \$CCCFG,SRC,2\*")
    assert has(v2, r"\{goby::acomms::modemdriver::in::WHOI_MICROMODEM::2\}: << \$CARXD,")
    # (rate: goby3 reads no rate from a received packet, so the received transmission says 0)
    assert has(
        v2,
        r"\{goby::acomms::queue::in::2\}: received 1->2, rate 0, \d frame\(s\), \d+ B: "
        r"pygoby\.examples\.Command \(ack requested\)$",
    )
    assert has(v2, r"\{goby::moos::translator\}: published COMMAND_IN, DESIRED_HEADING$")
    assert not has(v2, r"amac::2\}: slot|contest for")

    # DEBUG2 (vehicle 1's file log): MAC slot timing and the priority contests, NMEA too
    file_head = r"^\[ \d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d{3} \] "
    assert has(
        v1_file,
        file_head + r"\{goby::acomms::amac::1\}: slot 0 \(1->-1, rate 1, 3 s\) "
        r"starts at \d\d:\d\d:\d\d\.\d{3} \([\d.]+ s late\): ours, initiating$",
    )
    assert has(
        v1_file, r"\{goby::acomms::amac::1\}: cycle of 2 slots, 6 s: \[1->-1 3 s, 2->-1 3 s\]"
    )
    assert has(
        v1_file,
        r"\{goby::acomms::queue::priority::1\}: contest for 1->-1 \(0 B used\): "
        r"pygoby\.examples\.SimpleStatus: empty; pygoby\.examples\.Command: priority "
        r"[\d.e-]+ -> winner pygoby\.examples\.Command$",
    )
    assert has(v1_file, r"modemdriver::out::WHOI_MICROMODEM::1\}: >> \$CCCYC,")
    assert not any("\x1b[" in line for line in v1 + v1_file)  # no colour codes off a terminal


def test_queue_expiry_and_max_queue_drops_are_logged(caplog):
    clock = VirtualClock(1_000_000.0)
    codec = Codec(clock=clock)
    status = codec.load_proto(PROTO, STATUS)
    queue = QueueManager(codec, clock)
    queue.set_cfg(acomms_pb.QueueManagerConfig(modem_id=1))
    entry = acomms_pb.QueuedMessageEntry(protobuf_name=STATUS, max_queue=1, ttl=5, ack=False)
    entry.role.add(type=acomms_pb.QueuedMessageEntry.Role.SOURCE_ID, field="src")
    queue.add_queue(entry, status)
    report = {
        "src": 1,
        "time": clock.now(),
        "nav_x": 1,
        "nav_y": 2,
        "speed": 0,
        "heading": 0,
        "depth": 0,
    }
    with caplog.at_level("INFO", logger="pygoby.acomms.queue"):
        queue.push_message(status(**report))
        queue.push_message(status(**report))
        clock.advance(10)
        queue.do_work()
    lines = [(r.name, r.getMessage()) for r in caplog.records]
    assert (
        "pygoby.acomms.queue.push.1",
        f"{STATUS} queue full (max_queue 1): dropped the oldest message (1->0)",
    ) in lines
    assert (
        "pygoby.acomms.queue.pop.1",
        f"expired {STATUS} (1->0) after its ttl of 5 s; queue size 0",
    ) in lines


async def test_show_gui_live_view(tmp_path):
    """show_gui's view (textual's pilot): the status panel with the queues and the MAC slot,
    the log of every group and of one group chosen in the list; `q` stops the app."""
    async with TwoCommunities(
        tmp_path, common="log: false  app_tick: 20  verbosity: VERBOSE"
    ) as net:
        app = net.apps[0]
        gui = AppGUI(app)
        for logger in (app.log, logging.getLogger(LIBRARY_ROOT)):  # as run() does at start
            logger.addHandler(gui.handler)
        try:
            async with gui.run_test(size=(160, 40)) as pilot:
                await net.ready()
                r1 = net.recorders[0]
                for var, value in NAV.items():
                    r1.client.publish(var, value)
                r1.client.publish("COMMAND_OUT", "dest=2,command_id=3,heading=9,speed=1,depth=2")
                await net.recorders[1].wait_for("COMMAND_IN", timeout=30)
                await pilot.pause(0.5)
                status = str(gui.query_one("#status", Static).render())
                assert "MOOSDB 127.0.0.1:" in status and ": connected" in status
                assert "primary driver WHOI_MICROMODEM::1: running" in status
                assert re.search(r"MAC slot \d \(\d->-1, rate 1, 3 s\); next in [\d.]+ s", status)
                assert f"queue {STATUS} (20): 0" in status and f"queue {COMMAND} (21): " in status
                log_text = "\n".join(line.text for line in gui.query_one("#log", RichLog).lines)
                assert "{goby::acomms::queue::push::1}: pushed pygoby.examples.Command" in log_text
                assert "{goby::acomms::queue::out::1}: transmit slot 0" in log_text

                groups = gui.query_one("#groups", OptionList)
                groups.focus()
                groups.highlighted = groups.get_option_index("goby::acomms::queue::out::1")
                await pilot.press("enter")
                await pilot.pause()
                shown = [line.text for line in gui.query_one("#log", RichLog).lines]
                assert shown and all("{goby::acomms::queue::out::1}" in line for line in shown)

                await pilot.press("q")
                await pilot.pause()
                assert app.stop_requested
        finally:
            for logger in (app.log, logging.getLogger(LIBRARY_ROOT)):
                logger.removeHandler(gui.handler)


async def test_show_gui_off_a_terminal_keeps_plain_text(tmp_path):
    """goby3-examples' missions say show_gui: true; under antler or a pipe that must not break
    the output: one line says so and the log goes on as text (here at -vv: DEBUG1, above the
    mission's VERBOSE)."""
    async with MOOSDB(port=0, clock=mission_clock()) as db:
        mission = tmp_path / "gui.moos"
        common = "log: false verbosity: VERBOSE show_gui: true"
        mission.write_text(mission_text(1, db.port, 0, driver="", common=common))
        recorder = Recorder("watcher", db.port, mission_clock())
        await recorder.start(["MODEM_ID"])
        proc = await asyncio.create_subprocess_exec(
            PACOMMSHANDLER,
            str(mission),
            "-vv",
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT,
        )
        try:
            await recorder.wait_for("MODEM_ID", timeout=30)
        finally:
            proc.send_signal(2)
            out, _ = await asyncio.wait_for(proc.communicate(), 15)
            await recorder.close()
    lines = out.decode().splitlines()
    assert proc.returncode == 0
    assert has(
        lines,
        r"^pAcommsHandler \[.*\]: show_gui: standard output is not a terminal; the log "
        r"stays plain text$",
    )
    assert has(lines, r"\{goby::acomms::amac::1\}: MAC MAC_FIXED_DECENTRALIZED started")
    assert has(lines, r"\{goby::acomms::amac::1\}: cycle of 2 slots")  # DEBUG1: -vv
    assert not any("\x1b" in line for line in lines)
