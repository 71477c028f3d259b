"""An app whose MOOSDB cannot be reached says so at the default verbosity, within a few seconds,
then once a minute (it kept silent unless run with -vv)."""

from __future__ import annotations

import selectors
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pygoby.moos.client import (
    UNREACHABLE_FIRST_WARNING,
    UNREACHABLE_WARNING_EVERY,
    UnreachableWarnings,
)


def test_the_first_warning_after_a_few_seconds_then_one_a_minute():
    warnings = UnreachableWarnings()
    attempts = [100.0 + 0.5 * i for i in range(int(2.5 * UNREACHABLE_WARNING_EVERY / 0.5))]
    due = [t - 100.0 for t in attempts if warnings.failed(t)]
    assert due == [
        UNREACHABLE_FIRST_WARNING,
        UNREACHABLE_FIRST_WARNING + UNREACHABLE_WARNING_EVERY,
        UNREACHABLE_FIRST_WARNING + 2 * UNREACHABLE_WARNING_EVERY,
    ]
    warnings.reset()  # connected; a later outage is told about a few seconds in again
    assert not warnings.failed(1000.0) and warnings.failed(1000.0 + UNREACHABLE_FIRST_WARNING)


@pytest.mark.timeout(60)
def test_ptranslator_with_a_wrong_server_port_warns(tmp_path):
    with socket.create_server(("127.0.0.1", 0)) as free:
        port = free.getsockname()[1]  # closed again below: nothing listens there
    mission = tmp_path / "m.moos"
    mission.write_text(
        f"ServerHost = localhost\nServerPort = {port}\nProcessConfig = pTranslator\n{{\n}}\n"
    )
    script = Path(sys.executable).with_name("pTranslator")
    app = subprocess.Popen(
        [str(script), str(mission)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        cwd=tmp_path,  # its log file goes there
    )
    try:
        chooser = selectors.DefaultSelector()
        chooser.register(app.stdout, selectors.EVENT_READ)
        deadline = time.monotonic() + 30
        lines: list[str] = []
        while time.monotonic() < deadline and not any("cannot connect" in x for x in lines):
            if chooser.select(timeout=1):
                line = app.stdout.readline()
                if not line:
                    break
                lines.append(line)
        warned = [x for x in lines if "cannot connect" in x]
        assert warned, lines
        assert (
            f"cannot connect to the MOOSDB at 127.0.0.1:{port} (ServerHost/ServerPort)" in warned[0]
        )
        assert "(Warning)" in warned[0] and "still trying" in warned[0]
    finally:
        app.terminate()
        app.wait(10)
