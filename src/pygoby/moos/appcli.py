"""The command line of every Goby MOOS application.

    APP [options] mission.moos [moos_name]

`-c/--moos_file` and `-a/--moos_name` are the two positionals by name, `-e/--example_config`
prints a ProcessConfig block, `-V/--version` the version, `-v/--verbose` (repeated: -vvv)
raises the terminal's verbosity, and `--<field> <value>` (or
`--<field>=<value>`) overrides any top-level configuration field. `run_app(app_class, argv)` is
what `GobyMOOSApp.main` does: read the configuration (a configuration error prints one clear
message and exits 1 before connecting), then run the app until SIGINT/SIGTERM or until it stops
itself, and return its exit status. A signal always ends the app within a few seconds.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
from collections.abc import Sequence
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from pygoby.errors import ConfigError
from pygoby.moos.appconfig import collecting_notes
from pygoby.moos.moosfile import MissionFile
from pygoby.util.aiorun import StopSignals
from pygoby.util.console import quiet_broken_pipe
from pygoby.util.errors import MissingExtraError

if TYPE_CHECKING:
    from google.protobuf.message import Message


class CommandLineApp(Protocol):
    """What the command line needs of an app class and its instances
    (pygoby.moos.app.GobyMOOSApp is one): typed here so this module does not import the app base
    that calls it."""

    default_name: ClassVar[str]
    name: str
    failure: str | None
    exit_status: int
    config_notes: list[str]

    def __init__(
        self, cfg: Message, *, name: str | None = None, mission: MissionFile | None = None
    ) -> None: ...

    @classmethod
    def read_config(
        cls, mission: MissionFile | None, name: str, overrides: Sequence[tuple[str, str]] = ()
    ) -> Message: ...

    @classmethod
    def example_config(cls, name: str | None = None) -> str: ...

    def request_stop(self) -> None: ...

    async def run(self) -> None: ...


Overrides = list[tuple[str, str]]
VERBOSE_ENUM = 4  # goby.util.protobuf.GLogConfig.Verbosity.VERBOSE


def package_version() -> str:
    try:
        return version("pygoby")
    except PackageNotFoundError:
        return "unknown"


def program_name(app_class: type[CommandLineApp], argv0: str) -> str:
    """The name the program was started as; the app's default name when run from Python."""
    base = Path(argv0).name
    if not base or base.endswith(".py") or base in ("python", "python3", "-c"):
        return app_class.default_name or app_class.__name__
    return base


def argument_parser(program: str, command: str | None = None) -> argparse.ArgumentParser:
    """The app's command line; `command` is how it is typed when that is not `program` (e.g.
    `pygoby liaison`), for the usage and --version lines."""
    parser = argparse.ArgumentParser(
        prog=command or program, description=f"{program}: a Goby MOOS application"
    )
    parser.add_argument("mission", nargs="?", help=".moos mission file")
    parser.add_argument("alias", nargs="?", help="name to use with the MOOSDB and ProcessConfig")
    parser.add_argument("-c", "--moos_file", help="same as the mission positional")
    parser.add_argument("-a", "--moos_name", help="same as the alias positional")
    parser.add_argument(
        "-e",
        "--example_config",
        action="store_true",
        help="print an example ProcessConfig block and exit",
    )
    parser.add_argument(
        "-V", "--version", action="version", version=f"%(prog)s {package_version()}"
    )
    parser.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="terminal verbosity: -v VERBOSE, -vv DEBUG1, -vvv DEBUG2, -vvvv DEBUG3 "
        "(overrides common.verbosity)",
    )
    return parser


def parse_overrides(rest: list[str]) -> Overrides:
    """`--field value` / `--field=value` pairs; ValueError for anything else."""
    out = []
    items = iter(rest)
    for item in items:
        if not item.startswith("--"):
            raise ValueError(f"unexpected argument {item!r}")
        key, eq, value = item[2:].partition("=")
        if not eq:
            following = next(items, None)
            if following is None:
                raise ValueError(f"option --{key} needs a value")
            value = following
        out.append((key, value))
    return out


def read_mission(path: str | None, name: str) -> MissionFile | None:
    """The mission file, or None (with a warning) when there is none or it cannot be opened:
    the configuration may still be complete from defaults and options."""
    if not path:
        return None
    try:
        return MissionFile.read(path)
    except OSError as err:
        print(f"{name}: warning: cannot open mission file {path}: {err.strerror}", file=sys.stderr)
        return None


def run_app(
    app_class: type[CommandLineApp],
    argv: Sequence[str] | None = None,
    prog: str | None = None,
    command: str | None = None,
) -> int:
    """`app_class.main`: parse the command line (`sys.argv` without `argv`), build the app and
    run it; returns the exit status. `prog` is the program's name (the default app name),
    `command` how it is typed when that differs (a pygoby subcommand)."""
    args_in = list(sys.argv[1:] if argv is None else argv)
    program = prog or program_name(app_class, sys.argv[0] if argv is None else "")
    parser = argument_parser(program, command)
    known, rest = parser.parse_known_args(args_in)
    name = known.moos_name or known.alias or program
    if known.example_config:
        return quiet_broken_pipe(lambda: sys.stdout.write(app_class.example_config(name)) and 0)
    try:
        overrides = parse_overrides(rest)
    except ValueError as err:
        parser.error(str(err))
    mission = read_mission(known.moos_file or known.mission, name)
    try:
        with collecting_notes() as notes:
            cfg: Any = app_class.read_config(mission, name, overrides)  # (every app: `common`)
        if known.verbose:  # Verbosity enum: VERBOSE=4, DEBUG1=5, DEBUG2=6, DEBUG3=7
            cfg.common.verbosity = VERBOSE_ENUM + min(known.verbose, 4) - 1
        app = app_class(cfg, name=name, mission=mission)
        app.config_notes = notes
    except ConfigError as err:
        print(f"{name}: fatal configuration error: {err}", file=sys.stderr)
        return 1
    except MissingExtraError as err:  # the app needs a package a pip extra installs
        print(f"{name}: {err}", file=sys.stderr)
        return 1
    return quiet_broken_pipe(lambda: run_until_signal(app))


def run_until_signal(app: CommandLineApp) -> int:
    """Run `app` until SIGINT/SIGTERM asks it to stop (it stops cleanly, or the process ends
    after `STOP_GRACE` s whatever it is doing: pygoby.util.aiorun.StopSignals) or it stops
    itself; its exit status (its `failure`, if any, printed on stderr)."""

    async def runner() -> None:
        with StopSignals(asyncio.get_running_loop(), app.request_stop, app.name):
            await app.run()

    try:
        asyncio.run(runner())
    except KeyboardInterrupt:  # before the handlers were in place
        return 130
    if app.failure:
        print(f"{app.name}: {app.failure}", file=sys.stderr)
    return app.exit_status
