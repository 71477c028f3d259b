"""`pygoby antler mission.moos`: pAntler for pygoby.

Starts the embedded MOOSDB (as `python -m pygoby.cli moosdb mission.moos`), then every `Run =`
program of the ANTLER block as a subprocess with the argument vector `<program> <mission> <MOOS
name> [extra args]`, pausing MSBetweenLaunches ms after each. A `Run = MOOSDB` line stands for
the DB (started as above). If the mission's ServerPort is already taken, antler refuses to start
(`--no-db` uses the MOOSDB already listening there instead).

What the operator sees: each program's output line by line behind its name (`name | ...`; in
colour for `NewConsole = true` on a terminal), or, with `logs=DIR`, one file per program
(`DIR/<name>.log`); a line for each program that exits, with its status. On SIGINT/SIGTERM every
child gets SIGINT, then SIGKILL after `grace` seconds. When every launched program has exited,
the DB is stopped. The exit status is 1 if a program (or the DB) died on its own with a non-zero
status, 0 otherwise.
"""

from __future__ import annotations

import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from pygoby.errors import ConfigError
from pygoby.moos.errors import AntlerError, MissionFileError
from pygoby.moos.moosfile import AntlerRun, MissionFile
from pygoby.moos.protocol import DEFAULT_PORT

log = logging.getLogger(__name__)

COLOURS = ("36", "33", "35", "32", "34", "31", "96", "93", "95", "92")  # ANSI, one per program
DB_NAME = "MOOSDB"


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


def describe_status(returncode: int) -> str:
    if returncode < 0:
        try:
            return f"was killed by {signal.Signals(-returncode).name}"
        except ValueError:
            return f"was killed by signal {-returncode}"
    return f"exited with status {returncode}"


@dataclass(eq=False)
class Child:
    """One launched program and the thread that copies its output."""

    name: str
    proc: subprocess.Popen[bytes]
    prefix: str = ""
    pump: threading.Thread | None = None
    reported: bool = False
    stopped: bool = False  # antler asked it to stop: its status is not a failure


class Antler:
    def __init__(
        self,
        mission_path: str | os.PathLike[str],
        start_db: bool = True,
        grace: float = 5.0,
        logs: str | os.PathLike[str] | None = None,
        colour: bool | None = None,
        out: IO[str] | None = None,
    ) -> None:
        """`logs`: a folder for one output file per program (instead of the terminal);
        `colour`: coloured prefixes for NewConsole programs (default: when `out` is a tty)."""
        self.mission_path = Path(mission_path).resolve()
        self.mission = MissionFile.read(self.mission_path)
        self.config = self.mission.antler()
        self._db_address()  # a bad ServerPort fails here, before anything is started
        self.start_db = start_db
        self.grace = grace
        self.logs = Path(logs) if logs is not None else None
        self.out = out if out is not None else sys.stdout
        self.err = sys.stderr if out is None else out
        self.colour = colour if colour is not None else self.out.isatty()
        self.children: list[Child] = []
        self.db: Child | None = None
        self.failed: list[str] = []
        self._stop = False
        self._write_lock = threading.Lock()

    # -- output --------------------------------------------------------------------------------

    def say(self, text: str) -> None:
        self._write(f"antler: {text}\n")

    def warn(self, text: str) -> None:
        """A problem: on stderr."""
        self._write(f"antler: {text}\n", self.err)

    def _write(self, text: str, stream: IO[str] | None = None) -> None:
        with self._write_lock:
            try:
                (stream or self.out).write(text)
                (stream or self.out).flush()
            except (BrokenPipeError, ValueError):
                pass  # our reader went away: the programs keep running

    def _prefix(self, name: str, new_console: bool) -> str:
        width = max([len(DB_NAME), *(len(r.moos_name) for r in self.config.runs)])
        if self.colour and new_console:
            colour = COLOURS[len(self.children) % len(COLOURS)]
            return f"\x1b[{colour}m{name:<{width}}\x1b[0m | "
        return f"{name:<{width}} | "

    def _spawn(self, name: str, argv: list[str], new_console: bool) -> Child:
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}  # lines as they are written
        if self.logs is not None:
            self.logs.mkdir(parents=True, exist_ok=True)
            with open(self.logs / f"{name}.log", "ab") as sink:
                proc = subprocess.Popen(argv, stdout=sink, stderr=subprocess.STDOUT, env=env)
            return Child(name, proc)
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env)
        child = Child(name, proc, self._prefix(name, new_console))
        child.pump = threading.Thread(target=self._copy_output, args=(child,), daemon=True)
        child.pump.start()
        return child

    def _copy_output(self, child: Child) -> None:
        assert child.proc.stdout is not None
        for raw in iter(child.proc.stdout.readline, b""):
            self._write(child.prefix + raw.decode("utf-8", "replace").rstrip("\r\n") + "\n")

    # -- life cycle ----------------------------------------------------------------------------

    def _db_address(self) -> tuple[str, int]:
        host = self.mission.get_value("ServerHost") or "localhost"
        port = self.mission.get_port("ServerPort") or DEFAULT_PORT
        return ("127.0.0.1" if host.upper() == "LOCALHOST" else host), port

    def launch(self) -> None:
        host, port = self._db_address()
        if self.start_db:
            if db_listening(host, port):
                raise AntlerError(
                    f"port {port} on {host} (ServerPort of {self.mission_path.name}) is already "
                    "in use by another process: stop it, change ServerPort, or run antler with "
                    "--no-db to use the MOOSDB listening there"
                )
            db_argv = [sys.executable, "-m", "pygoby.cli", "moosdb", str(self.mission_path)]
            self.db = self._spawn(DB_NAME, db_argv, new_console=False)
            deadline = time.monotonic() + 10.0
            while not db_listening(host, port):
                if self.db.proc.poll() is not None:
                    self._report(self.db)
                    raise AntlerError("the embedded MOOSDB could not start")
                if time.monotonic() > deadline:
                    raise AntlerError(f"the embedded MOOSDB is not listening on {host}:{port}")
                time.sleep(0.05)
        elif not db_listening(host, port):
            self.warn(f"warning: no MOOSDB listens on {host}:{port} yet (--no-db)")
        for run in self.config.runs:
            if self._stop:
                return
            if Path(run.program).name == DB_NAME:
                continue  # the DB is handled above
            argv = child_argv(run, self.mission_path, self.config.executable_path)
            if argv is None:
                self.warn(
                    f"{run.moos_name}: {run.program} is not available (no such program on "
                    "PATH); the other processes run without it"
                )
                continue
            new_console = run.options.get("NewConsole", "false").lower() == "true"
            self.children.append(self._spawn(run.moos_name, argv, new_console))
            self.say(f"launched {run.moos_name} ({' '.join(argv)})")
            time.sleep(self.config.ms_between_launches / 1000.0)

    def _report(self, child: Child) -> None:
        """Say how `child` ended (once); a program that died by itself with a non-zero status
        is a failure."""
        if child.reported or child.proc.returncode is None:
            return
        child.reported = True
        if child.pump is not None:
            child.pump.join(timeout=1.0)  # its last lines before the status line
        status = child.proc.returncode
        self.say(f"{child.name} {describe_status(status)}")
        if status != 0 and not child.stopped:
            self.failed.append(child.name)

    def poll(self) -> None:
        for child in [*self.children, *([self.db] if self.db else [])]:
            if child.proc.poll() is not None:
                self._report(child)

    def stop(self) -> None:
        everyone = [*self.children, *([self.db] if self.db is not None else [])]
        for child in everyone:
            if child.proc.poll() is None:
                child.stopped = True
                child.proc.send_signal(signal.SIGINT)
        deadline = time.monotonic() + self.grace
        for child in everyone:
            try:
                child.proc.wait(max(deadline - time.monotonic(), 0.01))
            except subprocess.TimeoutExpired:
                child.proc.kill()
                child.proc.wait()
            self._report(child)

    def run(self) -> int:
        def request_stop(signum: int, _frame: object) -> None:
            self._stop = True

        old = {s: signal.signal(s, request_stop) for s in (signal.SIGINT, signal.SIGTERM)}
        try:
            self.launch()
            while not self._stop:
                self.poll()
                if self.children and all(c.proc.returncode is not None for c in self.children):
                    break
                if not self.children and self.db is None:
                    break
                if self.db is not None and self.db.reported:
                    break  # the DB died: the mission cannot go on
                time.sleep(0.1)
        except AntlerError as err:
            self.warn(str(err))
            self.failed.append("antler")
        finally:
            self.stop()
            for sig, handler in old.items():
                signal.signal(sig, handler)
        if self.failed:
            self.warn(f"failed: {', '.join(self.failed)}")
            return 1
        return 0


def run_antler(
    mission: str, start_db: bool = True, logs: str | None = None, colour: bool | None = None
) -> int:
    logging.basicConfig(level=logging.INFO, format="antler: %(message)s")
    try:
        antler = Antler(mission, start_db=start_db, logs=logs, colour=colour)
    except (OSError, MissionFileError, ConfigError) as err:
        print(f"antler: {err}", file=sys.stderr)
        return 1
    return antler.run()
