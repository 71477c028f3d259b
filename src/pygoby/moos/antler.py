"""`pygoby antler mission.moos`: pAntler for pygoby (spec moos.md 19).

Starts the embedded MOOSDB (as `python -m pygoby.cli moosdb mission.moos`) unless something
already listens on the mission's ServerPort, then every `Run =` program of the ANTLER block as
a subprocess with the argument vector `<program> <mission> <MOOS name> [extra args]`, pausing
MSBetweenLaunches ms after each. A `Run = MOOSDB` line stands for the DB (started as above). On
SIGINT/SIGTERM every child gets SIGINT, then SIGKILL after `grace` seconds. When every launched
app has exited, the DB is stopped and antler exits.
"""

from __future__ import annotations

import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

from pygoby.errors import ConfigError
from pygoby.moos.errors import MissionFileError
from pygoby.moos.moosfile import AntlerRun, MissionFile
from pygoby.moos.protocol import DEFAULT_PORT

log = logging.getLogger(__name__)


def db_listening(host: str, port: int, timeout: float = 0.5) -> bool:
    """Whether something accepts TCP connections there (the connection is closed at once)."""
    try:
        with socket.create_connection((host, port), timeout=timeout):
            return True
    except OSError:
        return False


def child_argv(run: AntlerRun, mission: Path, executable_path: str | None) -> list[str] | None:
    options = {k.lower(): v for k, v in run.options.items()}
    directory = options.get("path") or executable_path
    if directory and directory.upper() != "SYSTEM":
        program = str(Path(directory) / run.program)
    else:
        # PATH, then beside this Python (pygoby's console scripts when its venv is not activated)
        beside = Path(sys.executable).with_name(run.program)
        program = shutil.which(run.program) or (str(beside) if beside.is_file() else "")
    if not program or not os.access(program, os.X_OK):
        return None
    argv = [program]
    if options.get("inhibitmoosparams", "false").lower() != "true":
        argv += [str(mission), run.moos_name]
    return argv + run.extra_args


class Antler:
    def __init__(self, mission_path: str | os.PathLike[str], start_db: bool = True, grace: float = 5.0) -> None:
        self.mission_path = Path(mission_path).resolve()
        self.mission = MissionFile.read(self.mission_path)
        self.config = self.mission.antler()
        self._db_address()  # a bad ServerPort fails here, before anything is started
        self.start_db = start_db
        self.grace = grace
        self.children: list[tuple[str, subprocess.Popen[bytes]]] = []
        self.db: subprocess.Popen[bytes] | None = None
        self._stop = False

    def _db_address(self) -> tuple[str, int]:
        host = self.mission.get_value("ServerHost") or "localhost"
        return ("127.0.0.1" if host.upper() == "LOCALHOST" else host), self.mission.get_port("ServerPort") or DEFAULT_PORT

    def launch(self) -> None:
        host, port = self._db_address()
        if self.start_db and not db_listening(host, port):
            argv = [sys.executable, "-m", "pygoby.cli", "moosdb", str(self.mission_path)]
            self.db = subprocess.Popen(argv)
            deadline = time.monotonic() + 10.0
            while not db_listening(host, port) and time.monotonic() < deadline:
                if self.db.poll() is not None:
                    raise RuntimeError(f"the embedded MOOSDB exited with status {self.db.returncode}")
                time.sleep(0.05)
            log.info("started the embedded MOOSDB on port %d (pid %d)", port, self.db.pid)
        elif self.start_db:
            log.info("a MOOSDB already listens on %s:%d; not starting one", host, port)
        for run in self.config.runs:
            if self._stop:
                return
            if Path(run.program).name == "MOOSDB":
                continue  # the DB is handled above
            argv = child_argv(run, self.mission_path, self.config.executable_path)
            if argv is None:
                log.error("cannot find executable %r; not launched", run.program)
                print(f"antler: {run.moos_name}: {run.program} is not available (no such program "
                      "on PATH); the other processes run without it", file=sys.stderr, flush=True)  # fmt: skip
                continue
            if run.options.get("NewConsole", "false").lower() == "true":
                log.info("%s: NewConsole is not supported; running in this terminal", run.moos_name)
            self.children.append((run.moos_name, subprocess.Popen(argv)))
            print(f"antler: launched {run.moos_name} ({' '.join(argv)})", flush=True)
            time.sleep(self.config.ms_between_launches / 1000.0)

    def stop(self) -> None:
        procs = [proc for _, proc in self.children]
        if self.db is not None:
            procs.append(self.db)
        for proc in procs:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        deadline = time.monotonic() + self.grace
        for proc in procs:
            try:
                proc.wait(max(deadline - time.monotonic(), 0.01))
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()

    def run(self) -> int:
        def request_stop(signum: int, _frame: object) -> None:
            self._stop = True

        old = {s: signal.signal(s, request_stop) for s in (signal.SIGINT, signal.SIGTERM)}
        try:
            self.launch()
            while not self._stop:
                if self.children and all(proc.poll() is not None for _, proc in self.children):
                    break
                if not self.children and self.db is None:
                    break
                time.sleep(0.1)
        finally:
            self.stop()
            for sig, handler in old.items():
                signal.signal(sig, handler)
        return 0


def run_antler(mission: str, start_db: bool = True) -> int:
    logging.basicConfig(level=logging.INFO, format="antler: %(message)s")
    try:
        antler = Antler(mission, start_db=start_db)
    except (OSError, MissionFileError, ConfigError) as err:
        print(f"antler: {err}", file=sys.stderr)
        return 1
    return antler.run()
