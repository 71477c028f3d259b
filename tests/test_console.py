"""The console programs as a shell user meets them: `pygoby --version`, output piped into a
reader that goes away (`| head`), `--example_config` blocks that parse when copied."""

from __future__ import annotations

import asyncio
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from google.protobuf import text_format

import pygoby
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.moos.db import MOOSDB
from pygoby.util.console import BROKEN_PIPE_STATUS

pytestmark = pytest.mark.e2e

BIN = Path(sys.executable).parent
PROTO = Path(__file__).resolve().parent.parent / "examples" / "two_vehicles" / "two_vehicles.proto"


def test_pygoby_version():
    shown = subprocess.run(
        [BIN / "pygoby", "--version"], capture_output=True, text=True, check=True
    )
    assert shown.stdout == f"pygoby {pygoby.__version__}\n"
    app = subprocess.run(
        [BIN / "pAcommsHandler", "--version"], capture_output=True, text=True, check=True
    )
    assert app.stdout == f"pAcommsHandler {pygoby.__version__}\n"


def test_pygoby_subcommand_apps_show_how_they_are_typed():
    """`pygoby liaison --help` shows `usage: pygoby liaison` (the app's name stays liaison)."""
    shown = subprocess.run(
        [BIN / "pygoby", "liaison", "--help"], capture_output=True, text=True, check=True
    )
    assert shown.stdout.startswith("usage: pygoby liaison [-h]")
    assert "liaison: a Goby MOOS application" in shown.stdout
    example = subprocess.run(
        [BIN / "pygoby", "liaison", "--example_config"], capture_output=True, text=True, check=True
    )
    assert example.stdout.startswith("ProcessConfig = liaison\n")


def _with_reader_gone(argv: list[str]) -> subprocess.CompletedProcess:
    """Run `argv` with its stdout a pipe whose reader closed before it wrote anything."""
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()
    err = proc.stderr.read().decode()
    return subprocess.CompletedProcess(argv, proc.wait(), "", err)


def test_output_into_a_closed_pipe_ends_quietly(tmp_path):
    for argv in (
        [BIN / "pAcommsHandler", "--example_config"],
        [
            BIN / "pygoby",
            "dccl",
            "--proto",
            str(PROTO),
            "--message",
            "pygoby.examples.SimpleStatus",
            "analyze",
        ],
    ):
        done = _with_reader_gone([str(a) for a in argv])
        assert done.stderr == "", done.stderr  # no BrokenPipeError traceback
        assert done.returncode == BROKEN_PIPE_STATUS


async def test_a_running_app_whose_reader_went_away_carries_on(tmp_path):
    async with MOOSDB(port=0) as db:
        mission = tmp_path / "m.moos"
        mission.write_text(
            f"ServerPort = {db.port}\nProcessConfig = pAcommsHandler\n"
            "{\n common { log: false verbosity: DEBUG2 }\n modem_id: 1\n"
            " mac_cfg { type: MAC_FIXED_DECENTRALIZED slot { src: 1 slot_seconds: 0.5 } }"
            "\n}\n"
        )
        proc = subprocess.Popen(
            [BIN / "pAcommsHandler", mission], stdout=subprocess.PIPE, stderr=subprocess.PIPE
        )
        assert proc.stdout is not None
        await asyncio.to_thread(proc.stdout.readline)  # it is logging ...
        proc.stdout.close()  # ... and its reader goes away
        async with asyncio.timeout(20):
            while "pAcommsHandler" not in db.client_names:
                await asyncio.sleep(0.05)
        await asyncio.sleep(1.5)  # it goes on logging (a slot every 0.5 s)
        assert proc.poll() is None  # still running
        proc.send_signal(signal.SIGINT)
        _, err = await asyncio.to_thread(proc.communicate, timeout=15)
    assert proc.returncode == 0
    assert b"Traceback" not in err and b"Logging error" not in err, err.decode()


def test_example_config_required_fields_have_placeholders_that_parse():
    text = pAcommsHandler.example_config()
    assert "      type: INI_DOUBLE  # Type of the MOOS variable to post " in text.splitlines()
    # a copied initializer block (required type and moos_var included) parses as it is
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.strip().startswith("initializer {"))
    end = next(i for i in range(start, len(lines)) if lines[i].strip() == "}")
    block = "\n".join(lines[start : end + 1])
    cfg = pAcommsHandler.load_config_class()()
    text_format.Merge("common { " + block + " }", cfg)
    assert cfg.common.initializer[0].type == cfg.common.initializer[0].INI_DOUBLE
